//! Configurations named on the command line (`pcaline eval --config`): a
//! preset name, or a TOML or JSON file that names a preset and overrides
//! some of its fields:
//!
//! ```toml
//! preset = "default"          # paper | default | split-and-merge | ... (Preset)
//! sensor = "sick-lms"         # optional: utm30lx-ew | sick-lms | urg-04lx | rplidar
//! [detector.fitting]
//! eth = 30.0
//! min_line_points = 8
//! [map]
//! max_offset_m = 0.2
//! [aiding.estimator.motion]
//! rotation_per_m = 0.02       # the localization source's noise
//! ```
//!
//! `pcaline eval --show-config NAME` prints a preset in this form with every
//! field. An unknown key is an error naming it; an enum field (such as
//! `detector.segmentation.level2`) is replaced whole when the file names
//! another variant; an optional rule (such as `detector.noise_estimation` or
//! `map.merge_gate`) is turned off by `false`.

use crate::exit::BadInput;
use anyhow::Result;
use pcaline::aiding::{AidingConfig, AidingMode, LoopClosureConfig};
use pcaline::geometry::SensorProfile;
use pcaline::mapping::MapConfig;
use pcaline::{Config, ConfigError, Pose2, RangeNoise};
use serde::{Deserialize, Serialize};
use std::path::Path;
use toml::Value;

/// The presets a configuration may start from: the one registry of their
/// names and of what each holds ([`Preset::configs`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Preset {
    /// The paper exactly: its detector, map and heading aiding.
    Paper,
    /// The default detector (noise-aware rules, the range noise estimated
    /// from each scan with the UTM-30LX-EW datasheet as its nominal).
    Default,
    /// The split-and-merge baseline.
    SplitAndMerge,
    /// The default told the range noise (constant).
    ToldSigma,
    /// The default's rules at the UTM-30LX-EW datasheet noise, not
    /// estimated (the default before 2026-12-05).
    Datasheet,
    /// Estimation and curved-surface chords refused.
    Adaptive,
}

impl Preset {
    /// Every preset, in the order the evaluation lists them.
    pub const ALL: [Preset; 6] = [
        Preset::Paper,
        Preset::Default,
        Preset::SplitAndMerge,
        Preset::ToldSigma,
        Preset::Datasheet,
        Preset::Adaptive,
    ];

    /// The name a command line and a configuration file write
    /// (`split-and-merge`).
    pub fn name(self) -> &'static str {
        match self {
            Preset::Paper => "paper",
            Preset::Default => "default",
            Preset::SplitAndMerge => "split-and-merge",
            Preset::ToldSigma => "told-sigma",
            Preset::Datasheet => "datasheet",
            Preset::Adaptive => "adaptive",
        }
    }

    /// The preset named `name`, or `None`.
    pub fn from_name(name: &str) -> Option<Self> {
        // `estimated` named the default estimating the noise before the
        // default did (2026-12-05): files that name it keep working.
        if name == "estimated" {
            return Some(Preset::Default);
        }
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The names, comma-separated, for messages.
    pub fn names() -> String {
        Self::ALL.map(Preset::name).join(", ")
    }

    /// The detector and map of the preset; `told-sigma` is told the range
    /// noise `sigma_m` (constant, at least 1 mm).
    pub fn configs(self, sigma_m: f64) -> (Config, MapConfig) {
        let map = MapConfig::default();
        match self {
            Preset::Paper => (Config::paper(), MapConfig::paper()),
            Preset::Default => (Config::default(), map),
            Preset::SplitAndMerge => (Config::split_and_merge(), map),
            Preset::ToldSigma => {
                (Config::noise_aware(RangeNoise::constant(sigma_m.max(1e-3))), map)
            }
            Preset::Datasheet => (Config::datasheet(SensorProfile::Utm30lxEw), map),
            Preset::Adaptive => (Config::adaptive(), map),
        }
    }
}

