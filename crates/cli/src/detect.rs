//! `pcaline detect FILE`: the lines of every scan of a log or scan file.

use crate::config_file::resolve;
use crate::exit::BadInput;
use crate::log_args::LogArgs;
use crate::progress;
use anyhow::Result;
use pcaline::LineDetector;
use pcaline_io::{
    LineRecord, LogRecord, NoiseRecord, ScanLines, lines_to_csv, lines_to_json, read_log,
    write_atomic,
};
use std::ops::ControlFlow;
use std::path::PathBuf;

/// Arguments of `pcaline detect`.
#[derive(Debug, clap::Args)]
pub struct DetectArgs {
    /// Log or scan file (CARMEN, ROS 1 bag, ROS 2 bag or folder, MCAP, JSON, CSV).
    file: PathBuf,
    #[command(flatten)]
    log: LogArgs,
    /// Detector: a preset (default, paper, split-and-merge, told-sigma,
    /// estimated, adaptive) or a configuration file (see `pcaline eval
    /// --show-config`).
    #[arg(long, default_value = "default")]
    config: String,
    /// Write CSV (one line per detected line) instead of JSON.
    #[arg(long)]
    csv: bool,
    /// Output file; stdout when absent.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

/// Runs `pcaline detect`.
pub fn run(args: &DetectArgs, quiet: bool) -> Result<()> {
    if !args.file.exists() {
        return Err(BadInput(format!("{}: no such file or folder", args.file.display())).into());
    }
    let config = resolve(&args.config, 0.01)?;
    let sensor = args.log.sensor(&args.file, config.sensor)?;
    let mut detector = LineDetector::new(config.detector_for(sensor))?;
    let bar = progress::spinner("scans", quiet);
    let mut out: Vec<ScanLines> = Vec::new();
    let mut scan_index = 0;
    read_log(&args.file, &args.log.options(), |record| {
        if let LogRecord::Scan(s) = record {
            let d = detector.detect(&s.scan);
            out.push(ScanLines {
                scan: scan_index,
                position: s.position,
                stamp_s: s.scan.stamp_s,
                noise: d.noise.map(|n| NoiseRecord {
                    near_sigma_m: n.near_sigma_m,
                    far_sigma_m: n.far_sigma_m,
                    far_from_m: n.far_from_m.is_finite().then_some(n.far_from_m),
                    estimated: d.noise_estimate.is_some(),
                    range_step_m: d.noise_estimate.map(|e| e.range_step_m),
                }),
                lines: d
                    .lines
                    .iter()
                    .map(|l| {
                        let s = l.straightness;
                        LineRecord::new(&l.line, Some((l.first_beam, l.last_beam)))
                            .with_straightness(s.residual_ratio, s.runs_z, s.bow_m)
                    })
                    .collect(),
            });
            scan_index += 1;
            bar.inc(1);
        }
        ControlFlow::Continue(())
    })?;
    bar.finish_and_clear();
    let text = if args.csv { lines_to_csv(&out) } else { lines_to_json(&out) };
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
