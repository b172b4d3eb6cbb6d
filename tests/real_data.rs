//! Every real dataset in `../shared/data` (or `$PCALINE_DATA`), in every
//! format: the readers return as many scans as the files hold, and the
//! detector finds centimetre-level lines in the UTM-30LX-EW bag. A missing
//! dataset fails under `CI=true` and is reported loudly otherwise.

mod support;
use support::data;

use pcaline::{Config, LineDetector};
use pcaline_io::{LogOptions, LogRecord, read_log, read_relations};
use std::ops::ControlFlow;

fn count_scans(rel: &str) -> Option<usize> {
    let path = data(rel)?;
    let mut seen = 0;
    let n = read_log(&path, &LogOptions::default(), |r| {
        if matches!(r, LogRecord::Scan(_)) {
            seen += 1;
        }
        ControlFlow::Continue(())
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(n, seen);
    Some(n)
}

#[test]
fn every_file_yields_all_its_scans() {
    for (rel, expected) in [
        ("intel/intel.gfs.log", 910),
        ("mit-csail/mit-csail.clf", 1988),
        ("mit-csail/csail.corrected.log", 406),
        ("utm30lx-ros2/rosbag2_2024_02_21-16_20_44_0.db3", 885),
        ("utm30lx-ros2", 885),
        ("ros1/laser_scan_matcher_demo.bag", 360),
        ("single-scans/laser_scan_1.json", 1),
        ("single-scans/laser_scan_6.json", 1),
    ] {
        if let Some(n) = count_scans(rel) {
            assert_eq!(n, expected, "{rel}");
        }
    }
}

#[test]
fn relations_parse() {
    if let Some(path) = data("intel/intel.relations") {
        let rel = read_relations(&path).unwrap();
        assert_eq!(rel.len(), 2984);
    }
}

#[test]
fn utm30lx_lines_are_centimetre_level() {
    let Some(path) = data("utm30lx-ros2") else { return };
    let mut detector = LineDetector::new(Config::default()).unwrap();
    let mut residuals = Vec::new();
    let mut beams = 0;
    read_log(&path, &LogOptions::default(), |r| {
        if let LogRecord::Scan(s) = r {
            beams = s.scan.len();
            residuals.extend(detector.detect(&s.scan).lines.iter().map(|l| l.line.residual_std()));
        }
        ControlFlow::Continue(())
    })
    .unwrap();
    assert_eq!(beams, 1081);
    residuals.sort_by(f64::total_cmp);
    let median = residuals[residuals.len() / 2];
    assert!(residuals.len() > 885, "{} lines", residuals.len());
    assert!((0.001..0.03).contains(&median), "median residual std {median} m");
}
