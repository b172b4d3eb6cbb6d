//! `pcaline eval`: line detection against ground truth on the shipped scenes
//! (design, section 5): detection, mapping and localization for the presets
//! or any configurations side by side, and fit accuracy against the
//! Cramer-Rao bound; `--real` for the real datasets.

use crate::config_file::{NamedConfig, Preset, resolve};
use crate::exit::BadInput;
use crate::out::{out, outln};
use anyhow::{Context, Result};
use pcaline::aiding::{AidingConfig, AidingMode, SensorLine};
use pcaline::{LineDetector, LineSegment};
use pcaline_eval::{
    AidedRun, AidedScore, DetectFn, DetectionCriteria, DetectionEval, DetectorResult, FaultMode,
    evaluate_detectors, oracle_lines,
};
use pcaline_io::parse_scene;
use pcaline_sim::{Scene, SimFrame, Simulator, World};
use rayon::prelude::*;
use serde::Serialize;
use std::path::Path;

/// The scenes, embedded.
const SCENES: [(&str, &str); 4] = [
    ("corridor-doors", include_str!("../scenes/corridor-doors.toml")),
    ("office-clutter", include_str!("../scenes/office-clutter.toml")),
    ("hall-pillars", include_str!("../scenes/hall-pillars.toml")),
    ("paper-maze", include_str!("../scenes/paper-maze.toml")),
];

/// Arguments of `pcaline eval`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  pcaline eval                                    the shipped scenes at 10 and 30 mm
  pcaline eval --scene my-maze.toml --sigma-mm 20 --config default --config adaptive
  pcaline eval --no-localization --oracle --seeds 5
  pcaline eval --real --drift-grid --json         the shared real logs
  pcaline eval --show-config default > mine.toml  a configuration file to edit")]
pub struct EvalArgs {
    /// Range noise of the simulated sensor, millimetres (repeat for several).
    #[arg(long = "sigma-mm", default_values_t = [10.0, 30.0])]
    sigma_mm: Vec<f64>,
    /// Seeds per scene.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..))]
    seeds: u64,
    /// Scans per scene and seed for detection.
    #[arg(long, default_value_t = 60, value_parser = crate::count_at_least_one)]
    scans: usize,
    /// Configurations to evaluate, side by side (repeat): a preset (paper,
    /// default, split-and-merge, told-sigma, datasheet, adaptive) or a TOML/JSON file
    /// naming a preset and overriding fields (see --show-config). Default:
    /// all presets.
    #[arg(long = "config")]
    configs: Vec<String>,
    /// Print a preset as a configuration file (every field) and exit.
    #[arg(long, value_name = "PRESET", value_enum)]
    show_config: Option<Preset>,
    /// Add two detection rows for a perfect segmentation (each true wall
    /// fitted on its own points; all, and those known to 2°): the bound of
    /// any detector that fits each wall on its own points.
    #[arg(long)]
    oracle: bool,
    /// Skip the mapping and localization runs (whole trajectories).
    #[arg(long)]
    no_localization: bool,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
    /// Evaluate on real data instead: the MIT CSAIL log against its corrected
    /// poses, the relation metric on the Intel log, and per-line residuals of
    /// the UTM-30LX-EW bag (with the first --config, or the default).
    #[arg(long)]
    real: bool,
    /// Also run the drift grid on Intel (for --real): heading-rate biases
    /// 0.1, 0.3 and 1°/s, speed errors 2-3%, seeds 1-4, every aiding mode;
    /// and MIT CSAIL's sensitivity runs: its raw odometry plus a tiny random
    /// walk, seeds 1 to --sensitivity-seeds, the estimator alone and with
    /// loop closure.
    #[arg(long)]
    drift_grid: bool,
    /// Seed of the synthetic drift added to the Intel log's poses (for --real).
    #[arg(long, default_value_t = 1)]
    drift_seed: u64,
    /// Number of MIT CSAIL sensitivity runs (for --real --drift-grid):
    /// seeds 1 to N. A single run is one draw of a chaotic process; compare
    /// changes over 32 or more.
    #[arg(
        long,
        default_value_t = 8,
        requires = "drift_grid",
        value_parser = clap::value_parser!(u64).range(1..=1000)
    )]
    sensitivity_seeds: u64,
    /// The datasets folder (for --real); `$PCALINE_DATA` or `../shared/data`.
    #[arg(long)]
    data: Option<std::path::PathBuf>,
    /// Evaluate on these scene files (TOML or JSON, repeat or list several)
    /// instead of the four shipped scenes: detection, and mapping and
    /// localization, as for the shipped ones.
    #[arg(long = "scene", num_args = 1.., value_name = "FILE")]
    scenes: Vec<std::path::PathBuf>,
    /// Beam faults of the detection runs: `off` (the default) has no
    /// outliers, dropouts or mixed pixels whatever the scene says; `on` uses
    /// each scene's own, or 0.5% outliers, 1% dropouts and mixed pixels at
    /// 30% of depth edges for a scene that sets none.
    #[arg(long, value_enum, default_value_t = Faults::Off)]
    faults: Faults,
    /// Range resolution of the simulated sensor for detection, millimetres:
    /// every range is rounded to a multiple of it (0: none).
    #[arg(long = "range-step-mm", default_value_t = 0.0)]
    range_step_mm: f64,
    /// Keep each scene's motion skew and scan-plane tilt in the detection
    /// runs (by default every beam of a scan is taken at one level pose).
    #[arg(long)]
    keep_motion: bool,
}

/// `--faults`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Faults {
    /// No beam faults.
    Off,
    /// The scene's faults, or a typical mix.
    On,
}

