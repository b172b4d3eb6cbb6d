//! `pcaline eval --real`: the real-data part of the evaluation (design,
//! section 5). The MIT CSAIL log's raw and aided odometry against its
//! GMapping-corrected poses; the relation metric on the Intel log, first of
//! its own corrected poses (a check of the metric) and then of the same poses
//! with a seeded synthetic drift, raw and aided; and the per-line residuals
//! of the UTM-30LX-EW bag.

use crate::config_file::NamedConfig;
use anyhow::{Context, Result};
use pcaline::aiding::{
    AidingConfig, AidingMode, BeamCloud, Localizer, LoopClosing, LoopClosureConfig,
    ScanMatchConfig, SensorLine,
};
use pcaline::geometry::{SensorProfile, wrap_angle};
use pcaline::{LineDetector, Pose2};
use pcaline_eval::{
    LoopCheck, RelationErrors, StampedTrajectory, aligned_trajectory_errors, perturbed,
    reference_by_registration, reference_by_source, relation_errors, rigid_alignment,
    rigidly_aligned_trajectory_errors, scan_agreement, trajectory_errors,
};
use pcaline_io::{
    CarmenOptions, CarmenReader, LogOptions, LogRecord, Relation, read_log, read_relations,
    read_scan_pairs,
};
use pcaline_sim::OdometryModel;
use rayon::prelude::*;
use serde::Serialize;
use std::ops::ControlFlow;
use std::path::Path;

/// `intel.relations` is stamped in absolute time, `intel.gfs.log` relative to
/// its start: this offset joins them (the datasets' README).
const INTEL_TIME_OFFSET_S: f64 = 976052857.34;
/// A relation's time meets a pose within this (the datasets' README).
const INTEL_TOLERANCE_S: f64 = 0.05;

/// The synthetic drift added to the Intel log's corrected poses: a gyro-like
/// heading-rate bias and random walk, a 3% speed error and a position random
/// walk, of the order of a wheeled robot's odometry.
pub const INTEL_DRIFT: OdometryModel = OdometryModel {
    heading_rate_bias_rad_s: 0.002,
    heading_random_walk_rad_sqrt_s: 0.002,
    speed_scale_error: 0.03,
    position_random_walk_m_sqrt_s: 0.005,
};

