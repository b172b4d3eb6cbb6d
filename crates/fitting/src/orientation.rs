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
}
