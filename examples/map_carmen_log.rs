//! Builds a line map from a CARMEN log with the default `Mapper` (the
//! estimator fusing the log's odometry and the line matches, with loop
//! closure), and prints the map's size and the last corrected pose.
//!
//! ```sh
//! cargo run --release --example map_carmen_log -- path/to/log.clf
//! ```
//!
//! Without an argument it reads the shared Intel log from `$PCALINE_DATA`
//! (default `../shared/data`).

// An example prints its results.
#![allow(clippy::print_stdout)]

use pcaline::{Mapper, MapperConfig};
use pcaline_io::{LogOptions, LogRecord, read_log};
use std::ops::ControlFlow;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).map(PathBuf::from).unwrap_or_else(|| {
        let data = std::env::var_os("PCALINE_DATA").unwrap_or_else(|| "../shared/data".into());
        PathBuf::from(data).join("intel/intel.gfs.log")
    });
    let mut mapper = Mapper::new(MapperConfig::default())?;
    let mut scans = 0;
    read_log(&path, &LogOptions::default(), |record| {
        if let LogRecord::Scan(s) = record {
            // The raw odometry where the log has it, else its own pose.
            let step = match s.odometry.or(s.pose) {
                Some(source) => mapper.process(&s.scan, &source),
                None => mapper.process_without_source(&s.scan),
            };
            scans += 1;
            if scans % 200 == 0 {
                let p = step.pose;
                println!(
                    "scan {scans}: pose ({:.2}, {:.2}) m, {:.1}°",
                    p.x(),
                    p.y(),
                    p.heading().to_degrees()
                );
            }
        }
        ControlFlow::Continue(())
    })?;
    mapper.optimize();
    let confirmed = mapper.map().lines().iter().filter(|l| l.is_confirmed()).count();
    println!(
        "{}: {scans} scans, {} map lines ({confirmed} confirmed)",
        path.display(),
        mapper.map().len()
    );
    if let Some(p) = mapper.pose() {
        println!("last pose ({:.2}, {:.2}) m, {:.1}°", p.x(), p.y(), p.heading().to_degrees());
    }
    Ok(())
}