/// The aiding modes compared on real data: the aiding, and loop closure on
/// top of it or not.
fn modes(config: &NamedConfig) -> [(&'static str, AidingConfig, Option<LoopClosureConfig>); 6] {
    let estimator = config.aiding_in(AidingMode::Estimator);
    [
        ("raw", AidingConfig::none(), None),
        ("paper-aided (eq. 11-14)", AidingConfig::paper(), None),
        ("heading-aided", AidingConfig::heading(), None),
        ("full-pose aided", AidingConfig::full_pose(), None),
        ("estimator-aided", estimator, None),
        ("estimator + loop closure", estimator, Some(config.loop_closure)),
    ]
}

/// One loop per mode.
fn runners(config: &NamedConfig) -> Result<Vec<Localizer>> {
    Ok(modes(config)
        .iter()
        .map(|(_, a, l)| Localizer::new(*a, config.map, *l))
        .collect::<Result<_, _>>()?)
}

/// One trajectory against a reference: absolute errors after aligning at the
/// first pose, and the relation metric.
#[derive(Debug, Serialize)]
pub struct TrajectoryRow {
    /// Which trajectory.
    pub name: String,
    /// Heading rms after alignment, degrees (absent for relation-only rows).
    pub heading_rms_deg: Option<f64>,
    /// Largest heading error after alignment, degrees.
    pub heading_max_deg: Option<f64>,
    /// Position rms after alignment, metres.
    pub position_rms_m: Option<f64>,
    /// Position error of the last pose after alignment, metres.
    pub position_final_m: Option<f64>,
    /// Heading rms after the least-squares rigid alignment of all poses,
    /// degrees.
    pub rigid_heading_rms_deg: Option<f64>,
    /// Position rms after the least-squares rigid alignment, metres.
    pub rigid_position_rms_m: Option<f64>,
    /// Relation metric.
    pub relations: RelationRow,
}

/// The relation metric of a trajectory (Kuemmerle et al. 2009).
#[derive(Debug, Serialize)]
pub struct RelationRow {
    /// Relations scored.
    pub scored: usize,
    /// Relations with a time that met no pose.
    pub unmatched: usize,
    /// Mean and standard deviation of the translational error, metres.
    pub translation_mean_m: f64,
    /// Standard deviation of the translational error, metres.
    pub translation_std_m: f64,
    /// Mean rotational error, degrees.
    pub rotation_mean_deg: f64,
    /// Standard deviation of the rotational error, degrees.
    pub rotation_std_deg: f64,
}

impl From<RelationErrors> for RelationRow {
    fn from(e: RelationErrors) -> Self {
        RelationRow {
            scored: e.relations,
            unmatched: e.unmatched,
            translation_mean_m: e.translation_mean_m,
            translation_std_m: e.translation_std_m,
            rotation_mean_deg: e.rotation_mean_rad.to_degrees(),
            rotation_std_deg: e.rotation_std_rad.to_degrees(),
        }
    }
}

/// Per-line residuals of a real scan log.
#[derive(Debug, Serialize)]
pub struct ResidualReport {
    /// The log.
    pub log: String,
    /// Scans read.
    pub scans: usize,
    /// Lines detected.
    pub lines: usize,
    /// Median points per line.
    pub median_points: usize,
    /// Percentiles 10, 50 and 90 of the per-line residual std, metres.
    pub residual_std_p10_p50_p90_m: [f64; 3],
    /// Fraction of lines whose residual std is under 2 cm.
    pub fraction_under_2cm: f64,
    /// LIDAR-only mode (no odometry in the bag): occupied 5 cm cells when
    /// every return is placed with the estimator's trajectory, with no
    /// motion assumed, and the estimator without deskew (fewer is sharper).
    pub occupied_cells_lidar_only: usize,
    /// The same with every scan placed at the first scan's pose.
    pub occupied_cells_not_moving: usize,
    /// The same for the estimator without motion deskew.
    pub occupied_cells_lidar_only_without_deskew: usize,
}

/// Everything `pcaline eval --real` measures.
#[derive(Debug, Serialize)]
pub struct RealReport {
    /// The detector and map configuration.
    pub config: String,
    /// MIT CSAIL: scans with corrected poses.
    pub csail_pairs: usize,
    /// MIT CSAIL: how far the corrected poses' own heading jitters.
    pub csail_reference_jitter: Option<ReferenceJitter>,
    /// MIT CSAIL trajectories against the corrected poses (relations between
    /// consecutive corrected scans).
    pub csail: Vec<TrajectoryRow>,
    /// MIT CSAIL: the default trajectory and the corrected poses judged by
    /// the scans.
    pub csail_scan_agreement: CsailAgreement,
    /// MIT CSAIL: the loops of each loop-closing mode against the corrected
    /// poses.
    pub csail_loops: Vec<LoopRow>,
    /// MIT CSAIL with [`pcaline_eval::perturbed`] raw odometry, seeds
    /// [`RealOptions::sensitivity_seeds`], the estimator alone and with loop
    /// closure; empty unless asked for (`--drift-grid`).
    pub csail_sensitivity: Vec<SensitivityRun>,
    /// Intel: the relation metric of the log's own poses, then of the drifted
    /// poses raw and aided.
    pub intel: Vec<TrajectoryRow>,
    /// Intel: the loops of the loop-closing mode, with the log's own poses
    /// and with the seeded drift as the source, against the corrected poses.
    pub intel_loops: Vec<LoopRow>,
    /// Intel and CSAIL with their own corrected poses as the source: how far
    /// each mode moves them.
    pub own_poses: Vec<MovedRow>,
    /// Intel with the drift grid ([`DRIFT_GRID_BIAS_DEG_S`] x
    /// [`DRIFT_GRID_SEEDS`]); empty unless asked for.
    pub drift_grid: Vec<DriftCell>,
    /// Intel: the seed of the synthetic drift.
    pub intel_drift_seed: u64,
    /// The UTM-30LX-EW bag.
    pub utm: ResidualReport,
    /// Detection statistics of every shared log.
    pub detection: Vec<DetectionStats>,
    /// The same, with the detector on each log's own sensor profile
    /// ([`DETECTION_LOGS`]).
    pub detection_with_sensor: Vec<DetectionStats>,
}

/// The shared logs whose detection statistics `eval --real` reports, under
/// the datasets folder, with the sensor each was recorded with (the datasets'
/// README; the ROS 1 bag's 681 beams of 0.35° to 5.6 m are a URG-04LX's; the
/// single scans' sensor is not named, and their 270° and 19.8 m are taken as
/// the UTM class).
pub const DETECTION_LOGS: [(&str, SensorProfile); 10] = [
    ("intel/intel.gfs.log", SensorProfile::SickLms),
    ("mit-csail/mit-csail.clf", SensorProfile::SickLms),
    ("mit-csail/csail.corrected.log", SensorProfile::SickLms),
    ("utm30lx-ros2", SensorProfile::Utm30lxEw),
    ("ros1/laser_scan_matcher_demo.bag", SensorProfile::Urg04lx),
    ("single-scans/laser_scan_1.json", SensorProfile::Utm30lxEw),
    ("single-scans/laser_scan_2.json", SensorProfile::Utm30lxEw),
    ("single-scans/laser_scan_3.json", SensorProfile::Utm30lxEw),
    ("single-scans/laser_scan_4.json", SensorProfile::Utm30lxEw),
    ("single-scans/laser_scan_5.json", SensorProfile::Utm30lxEw),
];

/// Scans with fewer valid returns are not counted as having walls in view.
const MIN_RETURNS_IN_VIEW: usize = 20;

/// What the detector finds on one real log.
#[derive(Debug, Serialize)]
pub struct DetectionStats {
    /// The log, relative to the datasets folder.
    pub log: String,
    /// The sensor profile the detector was put on, when one was.
    pub sensor: Option<String>,
    /// Scans read.
    pub scans: usize,
    /// Scans with at least 20 valid returns.
    pub scans_with_returns: usize,
    /// Of those, scans that yield no line.
    pub scans_without_line: usize,
    /// Lines per scan, mean.
    pub lines_per_scan: f64,
    /// Valid returns on reported lines, as a fraction of all valid returns.
    pub points_on_lines: f64,
    /// Percentiles 10, 50 and 90 of the per-line residual std, metres.
    pub residual_std_p10_p50_p90_m: [f64; 3],
    /// Median over scans of the near-band sigma the thresholds used, metres.
    pub noise_used_median_m: f64,
    /// The range grid step found in most scans, metres (0: continuous).
    pub range_step_m: f64,
}

/// Sums over the scans of one log for [`DetectionStats`].
#[derive(Debug, Default)]
struct StatsSums {
    with_returns: usize,
    without_line: usize,
    lines: usize,
    on_lines: usize,
    valid: usize,
    residuals: Vec<f64>,
    noise: Vec<f64>,
    steps: Vec<f64>,
}

impl StatsSums {
    fn add(&mut self, d: &pcaline::Detection<'_>) {
        if d.points.len() >= MIN_RETURNS_IN_VIEW {
            self.with_returns += 1;
            self.without_line += usize::from(d.lines.is_empty());
        }
        self.lines += d.lines.len();
        self.valid += d.points.len();
        self.on_lines += d.lines.iter().map(|l| l.line.n_points()).sum::<usize>();
        self.residuals.extend(d.lines.iter().map(|l| l.line.residual_std()));
        self.noise.extend(d.noise.map(|n| n.near_sigma_m));
        self.steps.extend(d.noise_estimate.map(|e| e.range_step_m));
    }

    fn finish(mut self, log: &str, sensor: Option<SensorProfile>, scans: usize) -> DetectionStats {
        for v in [&mut self.residuals, &mut self.noise, &mut self.steps] {
            v.sort_by(f64::total_cmp);
        }
        let pick = |v: &[f64], q: f64| v.get(((v.len() as f64 - 1.0) * q) as usize).copied();
        DetectionStats {
            log: log.to_string(),
            sensor: sensor.map(|s| s.name().to_string()),
            scans,
            scans_with_returns: self.with_returns,
            scans_without_line: self.without_line,
            lines_per_scan: self.lines as f64 / scans.max(1) as f64,
            points_on_lines: self.on_lines as f64 / self.valid.max(1) as f64,
            residual_std_p10_p50_p90_m: [0.1, 0.5, 0.9]
                .map(|q| pick(&self.residuals, q).unwrap_or(f64::NAN)),
            noise_used_median_m: pick(&self.noise, 0.5).unwrap_or(f64::NAN),
            range_step_m: pick(&self.steps, 0.5).unwrap_or(0.0),
        }
    }
}

/// Detection statistics on the log at `path` (named `log` in the report),
/// in one read: of the detector of `config` as it is, and on `sensor`'s
/// datasheet noise.
pub fn detection_stats(
    path: &Path,
    log: &str,
    config: &NamedConfig,
    sensor: SensorProfile,
) -> Result<(DetectionStats, DetectionStats)> {
    let mut plain = LineDetector::new(config.detector)?;
    let mut profiled = LineDetector::new(config.detector_for(Some(sensor)))?;
    let (mut a, mut b) = (StatsSums::default(), StatsSums::default());
    let scans = read_log(path, &LogOptions::default(), |record| {
        if let LogRecord::Scan(s) = record {
            a.add(&plain.detect(&s.scan));
            b.add(&profiled.detect(&s.scan));
        }
        ControlFlow::Continue(())
    })?;
    Ok((a.finish(log, None, scans), b.finish(log, Some(sensor), scans)))
}

/// What `pcaline eval --real` runs besides its fixed measurements.
#[derive(Debug, Clone, PartialEq)]
pub struct RealOptions {
    /// Seed of the synthetic drift added to Intel's poses.
    pub drift_seed: u64,
    /// Whether to run Intel's drift grid and MIT CSAIL's sensitivity runs.
    pub drift_grid: bool,
    /// The seeds of MIT CSAIL's sensitivity runs (with `drift_grid`;
    /// `pcaline eval` runs 1 to `--sensitivity-seeds`, 8 by default:
    /// [`pcaline_eval::SENSITIVITY_SEEDS`]).
    pub sensitivity_seeds: Vec<u64>,
}

/// Runs every real-data measurement on the datasets folder `data`.
pub fn evaluate(data: &Path, config: &NamedConfig, options: &RealOptions) -> Result<RealReport> {
    let (seed, grid) = (options.drift_seed, options.drift_grid);
    let sensitivity_seeds: &[u64] = if grid { &options.sensitivity_seeds } else { &[] };
    // The logs on the thread pool; each part's figures do not depend on
    // the others or on the number of threads.
    let ((csail, intel), (csail_own, (detection, utm))) = rayon::join(
        || {
            rayon::join(
                || csail(data, config, sensitivity_seeds),
                || intel(data, seed, config, grid),
            )
        },
        || {
            rayon::join(
                || csail_own(data, config),
                || {
                    rayon::join(
                        || {
                            DETECTION_LOGS
                                .par_iter()
                                .map(|(log, sensor)| {
                                    detection_stats(&data.join(log), log, config, *sensor)
                                })
                                .collect::<Result<Vec<_>>>()
                        },
                        || utm_residuals(&data.join("utm30lx-ros2"), config),
                    )
                },
            )
        },
    );
    let CsailResult {
        pairs: csail_pairs,
        reference_jitter: csail_reference_jitter,
        rows: csail,
        loops: csail_loops,
        sensitivity,
        agreement: csail_scan_agreement,
    } = csail?;
    let IntelResult { rows: intel, moved: mut own_poses, cells: drift_grid, loops: intel_loops } =
        intel?;
    own_poses.extend(csail_own?);
    let (detection, detection_with_sensor): (Vec<_>, Vec<_>) = detection?.into_iter().unzip();
    Ok(RealReport {
        config: config.name.clone(),
        csail_pairs,
        csail_reference_jitter,
        csail,
        csail_scan_agreement,
        csail_loops,
        csail_sensitivity: sensitivity,
        intel,
        intel_loops,
        own_poses,
        drift_grid,
        intel_drift_seed: seed,
        utm: utm?,
        detection,
        detection_with_sensor,
    })
}

/// One detector and one aiding loop per mode, fed scan by scan.
struct Loops {
    detector: LineDetector,
    loops: Vec<Localizer>,
}

impl Loops {
    fn new(config: &NamedConfig) -> Result<Self> {
        Ok(Loops { detector: LineDetector::new(config.detector)?, loops: runners(config)? })
    }

    /// The pose of each mode after the scan `scan` with source pose `source`.
    fn step(&mut self, scan: &pcaline::Scan, source: &Pose2) -> Vec<Pose2> {
        // The localizers take the detector's lines as they are.
        let lines = self.detector.detect(scan).lines;
        self.loops.iter_mut().map(|a| a.step_scan(scan, source, lines).0).collect()
    }

    /// Replaces the poses of the loop-closing modes by their optimized
    /// trajectories (every scan was stepped).
    fn finish(&mut self, poses: &mut [Vec<Pose2>]) {
        for (runner, out) in self.loops.iter_mut().zip(poses) {
            take_optimized(runner, out);
        }
    }
}

/// Finishes `runner` and, with loop closure, replaces each pose of `poses`
/// (one per stepped scan) by the optimized one where the graph places it.
fn take_optimized(runner: &mut Localizer, poses: &mut [Pose2]) {
    if let Some(final_poses) = runner.finish() {
        for (o, p) in poses.iter_mut().zip(final_poses) {
            *o = p.unwrap_or(*o);
        }
    }
}

/// A raw scan's corrected pose is carried from the nearest corrected scan
/// within this many scans by registering the two scans
/// ([`reference_by_registration`]), to check loops at keyframes without a
/// corrected pose of their own (the corrected log holds one scan in five).
/// Not by the raw odometry: it lags the scans by about 0.1 s
/// (`docs/accuracy.md`): carried over up to two scans of a fast turn, it
/// called 21 of 38 standing loops wrong (one by 55°), against 2 of 37 by
/// registration.
const CSAIL_REFERENCE_GAP_SCANS: usize = 2;

/// False loops ([`FALSE_LOOP_M`] or more off) are counted against the
/// corrected poses carried by the raw odometry ([`reference_by_source`])
/// from up to this many scans away, where registration may fail: the odometry's
/// lag in a turn costs a few degrees, which cannot make a right loop half a
/// metre wrong, and the keyframes that the strict reference leaves
/// unchecked are checked too. (A loop 34 m off stood unchecked in one of 96
/// sensitivity runs at 2 scans; `docs/accuracy.md`.)
pub const CSAIL_FALSE_LOOP_GAP_SCANS: usize = 5;

/// A standing loop this far off the reference is a false loop, metres.
pub const FALSE_LOOP_M: f64 = 0.5;

/// The reference poses loops are checked against: `strict` for right and
/// wrong (within 0.3 m and 2°), `loose` (carried further, reaching more
/// keyframes) for false loops alone.
#[derive(Clone, Copy)]
struct LoopReference<'a> {
    strict: &'a [Option<Pose2>],
    loose: &'a [Option<Pose2>],
}

