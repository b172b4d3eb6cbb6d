//! `pcaline detect FILE`: the lines of every scan of a log or scan file,
//! streamed scan by scan to JSON or CSV (and to a Foxglove MCAP file with
//! `--mcap`), so memory does not grow with the log.

use crate::config_file::resolve;
use crate::exit::{BadInput, stdout_error};
use crate::log_args::LogArgs;
use crate::mcap_out::McapOut;
use crate::pipeline::for_each_scan;
use crate::progress;
use anyhow::Result;
use pcaline::{Detection, LineDetector, LineSegment};
use pcaline_io::{
    AtomicFile, LineRecord, LinesFormat, LinesWriter, NoiseRecord, PoseKind, ScanLines, ScanRecord,
};
use rayon::prelude::*;
use std::io::{BufWriter, Write};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

/// Arguments of `pcaline detect`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  pcaline detect scans.bag                        JSON Lines on stdout, one scan per line
  pcaline detect log.clf --fov 180 -o lines.json  a CARMEN log of unusual beam counts
  pcaline detect bag_dir --topic /scan --csv -o lines.csv
  pcaline detect log.mcap --sensor rplidar --mcap lines.mcap   also for Foxglove")]
pub struct DetectArgs {
    /// Log or scan file (CARMEN, ROS 1 bag, ROS 2 bag or folder, MCAP, JSON, CSV).
    file: PathBuf,
    #[command(flatten)]
    log: LogArgs,
    /// Detector: a preset (default, paper, split-and-merge, told-sigma,
    /// datasheet, adaptive) or a configuration file (see `pcaline eval
    /// --show-config`).
    #[arg(long, default_value = "default")]
    config: String,
    /// Write CSV (one row per detected line) instead of JSON.
    #[arg(long)]
    csv: bool,
    /// Output file: a JSON array with one scan per line of text, or JSON
    /// Lines when the name ends in `.jsonl`. Absent or `-`: JSON Lines (one
    /// scan object per line) on stdout.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Also write every scan and its lines to this MCAP file, for Foxglove
    /// (topics /scan, /lines, /tf and /pose/source: see the README).
    #[arg(long, value_name = "OUT.mcap")]
    mcap: Option<PathBuf>,
}

/// Scans one detector takes in turn within a batch.
const SCANS_PER_TASK: usize = 16;

