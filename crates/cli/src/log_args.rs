//! Arguments shared by the commands that read logs.

use crate::exit::BadInput;
use clap::ValueEnum;
use pcaline::geometry::SensorProfile;
use pcaline_io::{DecompressedBag, Echo, LogFormat, LogOptions, LogRecord, read_log};
use std::ops::ControlFlow;
use std::path::Path;

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

/// Which echo of a multi-echo scan, for `--echo`.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum EchoArg {
    /// The nearest return: the first surface the beam met.
    First,
    /// The farthest return: past glass, dust, rain or foliage.
    Last,
    /// The return of the highest intensity (the first without intensities).
    Strongest,
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
    /// Which echo of each beam a `sensor_msgs/MultiEchoLaserScan` gives
    /// (ROS formats; LaserScans have one).
    #[arg(long, value_enum, default_value = "first")]
    pub echo: EchoArg,
    /// Field of view of CARMEN FLASER lines, degrees, in (0, 360] (needed
    /// for beam counts other than 180, 181 and 361).
    #[arg(long, allow_negative_numbers = true)]
    pub fov: Option<f64>,
    /// CARMEN ranges at or above this are no return, metres (> 0).
    #[arg(long, default_value_t = 80.0, allow_negative_numbers = true)]
    pub max_range: f64,
    /// The sensor: utm30lx-ew, sick-lms, urg-04lx or rplidar. The detector's
    /// thresholds use its datasheet noise (the nominal the default's
    /// estimate starts from). Absent: the configuration file's
    /// `sensor`, else the sensor the log names (CARMEN ROBOTLASER1), else the
    /// configuration's own (the UTM-30LX-EW for the presets).
    #[arg(long, value_parser = parse_sensor)]
    pub sensor: Option<SensorProfile>,
}

/// `--sensor NAME`.
fn parse_sensor(name: &str) -> Result<SensorProfile, String> {
    SensorProfile::from_name(name)
        .ok_or_else(|| format!("unknown sensor {name:?} ({})", SensorProfile::names()))
}

impl LogArgs {
    /// The sensor `file` was recorded with: `--sensor`, else `configured`
    /// (a configuration file's), else the one the log's first scan names.
    /// `None`: keep the configuration's noise.
    pub fn sensor(
        &self,
        file: &Path,
        configured: Option<SensorProfile>,
    ) -> anyhow::Result<Option<SensorProfile>> {
        if let Some(s) = self.sensor.or(configured) {
            return Ok(Some(s));
        }
        let mut named = None;
        read_log(file, &self.options()?, |record| match record {
            LogRecord::Scan(s) => {
                named = s.sensor;
                ControlFlow::Break(())
            }
            _ => ControlFlow::Continue(()),
        })?;
        Ok(named)
    }

    /// Keeps the decompressed copies of `file`'s ROS 2 bag files that
    /// rosbag2 compressed whole, for every pass over the log while the
    /// result lives (the sensor's, the motion's, the scans'): each file is
    /// decompressed once. `None` for other logs, and when the log cannot be
    /// read: the pass that reads it then reports why.
    pub fn keep_decompressed(&self, file: &Path) -> Option<DecompressedBag> {
        let options = self.options().ok()?;
        let format = options.format.map_or_else(|| LogFormat::detect(file), Ok).ok()?;
        (format == LogFormat::Ros2Bag).then(|| pcaline_io::keep_decompressed(file).ok()).flatten()
    }

    /// The reader options; an error naming the option for a field of view
    /// outside (0, 360] degrees or a maximum range that is not a positive
    /// number.
    pub fn options(&self) -> anyhow::Result<LogOptions> {
        if let Some(fov) = self.fov
            && !(fov > 0.0 && fov <= 360.0)
        {
            return Err(BadInput(format!("--fov {fov}: must be in (0, 360] degrees")).into());
        }
        if !(self.max_range > 0.0 && self.max_range.is_finite()) {
            return Err(BadInput(format!(
                "--max-range {}: must be a positive number of metres",
                self.max_range
            ))
            .into());
        }
        let mut options = LogOptions::default();
        options.format = self.format.map(|f| match f {
            FormatArg::Carmen => LogFormat::Carmen,
            FormatArg::Ros1 => LogFormat::Ros1Bag,
            FormatArg::Ros2 => LogFormat::Ros2Bag,
            FormatArg::Mcap => LogFormat::Mcap,
            FormatArg::Json => LogFormat::Json,
            FormatArg::Csv => LogFormat::Csv,
        });
        options.topic = self.topic.clone();
        options.echo = match self.echo {
            EchoArg::First => Echo::First,
            EchoArg::Last => Echo::Last,
            EchoArg::Strongest => Echo::Strongest,
        };
        options.carmen.fov_rad = self.fov.map(f64::to_radians);
        options.carmen.max_range_m = self.max_range;
        Ok(options)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        log: LogArgs,
    }

    /// `--echo` reaches the reader's options; the first echo by default.
    #[test]
    fn echo_reaches_the_reader() {
        let parse = |args: &[&str]| {
            let cli = Cli::try_parse_from(std::iter::once("x").chain(args.iter().copied()));
            cli.unwrap().log.options().unwrap().echo
        };
        assert_eq!(parse(&[]), Echo::First);
        assert_eq!(parse(&["--echo", "last"]), Echo::Last);
        assert_eq!(parse(&["--echo", "strongest"]), Echo::Strongest);
        assert!(Cli::try_parse_from(["x", "--echo", "second"]).is_err());
    }
}
