//! Log formats and the one entry point that reads any of them, streaming.

use crate::ros::{read_mcap, read_ros1_bag, read_ros2_bag};
use crate::scan_text::{read_scan_csv, read_scan_json};
use crate::{CarmenOptions, CarmenReader, IoError, LogRecord};
use std::io::Read;
use std::ops::ControlFlow;
use std::path::Path;

/// The formats `pcaline` reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
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
#[non_exhaustive]
pub struct LogOptions {
    /// The format; detected from the file when `None`.
    pub format: Option<LogFormat>,
    /// Only this topic (ROS formats).
    pub topic: Option<String>,
    /// Which echo of a `MultiEchoLaserScan`'s beams is read (ROS formats;
    /// the first by default).
    pub echo: crate::Echo,
    /// CARMEN options (field of view, max range, time offset).
    pub carmen: CarmenOptions,
}

impl LogFormat {
    /// Every format, in the order of [`LogFormat::names`].
    pub const ALL: [LogFormat; 6] = [
        LogFormat::Carmen,
        LogFormat::Ros1Bag,
        LogFormat::Ros2Bag,
        LogFormat::Mcap,
        LogFormat::Json,
        LogFormat::Csv,
    ];

    /// The short name the command line's `--format` takes: `carmen`,
    /// `ros1`, `ros2`, `mcap`, `json` or `csv`.
    pub const fn name(self) -> &'static str {
        match self {
            LogFormat::Carmen => "carmen",
            LogFormat::Ros1Bag => "ros1",
            LogFormat::Ros2Bag => "ros2",
            LogFormat::Mcap => "mcap",
            LogFormat::Json => "json",
            LogFormat::Csv => "csv",
        }
    }

    /// The format named `name` (as [`LogFormat::name`] writes it,
    /// case-insensitive), or `None`.
    ///
    /// ```
    /// use pcaline_io::LogFormat;
    /// assert_eq!(LogFormat::from_name("ROS2"), Some(LogFormat::Ros2Bag));
    /// assert_eq!(LogFormat::from_name("bag"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name().eq_ignore_ascii_case(name))
    }

    /// The names, comma-separated, for messages.
    pub fn names() -> String {
        Self::ALL.map(LogFormat::name).join(", ")
    }

    /// Detects the format from the extension, a bag directory, or the first
    /// bytes (magic numbers). A directory is a ROS 2 bag: of sqlite3 files
    /// ([`LogFormat::Ros2Bag`]), or of MCAP files, ROS 2's default storage
    /// since Iron ([`LogFormat::Mcap`]), when it has `.mcap` files and no
    /// `.db3` file.
    pub fn detect(path: &Path) -> Result<LogFormat, IoError> {
        if path.is_dir() {
            let has = |ext| crate::ros::files_with_extension(path, ext).map(|f| !f.is_empty());
            return Ok(if !has("db3")? && has("mcap")? {
                LogFormat::Mcap
            } else {
                LogFormat::Ros2Bag
            });
        }
        if crate::ros::is_compressed_db3(path) {
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
///
/// Every record is checked before `visit` sees it ([`check_record`]): a scan
/// whose header cannot be right (angles not finite or spanning more than a
/// turn, a zero increment, `range_max` not above `range_min`), or a stamp or
/// pose that is not finite or lies beyond [`MAX_COORDINATE_M`], is an error
/// naming the file and the line or scan. Ranges themselves are data: NaN,
/// infinite or out-of-range values are invalid returns, never errors.
pub fn read_log(
    path: &Path,
    options: &LogOptions,
    mut visit: impl FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    let format = match options.format {
        Some(f) => f,
        None => LogFormat::detect(path)?,
    };
    let mut invalid: Option<IoError> = None;
    let mut checked = |record: LogRecord| match check_record_in(path, format, &record) {
        Ok(()) => visit(record),
        Err(e) => {
            invalid = Some(e);
            ControlFlow::Break(())
        }
    };
    let count = read_format(path, format, options, &mut checked)?;
    match invalid {
        Some(e) => Err(e),
        None => Ok(count),
    }
}

/// [`check_record`]'s verdict on a record of the `format` file at `path`,
/// as the error [`read_log`] returns: at the record's line in the text
/// formats, naming the scan in the others.
pub(crate) fn check_record_in(
    path: &Path,
    format: LogFormat,
    record: &LogRecord,
) -> Result<(), IoError> {
    check_record(record).map_err(|message| {
        let position = match record {
            LogRecord::Scan(s) => s.position,
            LogRecord::Odometry(o) => o.position,
        };
        match format {
            // Positions are line numbers in the text formats.
            LogFormat::Carmen | LogFormat::Csv => IoError::parse(path, Some(position), message),
            _ => IoError::parse(path, None, format!("scan {position}: {message}")),
        }
    })
}

/// Poses and positions beyond this, metres, are refused: no log of a
/// building, a city or a continent reaches them, and drawing or mapping
/// them would take unbounded work.
pub const MAX_COORDINATE_M: f64 = 1e8;

/// Why a record cannot be right, if it cannot: the scan header's angles and
/// range limits, the stamp, and the poses (see [`read_log`]).
pub fn check_record(record: &LogRecord) -> Result<(), String> {
    let (stamp, poses) = match record {
        LogRecord::Scan(s) => {
            check_scan_header(&s.scan)?;
            (s.scan.stamp_s, [s.pose, s.odometry])
        }
        LogRecord::Odometry(o) => (Some(o.stamp_s), [Some(o.pose), None]),
    };
    if let Some(t) = stamp.filter(|t| !t.is_finite()) {
        return Err(format!("the timestamp is not finite ({t})"));
    }
    for (p, name) in poses.iter().zip(["pose", "odometry"]) {
        let Some(p) = p else { continue };
        if !(p.x().is_finite() && p.y().is_finite() && p.heading().is_finite()) {
            return Err(format!(
                "the {name} is not finite ({}, {}, {})",
                p.x(),
                p.y(),
                p.heading()
            ));
        }
        if p.x().abs() > MAX_COORDINATE_M || p.y().abs() > MAX_COORDINATE_M {
            return Err(format!(
                "the {name} ({}, {}) m lies beyond ±{MAX_COORDINATE_M:e} m",
                p.x(),
                p.y()
            ));
        }
    }
    Ok(())
}

/// Why a scan's header cannot be right, if it cannot: `angle_min` not finite
/// or beyond ±2π, `angle_increment` zero or not finite, beams spanning more
/// than a turn, `range_min` negative or not finite, `range_max` NaN or not
/// above `range_min` (an infinite `range_max` is no upper limit).
pub fn check_scan_header(scan: &pcaline_geometry::Scan) -> Result<(), String> {
    use std::f64::consts::TAU;
    let (a0, inc) = (f64::from(scan.angle_min), f64::from(scan.angle_increment));
    if !a0.is_finite() || a0.abs() > TAU + 1e-3 {
        return Err(format!("angle_min {a0} rad is not within ±2π"));
    }
    if !inc.is_finite() || inc == 0.0 {
        return Err(format!("angle_increment {inc} rad must be finite and not zero"));
    }
    let span = inc.abs() * scan.ranges.len().saturating_sub(1) as f64;
    if span > TAU + 1e-3 {
        return Err(format!(
            "{} beams of {inc} rad span {:.1}°, more than a turn",
            scan.ranges.len(),
            span.to_degrees()
        ));
    }
    let (min, max) = (scan.range_min, scan.range_max);
    if !min.is_finite() || min < 0.0 {
        return Err(format!("range_min {min} m must be finite and not negative"));
    }
    if max.is_nan() || max <= min {
        return Err(format!("range_max {max} m is not above range_min {min} m"));
    }
    Ok(())
}

fn read_format(
    path: &Path,
    format: LogFormat,
    options: &LogOptions,
    mut visit: impl FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
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
        LogFormat::Ros1Bag => read_ros1_bag(path, topic, options.echo, &mut visit),
        LogFormat::Ros2Bag => read_ros2_bag(path, topic, options.echo, &mut visit),
        LogFormat::Mcap => read_mcap(path, topic, options.echo, &mut visit),
        LogFormat::Json => read_scan_json(path, &mut visit),
        LogFormat::Csv => read_scan_csv(path, &mut visit),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::Scan;

    #[test]
    fn impossible_scan_headers_are_named() {
        let ok = Scan::new(-2.35, 0.0043633, 0.02, 60.0, vec![1.0; 1081]);
        check_scan_header(&ok).unwrap();
        let unbounded = Scan::new(-1.0, 0.01, 0.0, f32::INFINITY, vec![1.0; 10]);
        check_scan_header(&unbounded).unwrap();
        let bad = [
            (Scan::new(-1.0, 0.0, 0.0, 30.0, vec![1.0; 10]), "angle_increment"),
            (Scan::new(-1.0, 1e30, 0.0, 30.0, vec![1.0; 10]), "more than a turn"),
            (Scan::new(-1.0, 0.01, 0.0, 30.0, vec![1.0; 1000]), "more than a turn"),
            (Scan::new(1e38, 0.01, 0.0, 30.0, vec![1.0; 10]), "angle_min"),
            (Scan::new(f32::NAN, 0.01, 0.0, 30.0, vec![1.0; 10]), "angle_min"),
            (Scan::new(-1.0, 0.01, 5.0, 1.0, vec![1.0; 10]), "range_max"),
            (Scan::new(-1.0, 0.01, 0.0, -1.0, vec![1.0; 10]), "range_max"),
            (Scan::new(-1.0, 0.01, -1.0, 30.0, vec![1.0; 10]), "range_min"),
            (Scan::new(-1.0, 0.01, 0.0, f32::NAN, vec![1.0; 10]), "range_max"),
        ];
        for (scan, what) in bad {
            let e = check_scan_header(&scan).unwrap_err();
            assert!(e.contains(what), "{e}");
        }
    }

    #[test]
    fn non_finite_or_far_poses_and_stamps_are_refused() {
        use crate::{OdometryRecord, ScanRecord};
        use pcaline_geometry::Pose2;
        let scan = |pose: Pose2, stamp: f64| {
            LogRecord::Scan(ScanRecord {
                scan: Scan::new(-1.0, 0.01, 0.0, 30.0, vec![1.0; 10]).with_stamp(stamp),
                pose: Some(pose),
                odometry: None,
                position: 3,
                sensor: None,
            })
        };
        check_record(&scan(Pose2::new(5e7, -5e7, 1.0), 1.0)).unwrap();
        assert!(
            check_record(&scan(Pose2::new(1e16, 0.0, 0.0), 1.0)).unwrap_err().contains("beyond")
        );
        let nan = Pose2::new(f64::NAN, 0.0, 0.0);
        assert!(check_record(&scan(nan, 1.0)).unwrap_err().contains("not finite"));
        assert!(check_record(&scan(Pose2::default(), f64::NAN)).unwrap_err().contains("timestamp"));
        let odom = LogRecord::Odometry(OdometryRecord {
            pose: Pose2::new(0.0, 0.0, f64::INFINITY),
            stamp_s: 0.0,
            position: 1,
        });
        assert!(check_record(&odom).is_err());
    }
}
