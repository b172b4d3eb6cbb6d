//! [`LogRecord`]: what every log reader yields, one record at a time.

use pcaline_geometry::{Pose2, Scan, SensorProfile};

/// One record of a log.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum LogRecord {
    /// A laser scan, with the poses the log gives for it.
    Scan(ScanRecord),
    /// An odometry pose without a scan (CARMEN `ODOM`).
    Odometry(OdometryRecord),
}

/// A scan from a log.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanRecord {
    /// The scan; its `stamp_s` is the log's timestamp when there is one.
    pub scan: Scan,
    /// The pose the log gives for the scan (`world_from_sensor` as the log
    /// estimated it: corrected in a GMapping log, raw odometry in a raw one).
    pub pose: Option<Pose2>,
    /// The raw odometry pose stored with the scan, when the log has one.
    pub odometry: Option<Pose2>,
    /// Where the record came from: a 1-based line number or message index.
    pub position: usize,
    /// The sensor the log names, when its format carries the type (CARMEN
    /// `ROBOTLASER1`'s `laser_type`); `None` otherwise.
    pub sensor: Option<SensorProfile>,
}

/// An odometry pose from a log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryRecord {
    /// The pose.
    pub pose: Pose2,
    /// Timestamp, seconds.
    pub stamp_s: f64,
    /// 1-based line number.
    pub position: usize,
}
