//! Polar to Cartesian conversion (paper eq. 1) with a cached cos/sin table.

use crate::{Scan, Twist2};
use nalgebra::Point2;

/// Converts one return to a point in the sensor frame: `x = r cos(theta)`,
/// `y = r sin(theta)` (paper eq. 1).
#[inline]
pub fn polar_to_cartesian(range_m: f64, angle_rad: f64) -> Point2<f64> {
    let (s, c) = angle_rad.sin_cos();
    Point2::new(range_m * c, range_m * s)
}

/// A cos/sin table for one scan geometry (angle_min, angle_increment, beam count).
///
/// [`BearingTable::update`] recomputes the table only when the geometry changes,
/// comparing the exact bits, so a log whose later scans have another geometry
/// never reuses stale bearings.
#[derive(Debug, Clone, Default)]
pub struct BearingTable {
    key: Option<(u32, u32, usize)>,
    angles: Vec<f64>,
    cos: Vec<f64>,
    sin: Vec<f64>,
}

impl BearingTable {
    /// Makes the table match `scan`'s geometry.
    pub fn update(&mut self, scan: &Scan) {
        let key = (scan.angle_min.to_bits(), scan.angle_increment.to_bits(), scan.len());
        if self.key == Some(key) {
            return;
        }
        self.key = Some(key);
        self.angles.clear();
        self.cos.clear();
        self.sin.clear();
        for i in 0..scan.len() {
            let a = scan.angle(i);
            let (s, c) = a.sin_cos();
            self.angles.push(a);
            self.cos.push(c);
            self.sin.push(s);
        }
    }

    /// Bearing of each beam in radians.
    pub fn angles(&self) -> &[f64] {
        &self.angles
    }

    /// Cosine of each beam's bearing.
    pub fn cos(&self) -> &[f64] {
        &self.cos
    }

    /// Sine of each beam's bearing.
    pub fn sin(&self) -> &[f64] {
        &self.sin
    }
}

/// The valid returns of one scan as points in the sensor frame, in beam order,
/// with the range, bearing and beam index of each (structure of arrays).
///
/// Buffers are reused across scans: filling allocates only when a scan has more
/// valid returns than any before it.
#[derive(Debug, Clone, Default)]
pub struct ScanPoints {
    /// Points in the sensor frame, metres.
    pub xy: Vec<Point2<f64>>,
    /// Range of each point in metres.
    pub range_m: Vec<f64>,
    /// Bearing of each point in radians (unwrapped, as `angle_min + i * increment`).
    pub angle_rad: Vec<f64>,
    /// Index of the beam each point came from.
    pub beam: Vec<u32>,
}

impl ScanPoints {
    /// Replaces the content with the valid returns of `scan` (eq. 1), using and
    /// updating `table`. A scan with unusable geometry (NaN or zero increment)
    /// gives no points.
    pub fn fill_from(&mut self, scan: &Scan, table: &mut BearingTable) {
        if !scan.has_usable_geometry() {
            self.clear();
            return;
        }
        table.update(scan);
        let n = scan.ranges.len();
        // Every beam is written to the next free slot, which advances only
        // when the range is valid: no branch on the data and no capacity
        // check per point. The buffers hold a slot per beam; those beyond
        // the last scan's points are filled once, then cut off below.
        self.xy.resize(n, Point2::origin());
        self.range_m.resize(n, 0.0);
        self.angle_rad.resize(n, 0.0);
        self.beam.resize(n, 0);
        let (xy, range_m) = (&mut self.xy[..n], &mut self.range_m[..n]);
        let (angle_rad, beam) = (&mut self.angle_rad[..n], &mut self.beam[..n]);
        // Most scans have no invalid range: then every beam is a point, and
        // each output is one loop over whole slices that the compiler
        // vectorises (the same products as below, so the same points).
        let valid = scan.ranges.iter().fold(true, |all, &r| all & scan.is_valid_range(r));
        if valid {
            for (p, (&r, (&c, &s))) in
                xy.iter_mut().zip(scan.ranges.iter().zip(table.cos.iter().zip(&table.sin)))
            {
                let r64 = f64::from(r);
                *p = Point2::new(r64 * c, r64 * s);
            }
            for (m, &r) in range_m.iter_mut().zip(&scan.ranges) {
                *m = f64::from(r);
            }
            angle_rad.copy_from_slice(&table.angles[..n]);
            for (i, b) in beam.iter_mut().enumerate() {
                *b = i as u32;
            }
            return;
        }
        let mut k = 0;
        // Zipped iterators: no bounds checks on the inputs.
        let bearings = table.cos.iter().zip(&table.sin).zip(&table.angles);
        for (i, (&r, ((&c, &s), &a))) in scan.ranges.iter().zip(bearings).enumerate() {
            let r64 = f64::from(r);
            // `k <= i < n`: the slot exists.
            xy[k] = Point2::new(r64 * c, r64 * s);
            range_m[k] = r64;
            angle_rad[k] = a;
            beam[k] = i as u32;
            k += usize::from(scan.is_valid_range(r));
        }
        self.xy.truncate(k);
        self.range_m.truncate(k);
        self.angle_rad.truncate(k);
        self.beam.truncate(k);
    }