/// A detector and map configuration with the name it was given.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedConfig {
    /// The preset name or the file's path.
    pub name: String,
    /// The preset it starts from.
    pub preset: Preset,
    /// The detector.
    pub detector: Config,
    /// The line map.
    pub map: MapConfig,
    /// The aiding (the estimator by default; `pcaline map --aiding` and the
    /// evaluation's comparison modes replace its mode, not its settings).
    pub aiding: AidingConfig,
    /// Loop closure (`pcaline map` closes loops unless `--no-loop-closure`).
    pub loop_closure: LoopClosureConfig,
    /// The sensor the file names (`sensor = "sick-lms"`): its datasheet
    /// noise is already in `detector`.
    pub sensor: Option<SensorProfile>,
    /// Where the LIDAR sits on the vehicle whose poses a log gives
    /// (`[vehicle_from_sensor]` in a file; `pcaline map --mount` overrides
    /// it); the identity for the presets.
    pub vehicle_from_sensor: Pose2,
}

impl NamedConfig {
    /// The detector for a log recorded with `sensor`: the configuration's,
    /// with every noise-aware rule on the sensor's datasheet noise when a
    /// sensor other than the file's own is given.
    pub fn detector_for(&self, sensor: Option<SensorProfile>) -> Config {
        match sensor {
            Some(s) if Some(s) != self.sensor => self.detector.with_noise(s.range_noise()),
            _ => self.detector,
        }
    }

    /// The configuration's aiding in mode `mode` (its estimator settings kept).
    pub fn aiding_in(&self, mode: AidingMode) -> AidingConfig {
        let mut a = match mode {
            AidingMode::Estimator => self.aiding,
            AidingMode::Heading => self.heading_aiding(),
            AidingMode::None => AidingConfig::none(),
            _ => AidingConfig::full_pose(),
        };
        a.estimator = self.aiding.estimator;
        a
    }

    /// The heading aiding that goes with the configuration: the paper's
    /// eq. 11-14 for the paper preset, inverse-variance weights otherwise.
    pub fn heading_aiding(&self) -> AidingConfig {
        if self.preset == Preset::Paper { AidingConfig::paper() } else { AidingConfig::heading() }
    }
}

/// The form of a configuration file.
#[derive(Debug, Serialize, Deserialize)]
struct ConfigFile {
    preset: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sensor: Option<SensorProfile>,
    detector: Config,
    map: MapConfig,
    aiding: AidingConfig,
    loop_closure: LoopClosureConfig,
    /// Where the LIDAR sits on the vehicle (`x`, `y` metres, `heading`
    /// radians); the identity when the file leaves it out.
    #[serde(default)]
    vehicle_from_sensor: Pose2,
}

/// Resolves `spec`: a preset name, or the path of a TOML (`.toml`) or JSON
/// file. `sigma_m` is the range noise `told-sigma` is told.
pub fn resolve(spec: &str, sigma_m: f64) -> Result<NamedConfig> {
    if let Some(preset) = Preset::from_name(spec) {
        let (detector, map) = preset.configs(sigma_m);
        return Ok(NamedConfig {
            name: spec.to_string(),
            preset,
            detector,
            map,
            aiding: AidingConfig::estimator(),
            loop_closure: LoopClosureConfig::standard(),
            sensor: None,
            vehicle_from_sensor: Pose2::identity(),
        });
    }
    let path = Path::new(spec);
    if !path.exists() {
        return Err(BadInput(format!(
            "--config {spec}: neither a preset ({}) nor a file",
            Preset::names()
        ))
        .into());
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| BadInput(format!("{}: cannot read: {e}", path.display())))?;
    let mut config = parse(path, &text, sigma_m)?;
    config.name = spec.to_string();
    Ok(config)
}

