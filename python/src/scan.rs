//! `pcaline.Scan`: one 2D scan as a driver publishes it (ROS
//! `sensor_msgs/LaserScan`), with what a log stores beside it (the log's
//! own pose, odometry, sensor and position).

use crate::convert::{pose_tuple, read_f32_into, value_error};
use numpy::PyArray1;
use pcaline::geometry::SensorProfile;
use pcaline::{Pose2, Scan};
use pyo3::prelude::*;

/// Sets `scan`'s header and checks it: angles finite and within a turn, a
/// non-zero increment, `0 <= range_min < range_max`. Ranges themselves are
/// data (NaN, inf, out of range are invalid returns).
pub fn set_header(
    scan: &mut Scan,
    angle_min: f64,
    angle_increment: f64,
    range_min: f64,
    range_max: f64,
    stamp: Option<f64>,
) -> PyResult<()> {
    scan.angle_min = angle_min as f32;
    scan.angle_increment = angle_increment as f32;
    scan.range_min = range_min as f32;
    scan.range_max = range_max as f32;
    if let Some(t) = stamp
        && !t.is_finite()
    {
        return Err(value_error(format!("stamp: {t} is not finite")));
    }
    scan.stamp_s = stamp;
    pcaline_io::check_scan_header(scan).map_err(value_error)
}

/// One scan: ranges in metres (float32; NaN, inf and values outside
/// `[range_min, range_max]` are beams without a return), the bearing of
/// beam `i` is `angle_min + i * angle_increment` radians, counter-clockwise
/// from the sensor's x axis.
#[pyclass(name = "Scan", module = "pcaline", frozen)]
#[derive(Debug, Clone)]
pub struct PyScan {
    pub scan: Scan,
    /// The log's own `world_from_sensor` (CARMEN's corrected pose).
    pub pose: Option<Pose2>,
    /// The odometry's `world_from_sensor`.
    pub odometry: Option<Pose2>,
    /// The sensor the log names.
    pub sensor: Option<SensorProfile>,
    /// Where it is in its log: the 1-based line of a text log, else the
    /// scan's index.
    pub position: usize,
}

#[pymethods]
impl PyScan {
    /// A scan. `ranges` is a 1-D float32 or float64 array or a sequence
    /// of numbers (copied once); `stamp` is in seconds, `time_increment`
    /// the time between beams in seconds (for motion skew). Raises
    /// `ValueError` for a header that cannot be right.
    #[new]
    #[pyo3(signature = (ranges, angle_min, angle_increment, range_min=0.0, range_max=f64::INFINITY, stamp=None, time_increment=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        ranges: &Bound<'_, PyAny>,
        angle_min: f64,
        angle_increment: f64,
        range_min: f64,
        range_max: f64,
        stamp: Option<f64>,
        time_increment: Option<f64>,
    ) -> PyResult<Self> {
        let mut scan = Scan::new(0.0, 1.0, 0.0, 1.0, Vec::new());
        read_f32_into(ranges, "ranges", &mut scan.ranges)?;
        set_header(&mut scan, angle_min, angle_increment, range_min, range_max, stamp)?;
        if let Some(dt) = time_increment {
            if !dt.is_finite() {
                return Err(value_error(format!("time_increment: {dt} is not finite")));
            }
            scan = scan.with_time_increment(dt);
        }
        Ok(PyScan { scan, pose: None, odometry: None, sensor: None, position: 0 })
    }

    /// The ranges, metres (a new float32 array).
    #[getter]
    fn ranges<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        PyArray1::from_slice(py, &self.scan.ranges)
    }

    /// The bearing of each beam, radians (float64).
    #[getter]
    fn angles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_iter(py, (0..self.scan.len()).map(|i| self.scan.angle(i)))
    }

    /// The first beam's bearing, radians.
    #[getter]
    fn angle_min(&self) -> f64 {
        f64::from(self.scan.angle_min)
    }

    /// The angle between beams, radians.
    #[getter]
    fn angle_increment(&self) -> f64 {
        f64::from(self.scan.angle_increment)
    }

    /// The shortest valid range, metres.
    #[getter]
    fn range_min(&self) -> f64 {
        f64::from(self.scan.range_min)
    }

    /// The longest valid range, metres.
    #[getter]
    fn range_max(&self) -> f64 {
        f64::from(self.scan.range_max)
    }

    /// The time of the first beam, seconds, when known.
    #[getter]
    fn stamp(&self) -> Option<f64> {
        self.scan.stamp_s
    }

    /// The time between beams, seconds, when known.
    #[getter]
    fn time_increment(&self) -> Option<f64> {
        self.scan.time_increment_s
    }

    /// The log's own pose `(x_m, y_m, heading_rad)` for the scan (CARMEN's
    /// corrected pose), when the log has one.
    #[getter]
    fn pose(&self) -> Option<(f64, f64, f64)> {
        self.pose.as_ref().map(pose_tuple)
    }

    /// The odometry pose `(x_m, y_m, heading_rad)`, when the log has one.
    #[getter]
    fn odometry(&self) -> Option<(f64, f64, f64)> {
        self.odometry.as_ref().map(pose_tuple)
    }

    /// The sensor the log names (CARMEN ROBOTLASER1), e.g. `"sick-lms"`.
    #[getter]
    fn sensor(&self) -> Option<&'static str> {
        self.sensor.map(SensorProfile::name)
    }

    /// Where the scan is in its log: the 1-based line of a text log, else
    /// its index; 0 for a scan made in Python.
    #[getter]
    fn position(&self) -> usize {
        self.position
    }

    fn __len__(&self) -> usize {
        self.scan.len()
    }

    fn __repr__(&self) -> String {
        let stamp = self.scan.stamp_s.map_or("None".to_string(), |t| t.to_string());
        format!(
            "Scan({} beams from {:.4} rad by {:.6} rad, stamp={stamp})",
            self.scan.len(),
            self.scan.angle_min,
            self.scan.angle_increment,
        )
    }
}
