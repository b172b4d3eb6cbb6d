//! `pcaline draw scan`: one scan with its level-1 and level-2 break-points,
//! clusters and fitted lines (the paper's Figures 1-3).

use crate::exit::BadInput;
use crate::log_args::LogArgs;
use crate::picture::{PictureFormat, write_picture};
use crate::svg::{Mark, Plot};
use anyhow::Result;
use clap::Subcommand;
use pcaline::LineDetector;
use pcaline_io::{LogRecord, read_log};
use std::ops::ControlFlow;
use std::path::PathBuf;

/// Pictures.
#[derive(Debug, Subcommand)]
pub enum DrawCommand {
    /// One scan of a log: points, level-1 and level-2 break-points, clusters
    /// and lines, in the sensor frame (the paper's Figures 1-3).
    #[command(after_help = "Examples:
  pcaline draw scan scans.db3 --index 40 -o scan.svg
  pcaline draw scan log.clf --fov 180 --config paper -o scan.png")]
    Scan(ScanArgs),
    /// A saved map (map.json of `run` or `map`) with the trajectories of a
    /// trajectory file (scans.json of `run`, trajectory.json of `map`): the
    /// paper's Figure 10.
    #[command(after_help = "Example:
  pcaline draw map out/map/map.json --trajectory out/map/trajectory.json -o map.png")]
    Map {
        /// The map (JSON).
        map: PathBuf,
        /// A trajectory file.
        #[arg(long)]
        trajectory: Option<PathBuf>,
        /// Output picture: `.svg`, or `.png` (other extensions are refused).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Headings over time from a trajectory file: the paper's Figure 11.
    #[command(after_help = "Example:
  pcaline draw heading out/run/scans.json -o heading.svg")]
    Heading {
        /// A trajectory file (scans.json of `run`, trajectory.json of `map`).
        trajectory: PathBuf,
        /// Output picture: `.svg`, or `.png` (other extensions are refused).
        #[arg(short, long)]
        output: PathBuf,
    },
}

const SERIES_COLOURS: [&str; 5] = ["#2ca02c", "#1f77b4", "#ff7f0e", "#9467bd", "#8c564b"];

fn draw_map(
    map: &std::path::Path,
    trajectory: Option<&std::path::Path>,
    output: &std::path::Path,
) -> Result<()> {
    let map = pcaline_io::read_map(map)?;
    let series = match trajectory {
        Some(t) => pcaline_io::read_pose_series(t)?,
        None => Vec::new(),
    };
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut grow = |p: [f64; 2]| {
        if p[0].is_finite() && p[1].is_finite() {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
    };
    for m in map.lines() {
        grow([m.line.start().x, m.line.start().y]);
        grow([m.line.end().x, m.line.end().y]);
    }
    for (_, s) in &series {
        s.iter().flatten().for_each(|p| grow([p.x(), p.y()]));
    }
    if !lo[0].is_finite() {
        return Err(BadInput("the map and trajectory are empty".into()).into());
    }
    let mut plot = Plot::new(lo, hi, 1000.0);
    for m in map.lines() {
        let l = &m.line;
        plot.line([l.start().x, l.start().y], [l.end().x, l.end().y], "#d62728", 2.0);
    }
    plot.legend(&format!("line map ({} lines)", map.len()), "#d62728", Mark::Line(2.0));
    for ((name, s), colour) in series.iter().zip(SERIES_COLOURS.iter().cycle()) {
        let pts: Vec<[f64; 2]> = s.iter().flatten().map(|p| [p.x(), p.y()]).collect();
        plot.polyline(&pts, colour, 1.5, false);
        plot.legend(name, colour, Mark::Line(1.5));
    }
    write_picture(output, &plot.finish("Line map and trajectories"))
}

fn draw_heading(trajectory: &std::path::Path, output: &std::path::Path) -> Result<()> {
    let series = pcaline_io::read_pose_series(trajectory)?;
    let n = series.iter().map(|(_, s)| s.len()).max().unwrap_or(0);
    // Unwrapped headings in degrees against the record index.
    let unwrapped: Vec<(String, Vec<[f64; 2]>)> = series
        .iter()
        .map(|(name, s)| {
            let mut out = Vec::new();
            let (mut acc, mut prev): (f64, Option<f64>) = (0.0, None);
            for (k, p) in s.iter().enumerate() {
                let Some(p) = p else { continue };
                acc += prev.map_or(p.heading(), |q| pcaline::geometry::wrap_angle(p.heading() - q));
                prev = Some(p.heading());
                out.push([k as f64, acc.to_degrees()]);
            }
            (name.clone(), out)
        })
        .collect();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in unwrapped.iter().flat_map(|(_, s)| s.iter()) {
        lo = lo.min(p[1]);
        hi = hi.max(p[1]);
    }
    if !lo.is_finite() {
        return Err(BadInput(format!("{}: no poses", trajectory.display())).into());
    }
    let mut plot =
        Plot::chart([0.0, lo], [n.max(1) as f64, hi], 1000.0, 420.0, ["scan", "heading (°)"]);
    for ((name, s), colour) in unwrapped.iter().zip(SERIES_COLOURS.iter().cycle()) {
        plot.polyline(s, colour, 1.5, false);
        plot.legend(name, colour, Mark::Line(1.5));
    }
    write_picture(output, &plot.finish("Heading over time"))
}

/// Arguments of `pcaline draw scan`.
#[derive(Debug, clap::Args)]
pub struct ScanArgs {
    /// Log or scan file.
    file: PathBuf,
    #[command(flatten)]
    log: LogArgs,
    /// Which scan, from 0.
    #[arg(long, default_value_t = 0)]
    index: usize,
    /// Detector: a preset or a configuration file (as `pcaline detect`).
    #[arg(long, default_value = "default")]
    config: String,
    /// Output picture: `.svg`, or `.png` (other extensions are refused).
    #[arg(short, long)]
    output: PathBuf,
}

/// The most beams `draw scan` draws (a 360° scan at 0.01° has 36,000): a
/// picture of more is unreadable, and its SVG would run to gigabytes.
const MAX_DRAWN_BEAMS: usize = 100_000;

const PALETTE: [&str; 6] = ["#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#17becf"];

/// Runs `pcaline draw`.
pub fn run(cmd: &DrawCommand, quiet: bool) -> Result<()> {
    // An unsupported picture format is refused before any reading.
    let (DrawCommand::Scan(ScanArgs { output, .. })
    | DrawCommand::Map { output, .. }
    | DrawCommand::Heading { output, .. }) = cmd;
    PictureFormat::of(output)?;
    let args = match cmd {
        DrawCommand::Scan(args) => args,
        DrawCommand::Map { map, trajectory, output } => {
            draw_map(map, trajectory.as_deref(), output)?;
            if !quiet {
                eprintln!("wrote {}", output.display());
            }
            return Ok(());
        }
        DrawCommand::Heading { trajectory, output } => {
            draw_heading(trajectory, output)?;
            if !quiet {
                eprintln!("wrote {}", output.display());
            }
            return Ok(());
        }
    };
    let mut found = None;
    let mut named_sensor = None;
    let mut k = 0;
    // The whole file is read, as `detect` reads it, so a file broken after
    // the scan drawn is refused too.
    read_log(&args.file, &args.log.options()?, |r| {
        if let LogRecord::Scan(s) = r {
            if k == args.index {
                named_sensor = s.sensor;
                found = Some(s.scan);
            }
            k += 1;
        }
        ControlFlow::Continue(())
    })?;
    let Some(scan) = found else {
        return Err(BadInput(format!(
            "{}: no scan {} (the file has {k})",
            args.file.display(),
            args.index
        ))
        .into());
    };
    if scan.ranges.len() > MAX_DRAWN_BEAMS {
        return Err(BadInput(format!(
            "{}: scan {} has {} beams; draw scan draws at most {MAX_DRAWN_BEAMS}",
            args.file.display(),
            args.index,
            scan.ranges.len()
        ))
        .into());
    }
    let config = crate::config_file::resolve(&args.config, 0.01)?;
    let sensor = args.log.sensor.or(config.sensor).or(named_sensor);
    let mut detector = LineDetector::new(config.detector_for(sensor))?;
    let d = detector.detect(&scan);
    let pts: Vec<[f64; 2]> = d.points.xy.iter().map(|p| [p.x, p.y]).collect();
    let (mut lo, mut hi) = ([0.0f64; 2], [0.0f64; 2]); // include the sensor
    for p in &pts {
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    let mut plot = Plot::new(lo, hi, 1000.0);
    plot.dots(&pts, "#bbbbbb", 1.5);
    for (i, c) in d.clusters.iter().enumerate() {
        plot.dots(&pts[c.clone()], PALETTE[i % PALETTE.len()], 1.8);
    }
    let l1: Vec<[f64; 2]> = d.level1_breaks.iter().map(|&i| pts[i]).collect();
    let l2: Vec<[f64; 2]> = d.level2_breaks().map(|i| pts[i]).collect();
    plot.rings(&l1, "#000000", 5.0);
    plot.rings(&l2, "#d62728", 4.0);
    for l in d.lines {
        let s = &l.line;
        plot.line([s.start().x, s.start().y], [s.end().x, s.end().y], "#d62728", 2.5);
    }
    // The sensor: a triangle along its x axis, not a dot that reads as a
    // point or a break-point.
    plot.sensor([0.0, 0.0], 0.0, "#444444");
    plot.legend("points (colour: level-1 cluster)", "#1f77b4", Mark::Dot);
    plot.legend("level-1 break-points", "#000000", Mark::Ring);
    plot.legend("level-2 break-points", "#d62728", Mark::Ring);
    plot.legend("fitted lines", "#d62728", Mark::Line(2.5));
    plot.legend("sensor (origin, facing x)", "#444444", Mark::Sensor);
    let title = format!(
        "{} scan {}: {} points, {} clusters, {} lines",
        args.file.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default(),
        args.index,
        pts.len(),
        d.clusters.len(),
        d.lines.len()
    );
    write_picture(&args.output, &plot.finish(&title))?;
    if !quiet {
        eprintln!("wrote {}", args.output.display());
    }
    Ok(())
}
