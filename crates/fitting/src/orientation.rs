//! The orientation test: a final line is reported only when the sensor noise
//! determines its orientation well enough to be useful.

use crate::Moments;
use crate::SymmetricEigen2;
use pcaline_geometry::RangeNoise;

/// Accepts a line when the standard deviation of its orientation predicted
/// from the range noise, `sigma / sqrt(N lambda_max)` (the Cramer-Rao bound
/// `sqrt(12 / N) sigma / L` for evenly spaced points), is at most
/// `max_std_rad`. `sigma` is the noise at the line's range (the norm of its
/// centroid, the sensor at the origin).
///
/// The paper's `ETh` test asks for `L > sqrt(12 ETh) sigma`, a length that
/// grows with the noise but ignores how many points support the line; this
/// test asks directly whether the orientation is known. Under noise a short
/// wall's orientation is not: at 30 mm a 0.4 m wall seen with 15 points has
/// a standard deviation near 4°.
///
/// ```
/// use pcaline_fitting::{Moments, OrientationTest};
/// use pcaline_geometry::{Point2, RangeNoise};
/// let test = OrientationTest::new(1f64.to_radians(), RangeNoise::constant(0.01));
/// let wall = |n: usize, len: f64| -> Moments {
///     Moments::from_points(&(0..n).map(|i| Point2::new(3.0, len * i as f64 / (n - 1) as f64)).collect::<Vec<_>>())
/// };
/// let (long, short) = (wall(40, 2.0), wall(10, 0.2));
/// assert!(test.accepts(&long, &long.eigen()));   // 0.05°
/// assert!(!test.accepts(&short, &short.eigen())); // 3.2°
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct OrientationTest {
    /// Largest predicted orientation standard deviation, radians.
    pub max_std_rad: f64,
    /// The sensor's range noise.
    pub noise: RangeNoise,
}

impl OrientationTest {
    /// Accepts a line whose orientation standard deviation under range
    /// noise `noise` is at most `max_std_rad` radians.
    pub const fn new(max_std_rad: f64, noise: RangeNoise) -> Self {
        OrientationTest { max_std_rad, noise }
    }

    /// The predicted orientation standard deviation of the line through the
    /// points with `moments`, radians (`inf` for fewer than 2 points or no
    /// spread).
    pub fn predicted_std_rad(&self, moments: &Moments, eigen: &SymmetricEigen2) -> f64 {
        let information = moments.n as f64 * eigen.lambda_max;
        if moments.n < 2 || information.is_nan() || information <= 0.0 {
            return f64::INFINITY;
        }
        self.noise.sigma_at(moments.mean.coords.norm()) / information.sqrt()
    }

    /// True when the predicted standard deviation is at most `max_std_rad`.
    pub fn accepts(&self, moments: &Moments, eigen: &SymmetricEigen2) -> bool {
        self.predicted_std_rad(moments, eigen) <= self.max_std_rad
    }

    /// True when no line fitted to some of the points with `moments` can be
    /// accepted either: the whole set fails even at the smaller of the two
    /// range bands' sigmas. A subset's scatter matrix is at most the whole
    /// set's (`N lambda_max` can only fall), and only its centroid, which
    /// picks the band, can move; so a line cut shorter by later tests need
    /// not be cut first.
    ///
    /// Edge cases: `moments` of fewer than 2 points, no spread or non-finite
    /// sums give `false` (nothing is claimed).
    ///
    /// ```
    /// use pcaline_fitting::{Moments, OrientationTest};
    /// use pcaline_geometry::{Point2, RangeNoise};
    /// let test = OrientationTest::new(1f64.to_radians(), RangeNoise::constant(0.01));
    /// let wall = |n: usize, len: f64| -> Moments {
    ///     Moments::from_points(&(0..n).map(|i| Point2::new(3.0, len * i as f64 / (n - 1) as f64)).collect::<Vec<_>>())
    /// };
    /// let (long, short) = (wall(40, 2.0), wall(10, 0.2));
    /// assert!(!test.rejects_every_part(&long, &long.eigen()));
    /// assert!(test.rejects_every_part(&short, &short.eigen()));
    /// ```
    pub fn rejects_every_part(&self, moments: &Moments, eigen: &SymmetricEigen2) -> bool {
        let information = moments.n as f64 * eigen.lambda_max;
        let quietest = self.noise.near_sigma_m.min(self.noise.far_sigma_m);
        moments.n >= 2
            && information > 0.0
            && information.is_finite()
            && quietest > self.max_std_rad * information.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::Point2;
    use proptest::prelude::*;

    proptest! {
        /// Whatever run of a set's points a later test keeps, a set that
        /// rejects every part has none accepted: the bound holds across the
        /// two range bands (walls around the 5 m band edge).
        #[test]
        fn no_part_of_a_set_rejecting_every_part_is_accepted(
            range in 4.0f64..6.0,
            along in prop::collection::vec((0.0f64..1.0, -0.02f64..0.02), 4..40),
            length in 0.05f64..1.0,
            max_std_deg in 0.2f64..5.0,
            (first, len) in (0usize..40, 2usize..40),
        ) {
            // A wall across the beam at `range`, ending near the band edge.
            let pts: Vec<_> = along
                .iter()
                .map(|&(t, off)| Point2::new(range + off + 0.5 * t * length, t * length))
                .collect();
            let mut noise = RangeNoise::constant(0.01);
            (noise.far_sigma_m, noise.far_from_m) = (0.03, 5.0);
            let test = OrientationTest::new(max_std_deg.to_radians(), noise);
            let whole = Moments::from_points(&pts);
            prop_assume!(test.rejects_every_part(&whole, &whole.eigen()));
            let first = first % pts.len();
            let part = Moments::from_points(&pts[first..(first + len).min(pts.len())]);
            prop_assert!(!test.accepts(&part, &part.eigen()));
        }
    }
}