/// Parses the text of a configuration file: TOML, or JSON when `path` ends
/// in `.json`; `path` names the file in every error. `sigma_m` is the range
/// noise the `told-sigma` preset is told. Errors name the field path the
/// file uses (`detector.fitting.eth`).
pub fn parse(path: &Path, text: &str, sigma_m: f64) -> Result<NamedConfig> {
    // TOML values carry what a preset may hold (infinities) and JSON does not.
    let overrides: Value = if path.extension().is_some_and(|e| e == "json") {
        let v: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| BadInput(format!("{}: not JSON: {e}", path.display())))?;
        Value::try_from(v).map_err(|e| BadInput(format!("{}: {e}", path.display())))?
    } else {
        toml::from_str(text).map_err(|e| BadInput(format!("{}: not TOML: {e}", path.display())))?
    };
    let Some(base_name) = overrides.get("preset").and_then(Value::as_str) else {
        return Err(BadInput(format!(
            "{}: missing `preset = \"...\"` ({})",
            path.display(),
            Preset::names()
        ))
        .into());
    };
    let Some(preset) = Preset::from_name(base_name) else {
        return Err(BadInput(format!(
            "{}: unknown preset {base_name:?} ({})",
            path.display(),
            Preset::names()
        ))
        .into());
    };
    let (detector, map) = preset.configs(sigma_m);
    // A sensor named in the file sets the noise every rule starts from;
    // the file's own overrides of those rules still win.
    let sensor = match overrides.get("sensor") {
        None => None,
        Some(v) => Some(v.as_str().and_then(SensorProfile::from_name).ok_or_else(|| {
            BadInput(format!(
                "{}: sensor: {v} is not a sensor ({})",
                path.display(),
                SensorProfile::names()
            ))
        })?),
    };
    let detector = sensor.map_or(detector, |s| detector.with_noise(s.range_noise()));
    let aiding = AidingConfig::estimator();
    let loop_closure = LoopClosureConfig::standard();
    let merged = Value::try_from(ConfigFile {
        preset: base_name.into(),
        sensor,
        detector,
        map,
        aiding,
        loop_closure,
        vehicle_from_sensor: Pose2::identity(),
    })?;
    let file = merged_file(merged, &overrides, &path.display().to_string())?;
    Ok(NamedConfig {
        name: path.display().to_string(),
        preset,
        detector: file.detector,
        map: file.map,
        aiding: file.aiding,
        loop_closure: file.loop_closure,
        sensor: file.sensor,
        vehicle_from_sensor: file.vehicle_from_sensor,
    })
}

/// Resolves `spec` as [`resolve`] does, then writes `overrides` over it:
/// a table in the file's form (`{detector: {fitting: {eth: 30}}}`), merged
/// and checked as a file's own fields are. `label` names the overrides in
/// errors (the Python keyword arguments, say), which also name the field
/// path (`unknown key `detector.fitting.eht``).
pub fn resolve_with_overrides(
    spec: &str,
    sigma_m: f64,
    overrides: &Value,
    label: &str,
) -> Result<NamedConfig> {
    let base = resolve(spec, sigma_m)?;
    if overrides.as_table().is_none_or(|t| t.is_empty()) {
        return Ok(base);
    }
    let merged = Value::try_from(ConfigFile {
        preset: base.preset.name().into(),
        sensor: base.sensor,
        detector: base.detector,
        map: base.map,
        aiding: base.aiding,
        loop_closure: base.loop_closure,
        vehicle_from_sensor: base.vehicle_from_sensor,
    })?;
    let file = merged_file(merged, overrides, label)?;
    Ok(NamedConfig {
        detector: file.detector,
        map: file.map,
        aiding: file.aiding,
        loop_closure: file.loop_closure,
        vehicle_from_sensor: file.vehicle_from_sensor,
        ..base
    })
}

/// The preset as a configuration file (TOML), every field written.
pub fn show(preset: Preset) -> Result<String> {
    let (detector, map) = preset.configs(0.01);
    let aiding = AidingConfig::estimator();
    let loop_closure = LoopClosureConfig::standard();
    Ok(toml::to_string(&ConfigFile {
        preset: preset.name().into(),
        sensor: None,
        detector,
        map,
        aiding,
        loop_closure,
        vehicle_from_sensor: Pose2::identity(),
    })?)
}

