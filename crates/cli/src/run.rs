//! `pcaline run`: the main job on a simulated scene. Every scan is simulated
//! and its lines detected once; three mapping loops then run side by side:
//! without aiding, with heading aiding (the paper's section 2.1) and with
//! the estimator (odometry and line matches fused by their uncertainty). The summary compares their errors against the truth;
//! pictures and JSON go to the output folder.

use crate::exit::BadInput;
use crate::mcap_out::McapOut;
use crate::out::outln;
use crate::picture::add_svg_and_png;
use crate::progress;
use crate::scene_cmd::draw_scene;
use crate::svg::{Mark, Plot};
use anyhow::{Context, Result};
use pcaline::aiding::{Aiding, AidingConfig, AidingMode, SensorLine};
use pcaline::{LineDetector, LineSegment, Pose2};
use pcaline_eval::{AidedRun, AidedScore, ObservedRunError, RunStep};
use pcaline_io::{
    LineRecord, OutputSet, PoseKind, json_bytes, map_csv_text, map_json_bytes, parse_scene,
    read_scene,
};
use pcaline_sim::{Scene, Simulator};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The default scene, embedded so `pcaline run` works from anywhere.
const DEFAULT_SCENE: &str = include_str!("../scenes/paper-maze.toml");
const DEFAULT_SCENE_NAME: &str = "sim-scenes/paper-maze.toml";

/// Arguments of `pcaline run`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  pcaline run                                     the embedded maze, pictures in out/run
  pcaline run sim-scenes/hall-pillars.toml --seed 3 --out out/hall --png
  pcaline run my-maze.toml --config paper --json  the paper's detector and aiding
  pcaline run --mcap out/run.mcap                 every scan, map and pose for Foxglove")]
pub struct RunArgs {
    /// Scene file (TOML or JSON); the embedded paper-like maze when absent.
    scene: Option<PathBuf>,
    /// Random seed of the simulation.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Detector and map: a preset (default, paper, split-and-merge,
    /// told-sigma, datasheet, adaptive) or a configuration file (see `pcaline eval
    /// --show-config`); the paper preset also brings the paper's heading aiding.
    #[arg(long, default_value = "default")]
    config: String,
    /// Output folder for pictures and JSON.
    #[arg(long, default_value = "out/run")]
    out: PathBuf,
    /// Print the summary as JSON on stdout instead of a table.
    #[arg(long)]
    json: bool,
    /// Also write each picture as PNG.
    #[arg(long)]
    png: bool,
    /// Also write the run scan by scan to this MCAP file, for Foxglove:
    /// scans, lines, the map as it grows, odometry, corrected and true
    /// poses, and the true walls (topics in the README).
    #[arg(long, value_name = "OUT.mcap")]
    mcap: Option<PathBuf>,
}

/// The loops compared, in the order of `AidedRun`'s loops and estimates:
/// three aiding modes, then the estimator with loop closure.
#[derive(Debug, Clone, Copy)]
enum Loop {
    Unaided,
    Heading,
    Estimator,
    EstimatorWithLoops,
}

impl Loop {
    const ALL: [Loop; 4] =
        [Loop::Unaided, Loop::Heading, Loop::Estimator, Loop::EstimatorWithLoops];

    /// The label of the summary's rows.
    fn label(self) -> &'static str {
        match self {
            Loop::Unaided => "unaided",
            Loop::Heading => "heading",
            Loop::Estimator => "estimator",
            Loop::EstimatorWithLoops => "estimator + loops",
        }
    }

    /// Its index in `AidedRun::loops` (the aiding modes) and
    /// `AidedRun::estimates` (all four).
    fn index(self) -> usize {
        self as usize
    }
}

#[derive(Debug, Serialize)]
struct ModeSummary {
    mode: &'static str,
    heading_rms_deg: f64,
    heading_max_deg: f64,
    position_rms_m: f64,
    position_final_m: f64,
    map_lines: usize,
    map_worst_line_m: f64,
    map_lines_off_wall: usize,
    map_covered_fraction: f64,
}