/// Detects and encodes the scans of `batch`, the first of which is scan
/// `first` of the log, on every thread of the pool: for each scan, in
/// order, its record as `format` encodes it, its number of lines, and (with
/// `keep_lines`) the lines. Each task detects with its own copy of `detector`, and a scan's
/// lines do not depend on the scans before it, so the result is the same
/// byte for byte whatever the number of threads.
fn detect_batch(
    detector: &LineDetector,
    batch: &[ScanRecord],
    first: usize,
    format: LinesFormat,
    keep_lines: bool,
) -> Vec<(Vec<u8>, usize, Vec<LineSegment>)> {
    batch
        .par_chunks(SCANS_PER_TASK)
        .enumerate()
        .flat_map_iter(|(task, scans)| {
            let mut detector = detector.clone();
            let first = first + task * SCANS_PER_TASK;
            scans
                .iter()
                .enumerate()
                .map(|(k, s)| {
                    let d = detector.detect(&s.scan);
                    let record = scan_lines(first + k, s, &d);
                    let mut body = Vec::new();
                    // Encoding into memory cannot fail.
                    let _ = format.encode(&record, &mut body);
                    let lines = if keep_lines {
                        d.lines.iter().map(|l| l.line).collect()
                    } else {
                        Vec::new()
                    };
                    (body, d.lines.len(), lines)
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The output record of scan `index` of the log.
fn scan_lines(index: usize, s: &ScanRecord, d: &Detection<'_>) -> ScanLines {
    ScanLines {
        scan: index,
        position: s.position,
        stamp_s: s.scan.stamp_s,
        noise: d.noise.map(|n| NoiseRecord {
            near_sigma_m: n.near_sigma_m,
            far_sigma_m: n.far_sigma_m,
            far_from_m: n.far_from_m.is_finite().then_some(n.far_from_m),
            estimated: d.noise_estimate.is_some(),
            range_step_m: d.noise_estimate.map(|e| e.range_step_m),
        }),
        lines: d.lines.iter().map(line_record).collect(),
    }
}

/// A detected line as the JSON and CSV outputs write it: the line, its
/// beams and its straightness.
pub(crate) fn line_record(l: &pcaline::DetectedLine) -> LineRecord {
    let s = l.straightness;
    LineRecord::new(&l.line, Some((l.first_beam, l.last_beam))).with_straightness(
        s.residual_ratio,
        s.runs_z,
        s.bow_m,
    )
}

/// Where the lines go: a file written atomically, or stdout.
enum Sink {
    File(AtomicFile),
    Stdout(BufWriter<std::io::StdoutLock<'static>>),
}

/// The error of a failed write to `output` (`None`: stdout), naming it.
fn sink_error(output: Option<&Path>, e: std::io::Error) -> anyhow::Error {
    match output {
        Some(path) => pcaline_io::IoError::io(path, e).into(),
        None => stdout_error(e),
    }
}

impl Sink {
    /// Puts a file in place; stdout is already flushed.
    fn commit(self) -> Result<()> {
        if let Sink::File(f) = self {
            f.commit()?;
        }
        Ok(())
    }
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self {
            Sink::File(f) => f.write(buf),
            Sink::Stdout(s) => s.write(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            Sink::File(f) => f.flush(),
            Sink::Stdout(s) => s.flush(),
        }
    }
}

/// Runs `pcaline detect`.
pub fn run(args: &DetectArgs, quiet: bool) -> Result<()> {
    if !args.file.exists() {
        return Err(BadInput(format!("{}: no such file or folder", args.file.display())).into());
    }
    let config = resolve(&args.config, 0.01)?;
    let _copies = args.log.keep_decompressed(&args.file);
    let sensor = args.log.sensor(&args.file, config.sensor)?;
    let detector = LineDetector::new(config.detector_for(sensor))?;
    let mut mcap = McapOut::create(args.mcap.as_deref())?;
    let output = args.output.as_deref().filter(|p| *p != Path::new("-"));
    let sink = match output {
        Some(path) => Sink::File(AtomicFile::create(path)?),
        None => Sink::Stdout(BufWriter::new(std::io::stdout().lock())),
    };
    let json_lines = output.is_none_or(|p| p.extension().is_some_and(|e| e == "jsonl"));
    let format = match (args.csv, json_lines) {
        (true, _) => LinesFormat::Csv,
        (false, true) => LinesFormat::JsonLines,
        (false, false) => LinesFormat::Json,
    };
    let mut out = LinesWriter::new(sink, format);
    let bar = progress::spinner("scans", quiet);
    let mut lines_total = 0usize;
    let mut failed: Option<anyhow::Error> = None;
    let keep_lines = mcap.is_some();
    let read = for_each_scan(
        &args.file,
        &args.log.options()?,
        |first, batch| detect_batch(&detector, batch, first, format, keep_lines),
        |s, (body, n_lines, lines)| {
            lines_total += n_lines;
            if let Some(m) = mcap.as_mut() {
                let stamp = m.stamp(s.scan.stamp_s);
                let pose = [(PoseKind::SensorFromLog, s.pose.or(s.odometry))];
                if let Err(e) = m.scan(stamp, &s.scan, lines.iter(), &pose) {
                    failed = Some(e);
                    return ControlFlow::Break(());
                }
            }
            if let Err(e) = out.write_encoded(&body) {
                failed = Some(sink_error(output, e));
                return ControlFlow::Break(());
            }
            bar.inc(1);
            ControlFlow::Continue(())
        },
    );
    // A failed write stops the run before anything read after it can.
    if let Some(e) = failed {
        return Err(e);
    }
    read?;
    bar.finish_and_clear();
    let scans = out.scans();
    if scans == 0 {
        // Nothing is written: the temporary files are dropped.
        return Err(BadInput(format!("{}: no scans", args.file.display())).into());
    }
    let sink = out.finish().map_err(|e| sink_error(output, e))?;
    sink.commit()?;
    if let Some(m) = mcap {
        m.finish(quiet)?;
    }
    if !quiet {
        eprintln!("{}: {} scans, {} lines", args.file.display(), scans, lines_total);
    }
    Ok(())
}
