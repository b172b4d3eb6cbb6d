//! [`Scan`]: one 2D LIDAR sweep with ROS `sensor_msgs/LaserScan` semantics (REP 117).

use std::f64::consts::TAU;

/// One sweep of a 2D LIDAR, as `sensor_msgs/LaserScan` defines it.
///
/// Beam `i` points at `angle_min + i * angle_increment` radians in the sensor
/// frame (x forward, y left); `angle_increment` may be negative (a sensor
/// mounted upside down). A range is a *valid return* only when it is finite and
/// within `[range_min, range_max]`; NaN, `±inf` and out-of-range values are
/// "no return" (REP 117) and never become points. A value exactly at
/// `range_max` is treated as no return too: many drivers report their maximum
/// when nothing reflected, and fitting such values produces phantom walls.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// Bearing of the first beam in radians.
    pub angle_min: f32,
    /// Angle between consecutive beams in radians (may be negative).
    pub angle_increment: f32,
    /// Smallest valid range in metres.
    pub range_min: f32,
    /// Largest range in metres; returns at or beyond it are not points.
    pub range_max: f32,
    /// Measured ranges in metres, one per beam.
    pub ranges: Vec<f32>,
    /// Optional intensities, one per beam when present.
    pub intensities: Option<Vec<f32>>,
    /// Optional acquisition time in seconds (of the first beam, as ROS
    /// stamps a `LaserScan`).
    pub stamp_s: Option<f64>,
    /// Time between two consecutive beams in seconds (ROS
    /// `time_increment`), when the format carries it; what motion deskew
    /// needs ([`crate::ScanPoints::deskew`]). `None`, zero or non-finite:
    /// unknown.
    pub time_increment_s: Option<f64>,
}

impl Scan {
    /// A scan without intensities or timestamp.
    pub fn new(
        angle_min: f32,
        angle_increment: f32,
        range_min: f32,
        range_max: f32,
        ranges: Vec<f32>,
    ) -> Self {
        Scan {
            angle_min,
            angle_increment,
            range_min,
            range_max,
            ranges,
            intensities: None,
            stamp_s: None,
            time_increment_s: None,
        }
    }

    /// Sets the time between consecutive beams in seconds.
    pub fn with_time_increment(mut self, time_increment_s: f64) -> Self {
        self.time_increment_s = Some(time_increment_s);
        self
    }

    /// The time between consecutive beams when it is known and usable
    /// (finite, positive, and the whole sweep at most a second).
    pub fn beam_period_s(&self) -> Option<f64> {
        self.time_increment_s
            .filter(|t| t.is_finite() && *t > 0.0 && *t * self.ranges.len() as f64 <= 1.0)
    }

    /// Sets the acquisition time in seconds.
    pub fn with_stamp(mut self, stamp_s: f64) -> Self {
        self.stamp_s = Some(stamp_s);
        self
    }

    /// Mirrors the scan, as seen with the sensor's y axis flipped: every
    /// bearing negated (`angle_min` and `angle_increment`), the beams, their
    /// ranges and timing unchanged. A sensor mounted upside down sees the
    /// plane mirrored; its scans mirrored are those of the sensor the right
    /// way up, with its x axis where it was. Mirroring twice gives the scan
    /// back.
    ///
    /// ```
    /// use pcaline_geometry::Scan;
    /// let mut scan = Scan::new(-1.0, 0.01, 0.1, 30.0, vec![2.0; 200]);
    /// scan.mirror();
    /// assert_eq!((scan.angle_min, scan.angle_increment), (1.0, -0.01));
    /// ```
    pub fn mirror(&mut self) {
        self.angle_min = -self.angle_min;
        self.angle_increment = -self.angle_increment;
    }

    /// Number of beams.
    pub fn len(&self) -> usize {
        self.ranges.len()
    }

    /// True when the scan has no beams.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Bearing of beam `i` in radians (computed in `f64`).
    pub fn angle(&self, i: usize) -> f64 {
        f64::from(self.angle_min) + i as f64 * f64::from(self.angle_increment)
    }

    /// True when `range_m` is a valid return for this scan (finite, at least
    /// `range_min`, strictly below `range_max`).
    #[inline]
    pub fn is_valid_range(&self, range_m: f32) -> bool {
        range_m.is_finite() && range_m >= self.range_min && range_m < self.range_max
    }

    /// True when the scan's geometry is usable at all: a finite, non-zero
    /// increment and a finite start angle. A scan whose geometry is not usable
    /// yields no points.
    pub fn has_usable_geometry(&self) -> bool {
        self.angle_min.is_finite()
            && self.angle_increment.is_finite()
            && self.angle_increment != 0.0
    }

    /// True when the beams cover a full turn, so the last beam is the first
    /// beam's neighbour across the ±180° seam (within half a beam spacing).
    pub fn is_closed(&self) -> bool {
        if !self.has_usable_geometry() || self.ranges.len() < 3 {
            return false;
        }
        let step = f64::from(self.angle_increment).abs();
        let coverage = step * self.ranges.len() as f64;
        coverage >= TAU - 0.5 * step && coverage <= TAU + 0.5 * step
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validity_follows_rep117() {
        let s = Scan::new(0.0, 0.01, 0.1, 30.0, vec![]);
        assert!(s.is_valid_range(1.0));
        assert!(s.is_valid_range(0.1));
        assert!(!s.is_valid_range(0.05));
        assert!(!s.is_valid_range(30.0), "max-range returns are not points");
        assert!(!s.is_valid_range(f32::NAN));
        assert!(!s.is_valid_range(f32::INFINITY));
        assert!(!s.is_valid_range(f32::NEG_INFINITY));
    }

    #[test]
    fn closed_scan_detection() {
        let n = 1440;
        let inc = (std::f64::consts::TAU / n as f64) as f32;
        let s = Scan::new(-std::f32::consts::PI, inc, 0.1, 30.0, vec![1.0; n]);
        assert!(s.is_closed());
        let open = Scan::new(-2.356, 0.25f32.to_radians(), 0.1, 30.0, vec![1.0; 1081]);
        assert!(!open.is_closed());
        let nan = Scan::new(0.0, f32::NAN, 0.1, 30.0, vec![1.0; 10]);
        assert!(!nan.is_closed());
        assert!(!nan.has_usable_geometry());
    }
}