#[derive(Debug, Serialize)]
struct Row {
    sigma_mm: f64,
    config: String,
    scans: usize,
    true_walls: usize,
    recall: f64,
    false_positive_fraction: f64,
    fragmentation: f64,
    alpha_median_deg: f64,
    alpha_rms_deg: f64,
    d_median_mm: f64,
    d_rms_mm: f64,
    endpoint_median_mm: f64,
    endpoint_rms_mm: f64,
    time_per_scan_us: f64,
    /// Recall of true walls under 0.5 m, 0.5-1 m, 1-2 m, 2 m and more.
    recall_by_length: [f64; 4],
    /// Detected lines' rms distance from the nearest true surface, in noise
    /// sigmas: the largest, and the 99th percentile.
    surface_rms_sigmas_max_p99: [f64; 2],
    /// Detected lines more than 3 noise sigmas (rms) from every surface.
    lines_off_surface: usize,
}

#[derive(Debug, Serialize)]
struct LocalizationRow {
    config: String,
    aiding: &'static str,
    runs: usize,
    scans: usize,
    heading_rms_deg: f64,
    heading_max_deg: f64,
    position_rms_m: f64,
    position_final_mean_m: f64,
    map_lines: usize,
    map_line_error_rms_m: f64,
    map_spurious_lines: usize,
    map_covered_fraction: f64,
}

#[derive(Debug, Serialize)]
struct Report {
    detection: Vec<Row>,
    localization: Vec<LocalizationRow>,
}

/// The aiding modes of the localization table.
fn aiding_modes() -> [(&'static str, AidingConfig); 5] {
    [
        ("none", AidingConfig::none()),
        ("paper (eq. 11-14)", AidingConfig::paper()),
        ("heading", AidingConfig::heading()),
        ("full-pose", AidingConfig::full_pose()),
        ("estimator", AidingConfig::estimator()),
    ]
}

/// The shipped scenes, or the files of `--scene`. A scene that cannot be
/// evaluated (no valid trajectory, no wall ever seen) is an error naming the
/// file and the item.
fn scenes(files: &[std::path::PathBuf]) -> Result<Vec<Scene>> {
    if files.is_empty() {
        return Ok(SCENES
            .iter()
            .map(|(name, text)| parse_scene(Path::new(&format!("{name}.toml")), text))
            .collect::<Result<Vec<_>, _>>()?);
    }
    let criteria = DetectionCriteria::default();
    files
        .iter()
        .map(|path| {
            let scene = pcaline_io::read_scene(path)?;
            let sim = Simulator::new(&scene, 1)
                .map_err(|e| BadInput(format!("{}: {e}", path.display())))?;
            if sim.is_empty() {
                return Err(BadInput(format!(
                    "{}: trajectory: gives no scan to evaluate",
                    path.display()
                ))
                .into());
            }
            let seen = (0..sim.len()).step_by((sim.len() / 20).max(1)).any(|k| {
                sim.frame(k).is_some_and(|f| {
                    !pcaline_eval::true_walls(&f, sim.world(), &criteria).is_empty()
                })
            });
            if !seen {
                return Err(BadInput(format!(
                    "{}: walls: no wall is seen along the trajectory as a visible wall of the \
                     protocol ({} beams and {} m or more)",
                    path.display(),
                    criteria.min_beams,
                    criteria.min_extent_m
                ))
                .into());
            }
            Ok(scene)
        })
        .collect()
}

/// Runs `pcaline eval`.
pub fn run(args: &EvalArgs, quiet: bool) -> Result<()> {
    if let Some(preset) = args.show_config {
        out!("{}", crate::config_file::show(preset)?)?;
        return Ok(());
    }
    if args.real {
        let data = args
            .data
            .clone()
            .or_else(|| std::env::var_os("PCALINE_DATA").map(Into::into))
            .unwrap_or_else(|| "../shared/data".into());
        // The first configuration named, or the default.
        let spec = args.configs.first().map_or("default", String::as_str);
        let options = crate::eval_real::RealOptions {
            drift_seed: args.drift_seed,
            drift_grid: args.drift_grid,
            sensitivity_seeds: (1..=args.sensitivity_seeds).collect(),
        };
        let report = crate::eval_real::evaluate(&data, &resolve(spec, 0.01)?, &options)?;
        if args.json {
            outln!("{}", serde_json::to_string_pretty(&report)?)?;
        } else {
            print_real(&report)?;
        }
        return Ok(());
    }
    if args.sigma_mm.iter().any(|s| !(s.is_finite() && *s >= 0.0)) {
        return Err(BadInput("--sigma-mm must be finite and >= 0".into()).into());
    }
    if !(args.range_step_mm.is_finite() && (0.0..=1000.0).contains(&args.range_step_mm)) {
        return Err(BadInput("--range-step-mm must be in [0, 1000]".into()).into());
    }
    let specs: Vec<String> = if args.configs.is_empty() {
        Preset::ALL.iter().map(|p| p.name().to_string()).collect()
    } else {
        args.configs.clone()
    };
    // Resolve every configuration once up front, so a bad file fails fast.
    for spec in &specs {
        resolve(spec, 0.01)?;
    }
    let scenes = scenes(&args.scenes)?;
    let mut report = Report { detection: Vec::new(), localization: Vec::new() };
    for &sigma_mm in &args.sigma_mm {
        let configs: Vec<NamedConfig> =
            specs.iter().map(|s| resolve(s, sigma_mm / 1000.0)).collect::<Result<_>>()?;
        report.detection.extend(detection_rows(&scenes, args, sigma_mm, &configs)?);
    }
    if !args.no_localization {
        // The scenes as shipped (their own sensor noise, the UTM-30LX-EW's):
        // `told-sigma` and `datasheet` would be `default` again (the
        // default's estimate is the datasheet's noise there).
        let configs: Vec<NamedConfig> = specs
            .iter()
            .filter(|s| !matches!(s.as_str(), "told-sigma" | "datasheet" | "estimated"))
            .map(|s| resolve(s, 0.01))
            .collect::<Result<_>>()?;
        report.localization = localization_rows(&scenes, args.seeds, &configs, quiet)?;
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?)?;
        return Ok(());
    }
    print_detection(&report.detection, specs.len() == 2 && !args.oracle)?;
    if !report.localization.is_empty() {
        print_localization(&report.localization, args.seeds)?;
    }
    print_fit_accuracy(&args.sigma_mm)?;
    print_range_bearing()?;
    Ok(())
}

