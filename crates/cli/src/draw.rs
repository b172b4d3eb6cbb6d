//! `pcaline draw scan`: one scan with its level-1 and level-2 break-points,
//! clusters and fitted lines (the paper's Figures 1-3).

use crate::exit::BadInput;
use crate::log_args::LogArgs;
use crate::picture::write_picture;
use crate::run::Preset;
use crate::svg::Plot;
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
    Scan(ScanArgs),
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
    /// Detector preset.
    #[arg(long, value_enum, default_value_t = Preset::Default)]
    config: Preset,
    /// Output picture: SVG, or PNG when the name ends in `.png`.
    #[arg(short, long)]
    output: PathBuf,
}

const PALETTE: [&str; 6] = ["#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#17becf"];

/// Runs `pcaline draw`.
pub fn run(cmd: &DrawCommand, quiet: bool) -> Result<()> {
    let DrawCommand::Scan(args) = cmd;
    let mut found = None;
    let mut k = 0;
    read_log(&args.file, &args.log.options(), |r| {
        if let LogRecord::Scan(s) = r {
            if k == args.index {
                found = Some(s.scan);
                return ControlFlow::Break(());
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
    let mut detector = LineDetector::new(args.config.mapper().detector)?;
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
        plot.line([s.start.x, s.start.y], [s.end.x, s.end.y], "#d62728", 2.5);
    }
    plot.dots(&[[0.0, 0.0]], "#000000", 4.0);
    plot.legend("points (colour: level-1 cluster)", "#1f77b4", true);
    plot.legend("level-1 break-points", "#000000", true);
    plot.legend("level-2 break-points", "#d62728", true);
    plot.legend("fitted lines", "#d62728", false);
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