/// `base` (a file's form) with `overrides` written over it, read back and
/// validated; errors start with `label`.
fn merged_file(mut base: Value, overrides: &Value, label: &str) -> Result<ConfigFile> {
    merge(&mut base, overrides, "").map_err(|e| BadInput(format!("{label}: {e}")))?;
    let file: ConfigFile = base.try_into().map_err(|e| BadInput(format!("{label}: {e}")))?;
    // The detector's own paths (`fitting.eth`) sit under `[detector]`.
    file.detector
        .validate()
        .map_err(|e| e.within("detector"))
        .and_then(|()| file.map.validate())
        .and_then(|()| file.aiding.validate())
        .and_then(|()| file.loop_closure.validate())
        .and_then(|()| {
            let m = file.vehicle_from_sensor;
            [("x", m.x()), ("y", m.y()), ("heading", m.heading())].into_iter().try_for_each(
                |(n, v)| {
                    ConfigError::check_field(
                        v.is_finite(),
                        "vehicle_from_sensor",
                        n,
                        v,
                        "must be finite",
                    )
                },
            )
        })
        .map_err(|e| BadInput(format!("{label}: {e}")))?;
    Ok(file)
}

/// Writes `overrides` into `base`: objects key by key, anything else whole.
/// A key absent from `base` is an error naming its path, except where `base`
/// holds an enum variant (an object of one key) and the override names another.
fn merge(base: &mut Value, overrides: &Value, path: &str) -> Result<(), String> {
    let (Value::Table(b), Value::Table(o)) = (&mut *base, overrides) else {
        *base = overrides.clone();
        return Ok(());
    };
    let is_variant = b.len() == 1 && o.len() == 1 && b.keys().next() != o.keys().next();
    if is_variant && b.values().next().is_some_and(Value::is_table) {
        *base = overrides.clone();
        return Ok(());
    }
    for (key, value) in o {
        let here = if path.is_empty() { key.clone() } else { format!("{path}.{key}") };
        // `false` turns an optional rule off.
        if *value == Value::Boolean(false) && optional_field(&here) {
            b.remove(key);
            continue;
        }
        match b.get_mut(key) {
            Some(slot) => merge(slot, value, &here)?,
            // Optional fields absent from the preset (`None`) may be set.
            None if path.is_empty() && key == "preset" => {}
            None if optional_field(&here) => {
                b.insert(key.clone(), value.clone());
            }
            None => return Err(format!("unknown key `{here}`")),
        }
    }
    Ok(())
}