/// MIT CSAIL: raw and aided odometry at the scans with corrected poses, and
/// the loops of the loop-closing modes against the corrected poses; for each
/// seed of `sensitivity_seeds`, the estimator's runs on perturbed odometry
/// ([`pcaline_eval::perturbed`]), each with its loops checked.
fn csail(data: &Path, config: &NamedConfig, sensitivity_seeds: &[u64]) -> Result<CsailResult> {
    let sensitivity = !sensitivity_seeds.is_empty();
    let dir = data.join("mit-csail");
    let pairs = read_scan_pairs(&dir.join("csail_corrected_to_raw_pairs.txt"))?;
    let mut loops = Loops::new(config)?;
    let mut poses: Vec<Vec<Pose2>> = vec![Vec::new(); modes(config).len()];
    let mut sources = Vec::new();
    // Each scan and its lines, kept for the sensitivity runs.
    let mut kept: Vec<(pcaline::Scan, Vec<SensorLine>)> = Vec::new();
    // Every scan's points: to carry the corrected poses to the keyframes by
    // registration, and to judge the corrected poses by the scans.
    let judge = ScanMatchConfig::standard();
    let mut clouds: Vec<Option<BeamCloud>> = Vec::new();
    for record in CarmenReader::open(&dir.join("mit-csail.clf"), CarmenOptions::default())? {
        let LogRecord::Scan(s) = record? else { continue };
        clouds.push(Some(BeamCloud::from_scan(&s.scan, &judge)));
        let source = s.odometry.or(s.pose).context("a FLASER line without odometry")?;
        let lines = loops.detector.detect(&s.scan).lines;
        for (out, l) in poses.iter_mut().zip(&mut loops.loops) {
            out.push(l.step_scan(&s.scan, &source, lines).0);
        }
        if sensitivity {
            kept.push((s.scan.clone(), lines.iter().map(SensorLine::from).collect()));
        }
        sources.push(source);
    }
    let corrected: Vec<(usize, Pose2)> =
        pairs.iter().map(|p| (p.raw_index, p.corrected_pose)).collect();
    let per_scan =
        reference_by_registration(&corrected, &sources, &clouds, CSAIL_REFERENCE_GAP_SCANS, &judge);
    let per_scan_loose = reference_by_source(&corrected, &sources, CSAIL_FALSE_LOOP_GAP_SCANS);
    let reference = LoopReference { strict: &per_scan, loose: &per_scan_loose };
    loops.finish(&mut poses);
    let loop_rows = check_loops(config, &loops.loops, reference);
    let score = CsailScore::new(&pairs);
    let rows = modes(config)
        .iter()
        .zip(&poses)
        .map(|((name, _, _), est)| score.row(&format!("{name} odometry"), est))
        .collect::<Result<_>>()?;
    let sensitivity = if sensitivity {
        // The stamps of a log without them count one second a scan.
        let times: Vec<f64> =
            kept.iter().enumerate().map(|(k, (s, _))| s.stamp_s.unwrap_or(k as f64)).collect();
        let runs: Vec<(u64, &'static str, AidingConfig, Option<LoopClosureConfig>)> =
            sensitivity_seeds
                .iter()
                .flat_map(|&seed| {
                    modes(config)
                        .into_iter()
                        .filter(|(_, a, _)| a.mode == AidingMode::Estimator)
                        .map(move |(name, a, l)| (seed, name, a, l))
                })
                .collect();
        runs.par_iter()
            .map(|&(seed, name, aiding, loop_closure)| {
                let source_poses = perturbed(&sources, &times, seed);
                let mut localizer = Localizer::new(aiding, config.map, loop_closure)?;
                let mut est: Vec<Pose2> = kept
                    .iter()
                    .zip(&source_poses)
                    .map(|((scan, lines), source)| localizer.step_scan(scan, source, lines).0)
                    .collect();
                take_optimized(&mut localizer, &mut est);
                let loops = localizer.loop_closing().map(|l| loop_row(name, l, reference));
                let row = score.row(&format!("{name} odometry"), &est)?;
                Ok(SensitivityRun { seed, row, loops })
            })
            .collect::<Result<Vec<_>>>()?
    } else {
        Vec::new()
    };
    let reference_jitter = reference_jitter(&pairs, &sources);
    let (name, _, _) = modes(config)[DEFAULT_MODE];
    let agreement =
        score.agreement(&format!("{name} odometry"), &poses[DEFAULT_MODE], clouds, &judge)?;
    Ok(CsailResult {
        pairs: pairs.len(),
        reference_jitter,
        rows,
        loops: loop_rows,
        sensitivity,
        agreement,
    })
}

/// The mode of [`modes`] that `pcaline map` runs by default (the estimator
/// with loop closure).
const DEFAULT_MODE: usize = 5;

/// MIT CSAIL's corrected poses and one of our trajectories judged by the
/// scans, link by link between consecutive corrected scans
/// ([`pcaline_eval::scan_agreement`]), and the trajectory's rigid errors
/// without the scans whose corrected pose the scans contradict from both
/// sides.
#[derive(Debug, Serialize)]
pub struct CsailAgreement {
    /// Which trajectory.
    pub trajectory: String,
    /// Links judged (consecutive corrected scans).
    pub links: usize,
    /// Mean over the links of the share of the later scan's points on the
    /// earlier scan's surfaces, with the corrected poses.
    pub reference_mean_share: f64,
    /// The same with the trajectory.
    pub estimate_mean_share: f64,
    /// Links (raw scan indices) where the corrected poses leave under
    /// [`pcaline_eval::CONTRADICTED_SHARE`] of the later scan's points on
    /// the earlier scan's surfaces and the trajectory at least
    /// [`pcaline_eval::AGREEING_SHARE`].
    pub reference_contradicted: Vec<[usize; 2]>,
    /// The same the other way round: the trajectory contradicted, the
    /// corrected poses not.
    pub estimate_contradicted: Vec<[usize; 2]>,
    /// Raw scans whose corrected pose the scans contradict from both sides
    /// ([`pcaline_eval::ScanAgreement::reference_outliers`]).
    pub reference_outliers: Vec<usize>,
    /// Heading rms after the rigid alignment of the other corrected scans,
    /// degrees.
    pub rigid_heading_rms_deg_without_outliers: f64,
    /// Position rms after the same alignment, metres.
    pub rigid_position_rms_m_without_outliers: f64,
    /// The trajectory's [`LARGEST_ERRORS_LISTED`] largest heading errors
    /// after the rigid alignment of all corrected scans, largest first:
    /// where the heading rms over all pairs comes from.
    pub largest_heading_errors: Vec<LargeHeadingError>,
    /// What those scans alone make of the rigid heading rms over all pairs
    /// (the root of the sum of their squared errors over the number of
    /// pairs), degrees.
    pub largest_heading_share_deg: f64,
    /// Rigid heading rms of the other scans, aligned without those, degrees.
    pub rigid_heading_rms_deg_without_largest: f64,
}

/// How many of a trajectory's largest heading errors against MIT CSAIL's
/// corrected poses [`CsailAgreement`] lists.
pub const LARGEST_ERRORS_LISTED: usize = 5;

/// One corrected scan's heading error (see
/// [`CsailAgreement::largest_heading_errors`]).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct LargeHeadingError {
    /// The raw scan's index.
    pub raw_index: usize,
    /// The trajectory's heading less the corrected one after the rigid
    /// alignment, degrees.
    pub error_deg: f64,
    /// Whether the scans contradict this scan's corrected pose: on the link
    /// into or out of it ([`pcaline_eval::LinkAgreement::reference_contradicted`]),
    /// or from both sides of a stretch holding it
    /// ([`pcaline_eval::ScanAgreement::reference_outliers`]).
    pub reference_contradicted: bool,
}