#[derive(Debug, Serialize)]
struct Summary {
    scene: String,
    seed: u64,
    preset: String,
    scans: usize,
    duration_s: f64,
    lines_per_scan_mean: f64,
    median_residual_std_m: f64,
    detection_time_per_scan_us: f64,
    modes: Vec<ModeSummary>,
    outputs: Vec<String>,
}

#[derive(Debug, Serialize)]
struct ScanRecord {
    index: usize,
    time_s: f64,
    true_pose: [f64; 3],
    odometry_pose: [f64; 3],
    heading_aided_pose: [f64; 3],
    estimator_pose: [f64; 3],
    /// The estimator with loop closure, after the last optimization.
    loop_closure_pose: [f64; 3],
    /// Lines in the sensor frame (the schema of `pcaline detect`).
    lines: Vec<LineRecord>,
}

/// The true trajectory: thick and light, drawn under the estimates.
const TRUTH_COLOUR: &str = "#a6dba0";
const TRUTH_WIDTH: f64 = 6.0;

fn pose_array(p: &Pose2) -> [f64; 3] {
    [p.x(), p.y(), p.heading()]
}

fn load(scene: &Option<PathBuf>) -> Result<(Scene, String)> {
    match scene {
        Some(path) => Ok((read_scene(path)?, path.display().to_string())),
        None => {
            let path = Path::new(DEFAULT_SCENE_NAME);
            let scene = parse_scene(path, DEFAULT_SCENE)?;
            scene.validate().map_err(|e| BadInput(format!("{DEFAULT_SCENE_NAME}: {e}")))?;
            Ok((scene, format!("{DEFAULT_SCENE_NAME} (embedded)")))
        }
    }
}

