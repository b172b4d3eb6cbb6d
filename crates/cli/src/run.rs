//! `pcaline run`: the main job on a simulated scene: simulate every scan,
//! detect lines, and report and draw what was found.

use crate::exit::BadInput;
use crate::progress;
use crate::scene_cmd::draw_scene;
use anyhow::{Context, Result};
use pcaline::{Config, LineDetector, LineSegment, Pose2};
use pcaline_io::{parse_scene, read_scene, write_atomic};
use pcaline_sim::{Scene, Simulator};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The default scene, embedded so `pcaline run` works from anywhere.
const DEFAULT_SCENE: &str = include_str!("../../../sim-scenes/paper-maze.toml");
const DEFAULT_SCENE_NAME: &str = "sim-scenes/paper-maze.toml";

/// Arguments of `pcaline run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Scene file (TOML or JSON); the embedded paper-like maze when absent.
    scene: Option<PathBuf>,
    /// Random seed of the simulation.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Detector preset.
    #[arg(long, value_enum, default_value_t = Preset::Default)]
    config: Preset,
    /// Output folder for pictures and JSON.
    #[arg(long, default_value = "out/run")]
    out: PathBuf,
    /// Print the summary as JSON on stdout instead of a table.
    #[arg(long)]
    json: bool,
}

/// Detector presets.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum Preset {
    /// `Config::default()`: noise-aware.
    Default,
    /// `Config::paper()`: exactly the paper's values.
    Paper,
}

impl Preset {
    /// The configuration of the preset.
    pub fn config(self) -> Config {
        match self {
            Preset::Default => Config::default(),
            Preset::Paper => Config::paper(),
        }
    }
}

#[derive(Debug, Serialize)]
struct Summary {
    scene: String,
    seed: u64,
    preset: String,
    scans: usize,
    duration_s: f64,
    lines_per_scan_mean: f64,
    lines_per_scan_min: usize,
    lines_per_scan_max: usize,
    median_residual_std_m: f64,
    detection_time_per_scan_us: f64,
    outputs: Vec<String>,
}

#[derive(Debug, Serialize)]
struct ScanLines {
    index: usize,
    time_s: f64,
    true_pose: [f64; 3],
    odometry_pose: [f64; 3],
    /// Lines in the sensor frame: alpha (rad), d (m), start, end, points, residual std (m).
    lines: Vec<LineOut>,
}

#[derive(Debug, Serialize)]
struct LineOut {
    alpha: f64,
    d: f64,
    start: [f64; 2],
    end: [f64; 2],
    n_points: usize,
    residual_std_m: f64,
}

fn pose_array(p: &Pose2) -> [f64; 3] {
    [p.x, p.y, p.heading]
}

fn line_out(l: &LineSegment) -> LineOut {
    LineOut {
        alpha: l.alpha,
        d: l.d,
        start: [l.start.x, l.start.y],
        end: [l.end.x, l.end.y],
        n_points: l.n_points,
        residual_std_m: l.residual_std,
    }
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
    let mut detector = LineDetector::new(args.preset_config())?;

    let bar = progress::bar(sim.len() as u64, "scans", quiet);
    let mut per_scan = Vec::with_capacity(sim.len());
    let mut residuals = Vec::new();
    let mut detect_time = 0.0;
    let mut drawn: Vec<LineSegment> = Vec::new();
    for frame in sim.frames() {
        let t0 = Instant::now();
        let detection = detector.detect(&frame.scan);
        detect_time += t0.elapsed().as_secs_f64();
        let lines: Vec<LineSegment> = detection.lines.iter().map(|l| l.line).collect();
        residuals.extend(lines.iter().map(|l| l.residual_std));
        if frame.index % 20 == 0 {
            drawn.extend(lines.iter().map(|l| l.transformed(&frame.true_pose)));
        }
        per_scan.push(ScanLines {
            index: frame.index,
            time_s: frame.time_s,
            true_pose: pose_array(&frame.true_pose),
            odometry_pose: pose_array(&frame.odometry_pose),
            lines: lines.iter().map(line_out).collect(),
        });
        bar.inc(1);
    }
    bar.finish_and_clear();

    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating output folder {}", args.out.display()))?;
    let lines_path = args.out.join("lines.json");
    let json = serde_json::to_vec(&per_scan)?;
    write_atomic(&lines_path, &json)?;

    let mut plot = draw_scene(&scene, None);
    for l in &drawn {
        plot.line([l.start.x, l.start.y], [l.end.x, l.end.y], "#d62728", 2.0);
    }
    let truth: Vec<[f64; 2]> = sim.true_poses().iter().map(|p| [p.x, p.y]).collect();
    plot.polyline(&truth, "#2ca02c", 1.0, false);
    plot.legend("detected lines (every 20th scan)", "#d62728", false);
    plot.legend("true trajectory", "#2ca02c", false);
    let svg_path = args.out.join("detections.svg");
    let title = format!("{}: lines detected along the trajectory", scene.name);
    write_atomic(&svg_path, plot.finish(&title).as_bytes())?;

    let counts: Vec<usize> = per_scan.iter().map(|s| s.lines.len()).collect();
    residuals.sort_by(f64::total_cmp);
    let summary = Summary {
        scene: scene_name,
        seed: args.seed,
        preset: format!("{:?}", args.config).to_lowercase(),
        scans: counts.len(),
        duration_s: sim.len() as f64 / sim.sensor().rate_hz,
        lines_per_scan_mean: counts.iter().sum::<usize>() as f64 / counts.len().max(1) as f64,
        lines_per_scan_min: counts.iter().copied().min().unwrap_or(0),
        lines_per_scan_max: counts.iter().copied().max().unwrap_or(0),
        median_residual_std_m: residuals.get(residuals.len() / 2).copied().unwrap_or(f64::NAN),
        detection_time_per_scan_us: 1e6 * detect_time / counts.len().max(1) as f64,
        outputs: vec![lines_path.display().to_string(), svg_path.display().to_string()],
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        print_summary(&summary);
    }
    Ok(())
}

impl RunArgs {
    fn preset_config(&self) -> Config {
        self.config.config()
    }
}

fn print_summary(s: &Summary) {
    println!("scene                 {}", s.scene);
    println!("seed / preset         {} / {}", s.seed, s.preset);
    println!("scans                 {} ({:.1} s)", s.scans, s.duration_s);
    println!(
        "lines per scan        mean {:.1}, min {}, max {}",
        s.lines_per_scan_mean, s.lines_per_scan_min, s.lines_per_scan_max
    );
    println!("median residual std   {:.1} mm", 1e3 * s.median_residual_std_m);
    println!("detection time        {:.1} us per scan", s.detection_time_per_scan_us);
    for o in &s.outputs {
        println!("wrote                 {o}");
    }
}