/// How far a reference's heading jitters from scan to scan, measured where
/// the raw odometry is trustworthy: on straight stretches.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ReferenceJitter {
    /// Stretches between consecutive corrected scans, at most
    /// [`JITTER_MAX_SCANS`] raw scans apart, over which the raw odometry
    /// turns less than [`JITTER_MAX_TURN_DEG`] at every step.
    pub stretches: usize,
    /// Rms of the corrected poses' heading change less the raw odometry's
    /// over those stretches, degrees.
    pub heading_rms_deg: f64,
}

/// The longest stretch [`ReferenceJitter`] takes, in raw scans.
const JITTER_MAX_SCANS: usize = 6;
/// The largest turn of a raw step on a stretch [`ReferenceJitter`] takes.
const JITTER_MAX_TURN_DEG: f64 = 0.5;

/// [`ReferenceJitter`] of `pairs` against the raw odometry `raw` (a pose
/// per raw scan). Over a straight second of travel wheel odometry turns by
/// a small fraction of a degree in error, and its latency cannot matter, so
/// what the corrected heading change adds is the reference's own jitter:
/// with a scatter independent from scan to scan, each corrected heading
/// scatters by the rms over the square root of 2, which any heading error
/// measured against the reference then carries. `None` without such a
/// stretch.
fn reference_jitter(pairs: &[pcaline_io::ScanPair], raw: &[Pose2]) -> Option<ReferenceJitter> {
    let straight = |from: usize, to: usize| {
        to > from
            && to - from <= JITTER_MAX_SCANS
            && to < raw.len()
            && (from..to).all(|k| {
                raw[k].between(&raw[k + 1]).heading().abs() < JITTER_MAX_TURN_DEG.to_radians()
            })
    };
    let diffs: Vec<f64> = pairs
        .windows(2)
        .filter(|w| straight(w[0].raw_index, w[1].raw_index))
        .map(|w| {
            let corrected = w[0].corrected_pose.between(&w[1].corrected_pose).heading();
            let odometry = raw[w[0].raw_index].between(&raw[w[1].raw_index]).heading();
            wrap_angle(corrected - odometry)
        })
        .collect();
    (!diffs.is_empty()).then(|| ReferenceJitter {
        stretches: diffs.len(),
        heading_rms_deg: (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64)
            .sqrt()
            .to_degrees(),
    })
}

/// What [`csail`] measures.
struct CsailResult {
    /// Scans with corrected poses.
    pairs: usize,
    /// The corrected poses' own heading jitter.
    reference_jitter: Option<ReferenceJitter>,
    /// A row per mode.
    rows: Vec<TrajectoryRow>,
    /// The loops of the loop-closing modes.
    loops: Vec<LoopRow>,
    /// The sensitivity runs, if asked for.
    sensitivity: Vec<SensitivityRun>,
    /// The default mode's trajectory and the corrected poses judged by the
    /// scans.
    agreement: CsailAgreement,
}

/// Scores a trajectory of the raw log's scans against MIT CSAIL's corrected
/// poses: absolute errors aligned at the first pair and rigidly, and the
/// relation metric between consecutive corrected scans (stamped by pair
/// index).
struct CsailScore<'a> {
    pairs: &'a [pcaline_io::ScanPair],
    reference: Vec<Pose2>,
    relations: Vec<Relation>,
}

impl<'a> CsailScore<'a> {
    fn new(pairs: &'a [pcaline_io::ScanPair]) -> Self {
        let reference: Vec<Pose2> = pairs.iter().map(|p| p.corrected_pose).collect();
        let relations = (1..reference.len())
            .map(|k| Relation {
                t1_s: (k - 1) as f64,
                t2_s: k as f64,
                relative: reference[k - 1].between(&reference[k]),
            })
            .collect();
        CsailScore { pairs, reference, relations }
    }

    /// The poses of `est` (a pose per raw scan) at the corrected scans.
    fn at_corrected_scans(&self, est: &[Pose2]) -> Result<Vec<Pose2>> {
        self.pairs
            .iter()
            .map(|p| {
                est.get(p.raw_index).copied().context("a pair names a raw scan beyond the log")
            })
            .collect()
    }

    /// The row of the trajectory `est` (a pose per raw scan), named `name`.
    fn row(&self, name: &str, est: &[Pose2]) -> Result<TrajectoryRow> {
        let picked = self.at_corrected_scans(est)?;
        let e = aligned_trajectory_errors(&picked, &self.reference).context("no pairs")?;
        let rigid =
            rigidly_aligned_trajectory_errors(&picked, &self.reference).context("no pairs")?;
        let stamped = StampedTrajectory::new(
            picked.iter().enumerate().map(|(k, p)| (k as f64, *p)).collect(),
        );
        let r = relation_errors(&stamped, &self.relations, 0.0).context("no relations")?;
        Ok(TrajectoryRow {
            name: name.to_string(),
            heading_rms_deg: Some(e.heading_rms_rad.to_degrees()),
            heading_max_deg: Some(e.heading_max_rad.to_degrees()),
            position_rms_m: Some(e.position_rms_m),
            position_final_m: Some(e.position_final_m),
            rigid_heading_rms_deg: Some(rigid.heading_rms_rad.to_degrees()),
            rigid_position_rms_m: Some(rigid.position_rms_m),
            relations: r.into(),
        })
    }

