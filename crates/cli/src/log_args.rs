//! Arguments shared by the commands that read logs.

use clap::ValueEnum;
use pcaline_io::{CarmenOptions, LogFormat, LogOptions};

/// A log format, for `--format`.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum FormatArg {
    /// CARMEN text log.
    Carmen,
    /// ROS 1 bag.
    Ros1,
    /// ROS 2 sqlite3 bag (.db3 or folder).
    Ros2,
    /// MCAP.
    Mcap,
    /// JSON scans.
    Json,
    /// CSV scans.
    Csv,
}

/// How to read a log.
#[derive(Debug, Clone, clap::Args)]
pub struct LogArgs {
    /// The format; detected from the file when absent.
    #[arg(long, value_enum)]
    pub format: Option<FormatArg>,
    /// Only this topic (ROS formats).
    #[arg(long)]
    pub topic: Option<String>,
    /// Field of view of CARMEN FLASER lines, degrees (needed for beam counts
    /// other than 180, 181 and 361).
    #[arg(long)]
    pub fov: Option<f64>,
    /// CARMEN ranges at or above this are no return, metres.
    #[arg(long, default_value_t = 80.0)]
    pub max_range: f64,
}

impl LogArgs {
    /// The reader options.
    pub fn options(&self) -> LogOptions {
        LogOptions {
            format: self.format.map(|f| match f {
                FormatArg::Carmen => LogFormat::Carmen,
                FormatArg::Ros1 => LogFormat::Ros1Bag,
                FormatArg::Ros2 => LogFormat::Ros2Bag,
                FormatArg::Mcap => LogFormat::Mcap,
                FormatArg::Json => LogFormat::Json,
                FormatArg::Csv => LogFormat::Csv,
            }),
            topic: self.topic.clone(),
            carmen: CarmenOptions {
                fov_rad: self.fov.map(f64::to_radians),
                max_range_m: self.max_range,
                ..CarmenOptions::default()
            },
        }
    }
}
