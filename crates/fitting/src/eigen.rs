//! Closed-form eigen decomposition of a symmetric 2x2 matrix.
//!
//! General-purpose iterative solvers (and some `SymmetricEigen2`
//! implementations) return NaN eigenvectors when the off-diagonal term is
//! exactly zero, which is the common case of an axis-aligned wall. This closed
//! form has no such case.

use pcaline_geometry::Vector2;

/// Eigen decomposition of `[[a, b], [b, c]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymmetricEigen2 {
    /// The larger eigenvalue.
    pub lambda_max: f64,
    /// The smaller eigenvalue (clamped to `>= 0` by [`SymmetricEigen2::of_covariance`]).
    pub lambda_min: f64,
    /// Unit eigenvector of `lambda_max` (the major axis).
    pub major: Vector2<f64>,
}

impl SymmetricEigen2 {
    /// Eigenvalues and major eigenvector of the symmetric matrix `[[a, b], [b, c]]`.
    ///
    /// When the two eigenvalues are equal (an isotropic point set) every
    /// direction is an eigenvector and `major` is the x axis.
    ///
    /// ```
    /// use pcaline_fitting::SymmetricEigen2;
    /// let e = SymmetricEigen2::new(1.0, 0.0, 4.0); // axis-aligned: no NaN
    /// assert_eq!(e.lambda_max, 4.0);
    /// assert_eq!(e.lambda_min, 1.0);
    /// assert!(e.major.x.abs() < 1e-15 && (e.major.y.abs() - 1.0).abs() < 1e-15);
    /// ```
    #[inline]
    pub fn new(a: f64, b: f64, c: f64) -> Self {
        let mean = 0.5 * (a + c);
        let half_diff = 0.5 * (a - c);
        // sqrt(x² + y²) rather than hypot: 5x faster, and covariance entries
        // of f32 ranges (at most ~1e77 when squared) cannot overflow it.
        let h = (half_diff * half_diff + b * b).sqrt();
        let lambda_max = mean + h;
        let lambda_min = mean - h;
        // (h + half_diff, b) and (b, h - half_diff) are both eigenvectors of
        // lambda_max; take the one that is better conditioned.
        let major = if half_diff >= 0.0 {
            Vector2::new(h + half_diff, b)
        } else {
            Vector2::new(b, h - half_diff)
        };
        let norm = major.norm();
        let major = if norm > 0.0 { major / norm } else { Vector2::new(1.0, 0.0) };
        SymmetricEigen2 { lambda_max, lambda_min, major }
    }

    /// As [`SymmetricEigen2::new`] for a covariance matrix: rounding can make
    /// the smaller eigenvalue of a positive semi-definite matrix slightly
    /// negative, so it is clamped to zero.
    #[inline]
    pub fn of_covariance(sxx: f64, sxy: f64, syy: f64) -> Self {
        let mut e = Self::new(sxx, sxy, syy);
        e.lambda_min = e.lambda_min.max(0.0);
        e.lambda_max = e.lambda_max.max(0.0);
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn satisfies_eigen_equation(a in -10.0f64..10.0, b in -10.0f64..10.0, c in -10.0f64..10.0) {
            let e = SymmetricEigen2::new(a, b, c);
            let v = e.major;
            let av = Vector2::new(a * v.x + b * v.y, b * v.x + c * v.y);
            prop_assert!((av - v * e.lambda_max).norm() < 1e-9 * (1.0 + e.lambda_max.abs()));
            prop_assert!((v.norm() - 1.0).abs() < 1e-12);
            prop_assert!(e.lambda_max >= e.lambda_min);
            prop_assert!((e.lambda_max + e.lambda_min - (a + c)).abs() < 1e-9);
        }
    }

    #[test]
    fn axis_aligned_cases() {
        let e = SymmetricEigen2::new(4.0, 0.0, 1.0);
        assert_eq!(e.major, Vector2::new(1.0, 0.0));
        let e = SymmetricEigen2::new(0.0, 0.0, 0.0);
        assert_eq!(e.major, Vector2::new(1.0, 0.0));
        assert_eq!(e.lambda_min, 0.0);
    }
}