/// The detection table's rows at range noise `sigma_mm`: every
/// configuration's detector (and the oracles, with `--oracle`) scored on
/// every scene and seed.
fn detection_rows(
    scenes: &[Scene],
    args: &EvalArgs,
    sigma_mm: f64,
    configs: &[NamedConfig],
) -> Result<Vec<Row>> {
    let mut detectors: Vec<LineDetector> =
        configs.iter().map(|c| LineDetector::new(c.detector)).collect::<Result<_, _>>()?;
    let criteria = DetectionCriteria::default();
    let sigma_m = sigma_mm / 1000.0;
    let (names, mut closures) =
        detectors_scored(configs, &mut detectors, args.oracle, criteria, sigma_m);
    let mut refs: Vec<&mut DetectFn<'_>> = closures.iter_mut().map(|c| c.as_mut()).collect();
    let eval = detection_eval(args, criteria, sigma_m);
    let results =
        evaluate_detectors(scenes, &eval, &mut refs).map_err(|e| BadInput(e.to_string()))?;
    Ok(names.into_iter().zip(results).map(|(name, r)| Row::new(name, sigma_mm, &r)).collect())
}

/// The detectors a detection table scores, with their names: one per
/// configuration, and with `oracle` the two perfect segmentations (every true
/// wall fitted on all of its own points; then only those whose orientation
/// is known to 2°).
fn detectors_scored<'a>(
    configs: &[NamedConfig],
    detectors: &'a mut [LineDetector],
    oracle: bool,
    criteria: DetectionCriteria,
    sigma_m: f64,
) -> (Vec<String>, Vec<Box<DetectFn<'a>>>) {
    let mut names: Vec<String> = configs.iter().map(|c| c.name.clone()).collect();
    let mut closures: Vec<Box<DetectFn<'a>>> = detectors
        .iter_mut()
        .map(|d| {
            Box::new(move |f: &SimFrame, _: &World| -> Vec<LineSegment> {
                d.detect(&f.scan).lines.iter().map(|l| l.line).collect()
            }) as Box<DetectFn<'a>>
        })
        .collect();
    if oracle {
        for (name, max_std) in [("oracle", f64::INFINITY), ("oracle, std <= 2°", 2f64.to_radians())]
        {
            names.push(name.to_string());
            closures.push(Box::new(move |f: &SimFrame, w: &World| {
                oracle_lines(f, w, &criteria, sigma_m, max_std)
            }));
        }
    }
    (names, closures)
}

/// The detection protocol as the command line sets it.
fn detection_eval(args: &EvalArgs, criteria: DetectionCriteria, sigma_m: f64) -> DetectionEval {
    let mut eval = DetectionEval::new(sigma_m, args.seeds, args.scans);
    eval.range_resolution_m = args.range_step_mm / 1000.0;
    eval.faults = match args.faults {
        Faults::Off => FaultMode::Off,
        Faults::On => FaultMode::On,
    };
    eval.keep_motion = args.keep_motion;
    eval.criteria = criteria;
    eval
}

impl Row {
    /// The table row of one detector's result at range noise `sigma_mm`.
    fn new(config: String, sigma_mm: f64, r: &DetectorResult) -> Row {
        let sigma_m = sigma_mm / 1000.0;
        let s = &r.score;
        let (am, ar) = s.alpha_error();
        let (dm, dr) = s.d_error();
        let (em, er) = s.endpoint_error();
        // Each line's rms distance from its surface, in noise sigmas.
        let mut sigmas: Vec<f64> = r.surface_rms_m.iter().map(|d| d / sigma_m.max(1e-3)).collect();
        sigmas.sort_by(f64::total_cmp);
        let p99 = sigmas.get((sigmas.len().saturating_sub(1) as f64 * 0.99) as usize);
        Row {
            sigma_mm,
            config,
            scans: s.scans,
            true_walls: s.true_walls,
            recall: s.recall(),
            false_positive_fraction: s.false_positive_fraction(),
            fragmentation: s.fragmentation(),
            alpha_median_deg: am.to_degrees(),
            alpha_rms_deg: ar.to_degrees(),
            d_median_mm: dm * 1e3,
            d_rms_mm: dr * 1e3,
            endpoint_median_mm: em * 1e3,
            endpoint_rms_mm: er * 1e3,
            time_per_scan_us: r.time_per_scan_us,
            recall_by_length: s.recall_by_length(),
            surface_rms_sigmas_max_p99: [
                sigmas.last().copied().unwrap_or(0.0),
                p99.copied().unwrap_or(0.0),
            ],
            lines_off_surface: r
                .surface_rms_m
                .iter()
                .filter(|d| **d > 3.0 * sigma_m.max(1e-3))
                .count(),
        }
    }
}