    /// Motion deskew: moves every point to where it lies in the sensor
    /// frame of the first beam, for a sensor moving with the constant
    /// velocity `velocity` (metres and radians per second, in its own frame)
    /// and beams `beam_period_s` seconds apart. Point `k` of beam `i` was
    /// taken `i * beam_period_s` after the first beam, from the pose
    /// `exp(velocity * t)` (the exact constant-twist motion,
    /// [`Twist2::motion_over`]).
    ///
    /// Ranges and bearings are left as measured. A non-finite velocity or
    /// period leaves the points as they are.
    pub fn deskew(&mut self, velocity: &Twist2, beam_period_s: f64) {
        if !(velocity.is_finite() && beam_period_s.is_finite() && beam_period_s > 0.0) {
            return;
        }
        for (p, &beam) in self.xy.iter_mut().zip(&self.beam) {
            let first_from_beam = velocity.motion_over(f64::from(beam) * beam_period_s);
            *p = first_from_beam.transform_point(p);
        }
    }

    /// Removes all points, keeping the buffers.
    pub fn clear(&mut self) {
        self.xy.clear();
        self.range_m.clear();
        self.angle_rad.clear();
        self.beam.clear();
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.xy.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.xy.is_empty()
    }

    /// Point `i` in the sensor frame.
    #[inline]
    pub fn point(&self, i: usize) -> Point2<f64> {
        self.xy[i]
    }

    /// Rotates the points so that point `start` comes first. Used for closed
    /// (360°) scans so that a wall across the ±180° seam is one contiguous run.
    /// Bearings of the moved points are shifted by a full turn so that they stay
    /// monotonic in the scan direction.
    pub fn rotate_start(&mut self, start: usize, turn_rad: f64) {
        if start == 0 || start >= self.len() {
            return;
        }
        for a in &mut self.angle_rad[..start] {
            *a += turn_rad;
        }
        self.xy.rotate_left(start);
        self.range_m.rotate_left(start);
        self.angle_rad.rotate_left(start);
        self.beam.rotate_left(start);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_follows_geometry_changes() {
        let mut t = BearingTable::default();
        let a = Scan::new(0.0, 0.1, 0.0, 10.0, vec![1.0; 3]);
        t.update(&a);
        assert!((t.angles()[2] - 0.2).abs() < 1e-6);
        let b = Scan::new(1.0, -0.1, 0.0, 10.0, vec![1.0; 4]);
        t.update(&b);
        assert_eq!(t.angles().len(), 4);
        assert!((t.angles()[3] - 0.7).abs() < 1e-6);
    }

    #[test]
    fn invalid_returns_are_not_points() {
        let s = Scan::new(
            0.0,
            0.1,
            0.2,
            10.0,
            vec![1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.1, 10.0, 11.0, 2.0],
        );
        let mut t = BearingTable::default();
        let mut p = ScanPoints::default();
        p.fill_from(&s, &mut t);
        assert_eq!(p.beam, vec![0, 7]);
        assert!((p.point(1) - polar_to_cartesian(2.0, 0.7)).norm() < 1e-6);
    }

    proptest::proptest! {
        /// Every valid beam, in order, bit for bit the product of its
        /// range and its cached bearing, whether the scan takes the path
        /// for scans without an invalid range or the one that skips them;
        /// buffers reused from a longer scan are cut to the points.
        #[test]
        fn points_are_the_valid_beams_in_order(
            ranges in proptest::collection::vec(
                proptest::prop_oneof![60 => 0.05f32..40.0, 1 => proptest::strategy::Just(f32::NAN)],
                0..120,
            ),
            previous in 0usize..300,
        ) {
            let scan = Scan::new(-2.0, 0.01, 0.1, 30.0, ranges);
            let mut table = BearingTable::default();
            let mut p = ScanPoints::default();
            p.fill_from(&Scan::new(-2.0, 0.02, 0.1, 30.0, vec![1.0; previous]), &mut table);
            p.fill_from(&scan, &mut table);
            let valid: Vec<usize> =
                (0..scan.len()).filter(|&i| scan.is_valid_range(scan.ranges[i])).collect();
            proptest::prop_assert_eq!(p.len(), valid.len());
            for (k, &i) in valid.iter().enumerate() {
                let r = f64::from(scan.ranges[i]);
                proptest::prop_assert_eq!(p.beam[k], i as u32);
                proptest::prop_assert_eq!(p.range_m[k], r);
                proptest::prop_assert_eq!(p.angle_rad[k], table.angles()[i]);
                let want = Point2::new(r * table.cos()[i], r * table.sin()[i]);
                proptest::prop_assert_eq!(p.xy[k], want);
            }
        }
    }

    #[test]
    fn nan_increment_gives_no_points() {
        let s = Scan::new(0.0, f32::NAN, 0.2, 10.0, vec![1.0; 5]);
        let mut p = ScanPoints::default();
        p.fill_from(&s, &mut BearingTable::default());
        assert!(p.is_empty());
    }
}