    /// The trajectory `est` (a pose per raw scan) and the corrected poses
    /// judged by the corrected scans' `clouds` (one entry per raw scan, the
    /// corrected ones taken) with `judge`.
    fn agreement(
        &self,
        name: &str,
        est: &[Pose2],
        mut clouds: Vec<Option<BeamCloud>>,
        judge: &ScanMatchConfig,
    ) -> Result<CsailAgreement> {
        let picked = self.at_corrected_scans(est)?;
        let ordered: Vec<BeamCloud> = self
            .pairs
            .iter()
            .map(|p| {
                clouds
                    .get_mut(p.raw_index)
                    .and_then(Option::take)
                    .context("a corrected scan was not read")
            })
            .collect::<Result<_>>()?;
        let a = scan_agreement(&ordered, &self.reference, &picked, judge);
        let mean = |share: fn(&pcaline_eval::LinkAgreement) -> f64| {
            a.links.iter().map(share).sum::<f64>() / a.links.len().max(1) as f64
        };
        let raw = |k: usize| self.pairs[k].raw_index;
        let links = |l: &pcaline_eval::LinkAgreement| [raw(l.from), raw(l.to)];
        let keep: Vec<usize> =
            (0..picked.len()).filter(|k| !a.reference_outliers.contains(k)).collect();
        let rigid = rigidly_aligned_trajectory_errors(
            &keep.iter().map(|&k| picked[k]).collect::<Vec<_>>(),
            &keep.iter().map(|&k| self.reference[k]).collect::<Vec<_>>(),
        )
        .context("no pairs")?;
        let largest = self.largest_heading_errors(&picked)?;
        let n = picked.len() as f64;
        let share = largest.iter().map(|&(_, e)| e * e).sum::<f64>() / n;
        let others: Vec<usize> =
            (0..picked.len()).filter(|k| !largest.iter().any(|&(j, _)| j == *k)).collect();
        let without_largest = rigidly_aligned_trajectory_errors(
            &others.iter().map(|&k| picked[k]).collect::<Vec<_>>(),
            &others.iter().map(|&k| self.reference[k]).collect::<Vec<_>>(),
        )
        .context("no pairs")?;
        let contradicted_at = |k: usize| {
            a.reference_outliers.contains(&k)
                || a.links.iter().any(|l| (l.from == k || l.to == k) && l.reference_contradicted())
        };
        Ok(CsailAgreement {
            trajectory: name.to_string(),
            links: a.links.len(),
            reference_mean_share: mean(|l| l.reference_share),
            estimate_mean_share: mean(|l| l.estimate_share),
            reference_contradicted: a.reference_contradicted().map(links).collect(),
            estimate_contradicted: a.estimate_contradicted().map(links).collect(),
            reference_outliers: a.reference_outliers.iter().map(|&k| raw(k)).collect(),
            rigid_heading_rms_deg_without_outliers: rigid.heading_rms_rad.to_degrees(),
            rigid_position_rms_m_without_outliers: rigid.position_rms_m,
            largest_heading_errors: largest
                .iter()
                .map(|&(k, e)| LargeHeadingError {
                    raw_index: raw(k),
                    error_deg: e.to_degrees(),
                    reference_contradicted: contradicted_at(k),
                })
                .collect(),
            largest_heading_share_deg: share.sqrt().to_degrees(),
            rigid_heading_rms_deg_without_largest: without_largest.heading_rms_rad.to_degrees(),
        })
    }

    /// The [`LARGEST_ERRORS_LISTED`] largest heading errors of `picked` (a
    /// pose per corrected scan) after the rigid alignment of all: (index
    /// among the corrected scans, signed error in radians), largest first.
    fn largest_heading_errors(&self, picked: &[Pose2]) -> Result<Vec<(usize, f64)>> {
        let reference_from_estimate =
            rigid_alignment(picked, &self.reference).context("no finite pairs")?;
        let mut errors: Vec<(usize, f64)> = picked
            .iter()
            .zip(&self.reference)
            .enumerate()
            .map(|(k, (e, r))| {
                (k, wrap_angle(reference_from_estimate.compose(e).heading() - r.heading()))
            })
            .filter(|(_, e)| e.is_finite())
            .collect();
        errors.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        errors.truncate(LARGEST_ERRORS_LISTED);
        Ok(errors)
    }
}

/// The loops of each loop-closing mode among `localizers` (one per
/// [`modes`]) checked against `reference` (a pose per scan), named as the
/// mode.
fn check_loops(
    config: &NamedConfig,
    localizers: &[Localizer],
    reference: LoopReference<'_>,
) -> Vec<LoopRow> {
    modes(config)
        .iter()
        .zip(localizers)
        .filter_map(|((name, _, _), runner)| {
            Some(loop_row(name, runner.loop_closing()?, reference))
        })
        .collect()
}

/// One loop-closing run's loops, `name`d, against `reference`: right and
/// wrong against its strict poses, false loops against its loose ones.
fn loop_row(name: &str, l: &LoopClosing, reference: LoopReference<'_>) -> LoopRow {
    let scans: Vec<usize> = l.keyframes().iter().map(|k| k.scan).collect();
    let loose = LoopCheck::of(l.loops(), &scans, reference.loose);
    LoopRow::new(name, &LoopCheck::of(l.loops(), &scans, reference.strict), &loose)
}

/// One loop-closing run's loops against a log's corrected poses
/// ([`LoopCheck`]; wrong: off by more than [`pcaline_eval::WRONG_LOOP_M`]
/// or [`pcaline_eval::WRONG_LOOP_DEG`]).
#[derive(Debug, Serialize)]
pub struct LoopRow {
    /// The run: the mode, prefixed by the source on Intel.
    pub name: String,
    /// Loop edges standing at the end of the run.
    pub standing: usize,
    /// Of those, wrong.
    pub standing_wrong: usize,
    /// Loop edges the optimizer switched off.
    pub switched_off: usize,
    /// Of those, wrong.
    pub switched_off_wrong: usize,
    /// Loop edges with a keyframe that has no reference pose.
    pub unchecked: usize,
    /// Median and largest error of the standing loops, metres.
    pub standing_error_m: [f64; 2],
    /// Median and largest error of the standing loops, degrees.
    pub standing_error_deg: [f64; 2],
    /// Standing loops [`FALSE_LOOP_M`] or more off the looser reference
    /// (MIT CSAIL: carried up to [`CSAIL_FALSE_LOOP_GAP_SCANS`] scans), which
    /// reaches keyframes the strict one leaves unchecked: false loops.
    pub standing_false: usize,
    /// The largest error of a standing loop against the looser reference,
    /// metres (0 without one).
    pub standing_worst_m: f64,
}

impl LoopRow {
    fn new(name: &str, c: &LoopCheck, loose: &LoopCheck) -> Self {
        let loose_m = || loose.standing_errors.iter().map(|e| e.0);
        let median_max = |mut v: Vec<f64>| -> [f64; 2] {
            v.sort_by(f64::total_cmp);
            match v.last() {
                Some(&max) => [v[(v.len() - 1) / 2], max],
                None => [f64::NAN; 2],
            }
        };
        LoopRow {
            name: name.to_string(),
            standing: c.standing,
            standing_wrong: c.standing_wrong,
            switched_off: c.switched_off,
            switched_off_wrong: c.switched_off_wrong,
            unchecked: c.unchecked,
            standing_error_m: median_max(c.standing_errors.iter().map(|e| e.0).collect()),
            standing_error_deg: median_max(c.standing_errors.iter().map(|e| e.1).collect()),
            standing_false: loose_m().filter(|m| *m >= FALSE_LOOP_M).count(),
            standing_worst_m: loose_m().fold(0.0, f64::max),
        }
    }
}

/// A record of the Intel log in time order: its time, corrected pose and
/// the lines of its scan, if it is one (detected once, shared by every run).
struct IntelRecord {
    time_s: f64,
    pose: Pose2,
    lines: Option<Vec<SensorLine>>,
    /// The scan of a scan record, stamped `time_s` (for the estimator's
    /// scan-to-scan registration).
    scan: Option<pcaline::Scan>,
}

/// How far an aided trajectory moved a log's own poses, when they are fed
/// as the source (a good source must come out essentially unchanged).
#[derive(Debug, Serialize)]
pub struct MovedRow {
    /// The log.
    pub log: String,
    /// The aiding mode.
    pub mode: String,
    /// Heading rms of aided minus source, degrees.
    pub heading_rms_deg: f64,
    /// Largest heading difference, degrees.
    pub heading_max_deg: f64,
    /// Position rms of aided minus source, metres.
    pub position_rms_m: f64,
    /// The relation metric of the aided trajectory (Intel only).
    pub relations: Option<RelationRow>,
}

