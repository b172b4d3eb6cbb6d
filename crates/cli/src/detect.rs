//! `pcaline detect FILE`: the lines of every scan of a log or scan file.

use crate::exit::BadInput;
use crate::log_args::LogArgs;
use crate::progress;
use crate::run::Preset;
use anyhow::Result;
use pcaline::LineDetector;
use pcaline_io::{LogRecord, read_log, write_atomic};
use serde::Serialize;
use std::fmt::Write as _;
use std::ops::ControlFlow;
use std::path::PathBuf;

/// Arguments of `pcaline detect`.
#[derive(Debug, clap::Args)]
pub struct DetectArgs {
    /// Log or scan file (CARMEN, ROS 1 bag, ROS 2 bag or folder, MCAP, JSON, CSV).
    file: PathBuf,
    #[command(flatten)]
    log: LogArgs,
    /// Detector preset.
    #[arg(long, value_enum, default_value_t = Preset::Default)]
    config: Preset,
    /// Write CSV (one line per detected line) instead of JSON.
    #[arg(long)]
    csv: bool,
    /// Output file; stdout when absent.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

/// Lines of one scan (sensor frame).
#[derive(Debug, Serialize)]
struct ScanLinesOut {
    /// Index of the scan in the file, from 0.
    scan: usize,
    /// Line or message number in the file.
    position: usize,
    stamp_s: Option<f64>,
    lines: Vec<LineOut>,
}

#[derive(Debug, Serialize)]
struct LineOut {
    alpha_rad: f64,
    d_m: f64,
    start: [f64; 2],
    end: [f64; 2],
    length_m: f64,
    n_points: usize,
    residual_std_m: f64,
    first_beam: u32,
    last_beam: u32,
}

/// Runs `pcaline detect`.
pub fn run(args: &DetectArgs, quiet: bool) -> Result<()> {
    if !args.file.exists() {
        return Err(BadInput(format!("{}: no such file or folder", args.file.display())).into());
    }
    let mut detector = LineDetector::new(args.config.mapper().detector)?;
    let bar = progress::spinner("scans", quiet);
    let mut out: Vec<ScanLinesOut> = Vec::new();
    let mut scan_index = 0;
    read_log(&args.file, &args.log.options(), |record| {
        if let LogRecord::Scan(s) = record {
            let d = detector.detect(&s.scan);
            out.push(ScanLinesOut {
                scan: scan_index,
                position: s.position,
                stamp_s: s.scan.stamp_s,
                lines: d
                    .lines
                    .iter()
                    .map(|l| LineOut {
                        alpha_rad: l.line.alpha,
                        d_m: l.line.d,
                        start: [l.line.start.x, l.line.start.y],
                        end: [l.line.end.x, l.line.end.y],
                        length_m: l.line.length(),
                        n_points: l.line.n_points,
                        residual_std_m: l.line.residual_std,
                        first_beam: l.first_beam,
                        last_beam: l.last_beam,
                    })
                    .collect(),
            });
            scan_index += 1;
            bar.inc(1);
        }
        ControlFlow::Continue(())
    })?;
    bar.finish_and_clear();
    let text = if args.csv { to_csv(&out) } else { serde_json::to_string_pretty(&out)? + "\n" };
    match &args.output {
        Some(path) => write_atomic(path, text.as_bytes())?,
        None => print!("{text}"),
    }
    if !quiet {
        let lines: usize = out.iter().map(|s| s.lines.len()).sum();
        eprintln!("{}: {} scans, {} lines", args.file.display(), out.len(), lines);
    }
    Ok(())
}

fn to_csv(scans: &[ScanLinesOut]) -> String {
    let mut s = String::from(
        "scan,position,stamp_s,alpha_rad,d_m,start_x,start_y,end_x,end_y,length_m,n_points,residual_std_m,first_beam,last_beam\n",
    );
    for scan in scans {
        for l in &scan.lines {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                scan.scan,
                scan.position,
                scan.stamp_s.map(|t| t.to_string()).unwrap_or_default(),
                l.alpha_rad,
                l.d_m,
                l.start[0],
                l.start[1],
                l.end[0],
                l.end[1],
                l.length_m,
                l.n_points,
                l.residual_std_m,
                l.first_beam,
                l.last_beam
            );
        }
    }
    s
}
