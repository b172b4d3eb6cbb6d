//! `pcaline eval --real`: raw and aided odometry of the MIT CSAIL log
//! against its GMapping-corrected poses.

use anyhow::{Context, Result};
use pcaline::aiding::{Aiding, AidingConfig, SensorLine};
use pcaline::{LineDetector, MapperConfig, Pose2};
use pcaline_eval::aligned_trajectory_errors;
use pcaline_io::{CarmenOptions, CarmenReader, LogRecord, read_scan_pairs};
use std::path::Path;

/// One row: a trajectory against the corrected poses.
pub struct RealRow {
    /// Which trajectory.
    pub name: &'static str,
    /// Heading rms, degrees.
    pub heading_rms_deg: f64,
    /// Heading max, degrees.
    pub heading_max_deg: f64,
    /// Position rms, metres.
    pub position_rms_m: f64,
    /// Position error of the last pair, metres.
    pub position_final_m: f64,
}

/// Runs the comparison on `data/mit-csail`.
pub fn csail(data: &Path) -> Result<(usize, Vec<RealRow>)> {
    let dir = data.join("mit-csail");
    let pairs = read_scan_pairs(&dir.join("csail_corrected_to_raw_pairs.txt"))?;
    let config = MapperConfig::default();
    let mut detector = LineDetector::new(config.detector)?;
    let modes = [
        ("raw odometry", AidingConfig::none()),
        ("heading-aided", AidingConfig::heading()),
        ("full-pose aided", AidingConfig::full_pose()),
    ];
    let mut loops: Vec<Aiding> =
        modes.iter().map(|(_, a)| Aiding::new(*a, config.map)).collect::<Result<_, _>>()?;
    let mut poses: Vec<Vec<Pose2>> = vec![Vec::new(); modes.len()];
    let log = dir.join("mit-csail.clf");
    let mut lines: Vec<SensorLine> = Vec::new();
    for record in CarmenReader::open(&log, CarmenOptions::default())? {
        let LogRecord::Scan(s) = record? else { continue };
        let source = s.odometry.or(s.pose).context("a FLASER line without odometry")?;
        lines.clear();
        lines.extend(detector.detect(&s.scan).lines.iter().map(SensorLine::from));
        for (aiding, out) in loops.iter_mut().zip(poses.iter_mut()) {
            out.push(aiding.step(&source, &lines).0);
        }
    }
    let reference: Vec<Pose2> = pairs.iter().map(|p| p.corrected_pose).collect();
    let mut rows = Vec::new();
    for ((name, _), est) in modes.iter().zip(&poses) {
        let picked: Vec<Pose2> = pairs
            .iter()
            .map(|p| {
                est.get(p.raw_index).copied().context("a pair names a raw scan beyond the log")
            })
            .collect::<Result<_>>()?;
        let e = aligned_trajectory_errors(&picked, &reference).context("no pairs")?;
        rows.push(RealRow {
            name,
            heading_rms_deg: e.heading_rms_rad.to_degrees(),
            heading_max_deg: e.heading_max_rad.to_degrees(),
            position_rms_m: e.position_rms_m,
            position_final_m: e.position_final_m,
        });
    }
    Ok((pairs.len(), rows))
}
