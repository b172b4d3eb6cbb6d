//! The elongation test: a point set is a line when the eigenvalue ratio of its
//! covariance, `r = lambda_max / lambda_min`, exceeds `ETh` (paper, section 2).

use crate::SymmetricEigen2;

/// The eigenvalue ratio `r = lambda_max / lambda_min` of the paper.
///
/// A perfect line (`lambda_min = 0`, `lambda_max > 0`) has `r = +inf`; a set of
/// coincident points (both zero) has `r = 1`, the ratio of an isotropic set.
///
/// ```
/// use pcaline_fitting::{elongation_ratio, SymmetricEigen2};
/// assert_eq!(elongation_ratio(&SymmetricEigen2::new(4.0, 0.0, 0.0)), f64::INFINITY);
/// assert_eq!(elongation_ratio(&SymmetricEigen2::new(0.0, 0.0, 0.0)), 1.0);
/// assert_eq!(elongation_ratio(&SymmetricEigen2::new(4.0, 0.0, 1.0)), 4.0);
/// ```
pub fn elongation_ratio(eigen: &SymmetricEigen2) -> f64 {
    if eigen.lambda_max <= 0.0 {
        1.0
    } else if eigen.lambda_min <= 0.0 {
        f64::INFINITY
    } else {
        eigen.lambda_max / eigen.lambda_min
    }
}

/// True when the point set is elongated enough to be a line: `r > eth`.
pub fn is_elongated(eigen: &SymmetricEigen2, eth: f64) -> bool {
    elongation_ratio(eigen) > eth
}