/// Every scene and seed, each configuration's detector feeding the four
/// aiding loops; errors pooled over all scans of all runs.
fn localization_rows(
    scenes: &[Scene],
    seeds: u64,
    configs: &[NamedConfig],
    quiet: bool,
) -> Result<Vec<LocalizationRow>> {
    let modes = aiding_modes();
    let bar = crate::progress::bar(
        (scenes.len() as u64) * seeds * configs.len() as u64,
        "localization runs",
        quiet,
    );
    // Every (configuration, scene, seed) run on the thread pool; the scores
    // are pooled afterwards in this order, so the sums, and the table, do
    // not depend on the number of threads.
    let runs: Vec<(usize, &Scene, u64)> = (0..configs.len())
        .flat_map(|c| {
            scenes.iter().flat_map(move |scene| (1..=seeds).map(move |seed| (c, scene, seed)))
        })
        .collect();
    let scores: Vec<Result<(usize, Vec<AidedScore>)>> = runs
        .par_iter()
        .map(|&(c, scene, seed)| {
            let scored = localization_run(&configs[c], scene, seed, &modes);
            bar.inc(1);
            scored
        })
        .collect();
    let mut scores = scores.into_iter();
    let mut rows = Vec::new();
    for c in configs {
        let mut pooled: Vec<Pooled> = modes.iter().map(|_| Pooled::default()).collect();
        for _ in 0..scenes.len() as u64 * seeds {
            let Some(run) = scores.next() else { break };
            let (scans, run) = run?;
            for (p, s) in pooled.iter_mut().zip(&run) {
                p.add(scans, s);
            }
        }
        for ((name, _), p) in modes.iter().zip(&pooled) {
            rows.push(p.row(&c.name, name));
        }
    }
    bar.finish_and_clear();
    Ok(rows)
}