/// Runs `pcaline run`.
pub fn run(args: &RunArgs, quiet: bool) -> Result<()> {
    let (scene, scene_name) = load(&args.scene)?;
    let sim =
        Simulator::new(&scene, args.seed).map_err(|e| BadInput(format!("{scene_name}: {e}")))?;
    let config = crate::config_file::resolve(&args.config, 0.01)?;
    let mut detector = LineDetector::new(config.detector)?;
    // In the order of `Loop`: the three aiding modes; loop closure comes last.
    let aiding_configs = [Loop::Unaided, Loop::Heading, Loop::Estimator].map(|l| match l {
        Loop::Unaided => AidingConfig::none(),
        Loop::Heading => config.heading_aiding(),
        _ => config.aiding_in(AidingMode::Estimator),
    });

    let bar = progress::bar(sim.len() as u64, "scans", quiet);
    let mut records = Vec::with_capacity(sim.len());
    let mut residuals = Vec::new();
    let mut line_count = 0usize;
    let mut detect_time = 0.0;
    let mut drawn: Vec<LineSegment> = Vec::new();
    let loop_closure = Some((config.aiding_in(AidingMode::Estimator), config.loop_closure));
    let mut mcap = McapOut::create(args.mcap.as_deref())?;
    if let Some(m) = mcap.as_mut() {
        let walls: Vec<[[f64; 2]; 2]> =
            sim.world().walls().iter().map(|w| [[w.a.x, w.a.y], [w.b.x, w.b.y]]).collect();
        m.walls(&walls)?;
    }
    let observe = |step: RunStep<'_>| -> Result<()> {
        let Some(m) = mcap.as_mut() else { return Ok(()) };
        let f = step.frame;
        let stamp = m.stamp(Some(f.time_s));
        let corrected = step.loop_closing().and_then(|l| l.pose());
        let poses = [
            (PoseKind::Source, Some(f.odometry_pose)),
            (PoseKind::Corrected, corrected),
            (PoseKind::Truth, Some(f.true_pose)),
        ];
        m.scan(stamp, &f.scan, step.lines.iter().map(|l| &l.line), &poses)?;
        match step.loop_closing() {
            Some(l) => m.map_if_due(stamp, l.map()),
            None => Ok(()),
        }
    };
    let run = AidedRun::run_observed(
        &sim,
        config.map,
        &aiding_configs,
        loop_closure,
        |frame, velocity| {
            let t0 = Instant::now();
            let detection = detector.detect_moving(&frame.scan, velocity.as_ref());
            detect_time += t0.elapsed().as_secs_f64();
            let sensor_lines: Vec<SensorLine> =
                detection.lines.iter().map(SensorLine::from).collect();
            line_count += sensor_lines.len();
            residuals.extend(sensor_lines.iter().map(|l| l.line.residual_std()));
            if frame.index % 20 == 0 {
                drawn.extend(sensor_lines.iter().map(|l| l.line.transformed(&frame.true_pose)));
            }
            records.push(ScanRecord {
                index: frame.index,
                time_s: frame.time_s,
                true_pose: pose_array(&frame.true_pose),
                odometry_pose: pose_array(&frame.odometry_pose),
                // Filled in from the loops' estimates once the run is over.
                heading_aided_pose: [f64::NAN; 3],
                estimator_pose: [f64::NAN; 3],
                loop_closure_pose: [f64::NAN; 3],
                lines: detection.lines.iter().map(crate::detect::line_record).collect(),
            });
            bar.inc(1);
            sensor_lines
        },
        observe,
    )
    .map_err(|e| match e {
        ObservedRunError::Config(c) => anyhow::Error::from(c),
        ObservedRunError::Stopped(e) => e,
        _ => anyhow::anyhow!("the run stopped"),
    })?;
    bar.finish_and_clear();
    let estimates = &run.estimates;
    for (k, record) in records.iter_mut().enumerate() {
        record.heading_aided_pose = pose_array(&estimates[Loop::Heading.index()][k]);
        record.estimator_pose = pose_array(&estimates[Loop::Estimator.index()][k]);
        record.loop_closure_pose = pose_array(&estimates[Loop::EstimatorWithLoops.index()][k]);
    }
    // The map of the default: the estimator with loop closure.
    let full =
        run.loop_closing().map_or(run.loops[Loop::Estimator.index()].aiding(), |l| l.aiding());

    let scores = run.scores(sim.true_poses()).context("the scene has no scans")?;
    let modes: Vec<ModeSummary> = Loop::ALL
        .iter()
        .zip(&scores)
        .map(|(mode, AidedScore { errors: e, map: q, .. })| ModeSummary {
            mode: mode.label(),
            heading_rms_deg: e.heading_rms_rad.to_degrees(),
            heading_max_deg: e.heading_max_rad.to_degrees(),
            position_rms_m: e.position_rms_m,
            position_final_m: e.position_final_m,
            map_lines: q.lines,
            map_worst_line_m: q.line_errors_m.iter().copied().fold(0.0, f64::max),
            map_lines_off_wall: q.spurious,
            map_covered_fraction: q.covered_fraction,
        })
        .collect();

    // An output folder that cannot be made (a file in its path, no
    // permission) is the user's argument: exit 2, naming the folder.
    std::fs::create_dir_all(&args.out)
        .map_err(|e| pcaline_io::IoError::io(&args.out, e))
        .context("creating the output folder")?;
    // Written as a set, as `map` writes its files: all or none.
    let mut set = OutputSet::new();
    let path = args.out.join("scans.json");
    set.add(&path, &json_bytes(&path, &records)?)?;
    let path = args.out.join("map.json");
    set.add(&path, &map_json_bytes(&path, full.map())?)?;
    set.add(&args.out.join("map.csv"), map_csv_text(full.map()).as_bytes())?;
    let pictures = [
        ("detections", draw_detections(&scene, &sim, &drawn)),
        ("map", draw_map(&scene, &sim, full, estimates)),
        ("heading", draw_heading(&sim, estimates)),
        ("heading-error", draw_heading_error(&sim, estimates)),
    ];
    for (name, svg) in &pictures {
        add_svg_and_png(&mut set, &args.out, name, svg, args.png)?;
    }
    let mut outputs: Vec<String> = set.commit()?.iter().map(|p| p.display().to_string()).collect();
    if let Some(mut m) = mcap {
        m.final_map(full.map())?;
        outputs.push(m.finish(true)?.display().to_string());
    }

    residuals.sort_by(f64::total_cmp);
    let scans = sim.len();
    let summary = Summary {
        scene: scene_name,
        seed: args.seed,
        preset: config.name.clone(),
        scans,
        duration_s: scans as f64 / sim.sensor().rate_hz,
        lines_per_scan_mean: line_count as f64 / scans.max(1) as f64,
        median_residual_std_m: residuals.get(residuals.len() / 2).copied().unwrap_or(f64::NAN),
        detection_time_per_scan_us: 1e6 * detect_time / scans.max(1) as f64,
        modes,
        outputs,
    };
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&summary)?)?;
    } else {
        print_summary(&summary)?;
    }
    Ok(())
}