/// One cell of the drift grid: Intel's corrected poses (the truth here)
/// with a synthetic drift, raw and aided.
#[derive(Debug, Serialize)]
pub struct DriftCell {
    /// Heading-rate bias, degrees per second.
    pub heading_rate_bias_deg_s: f64,
    /// Speed scale error (0.03 = 3% too long).
    pub speed_scale_error: f64,
    /// The drift's seed.
    pub seed: u64,
    /// The aiding mode.
    pub mode: String,
    /// Heading rms against the corrected poses at the scans, aligned at
    /// the first scan, degrees.
    pub heading_rms_deg: f64,
    /// Position rms against the corrected poses at the scans, aligned at
    /// the first scan, metres.
    pub position_rms_m: f64,
    /// The relation metric.
    pub relations: RelationRow,
}

/// One MIT CSAIL sensitivity run ([`pcaline_eval::perturbed`]).
#[derive(Debug, Serialize)]
pub struct SensitivityRun {
    /// The perturbation's seed.
    pub seed: u64,
    /// The trajectory against the corrected poses (named by its mode).
    pub row: TrajectoryRow,
    /// The run's loops against the corrected poses, for a loop-closing
    /// mode (`None` for the estimator alone).
    pub loops: Option<LoopRow>,
}

/// The Intel log's records in time order, with each scan's lines.
struct IntelLog {
    records: Vec<IntelRecord>,
    /// Indices into `records` in the log's own order.
    log_order: Vec<usize>,
}

/// The Intel log's records, time-ordered, with each scan's lines.
fn intel_records(data: &Path, config: &NamedConfig) -> Result<IntelLog> {
    let mut options = CarmenOptions::default();
    options.time_offset_s = INTEL_TIME_OFFSET_S;
    let log = data.join("intel").join("intel.gfs.log");
    let mut detector = LineDetector::new(config.detector)?;
    let mut in_log = Vec::new();
    for record in CarmenReader::open(&log, options)? {
        in_log.push(match record? {
            LogRecord::Scan(s) => IntelRecord {
                time_s: s.scan.stamp_s.context("a FLASER line without a timestamp")?,
                pose: s.pose.context("a FLASER line without a pose")?,
                lines: Some(detector.detect(&s.scan).lines.iter().map(SensorLine::from).collect()),
                scan: Some(s.scan),
            },
            LogRecord::Odometry(o) => {
                IntelRecord { time_s: o.stamp_s, pose: o.pose, lines: None, scan: None }
            }
            // A CARMEN log has scans and odometry only.
            _ => continue,
        });
    }
    // A stable sort: records stamped alike keep the log's order.
    let mut by_time: Vec<usize> = (0..in_log.len()).collect();
    by_time.sort_by(|&a, &b| in_log[a].time_s.total_cmp(&in_log[b].time_s));
    let mut log_order = vec![0; in_log.len()];
    for (k, &i) in by_time.iter().enumerate() {
        log_order[i] = k;
    }
    let mut in_log: Vec<Option<IntelRecord>> = in_log.into_iter().map(Some).collect();
    let records = by_time.iter().filter_map(|&i| in_log[i].take()).collect();
    Ok(IntelLog { records, log_order })
}

/// Each mode's pose at every record with `source` (one pose per record) as
/// the localization source, with the loops of each loop-closing mode checked
/// against `reference`, the corrected pose of each scan (exact: the drift is
/// added to them).
///
/// At a scan, the pose is the aiding loop's output (the optimized one for a
/// loop-closing mode). Between scans, the records are placed along the log's
/// own order, not their stamps: in `intel.gfs.log` the odometry lines before
/// a scan are stamped up to a second after it, and are raw odometry composed
/// on the previous scan's corrected pose. An online mode composes the
/// source's motion since the log's last scan onto that scan's pose. A
/// loop-closing mode's trajectory is optimized after the run, so between two
/// scans it also knows the next: each record is blended, by its place among
/// the records between the scans, from the motion since the last scan and the
/// motion to the last odometry record before the next scan, which stands for
/// the odometry at that scan.
fn intel_run(
    IntelLog { records, log_order }: &IntelLog,
    source: &[Pose2],
    reference: &[Option<Pose2>],
    config: &NamedConfig,
) -> Result<(Vec<Vec<Pose2>>, Vec<LoopRow>)> {
    let mut loops = runners(config)?;
    // Every scan stepped in time order; each mode's pose at each scan record.
    let mut at_scan: Vec<Vec<Option<Pose2>>> = vec![vec![None; records.len()]; loops.len()];
    let mut scan_records = Vec::new();
    for (i, (record, source)) in records.iter().zip(source).enumerate() {
        if let (Some(lines), Some(scan)) = (&record.lines, &record.scan) {
            for (runner, poses) in loops.iter_mut().zip(&mut at_scan) {
                poses[i] = Some(runner.step_scan(scan, source, lines).0);
            }
            scan_records.push(i);
        }
    }
    let mut optimized = vec![false; loops.len()];
    for ((runner, poses), optimized) in loops.iter_mut().zip(&mut at_scan).zip(&mut optimized) {
        if let Some(final_poses) = runner.finish() {
            *optimized = true;
            for (&i, pose) in scan_records.iter().zip(final_poses) {
                if let Some(p) = pose {
                    poses[i] = Some(p);
                }
            }
        }
    }
    let out = at_scan
        .iter()
        .zip(optimized)
        .map(|(at_scan, optimized)| {
            place_between_scans(records, log_order, source, at_scan, optimized)
        })
        .collect();
    Ok((out, check_loops(config, &loops, LoopReference { strict: reference, loose: reference })))
}

/// A pose at every record from the poses at the scans (`at_scan`, one entry
/// per record, `None` off the scans); `log_order` gives the records' indices
/// in the log's own order.
///
/// The records before the first scan keep `source`. The others are placed
/// along the log's own order, not their stamps: in `intel.gfs.log` the
/// odometry lines before a scan are stamped up to a second after it, and are
/// raw odometry composed on the previous scan's corrected pose. Each record
/// takes the source's motion since the log's last scan, composed onto that
/// scan's pose. With `smooth` (a trajectory optimized after the run, which
/// knows the next scan too), the records between two scans are also placed
/// back from the next scan, by the source's motion to the last record before
/// it (which stands for the odometry at that scan), and the two placements
/// are blended by the record's place among them.
fn place_between_scans(
    records: &[IntelRecord],
    log_order: &[usize],
    source: &[Pose2],
    at_scan: &[Option<Pose2>],
    smooth: bool,
) -> Vec<Pose2> {
    let mut out = source.to_vec();
    let mut last_scan: Option<(usize, Pose2)> = None;
    let mut between: Vec<usize> = Vec::new();
    // The records in the log's order, one run between scans at a time (the
    // end of the log closes the last run).
    for i in log_order.iter().copied().map(Some).chain([None]) {
        let next_scan = match i {
            Some(i) if records[i].lines.is_none() => {
                between.push(i);
                continue;
            }
            Some(i) => Some((i, at_scan[i].unwrap_or(source[i]))),
            None => None,
        };
        if let Some((k, at_k)) = last_scan {
            let next = next_scan
                .filter(|_| smooth)
                .and_then(|(_, at_next)| Some((at_next, source[*between.last()?])));
            for (j, &r) in between.iter().enumerate() {
                let forward = at_k.compose(&source[k].between(&source[r]));
                out[r] = match next {
                    Some((at_next, source_end)) => {
                        let backward = at_next.compose(&source_end.between(&source[r]));
                        forward.lerp(&backward, (j + 1) as f64 / between.len() as f64)
                    }
                    None => forward,
                };
            }
        }
        if let Some((n, at_n)) = next_scan {
            out[n] = at_n;
            last_scan = Some((n, at_n));
        }
        between.clear();
    }
    out
}

