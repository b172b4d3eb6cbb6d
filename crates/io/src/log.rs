//! Log formats and the one entry point that reads any of them, streaming.

use crate::ros::{read_mcap, read_ros1_bag, read_ros2_bag};
use crate::scan_text::{read_scan_csv, read_scan_json};
use crate::{CarmenOptions, CarmenReader, IoError, LogRecord};
use std::io::Read;
use std::ops::ControlFlow;
use std::path::Path;

/// The formats `pcaline` reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogFormat {
    /// CARMEN text log.
    Carmen,
    /// ROS 1 bag, format 2.0.
    Ros1Bag,
    /// ROS 2 bag, sqlite3 (a `.db3` file or a bag directory).
    Ros2Bag,
    /// MCAP with CDR LaserScans.
    Mcap,
    /// Scans as JSON.
    Json,
    /// Scans as CSV.
    Csv,
}

/// Options of [`read_log`].
#[derive(Debug, Clone, Default)]
pub struct LogOptions {
    /// The format; detected from the file when `None`.
    pub format: Option<LogFormat>,
    /// Only this topic (ROS formats).
    pub topic: Option<String>,
    /// CARMEN options (field of view, max range, time offset).
    pub carmen: CarmenOptions,
}

impl LogFormat {
    /// Detects the format from the extension, a bag directory, or the first
    /// bytes (magic numbers).
    pub fn detect(path: &Path) -> Result<LogFormat, IoError> {
        if path.is_dir() {
            return Ok(LogFormat::Ros2Bag);
        }
        let ext =
            path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        match ext.as_str() {
            "bag" => return Ok(LogFormat::Ros1Bag),
            "db3" => return Ok(LogFormat::Ros2Bag),
            "mcap" => return Ok(LogFormat::Mcap),
            "json" | "jsonl" => return Ok(LogFormat::Json),
            "csv" => return Ok(LogFormat::Csv),
            "clf" | "carmen" => return Ok(LogFormat::Carmen),
            _ => {}
        }
        let mut head = [0u8; 16];
        let n = std::fs::File::open(path)
            .and_then(|mut f| f.read(&mut head))
            .map_err(|e| IoError::io(path, e))?;
        let head = &head[..n];
        Ok(if head.starts_with(b"#ROSBAG") {
            LogFormat::Ros1Bag
        } else if head.starts_with(b"\x89MCAP") {
            LogFormat::Mcap
        } else if head.starts_with(b"SQLite format 3") {
            LogFormat::Ros2Bag
        } else if head.first().is_some_and(|b| *b == b'{' || *b == b'[') {
            LogFormat::Json
        } else if head.iter().all(|b| b.is_ascii()) && !head.is_empty() {
            LogFormat::Carmen
        } else {
            return Err(IoError::UnknownFormat {
                path: path.to_path_buf(),
                expected: "CARMEN (.clf/.log), ROS 1 (.bag), ROS 2 (.db3 or bag folder), MCAP (.mcap), JSON, CSV",
            });
        })
    }
}

/// Reads the log at `path`, calling `visit` for each record in order until
/// it returns `ControlFlow::Break`. Returns the number of scans read. Every
/// format streams except a JSON file whose top level is an array.
pub fn read_log(
    path: &Path,
    options: &LogOptions,
    mut visit: impl FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    let format = match options.format {
        Some(f) => f,
        None => LogFormat::detect(path)?,
    };
    let topic = options.topic.as_deref();
    match format {
        LogFormat::Carmen => {
            let mut count = 0;
            for record in CarmenReader::open(path, options.carmen)? {
                let record = record?;
                count += matches!(record, LogRecord::Scan(_)) as usize;
                if visit(record).is_break() {
                    break;
                }
            }
            Ok(count)
        }
        LogFormat::Ros1Bag => read_ros1_bag(path, topic, &mut visit),
        LogFormat::Ros2Bag => read_ros2_bag(path, topic, &mut visit),
        LogFormat::Mcap => read_mcap(path, topic, &mut visit),
        LogFormat::Json => read_scan_json(path, &mut visit),
        LogFormat::Csv => read_scan_csv(path, &mut visit),
    }
}