/// Fields of type `Option<_>` that a preset may leave out (`None`).
fn optional_field(path: &str) -> bool {
    const OPTIONAL: [&str; 24] = [
        "map.lifecycle",
        "aiding.estimator.scan_matching",
        "aiding.estimator.window",
        "aiding.estimator.recovery",
        "aiding.estimator.tentative_variance_scale",
        "aiding.estimator.adaptation",
        "aiding.estimator.measurement_adaptation",
        "aiding.estimator.calibration",
        "aiding.estimator.calibration.heading_rate_bias_std_rad_s",
        "aiding.estimator.calibration.speed_scale_std",
        "aiding.estimator.calibration.latency_std_s",
        "detector.noise_estimation",
        "detector.fitting.residual_test",
        "detector.fitting.orientation_test",
        "detector.fitting.straightness_test",
        "detector.fitting.kink_test",
        "detector.fitting.edge_on_ends",
        "detector.noisy_scan_tests",
        "detector.noisy_scan_tests.edge_on_ends",
        "map.max_offset_m",
        "map.max_new_alpha_std_rad",
        "map.merge_gate",
        "detector.segmentation.level2",
        "loop_closure.place_recognition",
    ];
    OPTIONAL.contains(&path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("pcaline-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn overrides_in_code_are_a_files_overrides() {
        let table = |text: &str| toml::from_str::<Value>(text).unwrap();
        let file = write("eth30.toml", "preset = \"paper\"\n[detector.fitting]\neth = 30\n");
        let by_file = resolve(file.to_str().unwrap(), 0.01).unwrap();
        let by_code = resolve_with_overrides(
            "paper",
            0.01,
            &table("[detector.fitting]\neth = 30\n"),
            "overrides",
        )
        .unwrap();
        assert_eq!(by_code.detector, by_file.detector);
        assert_ne!(by_code.detector, resolve("paper", 0.01).unwrap().detector);
        // No overrides: the preset itself; a bad one names its path.
        let none = resolve_with_overrides("adaptive", 0.01, &table(""), "x").unwrap();
        assert_eq!(none, resolve("adaptive", 0.01).unwrap());
        let e = resolve_with_overrides("default", 0.01, &table("[map]\nmax_ofset_m = 1\n"), "kw")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("kw: ") && e.contains("map.max_ofset_m"), "{e}");
        let e =
            resolve_with_overrides("default", 0.01, &table("[detector.fitting]\neth = -1\n"), "kw")
                .unwrap_err()
                .to_string();
        assert!(e.contains("eth"), "{e}");
    }

    #[test]
    fn a_file_sets_the_sensor_mount() {
        let file = write(
            "mount.toml",
            "preset = \"default\"\n[vehicle_from_sensor]\nx = 0.25\ny = 0.0\nheading = 3.0\n",
        );
        let c = resolve(file.to_str().unwrap(), 0.01).unwrap();
        assert_eq!(c.vehicle_from_sensor, Pose2::new(0.25, 0.0, 3.0));
        assert_eq!(resolve("default", 0.01).unwrap().vehicle_from_sensor, Pose2::identity());
        let bad = write("bad-mount.toml", "preset = \"default\"\n[vehicle_from_sensor]\ny = nan\n");
        let e = resolve(bad.to_str().unwrap(), 0.01).unwrap_err().to_string();
        assert!(e.contains("bad-mount.toml") && e.contains("`vehicle_from_sensor.y`"), "{e}");
    }

    #[test]
    fn preset_names_are_the_command_lines() {
        use clap::ValueEnum;
        for p in Preset::ALL {
            assert_eq!(Preset::from_name(p.name()), Some(p));
            assert_eq!(p.to_possible_value().unwrap().get_name(), p.name());
        }
        assert_eq!(Preset::value_variants().len(), Preset::ALL.len());
        assert_eq!(Preset::from_name("Paper"), None);
    }

    #[test]
    fn errors_name_the_path_the_file_writes() {
        let cases = [
            ("default", "[detector.fitting]\neth = -1", "detector.fitting.eth"),
            (
                "default",
                "[detector.segmentation.level1.Adaptive]\nlambda_rad = 3.0",
                "detector.segmentation.level1.Adaptive.lambda_rad",
            ),
            (
                "default",
                "[detector.segmentation.level1.Adaptive.noise]\nfar_sigma_m = -1",
                "detector.segmentation.level1.Adaptive.noise.far_sigma_m",
            ),
            (
                "default",
                "[detector.segmentation.level2.SplitAtFarthest]\nsigma_factor = 0",
                "detector.segmentation.level2.SplitAtFarthest.sigma_factor",
            ),
            (
                "default",
                "[detector.fitting.merge.ResidualIncrease]\nmax_chi2 = -1",
                "detector.fitting.merge.ResidualIncrease.max_chi2",
            ),
            (
                "paper",
                "[detector.fitting.merge.Angles]\nalpha_t_rad = -1",
                "detector.fitting.merge.Angles.alpha_t_rad",
            ),
            (
                "adaptive",
                "[detector.noise_estimation]\nmin_samples = 1",
                "detector.noise_estimation.min_samples",
            ),
            ("default", "[map]\nmax_d_alpha_rad = -1", "map.max_d_alpha_rad"),
            ("default", "[map]\nmax_new_alpha_std_rad = 0", "map.max_new_alpha_std_rad"),
            ("default", "[map.merge_gate]\nmax_gap_m = -1", "map.merge_gate.max_gap_m"),
            (
                "default",
                "[map.lifecycle]\nstraightness_floor_m = -1",
                "map.lifecycle.straightness_floor_m",
            ),
            ("default", "[aiding]\nmax_heading_step_rad = 0", "aiding.max_heading_step_rad"),
            (
                "default",
                "[aiding.heading_weights.inverse-variance]\nfloor_rad = 0",
                "aiding.heading_weights.inverse-variance.floor_rad",
            ),
            (
                "default",
                "[aiding.estimator.motion]\nrotation_per_m = -1",
                "aiding.estimator.motion.rotation_per_m",
            ),
            (
                "default",
                "[aiding.estimator.adaptation]\nrate = -1",
                "aiding.estimator.adaptation.rate",
            ),
            ("default", "[loop_closure]\nsearch_sigmas = -1", "loop_closure.search_sigmas"),
        ];
        for (preset, overrides, path) in cases {
            let table: Value = toml::from_str(overrides).unwrap();
            let e = resolve_with_overrides(preset, 0.01, &table, "kw").unwrap_err().to_string();
            assert!(e.contains(&format!("`{path}`")), "{overrides}: {e}");
        }
    }

    #[test]
    fn every_preset_round_trips_through_its_file_form() {
        for preset in Preset::ALL {
            let name = preset.name();
            let text = show(preset).unwrap();
            let path = write(&format!("{name}.toml"), &text);
            let c = resolve(path.to_str().unwrap(), 0.01).unwrap();
            let p = resolve(name, 0.01).unwrap();
            assert_eq!(
                (c.detector, c.map, c.aiding, c.loop_closure),
                (p.detector, p.map, p.aiding, p.loop_closure),
                "{name}:\n{text}"
            );
        }
    }

    /// Every preset survives JSON, which has no infinity: serde_json writes
    /// an infinite limit as `null`, and every such field reads `null` back
    /// as infinite.
    #[test]
    fn every_preset_round_trips_through_json() {
        for name in Preset::ALL.map(Preset::name) {
            let p = resolve(name, 0.01).unwrap();
            let file = ConfigFile {
                preset: name.into(),
                sensor: Some(SensorProfile::SickLms),
                detector: p.detector,
                map: p.map,
                aiding: p.aiding,
                loop_closure: p.loop_closure,
                vehicle_from_sensor: Pose2::new(0.25, -0.1, 3.0),
            };
            let json = serde_json::to_string(&file).unwrap();
            let back: ConfigFile =
                serde_json::from_str(&json).unwrap_or_else(|e| panic!("{name}: {e}\n{json}"));
            assert_eq!(back.vehicle_from_sensor, file.vehicle_from_sensor);
            assert_eq!(
                (back.sensor, back.detector, back.map, back.aiding, back.loop_closure),
                (file.sensor, file.detector, file.map, file.aiding, file.loop_closure),
                "{name}"
            );
        }
    }

    #[test]
    fn a_file_overrides_only_the_fields_it_names() {
        let path = write(
            "eth.toml",
            "preset = \"default\"\n[detector.fitting]\neth = 30.0\n[map]\nmax_offset_m = 0.2\n",
        );
        let c = resolve(path.to_str().unwrap(), 0.01).unwrap();
        let mut expected = Config::default();
        expected.fitting.eth = 30.0;
        assert_eq!(c.detector, expected);
        assert_eq!(c.map.max_offset_m, Some(0.2));
        assert_eq!(c.map.max_d_rho_m, MapConfig::default().max_d_rho_m);
        // An optional rule turns off with `false`.
        let path =
            write("off.toml", "preset = \"default\"\n[detector]\nnoise_estimation = false\n");
        let c = resolve(path.to_str().unwrap(), 0.01).unwrap();
        let mut expected = Config::noise_aware(RangeNoise::utm30lx());
        expected.noisy_scan_tests = Config::default().noisy_scan_tests;
        assert_eq!(c.detector, expected);
        let path =
            write("quiet.toml", "preset = \"default\"\n[detector]\nnoisy_scan_tests = false\n");
        let c = resolve(path.to_str().unwrap(), 0.01).unwrap();
        assert_eq!(c.detector.noisy_scan_tests, None);
        assert_eq!(c.detector.noise_estimation, Config::default().noise_estimation);
        // Scan-to-scan registration is on in the default, off with `false`,
        // and its settings are checked with the path named.
        assert!(c.aiding.estimator.scan_matching.is_some());
        let path = write(
            "no-registration.toml",
            "preset = \"default\"\n[aiding.estimator]\nscan_matching = false\n",
        );
        let c = resolve(path.to_str().unwrap(), 0.01).unwrap();
        assert_eq!(c.aiding.estimator.scan_matching, None);
        let path = write(
            "bad-registration.toml",
            "preset = \"default\"\n[aiding.estimator.scan_matching]\ninlier_m = -1.0\n",
        );
        let e = resolve(path.to_str().unwrap(), 0.01).unwrap_err().to_string();
        assert!(e.contains("`aiding.estimator.scan_matching.inlier_m`"), "{e}");
        // The noisy scans' edge-on cut is checked, and its error names the path.
        let path = write(
            "bad-cut.toml",
            "preset = \"default\"\n[detector.noisy_scan_tests.edge_on_ends]\nmin_points = 2\n",
        );
        let e = resolve(path.to_str().unwrap(), 0.01).unwrap_err().to_string();
        assert!(e.contains("`detector.noisy_scan_tests.edge_on_ends.min_points`"), "{e}");
        // The estimator's recovery is off in the presets; a file turns it
        // on with every field, and a bad value names its path.
        let recovery = |runner_up: f64| {
            format!(
                "preset = \"default\"\n[aiding.estimator.recovery]\nmap_radius_m = 15.0\n\
                 radius_m = 1.0\nmax_rotation_rad = 0.5\nmin_gain_m = 1.0\n\
                 min_matched_fraction = 0.5\nmin_weakest_direction_m = 0.5\nmax_rms_m = 0.04\n\
                 max_runner_up = {runner_up}\nmin_change_chi2 = 100.0\n\
                 [aiding.estimator.recovery.alignment]\nmin_pair_angle_rad = 0.5\n\
                 pair_angle_tolerance_rad = 0.05\nmatch_angle_rad = 0.05\n\
                 match_distance_m = 0.1\nmin_overlap_m = 0.2\nhypothesis_lines = 12\n\
                 max_corner_distance_m = 2.0\nrefine_iterations = 5\n"
            )
        };
        assert_eq!(resolve("default", 0.01).unwrap().aiding.estimator.recovery, None);
        let path = write("recovery.toml", &recovery(0.7));
        let c = resolve(path.to_str().unwrap(), 0.01).unwrap();
        assert_eq!(c.aiding.estimator.recovery.map(|r| r.max_runner_up), Some(0.7));
        let path = write("bad-recovery.toml", &recovery(1.5));
        let e = resolve(path.to_str().unwrap(), 0.01).unwrap_err().to_string();
        assert!(e.contains("aiding.estimator.recovery.max_runner_up"), "{e}");
        // A file naming some of loop closure's alignment keeps the rest,
        // its facing rule included (a field newer than the file).
        let path = write(
            "alignment.toml",
            "preset = \"default\"\n[loop_closure.alignment]\nrefine_iterations = 7\n",
        );
        let c = resolve(path.to_str().unwrap(), 0.01).unwrap();
        let mut expected = pcaline::aiding::AlignmentConfig::sided();
        expected.refine_iterations = 7;
        assert_eq!(c.loop_closure.alignment, expected);
        // The paper's map has no offset gate; a file may add one.
        let path = write("paper.json", r#"{"preset": "paper", "map": {"max_offset_m": 0.1}}"#);
        assert_eq!(resolve(path.to_str().unwrap(), 0.01).unwrap().map.max_offset_m, Some(0.1));
    }

    #[test]
    fn bad_files_name_the_file_and_the_key() {
        let cases = [
            (
                "typo.toml",
                "preset = \"default\"\n[detector.fitting]\nethh = 3.0\n",
                "detector.fitting.ethh",
            ),
            ("nopreset.toml", "[map]\nmax_d_rho_m = 2.0\n", "missing `preset"),
            ("badpreset.toml", "preset = \"best\"\n", "unknown preset"),
            ("invalid.toml", "preset = \"default\"\n[detector.fitting]\neth = 0.5\n", "eth"),
            ("type.toml", "preset = \"default\"\n[map]\nmax_d_rho_m = \"far\"\n", "invalid type"),
            ("syntax.toml", "preset = \n", "not TOML"),
            (
                "loops.toml",
                "preset = \"default\"\n[loop_closure]\nmax_search_radius_m = -1.0\n",
                "loop_closure.max_search_radius_m",
            ),
        ];
        for (name, text, expect) in cases {
            let path = write(name, text);
            let e = resolve(path.to_str().unwrap(), 0.01).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(expect), "{name}: {e}");
        }
        let e = resolve("no-such-preset-or-file", 0.01).unwrap_err().to_string();
        assert!(e.contains("neither a preset"), "{e}");
    }
}