/// The relation metric of poses at the Intel records' times.
fn intel_score(
    records: &[IntelRecord],
    relations: &[Relation],
    poses: &[Pose2],
) -> Result<RelationRow> {
    let stamped =
        StampedTrajectory::new(records.iter().zip(poses).map(|(r, p)| (r.time_s, *p)).collect());
    Ok(relation_errors(&stamped, relations, INTEL_TOLERANCE_S)
        .context("no relation of intel.relations meets a pose of intel.gfs.log")?
        .into())
}

/// The heading-rate biases of the drift grid, degrees per second.
pub const DRIFT_GRID_BIAS_DEG_S: [f64; 3] = [0.1, 0.3, 1.0];
/// The seeds of the drift grid; odd seeds get a 3% speed scale error, even
/// seeds 2%.
pub const DRIFT_GRID_SEEDS: [u64; 4] = [1, 2, 3, 4];

/// The drift grid's model: [`INTEL_DRIFT`]'s random walks with the given
/// heading-rate bias and speed scale error.
fn drift_model(bias_deg_s: f64, seed: u64) -> OdometryModel {
    OdometryModel {
        heading_rate_bias_rad_s: bias_deg_s.to_radians(),
        speed_scale_error: if seed % 2 == 1 { 0.03 } else { 0.02 },
        ..INTEL_DRIFT
    }
}

/// Intel: the relation metric of the log's own poses, how far each mode
/// moves them when they are the source, the seeded drift [`INTEL_DRIFT`],
/// and the drift grid.
fn intel(data: &Path, seed: u64, config: &NamedConfig, grid: bool) -> Result<IntelResult> {
    let relations = read_relations(&data.join("intel").join("intel.relations"))?;
    let log = intel_records(data, config)?;
    let records = &log.records;
    let corrected: Vec<Pose2> = records.iter().map(|r| r.pose).collect();
    let times: Vec<f64> = records.iter().map(|r| r.time_s).collect();
    let row = |name: String, relations: RelationRow| TrajectoryRow {
        name,
        heading_rms_deg: None,
        heading_max_deg: None,
        position_rms_m: None,
        position_final_m: None,
        rigid_heading_rms_deg: None,
        rigid_position_rms_m: None,
        relations,
    };
    // The log's own poses between scans as a loop-closing mode places its
    // own: the reference for the optimized trajectories.
    let own_at_scans: Vec<Option<Pose2>> =
        records.iter().map(|r| r.lines.as_ref().map(|_| r.pose)).collect();
    let own_smoothed =
        place_between_scans(records, &log.log_order, &corrected, &own_at_scans, true);
    let mut rows = vec![
        row("log's own (GMapping) poses".into(), intel_score(records, &relations, &corrected)?),
        row(
            "log's own poses, blended between scans".into(),
            intel_score(records, &relations, &own_smoothed)?,
        ),
    ];
    let drifted = INTEL_DRIFT.corrupt_stamped(&corrected, &times, seed);
    let grid_cells: Vec<(f64, u64)> = if grid {
        DRIFT_GRID_BIAS_DEG_S
            .iter()
            .flat_map(|&b| DRIFT_GRID_SEEDS.iter().map(move |&s| (b, s)))
            .collect()
    } else {
        Vec::new()
    };
    let grid_sources: Vec<(OdometryModel, Vec<Pose2>)> = grid_cells
        .iter()
        .map(|&(bias, s)| {
            let model = drift_model(bias, s);
            let source = model.corrupt_stamped(&corrected, &times, s);
            (model, source)
        })
        .collect();
    let at_scan_reference: Vec<Option<Pose2>> =
        at_scans(records, &corrected).into_iter().map(Some).collect();
    // Every run on the thread pool at once, gathered in order: the log's own
    // poses, the seeded drift, then the grid's cells.
    let sources: Vec<&[Pose2]> = [&corrected[..], &drifted[..]]
        .into_iter()
        .chain(grid_sources.iter().map(|(_, source)| &source[..]))
        .collect();
    let mut runs = sources
        .par_iter()
        .map(|source| intel_run(&log, source, &at_scan_reference, config))
        .collect::<Result<Vec<_>>>()?
        .into_iter();
    let (Some((own_runs, own_loops)), Some((drift_runs, drift_loops))) = (runs.next(), runs.next())
    else {
        anyhow::bail!("the Intel runs are missing");
    };
    let mut loop_rows = Vec::new();
    for (prefix, rows) in [("own poses", own_loops), ("drifted", drift_loops)] {
        loop_rows.extend(rows.into_iter().map(|mut r| {
            r.name = format!("{prefix}, {}", r.name);
            r
        }));
    }
    let mut moved = Vec::new();
    for ((name, _, _), poses) in modes(config).iter().zip(own_runs) {
        // At the scans, as `pcaline map` writes them: between scans the log
        // has raw odometry hung on the last scan, not GMapping's estimates.
        let e = trajectory_errors(&at_scans(records, &poses), &at_scans(records, &corrected))
            .context("no poses")?;
        moved.push(MovedRow {
            log: "intel.gfs.log".into(),
            mode: name.to_string(),
            heading_rms_deg: e.heading_rms_rad.to_degrees(),
            heading_max_deg: e.heading_max_rad.to_degrees(),
            position_rms_m: e.position_rms_m,
            relations: Some(intel_score(records, &relations, &poses)?),
        });
    }
    for ((name, _, _), poses) in modes(config).iter().zip(drift_runs) {
        rows.push(row(format!("drifted, {name}"), intel_score(records, &relations, &poses)?));
    }
    let runs: Vec<Vec<Vec<Pose2>>> = runs.map(|(poses, _)| poses).collect();
    let cells = grid_cells
        .par_iter()
        .zip(&grid_sources)
        .zip(&runs)
        .map(|((&(bias, s), (model, _)), cell_runs)| {
            modes(config)
                .iter()
                .zip(cell_runs)
                .map(|((name, _, _), poses)| {
                    // At the scans, aligned at the first scan: the drift
                    // before it is no aiding's to undo.
                    let e = aligned_trajectory_errors(
                        &at_scans(records, poses),
                        &at_scans(records, &corrected),
                    )
                    .context("no scans")?;
                    Ok(DriftCell {
                        heading_rate_bias_deg_s: bias,
                        speed_scale_error: model.speed_scale_error,
                        seed: s,
                        mode: name.to_string(),
                        heading_rms_deg: e.heading_rms_rad.to_degrees(),
                        position_rms_m: e.position_rms_m,
                        relations: intel_score(records, &relations, poses)?,
                    })
                })
                .collect::<Result<Vec<_>>>()
        })
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect();
    Ok(IntelResult { rows, moved, cells, loops: loop_rows })
}

/// What [`intel`] measures.
struct IntelResult {
    /// The relation metric of the own, drifted and aided poses.
    rows: Vec<TrajectoryRow>,
    /// How far each mode moves the log's own poses.
    moved: Vec<MovedRow>,
    /// The drift grid.
    cells: Vec<DriftCell>,
    /// The loops of the own-pose and drifted runs against the corrected
    /// poses.
    loops: Vec<LoopRow>,
}

/// The poses at the records that are scans.
fn at_scans(records: &[IntelRecord], poses: &[Pose2]) -> Vec<Pose2> {
    records.iter().zip(poses).filter(|(r, _)| r.lines.is_some()).map(|(_, p)| *p).collect()
}

/// MIT CSAIL's corrected log with its own poses as the source: how far each
/// mode moves them.
fn csail_own(data: &Path, config: &NamedConfig) -> Result<Vec<MovedRow>> {
    let log = data.join("mit-csail").join("csail.corrected.log");
    let mut loops = Loops::new(config)?;
    let mut source = Vec::new();
    let mut poses: Vec<Vec<Pose2>> = vec![Vec::new(); modes(config).len()];
    for record in CarmenReader::open(&log, CarmenOptions::default())? {
        let LogRecord::Scan(s) = record? else { continue };
        let pose = s.pose.context("a FLASER line without a pose")?;
        source.push(pose);
        for (out, p) in poses.iter_mut().zip(loops.step(&s.scan, &pose)) {
            out.push(p);
        }
    }
    loops.finish(&mut poses);
    modes(config)
        .iter()
        .zip(&poses)
        .map(|((name, _, _), p)| {
            let e = trajectory_errors(p, &source).context("no scans in csail.corrected.log")?;
            Ok(MovedRow {
                log: "csail.corrected.log".into(),
                mode: name.to_string(),
                heading_rms_deg: e.heading_rms_rad.to_degrees(),
                heading_max_deg: e.heading_max_rad.to_degrees(),
                position_rms_m: e.position_rms_m,
                relations: None,
            })
        })
        .collect()
}