fn draw_detections(scene: &Scene, sim: &Simulator, drawn: &[LineSegment]) -> String {
    let mut plot = draw_scene(scene, None);
    for l in drawn {
        plot.line([l.start().x, l.start().y], [l.end().x, l.end().y], "#d62728", 2.0);
    }
    let truth: Vec<[f64; 2]> = sim.true_poses().iter().map(|p| [p.x(), p.y()]).collect();
    plot.polyline(&truth, "#2ca02c", 1.0, false);
    plot.legend("detected lines, every 20th scan", "#d62728", Mark::Line(2.0));
    plot.legend("true trajectory", "#2ca02c", Mark::Line(1.0));
    plot.finish(&format!("{}: lines detected along the trajectory", scene.name))
}

/// The paper's Figure 10: the line map over the true walls, with trajectories.
fn draw_map(scene: &Scene, sim: &Simulator, full: &Aiding, est: &[Vec<Pose2>]) -> String {
    let (lo, hi) = scene.bounds();
    let mut plot = Plot::new([lo.x, lo.y], [hi.x, hi.y], 1000.0);
    for w in sim.world().walls() {
        plot.line([w.a.x, w.a.y], [w.b.x, w.b.y], "#bbbbbb", 5.0);
    }
    for m in full.map().lines() {
        let l = &m.line;
        plot.line([l.start().x, l.start().y], [l.end().x, l.end().y], "#d62728", 2.0);
    }
    let path = |poses: &[Pose2]| poses.iter().map(|p| [p.x(), p.y()]).collect::<Vec<_>>();
    // The truth thick and light underneath, so the aided line drawn thin on
    // top of it stays visible where the two agree.
    plot.polyline(&path(sim.true_poses()), TRUTH_COLOUR, TRUTH_WIDTH, false);
    plot.polyline(&path(sim.odometry_poses()), "#1f77b4", 1.5, true);
    plot.polyline(&path(&est[1]), "#ff7f0e", 1.5, false);
    plot.polyline(&path(&est[2]), "#9467bd", 1.6, false);
    plot.legend("true walls", "#bbbbbb", Mark::Line(5.0));
    plot.legend("line map (estimator)", "#d62728", Mark::Line(2.0));
    plot.legend("true trajectory", TRUTH_COLOUR, Mark::Line(TRUTH_WIDTH));
    plot.legend("odometry (unaided)", "#1f77b4", Mark::Dashed(1.5));
    plot.legend("heading-aided", "#ff7f0e", Mark::Line(1.5));
    plot.legend("estimator", "#9467bd", Mark::Line(1.6));
    plot.finish(&format!("{}: line map and trajectories", scene.name))
}