/// One localization run of `scene` at `seed`: the configuration's detector
/// feeding one loop per aiding mode (the estimator with the configuration's
/// own settings). Returns the run's scan count and each loop's score.
fn localization_run(
    c: &NamedConfig,
    scene: &Scene,
    seed: u64,
    modes: &[(&'static str, AidingConfig)],
) -> Result<(usize, Vec<AidedScore>)> {
    let aiding: Vec<AidingConfig> = modes
        .iter()
        .map(|(_, a)| if a.mode == AidingMode::Estimator { c.aiding_in(a.mode) } else { *a })
        .collect();
    let sim = Simulator::new(scene, seed).map_err(|e| BadInput(e.to_string()))?;
    let mut detector = LineDetector::new(c.detector)?;
    let run = AidedRun::run(&sim, c.map, &aiding, |frame, velocity| {
        let detection = detector.detect_moving(&frame.scan, velocity.as_ref());
        detection.lines.iter().map(SensorLine::from).collect()
    })?;
    let scores = run.scores(sim.true_poses()).context("a scene without scans")?;
    Ok((sim.len(), scores))
}

/// Sums over runs for one configuration and aiding mode.
#[derive(Debug, Default)]
struct Pooled {
    runs: usize,
    scans: usize,
    heading_sq: f64,
    heading_max: f64,
    position_sq: f64,
    final_sum: f64,
    lines: usize,
    line_sq: f64,
    spurious: usize,
    covered_sum: f64,
}

impl Pooled {
    fn add(&mut self, scans: usize, s: &AidedScore) {
        let n = scans as f64;
        self.runs += 1;
        self.scans += scans;
        self.heading_sq += n * s.errors.heading_rms_rad.powi(2);
        self.heading_max = self.heading_max.max(s.errors.heading_max_rad);
        self.position_sq += n * s.errors.position_rms_m.powi(2);
        self.final_sum += s.errors.position_final_m;
        self.lines += s.map.lines;
        self.line_sq += s.map.line_errors_m.iter().map(|e| e * e).sum::<f64>();
        self.spurious += s.map.spurious;
        self.covered_sum += s.map.covered_fraction;
    }

    fn row(&self, config: &str, aiding: &'static str) -> LocalizationRow {
        let (runs, scans) = (self.runs.max(1) as f64, self.scans.max(1) as f64);
        LocalizationRow {
            config: config.to_string(),
            aiding,
            runs: self.runs,
            scans: self.scans,
            heading_rms_deg: (self.heading_sq / scans).sqrt().to_degrees(),
            heading_max_deg: self.heading_max.to_degrees(),
            position_rms_m: (self.position_sq / scans).sqrt(),
            position_final_mean_m: self.final_sum / runs,
            map_lines: self.lines,
            map_line_error_rms_m: (self.line_sq / self.lines.max(1) as f64).sqrt(),
            map_spurious_lines: self.spurious,
            map_covered_fraction: self.covered_sum / runs,
        }
    }
}

fn print_localization(rows: &[LocalizationRow], seeds: u64) -> anyhow::Result<()> {
    outln!()?;
    outln!(
        "Mapping and localization: every scene as shipped, {seeds} seed(s), whole trajectories; errors pooled over all scans"
    )?;
    outln!(
        "{:<22} {:<18} {:>7} {:>11} {:>11} {:>9} {:>9} {:>9} {:>9} {:>8} {:>8}",
        "config",
        "aiding",
        "scans",
        "heading rms",
        "heading max",
        "pos rms",
        "final",
        "map lines",
        "line rms",
        "spurious",
        "covered"
    )?;
    for r in rows {
        outln!(
            "{:<22} {:<18} {:>7} {:>9.3} ° {:>9.3} ° {:>7.3} m {:>7.3} m {:>9} {:>6.1}cm {:>8} {:>7.1}%",
            r.config,
            r.aiding,
            r.scans,
            r.heading_rms_deg,
            r.heading_max_deg,
            r.position_rms_m,
            r.position_final_mean_m,
            r.map_lines,
            r.map_line_error_rms_m * 100.0,
            r.map_spurious_lines,
            100.0 * r.map_covered_fraction
        )?;
    }
    Ok(())
}

/// Fit accuracy against the Cramer-Rao bound and covariance consistency, for
/// walls of 1, 2 and 5 m sampled as a UTM-30LX-EW at 5 m (2.2 cm spacing).
fn print_fit_accuracy(sigmas_mm: &[f64]) -> anyhow::Result<()> {
    outln!()?;
    outln!(
        "Fit accuracy (PCA, 4000 runs a row, noise across the wall) against the Cramer-Rao bound"
    )?;
    outln!(
        "{:>6} {:>6} {:>6} {:>12} {:>12} {:>12} {:>12} {:>9}",
        "sigma",
        "L m",
        "points",
        "std alpha",
        "CRB alpha",
        "std offset",
        "CRB offset",
        "NEES"
    )?;
    for &sigma_mm in sigmas_mm {
        for length in [1.0, 2.0, 5.0] {
            let n = (length / (5.0 * 0.25f64.to_radians())) as usize + 1;
            let r = pcaline_eval::fit_accuracy(n, length, sigma_mm / 1000.0, 4000, 1);
            let expected_nees = 2.0 * (n as f64 - 2.0) / (n as f64 - 4.0);
            outln!(
                "{:>4}mm {:>6} {:>6} {:>10.4}° {:>10.4}° {:>10.2}mm {:>10.2}mm {:>5.2}/{:.2}",
                sigma_mm,
                length,
                n,
                r.std_alpha_rad.to_degrees(),
                r.crb_alpha_rad.to_degrees(),
                r.std_offset_m * 1e3,
                r.crb_offset_m * 1e3,
                r.mean_nees,
                expected_nees
            )?;
        }
    }
    Ok(())
}

/// The unweighted and the weighted fit under range-and-bearing noise.
fn print_range_bearing() -> anyhow::Result<()> {
    outln!()?;
    outln!(
        "Range-and-bearing noise (a wall 4-14 m away at oblique incidence; range noise 10 mm below 10 m, 30 mm beyond; 4000 runs)"
    )?;
    outln!(
        "{:>13} {:>6} {:>15} {:>15} {:>11} {:>9} {:>13}",
        "sigma bearing",
        "beams",
        "std alpha PCA",
        "std weighted",
        "CRB alpha",
        "NEES PCA",
        "NEES weighted"
    )?;
    for sigma_bearing_deg in [0.0f64, 0.05, 0.1] {
        let r = pcaline_eval::range_bearing_accuracy(sigma_bearing_deg.to_radians(), 4000, 1);
        outln!(
            "{:>12}° {:>6} {:>14.4}° {:>14.4}° {:>10.4}° {:>9.2} {:>13.2}",
            sigma_bearing_deg,
            r.n,
            r.std_alpha_pca_rad.to_degrees(),
            r.std_alpha_weighted_rad.to_degrees(),
            r.crb_alpha_rad.to_degrees(),
            r.nees_pca,
            r.nees_weighted
        )?;
    }
    Ok(())
}

fn print_detection(rows: &[Row], compare: bool) -> anyhow::Result<()> {
    print_detection_table(rows, compare)?;
    outln!()?;
    print_recall_by_length(rows)?;
    outln!()?;
    print_lines_off_surface(rows)
}

/// One row per noise level and configuration; with `compare`, the second
/// configuration minus the first.
fn print_detection_table(rows: &[Row], compare: bool) -> anyhow::Result<()> {
    outln!(
        "{:>6}  {:<22} {:>6} {:>6} {:>7} {:>6} {:>6} {:>9} {:>9} {:>8} {:>8} {:>8} {:>8} {:>9}",
        "sigma",
        "config",
        "scans",
        "walls",
        "recall",
        "FP",
        "frag",
        "|da| med",
        "da rms",
        "|dd| med",
        "dd rms",
        "end med",
        "end rms",
        "us/scan"
    )?;
    for r in rows {
        outln!(
            "{:>4}mm  {:<22} {:>6} {:>6} {:>7.3} {:>6.3} {:>6.2} {:>8.3}° {:>8.3}° {:>6.1}mm {:>6.1}mm {:>6.1}mm {:>6.1}mm {:>9.1}",
            r.sigma_mm,
            r.config,
            r.scans,
            r.true_walls,
            r.recall,
            r.false_positive_fraction,
            r.fragmentation,
            r.alpha_median_deg,
            r.alpha_rms_deg,
            r.d_median_mm,
            r.d_rms_mm,
            r.endpoint_median_mm,
            r.endpoint_rms_mm,
            r.time_per_scan_us
        )?;
    }
    if compare {
        // Two configurations: the second minus the first, per noise level.
        for pair in rows.chunks(2) {
            let [a, b] = pair else { continue };
            outln!(
                "{:>4}mm  {:<22} {:>6} {:>6} {:>+7.3} {:>+6.3} {:>+6.2} {:>+8.3}° {:>+8.3}° {:>+6.1}mm {:>+6.1}mm {:>+6.1}mm {:>+6.1}mm {:>+9.1}",
                a.sigma_mm,
                "second - first",
                "",
                "",
                b.recall - a.recall,
                b.false_positive_fraction - a.false_positive_fraction,
                b.fragmentation - a.fragmentation,
                b.alpha_median_deg - a.alpha_median_deg,
                b.alpha_rms_deg - a.alpha_rms_deg,
                b.d_median_mm - a.d_median_mm,
                b.d_rms_mm - a.d_rms_mm,
                b.endpoint_median_mm - a.endpoint_median_mm,
                b.endpoint_rms_mm - a.endpoint_rms_mm,
                b.time_per_scan_us - a.time_per_scan_us
            )?;
        }
    }
    Ok(())
}

/// Recall in four bins of true wall length.
fn print_recall_by_length(rows: &[Row]) -> anyhow::Result<()> {
    outln!("Recall by true wall length")?;
    outln!(
        "{:>6}  {:<22} {:>9} {:>9} {:>9} {:>9}",
        "sigma",
        "config",
        "< 0.5 m",
        "0.5-1 m",
        "1-2 m",
        ">= 2 m"
    )?;
    for r in rows {
        let [a, b, c, d] = r.recall_by_length;
        outln!("{:>4}mm  {:<22} {a:>9.3} {b:>9.3} {c:>9.3} {d:>9.3}", r.sigma_mm, r.config)?;
    }
    Ok(())
}

/// How far the detected lines lie from the nearest true wall, in noise sigmas.
fn print_lines_off_surface(rows: &[Row]) -> anyhow::Result<()> {
    outln!(
        "Lines off their surface: rms distance of each detected line from the nearest true wall, in noise sigmas"
    )?;
    outln!("{:>6}  {:<22} {:>9} {:>9} {:>14}", "sigma", "config", "max", "99%", "lines > 3 sig")?;
    for r in rows {
        let [max, p99] = r.surface_rms_sigmas_max_p99;
        outln!(
            "{:>4}mm  {:<22} {max:>9.2} {p99:>9.2} {:>14}",
            r.sigma_mm,
            r.config,
            r.lines_off_surface
        )?;
    }
    Ok(())
}

fn print_real(r: &crate::eval_real::RealReport) -> anyhow::Result<()> {
    outln!("configuration: {}", r.config)?;
    print_csail(r)?;
    outln!()?;
    print_intel(r)?;
    outln!()?;
    print_own_poses(r)?;
    if !r.drift_grid.is_empty() {
        outln!()?;
        print_drift_grid(&r.drift_grid)?;
    }
    if !r.csail_sensitivity.is_empty() {
        outln!()?;
        print_sensitivity(&r.csail_sensitivity)?;
    }
    outln!()?;
    print_utm(&r.utm)?;
    outln!()?;
    outln!("Detection on every shared log (scans with walls in view: 20 valid returns or more)")?;
    print_detection_stats(&r.detection)?;
    outln!()?;
    outln!("The same, on each log's own sensor profile (--sensor)")?;
    print_detection_stats(&r.detection_with_sensor)?;
    Ok(())
}

/// MIT CSAIL's raw and aided odometry against its corrected poses.
fn print_csail(r: &crate::eval_real::RealReport) -> anyhow::Result<()> {
    outln!(
        "MIT CSAIL: {} scans with corrected poses; absolute errors after aligning at the first, and after the least-squares rigid alignment of all (rigid); relation metric between consecutive corrected scans",
        r.csail_pairs
    )?;
    outln!(
        "{:<32} {:>11} {:>11} {:>9} {:>9} {:>11} {:>9} {:>17} {:>17}",
        "trajectory",
        "heading rms",
        "heading max",
        "pos rms",
        "pos final",
        "rigid head.",
        "rigid pos",
        "rel. trans (m)",
        "rel. rot (deg)"
    )?;
    for t in &r.csail {
        let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2}"));
        outln!(
            "{:<32} {:>9} ° {:>9} ° {:>7} m {:>7} m {:>9} ° {:>7} m {:>8.3} ± {:<6.3} {:>8.3} ± {:<6.3}",
            t.name,
            f(t.heading_rms_deg),
            f(t.heading_max_deg),
            f(t.position_rms_m),
            f(t.position_final_m),
            f(t.rigid_heading_rms_deg),
            f(t.rigid_position_rms_m),
            t.relations.translation_mean_m,
            t.relations.translation_std_m,
            t.relations.rotation_mean_deg,
            t.relations.rotation_std_deg
        )?;
    }
    if let Some(j) = &r.csail_reference_jitter {
        outln!(
            "the corrected poses' own jitter: on {} straight stretches between corrected scans (raw odometry turning under 0.5° a step, 6 scans at most) their heading changes differ from the raw odometry's by {:.2}° rms (each corrected heading about {:.2}°, which every heading rms against them carries)",
            j.stretches,
            j.heading_rms_deg,
            j.heading_rms_deg / std::f64::consts::SQRT_2
        )?;
    }
    print_scan_agreement(&r.csail_scan_agreement)?;
    print_loops(&r.csail_loops)
}

/// Which of the corrected poses and the default trajectory the scans
/// contradict, and the rigid errors without the corrected poses contradicted
/// from both sides.
fn print_scan_agreement(a: &crate::eval_real::CsailAgreement) -> anyhow::Result<()> {
    let list = |links: &[[usize; 2]]| {
        links.iter().map(|[a, b]| format!("{a}->{b}")).collect::<Vec<_>>().join(", ")
    };
    outln!(
        "judged by the scans ({} links between consecutive corrected scans): the later scan's points on the earlier scan's surfaces, mean share {:.3} with the corrected poses, {:.3} with {}; a link contradicted when under {:.0}% fall there and the other trajectory puts {:.0}% or more: the corrected poses on {} ({}), {} on {} ({})",
        a.links,
        a.reference_mean_share,
        a.estimate_mean_share,
        a.trajectory,
        100.0 * pcaline_eval::CONTRADICTED_SHARE,
        100.0 * pcaline_eval::AGREEING_SHARE,
        a.reference_contradicted.len(),
        list(&a.reference_contradicted),
        a.trajectory,
        a.estimate_contradicted.len(),
        list(&a.estimate_contradicted)
    )?;
    outln!(
        "{} without the {} corrected scans the scans contradict from both sides (raw {:?}): rigid {:.2}° / {:.2} m",
        a.trajectory,
        a.reference_outliers.len(),
        a.reference_outliers,
        a.rigid_heading_rms_deg_without_outliers,
        a.rigid_position_rms_m_without_outliers
    )?;
    let largest = a
        .largest_heading_errors
        .iter()
        .map(|e| {
            let mark = if e.reference_contradicted { "*" } else { "" };
            format!("{}{mark} {:+.1}°", e.raw_index, e.error_deg)
        })
        .collect::<Vec<_>>()
        .join(", ");
    outln!(
        "{} rigid heading errors, the {} largest (raw scan; * where the scans contradict its corrected pose): {largest}; they alone make {:.2}° of the rms over all pairs, the others {:.2}° (aligned without them)",
        a.trajectory,
        a.largest_heading_errors.len(),
        a.largest_heading_share_deg,
        a.rigid_heading_rms_deg_without_largest
    )
}

/// One line per loop-closing run: its loops against the reference poses.
fn print_loops(rows: &[crate::eval_real::LoopRow]) -> anyhow::Result<()> {
    for l in rows {
        outln!(
            "{} loops against the corrected poses: {} standing, {} of them wrong (off by more than {} m or {}°; median {:.2} m / {:.2}°, max {:.2} m / {:.2}°); {} switched off, {} of them wrong; {} unchecked",
            l.name,
            l.standing,
            l.standing_wrong,
            pcaline_eval::WRONG_LOOP_M,
            pcaline_eval::WRONG_LOOP_DEG,
            l.standing_error_m[0],
            l.standing_error_deg[0],
            l.standing_error_m[1],
            l.standing_error_deg[1],
            l.switched_off,
            l.switched_off_wrong,
            l.unchecked
        )?;
    }
    Ok(())
}

/// Intel's drifted and aided trajectories by the relation metric.
fn print_intel(r: &crate::eval_real::RealReport) -> anyhow::Result<()> {
    outln!(
        "Intel: relation metric against intel.relations (drift seed {}; mean ± std)",
        r.intel_drift_seed
    )?;
    outln!(
        "{:<40} {:>9} {:>9} {:>17} {:>17}",
        "trajectory",
        "relations",
        "unmatched",
        "trans (m)",
        "rot (deg)"
    )?;
    for t in &r.intel {
        outln!(
            "{:<40} {:>9} {:>9} {:>8.3} ± {:<6.3} {:>8.3} ± {:<6.3}",
            t.name,
            t.relations.scored,
            t.relations.unmatched,
            t.relations.translation_mean_m,
            t.relations.translation_std_m,
            t.relations.rotation_mean_deg,
            t.relations.rotation_std_deg
        )?;
    }
    outln!(
        "(Between scans, an online mode composes the odometry since the last scan; a loop-closing \
         mode, optimized after the run, blends it with the odometry to the next scan, as the \
         second row does with the log's own poses. Pose moves are measured at the scans.)"
    )?;
    print_loops(&r.intel_loops)
}

/// How far each mode moves a log's own corrected poses.
fn print_own_poses(r: &crate::eval_real::RealReport) -> anyhow::Result<()> {
    outln!("Own corrected poses as the source: how far each mode moves them (aided minus source)")?;
    outln!(
        "{:<22} {:<26} {:>11} {:>11} {:>9} {:>17} {:>17}",
        "log",
        "mode",
        "heading rms",
        "heading max",
        "pos rms",
        "rel. trans (m)",
        "rel. rot (deg)"
    )?;
    for m in &r.own_poses {
        let (t, rot) = m.relations.as_ref().map_or(("-".into(), "-".into()), |r| {
            (
                format!("{:.3} ± {:.3}", r.translation_mean_m, r.translation_std_m),
                format!("{:.3} ± {:.3}", r.rotation_mean_deg, r.rotation_std_deg),
            )
        });
        outln!(
            "{:<22} {:<26} {:>9.3} ° {:>9.3} ° {:>7.3} m {:>17} {:>17}",
            m.log,
            m.mode,
            m.heading_rms_deg,
            m.heading_max_deg,
            m.position_rms_m,
            t,
            rot
        )?;
    }
    Ok(())
}

/// The Intel drift grid, cell by cell.
fn print_drift_grid(grid: &[crate::eval_real::DriftCell]) -> anyhow::Result<()> {
    outln!("Intel drift grid: corrected poses + synthetic drift, against the corrected poses")?;
    outln!(
        "{:>10} {:>6} {:>5}  {:<26} {:>11} {:>9} {:>17} {:>17}",
        "bias °/s",
        "speed",
        "seed",
        "mode",
        "heading rms",
        "pos rms",
        "rel. trans (m)",
        "rel. rot (deg)"
    )?;
    for c in grid {
        outln!(
            "{:>10.1} {:>5.0}% {:>5}  {:<26} {:>9.3} ° {:>7.3} m {:>8.3} ± {:<6.3} {:>8.3} ± {:<6.3}",
            c.heading_rate_bias_deg_s,
            100.0 * c.speed_scale_error,
            c.seed,
            c.mode,
            c.heading_rms_deg,
            c.position_rms_m,
            c.relations.translation_mean_m,
            c.relations.translation_std_m,
            c.relations.rotation_mean_deg,
            c.relations.rotation_std_deg
        )?;
    }
    Ok(())
}

/// MIT CSAIL's sensitivity runs, run by run, then each mode's median, mean
/// and range, and for a loop-closing mode the runs in which a wrong loop
/// stands.
fn print_sensitivity(runs: &[crate::eval_real::SensitivityRun]) -> anyhow::Result<()> {
    let p = pcaline_eval::SENSITIVITY_PERTURBATION;
    let mut seeds: Vec<u64> = runs.iter().map(|r| r.seed).collect();
    seeds.dedup();
    outln!(
        "MIT CSAIL sensitivity: the raw odometry plus a random walk of {} mm/sqrt(s) per axis and {:.4}°/sqrt(s), seeds {}",
        p.position_random_walk_m_sqrt_s * 1e3,
        p.heading_random_walk_rad_sqrt_s.to_degrees(),
        seed_list(&seeds)
    )?;
    outln!(
        "{:<34} {:>5} {:>11} {:>9} {:>11} {:>9} {:>17} {:>14}",
        "trajectory",
        "seed",
        "heading rms",
        "pos rms",
        "rigid head.",
        "rigid pos",
        "rel. rot (deg)",
        "loops wrong/up"
    )?;
    let f = |v: Option<f64>| v.unwrap_or(f64::NAN);
    for run in runs {
        let t = &run.row;
        let loops = run
            .loops
            .as_ref()
            .map_or_else(|| "-".to_owned(), |l| format!("{}/{}", l.standing_wrong, l.standing));
        outln!(
            "{:<34} {:>5} {:>9.2} ° {:>7.2} m {:>9.2} ° {:>7.2} m {:>8.3} ± {:<6.3} {:>14}",
            t.name,
            run.seed,
            f(t.heading_rms_deg),
            f(t.position_rms_m),
            f(t.rigid_heading_rms_deg),
            f(t.rigid_position_rms_m),
            t.relations.rotation_mean_deg,
            t.relations.rotation_std_deg,
            loops
        )?;
    }
    let mut names: Vec<&str> = Vec::new();
    for r in runs {
        if !names.contains(&r.row.name.as_str()) {
            names.push(&r.row.name);
        }
    }
    for name in names {
        let of_mode = || runs.iter().filter(|r| r.row.name == name);
        let of = |g: fn(&crate::eval_real::TrajectoryRow) -> Option<f64>| {
            let mut v: Vec<f64> = of_mode().filter_map(|r| g(&r.row)).collect();
            v.sort_by(f64::total_cmp);
            let median = v.get(v.len() / 2).copied().unwrap_or(f64::NAN);
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let (lo, hi) =
                (v.first().copied().unwrap_or(f64::NAN), v.last().copied().unwrap_or(f64::NAN));
            (median, mean, lo, hi)
        };
        let (h, h_mean, h_lo, h_hi) = of(|t| t.rigid_heading_rms_deg);
        let (p, p_mean, p_lo, p_hi) = of(|t| t.rigid_position_rms_m);
        outln!(
            "{name}: rigid heading rms median {h:.2}°, mean {h_mean:.2}° (range {h_lo:.2}-{h_hi:.2}°); rigid position rms median {p:.2} m, mean {p_mean:.2} m (range {p_lo:.2}-{p_hi:.2} m)"
        )?;
        let checked: Vec<&crate::eval_real::LoopRow> =
            of_mode().filter_map(|r| r.loops.as_ref()).collect();
        if !checked.is_empty() {
            let wrong = checked.iter().filter(|l| l.standing_wrong > 0).count();
            let far = checked.iter().filter(|l| l.standing_false > 0).count();
            let worst = checked.iter().map(|l| l.standing_worst_m).fold(0.0, f64::max);
            outln!(
                "{name}: a wrong loop stands in {wrong} of {} runs, one {} m or more off in {far} (worst {worst:.2} m; against the corrected poses carried over up to {} scans)",
                checked.len(),
                crate::eval_real::FALSE_LOOP_M,
                crate::eval_real::CSAIL_FALSE_LOOP_GAP_SCANS,
            )?;
        }
    }
    Ok(())
}

/// Seeds as `1-8` when there are more than two and each follows the last
/// by one, else listed.
fn seed_list(seeds: &[u64]) -> String {
    let consecutive = seeds.windows(2).all(|w| w[1] == w[0] + 1);
    match (seeds.first(), seeds.last()) {
        (Some(a), Some(b)) if seeds.len() > 2 && consecutive => format!("{a}-{b}"),
        _ => format!("{seeds:?}"),
    }
}

/// The UTM-30LX-EW bag: its lines and the LIDAR-only sharpness.
fn print_utm(u: &crate::eval_real::ResidualReport) -> anyhow::Result<()> {
    let [p10, p50, p90] = u.residual_std_p10_p50_p90_m;
    outln!(
        "UTM-30LX-EW bag {}: {} scans, {} lines (median {} points)",
        u.log,
        u.scans,
        u.lines,
        u.median_points
    )?;
    outln!(
        "per-line residual std: 10% {:.1} mm, median {:.1} mm, 90% {:.1} mm; {:.1}% of lines under 2 cm",
        p10 * 1e3,
        p50 * 1e3,
        p90 * 1e3,
        100.0 * u.fraction_under_2cm
    )?;
    outln!(
        "LIDAR-only sharpness (occupied 5 cm cells, fewer is sharper): estimator {}, estimator without deskew {}, every scan at the first pose {}",
        u.occupied_cells_lidar_only,
        u.occupied_cells_lidar_only_without_deskew,
        u.occupied_cells_not_moving
    )?;
    Ok(())
}

fn print_detection_stats(rows: &[crate::eval_real::DetectionStats]) -> anyhow::Result<()> {
    outln!(
        "{:<34} {:>10} {:>6} {:>8} {:>7} {:>10} {:>9}  {:>24} {:>9}",
        "log",
        "sensor",
        "scans",
        "no line",
        "lines",
        "on lines",
        "noise",
        "residual 10/50/90% (mm)",
        "grid"
    )?;
    for d in rows {
        let [p10, p50, p90] = d.residual_std_p10_p50_p90_m;
        outln!(
            "{:<34} {:>10} {:>6} {:>7.1}% {:>7.1} {:>9.1}% {:>6.1} mm  {:>8.1} {:>7.1} {:>7.1} {:>6.1} mm",
            d.log,
            d.sensor.as_deref().unwrap_or("-"),
            d.scans,
            100.0 * d.scans_without_line as f64 / d.scans_with_returns.max(1) as f64,
            d.lines_per_scan,
            100.0 * d.points_on_lines,
            d.noise_used_median_m * 1e3,
            p10 * 1e3,
            p50 * 1e3,
            p90 * 1e3,
            d.range_step_m * 1e3
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::seed_list;

    #[test]
    fn seeds_that_run_on_are_a_range() {
        assert_eq!(seed_list(&[1, 2, 3, 4, 5, 6, 7, 8]), "1-8");
        assert_eq!(seed_list(&[1, 2]), "[1, 2]");
        assert_eq!(seed_list(&[1, 3, 4]), "[1, 3, 4]");
        assert_eq!(seed_list(&[]), "[]");
    }
}
