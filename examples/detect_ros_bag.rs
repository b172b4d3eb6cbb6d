//! Detects the lines of every scan of a ROS bag (ROS 1 `.bag`, ROS 2 `.db3`
//! or folder, MCAP) with the default detector, and prints a line per scan.
//!
//! ```sh
//! cargo run --release --example detect_ros_bag -- path/to/scans.bag
//! ```
//!
//! Without an argument it reads the shared ROS 1 bag from `$PCALINE_DATA`
//! (default `../shared/data`).

// An example prints its results.
#![allow(clippy::print_stdout)]

use pcaline::{Config, LineDetector};
use pcaline_io::{LogOptions, LogRecord, read_log};
use std::ops::ControlFlow;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).map(PathBuf::from).unwrap_or_else(|| {
        let data = std::env::var_os("PCALINE_DATA").unwrap_or_else(|| "../shared/data".into());
        PathBuf::from(data).join("ros1/laser_scan_matcher_demo.bag")
    });
    let mut detector = LineDetector::new(Config::default())?;
    let (mut scans, mut lines) = (0usize, 0usize);
    read_log(&path, &LogOptions::default(), |record| {
        if let LogRecord::Scan(s) = record {
            let detection = detector.detect(&s.scan);
            if scans < 5 {
                println!("scan {scans}: {} lines", detection.lines.len());
                for l in detection.lines {
                    let l = &l.line;
                    println!(
                        "  alpha {:+.3} rad, d {:.3} m, {:.2} m long",
                        l.alpha(),
                        l.d(),
                        l.length()
                    );
                }
            }
            scans += 1;
            lines += detection.lines.len();
        }
        ControlFlow::Continue(())
    })?;
    println!("{}: {scans} scans, {lines} lines", path.display());
    Ok(())
}
