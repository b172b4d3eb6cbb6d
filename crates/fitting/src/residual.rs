//! The residual test: a fitted piece is a line only when the spread of its
//! points about the line is consistent with the sensor's range noise.

use crate::Moments;
use crate::SymmetricEigen2;
use pcaline_geometry::RangeNoise;

/// Accepts a piece when its residual standard deviation
/// `s = sqrt(N lambda_min / (N - 2))` is at most `max_sigmas` times the range
/// noise at the piece's range (the norm of its centroid, the sensor being at
/// the origin).
///
/// The eigenvalue-ratio test (`ETh`) only says a piece is elongated; an
/// L-shaped handful of points around a corner is elongated too, and fits a
/// line that belongs to neither wall. For points on a wall, `s² / sigma²`
/// follows `chi²(N - 2) / (N - 2)`, so 3 sigma rejects a true line with
/// probability below 1e-5 for 5 points and far less for more.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct ResidualTest {
    /// Largest residual std, in range-noise sigmas.
    pub max_sigmas: f64,
    /// The sensor's range noise.
    pub noise: RangeNoise,
}

impl ResidualTest {
    /// Accepts a piece whose residual standard deviation is at most
    /// `max_sigmas` range-noise sigmas of `noise`.
    pub const fn new(max_sigmas: f64, noise: RangeNoise) -> Self {
        ResidualTest { max_sigmas, noise }
    }

    /// True when the piece with `moments` (and their eigen decomposition) is
    /// consistent with the noise. Pieces of 2 points or fewer have no
    /// residual to test and are accepted.
    ///
    /// ```
    /// use pcaline_fitting::{Moments, ResidualTest};
    /// use pcaline_geometry::{Point2, RangeNoise};
    /// let test = ResidualTest::new(3.0, RangeNoise::constant(0.01));
    /// let wall: Vec<_> = (0..10).map(|i| Point2::new(2.0, 0.1 * i as f64 + if i % 2 == 0 { 0.0 } else { 0.0 })).collect();
    /// let m = Moments::from_points(&wall);
    /// assert!(test.accepts(&m, &m.eigen()));
    /// let corner: Vec<_> = (0..8).map(|i| Point2::new(2.0, 0.1 * i as f64))
    ///     .chain((1..4).map(|i| Point2::new(2.0 - 0.1 * i as f64, 0.7))).collect();
    /// let m = Moments::from_points(&corner);
    /// assert!(!test.accepts(&m, &m.eigen()));
    /// ```
    pub fn accepts(&self, moments: &Moments, eigen: &SymmetricEigen2) -> bool {
        if moments.n <= 2 {
            return true;
        }
        let n = moments.n as f64;
        let s2 = eigen.lambda_min * n / (n - 2.0);
        let sigma = self.noise.sigma_at(moments.mean.coords.norm());
        s2 <= (self.max_sigmas * sigma).powi(2)
    }
}