/// Per-line residual std of the detector `config` on a real log without
/// odometry, and the sharpness of its LIDAR-only trajectory.
pub fn utm_residuals(log: &Path, config: &NamedConfig) -> Result<ResidualReport> {
    let mut detector = LineDetector::new(config.detector)?;
    let (mut residuals, mut points) = (Vec::new(), Vec::new());
    let estimator = config.aiding_in(AidingMode::Estimator);
    let lidar_only = || Localizer::new(estimator, config.map, None);
    let (mut deskewed, mut skewed) = (lidar_only()?, lidar_only()?);
    let mut cells = [0.05; 3].map(pcaline_eval::OccupiedCells::new);
    let mut first: Option<Pose2> = None;
    let scans = read_log(log, &LogOptions::default(), |record| {
        if let LogRecord::Scan(s) = record {
            let detection = detector.detect(&s.scan);
            for l in detection.lines {
                residuals.push(l.line.residual_std());
                points.push(l.line.n_points());
            }
            let plain: Vec<SensorLine> = detection.lines.iter().map(SensorLine::from).collect();
            let (skew_pose, _) = skewed.step_scan_without_source(&s.scan, &plain);
            let velocity = deskewed.velocity();
            let lines: Vec<SensorLine> = detector
                .detect_moving(&s.scan, velocity.as_ref())
                .lines
                .iter()
                .map(SensorLine::from)
                .collect();
            let (pose, _) = deskewed.step_scan_without_source(&s.scan, &lines);
            cells[0].add(&s.scan, &pose);
            cells[1].add(&s.scan, first.get_or_insert(pose));
            cells[2].add(&s.scan, &skew_pose);
        }
        ControlFlow::Continue(())
    })?;
    residuals.sort_by(f64::total_cmp);
    points.sort_unstable();
    let pick = |q: f64| residuals.get(((residuals.len() as f64 - 1.0) * q) as usize).copied();
    Ok(ResidualReport {
        log: log.display().to_string(),
        scans,
        lines: residuals.len(),
        median_points: points.get(points.len() / 2).copied().unwrap_or(0),
        residual_std_p10_p50_p90_m: [0.1, 0.5, 0.9].map(|q| pick(q).unwrap_or(f64::NAN)),
        fraction_under_2cm: residuals.iter().filter(|r| **r < 0.02).count() as f64
            / residuals.len().max(1) as f64,
        occupied_cells_lidar_only: cells[0].count(),
        occupied_cells_not_moving: cells[1].count(),
        occupied_cells_lidar_only_without_deskew: cells[2].count(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(time_s: f64, pose: Pose2, scan: bool) -> IntelRecord {
        IntelRecord { time_s, pose, lines: scan.then(Vec::new), scan: None }
    }

    fn close(a: &Pose2, b: &Pose2) -> bool {
        (a.x() - b.x()).abs() < 1e-9
            && (a.y() - b.y()).abs() < 1e-9
            && wrap_angle(a.heading() - b.heading()).abs() < 1e-9
    }

    /// A scan, two odometry records 1 m apart, a scan, in time order; the
    /// poses of the two scans. The second odometry record is stamped after
    /// the last scan (as in `intel.gfs.log`), so in time order it comes last;
    /// it still belongs between the scans.
    struct Run {
        log: IntelLog,
        source: Vec<Pose2>,
        at_scan: [Option<Pose2>; 4],
    }

    fn run() -> Run {
        let source = vec![
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(1.0, 0.0, 0.0),
            Pose2::new(3.0, 0.0, 0.0),
            Pose2::new(2.0, 0.0, 0.0),
        ];
        let records = vec![
            record(0.0, source[0], true),
            record(1.0, source[1], false),
            record(2.0, source[2], true),
            record(2.5, source[3], false),
        ];
        Run {
            log: IntelLog { records, log_order: vec![0, 1, 3, 2] },
            source,
            at_scan: [Some(Pose2::new(0.0, 1.0, 0.0)), None, Some(Pose2::new(3.0, 2.0, 0.0)), None],
        }
    }

    /// A loop the strict reference cannot check (its keyframes far from a
    /// corrected scan) but the loose one can still counts as false.
    #[test]
    fn false_loops_are_counted_against_the_loose_reference() {
        let mut strict = LoopCheck::default();
        strict.standing = 1;
        strict.unchecked = 1;
        strict.standing_errors = vec![(0.05, 0.3)];
        let mut loose = strict.clone();
        loose.standing = 2;
        loose.unchecked = 0;
        loose.standing_errors = vec![(0.05, 0.3), (34.0, 62.0)];
        let row = LoopRow::new("loops", &strict, &loose);
        assert_eq!((row.standing, row.unchecked), (1, 1));
        assert_eq!(row.standing_error_m, [0.05, 0.05]);
        assert_eq!((row.standing_false, row.standing_worst_m), (1, 34.0));
        let right = LoopRow::new("loops", &strict, &strict);
        assert_eq!((right.standing_false, right.standing_worst_m), (0, 0.05));
    }

    #[test]
    fn an_online_trajectory_composes_the_odometry_since_the_scan_before_in_the_log() {
        let Run { log, source, at_scan } = run();
        let out = place_between_scans(&log.records, &log.log_order, &source, &at_scan, false);
        assert!(close(&out[0], &Pose2::new(0.0, 1.0, 0.0)));
        assert!(close(&out[1], &Pose2::new(1.0, 1.0, 0.0)));
        assert!(close(&out[2], &Pose2::new(3.0, 2.0, 0.0)));
        // From the first scan, not from the second (which is earlier in time).
        assert!(close(&out[3], &Pose2::new(2.0, 1.0, 0.0)), "{:?}", out[3]);
    }

    #[test]
    fn the_reference_jitter_is_taken_on_straight_stretches_only() {
        // Raw odometry straight along x, then a 10° turn a step; the
        // reference adds +1° and -1° on alternate scans.
        let raw: Vec<Pose2> = (0..12usize)
            .map(|k| {
                let turn = k.saturating_sub(6) as f64 * 10f64.to_radians();
                Pose2::new(k as f64 * 0.2, 0.0, turn)
            })
            .collect();
        let pairs: Vec<pcaline_io::ScanPair> = (0..12)
            .step_by(2)
            .map(|k| {
                let jitter = if k % 4 == 0 { 1f64 } else { -1f64 }.to_radians();
                let r = raw[k];
                pcaline_io::ScanPair {
                    corrected_index: k / 2,
                    raw_index: k,
                    raw_pose: r,
                    corrected_pose: Pose2::new(r.x(), r.y(), r.heading() + jitter),
                }
            })
            .collect();
        let j = reference_jitter(&pairs, &raw).unwrap();
        // 0-2, 2-4 and 4-6 are straight; 6-8 and on turn.
        assert_eq!(j.stretches, 3);
        assert!((j.heading_rms_deg - 2.0).abs() < 1e-9, "{j:?}");
        assert!(reference_jitter(&pairs[3..], &raw).is_none());
    }

    #[test]
    fn an_optimized_trajectory_blends_toward_the_next_scan() {
        let Run { log, source, at_scan } = run();
        let out = place_between_scans(&log.records, &log.log_order, &source, &at_scan, true);
        // The last record before the next scan stands for the odometry at
        // it: it takes the scan's pose. The one before is half way between
        // the forward placement (1, 1) and the backward one (2, 2): the
        // scan's pose less the source's 1 m from this record to the last.
        assert!(close(&out[3], &Pose2::new(3.0, 2.0, 0.0)), "{:?}", out[3]);
        assert!(close(&out[1], &Pose2::new(1.5, 1.5, 0.0)), "{:?}", out[1]);
        // Before the first scan and without scans, the source stays.
        let none = [None; 4];
        let records: Vec<IntelRecord> =
            (0..4).map(|i| record(i as f64, source[i], false)).collect();
        assert_eq!(place_between_scans(&records, &[0, 1, 2, 3], &source, &none, true), source);
    }
}