/// The paper's Figure 11: heading over time with and without aiding.
fn draw_heading(sim: &Simulator, est: &[Vec<Pose2>]) -> String {
    let dt = 1.0 / sim.sensor().rate_hz;
    // Unwrapped headings in degrees, so turns do not jump at ±180°.
    let series = |poses: &[Pose2]| {
        let mut out = Vec::with_capacity(poses.len());
        let mut acc = 0.0;
        let mut prev: Option<f64> = None;
        for (k, p) in poses.iter().enumerate() {
            acc += prev.map_or(p.heading(), |q| pcaline::geometry::wrap_angle(p.heading() - q));
            prev = Some(p.heading());
            out.push([k as f64 * dt, acc.to_degrees()]);
        }
        out
    };
    let all =
        [series(sim.true_poses()), series(sim.odometry_poses()), series(&est[1]), series(&est[2])];
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in all.iter().flatten() {
        lo = lo.min(p[1]);
        hi = hi.max(p[1]);
    }
    let t_end = sim.len() as f64 * dt;
    let mut plot = Plot::chart([0.0, lo], [t_end, hi], 1000.0, 420.0, ["time (s)", "heading (°)"]);
    let styles = [
        ("true", TRUTH_COLOUR, TRUTH_WIDTH, false),
        ("odometry (unaided)", "#1f77b4", 1.5, true),
        ("heading-aided", "#ff7f0e", 1.5, false),
        ("estimator", "#9467bd", 1.6, false),
    ];
    for (s, (name, color, width, dashed)) in all.iter().zip(styles) {
        plot.polyline(s, color, width, dashed);
        plot.legend(name, color, if dashed { Mark::Dashed(width) } else { Mark::Line(width) });
    }
    plot.finish("Heading over time, with and without aiding")
}

/// Heading error over time, with and without aiding.
fn draw_heading_error(sim: &Simulator, est: &[Vec<Pose2>]) -> String {
    let dt = 1.0 / sim.sensor().rate_hz;
    let truth = sim.true_poses();
    let error = |poses: &[Pose2]| -> Vec<[f64; 2]> {
        poses
            .iter()
            .zip(truth)
            .enumerate()
            .map(|(k, (p, t))| {
                [
                    k as f64 * dt,
                    pcaline::geometry::wrap_angle(p.heading() - t.heading()).to_degrees(),
                ]
            })
            .collect()
    };
    let all = [error(sim.odometry_poses()), error(&est[1]), error(&est[2])];
    let (mut lo, mut hi) = (-0.5f64, 0.5f64);
    for p in all.iter().flatten() {
        lo = lo.min(p[1]);
        hi = hi.max(p[1]);
    }
    let t_end = sim.len() as f64 * dt;
    let mut plot =
        Plot::chart([0.0, lo], [t_end, hi], 1000.0, 420.0, ["time (s)", "heading error (°)"]);
    let styles =
        [("odometry (unaided)", "#1f77b4"), ("heading-aided", "#ff7f0e"), ("estimator", "#9467bd")];
    for (s, (name, color)) in all.iter().zip(styles) {
        plot.polyline(s, color, 1.5, false);
        plot.legend(name, color, Mark::Line(1.5));
    }
    plot.finish("Heading error against the truth")
}

fn print_summary(s: &Summary) -> anyhow::Result<()> {
    outln!("scene                {}", s.scene)?;
    outln!("seed / preset        {} / {}", s.seed, s.preset)?;
    outln!("scans                {} ({:.1} s)", s.scans, s.duration_s)?;
    outln!(
        "lines per scan       {:.1} (median residual std {:.1} mm)",
        s.lines_per_scan_mean,
        1e3 * s.median_residual_std_m
    )?;
    outln!("detection time       {:.1} us per scan", s.detection_time_per_scan_us)?;
    outln!()?;
    outln!(
        "{:<17} {:>12} {:>12} {:>12} {:>12} {:>9} {:>11} {:>9} {:>9}",
        "aiding",
        "heading rms",
        "heading max",
        "pos rms",
        "pos final",
        "map lines",
        "worst line",
        "off wall",
        "covered"
    )?;
    for m in &s.modes {
        outln!(
            "{:<17} {:>10.3} ° {:>10.3} ° {:>10.3} m {:>10.3} m {:>9} {:>8.1} cm {:>9} {:>8.1}%",
            m.mode,
            m.heading_rms_deg,
            m.heading_max_deg,
            m.position_rms_m,
            m.position_final_m,
            m.map_lines,
            100.0 * m.map_worst_line_m,
            m.map_lines_off_wall,
            100.0 * m.map_covered_fraction
        )?;
    }
    outln!()?;
    for o in &s.outputs {
        outln!("wrote                {o}")?;
    }
    Ok(())
}
