//! PCA line fit (paper eq. 3, 5, 6): the line through the centroid along the
//! major eigenvector of the points' covariance, with endpoints projected from
//! the first and last point and the (alpha, d) covariance.

use crate::{Moments, SymmetricEigen2};
use pcaline_geometry::{LineSegment, Matrix2, Point2, SlopeIntercept, Vector2};

/// Fits a line to `points` by PCA (eq. 3, 5, 6), without the elongation test.
///
/// Returns `None` when there are fewer than 2 points, when all points coincide
/// (no direction), or when a coordinate is not finite. A perfect line
/// (`lambda_min = 0`) is a valid fit with zero residual.
///
/// ```
/// use pcaline_fitting::fit_pca;
/// use pcaline_geometry::Point2;
/// let pts: Vec<_> = (0..10).map(|i| Point2::new(3.0, i as f64 * 0.1)).collect();
/// let line = fit_pca(&pts).unwrap();   // a vertical wall at x = 3
/// assert!(line.alpha().abs() < 1e-12 && (line.d() - 3.0).abs() < 1e-12);
/// assert!((line.length() - 0.9).abs() < 1e-12);
/// ```
pub fn fit_pca(points: &[Point2<f64>]) -> Option<LineSegment> {
    let (first, last) = (points.first()?, points.last()?);
    line_from_moments(&Moments::from_points(points), first, last)
}

/// The paper's PCA fit as `y = m_L x + n_L` (eq. 3-6): the covariance `Q`,
/// its major eigenvector `(lambda_x, lambda_y)`, `m_L = lambda_y / lambda_x`
/// (eq. 5) and `n_L = y_C - m_L x_C` (eq. 6). This is what the paper times
/// against least squares (Table 1); [`fit_pca`] builds a whole
/// [`LineSegment`] (Hessian form, endpoints, covariance) instead.
///
/// `None` for fewer than 2 points, coincident points, or a vertical line
/// (eq. 5 is undefined there).
///
/// ```
/// use pcaline_fitting::fit_pca_slope_intercept;
/// use pcaline_geometry::Point2;
/// let pts = [Point2::new(0.0, 1.0), Point2::new(1.0, 3.0), Point2::new(2.0, 5.0)];
/// let f = fit_pca_slope_intercept(&pts).unwrap();
/// assert!((f.m - 2.0).abs() < 1e-12 && (f.n - 1.0).abs() < 1e-12);
/// ```
pub fn fit_pca_slope_intercept(points: &[Point2<f64>]) -> Option<SlopeIntercept> {
    if points.len() < 2 {
        return None;
    }
    let moments = Moments::from_points(points);
    // The major eigenvector of the scatter (Q times N has the same
    // eigenvectors), unnormalised: eq. 5 only needs its slope.
    let (a, b, c) = (moments.sxx, moments.sxy, moments.syy);
    let half_diff = 0.5 * (a - c);
    let h = (half_diff * half_diff + b * b).sqrt();
    let (vx, vy) = if half_diff >= 0.0 { (h + half_diff, b) } else { (b, h - half_diff) };
    if h <= 0.0 && half_diff == 0.0 || vx.abs() <= 1e-12 * vy.abs() {
        return None; // coincident points, or vertical
    }
    let m = vy / vx;
    let fit = SlopeIntercept { m, n: moments.mean.y - m * moments.mean.x };
    (fit.m.is_finite() && fit.n.is_finite()).then_some(fit)
}

/// The PCA line (eq. 5, 6) of a point set given its [`Moments`] and its first
/// and last points (for the endpoints).
///
/// The covariance of (alpha, d) is the first-order propagation of an
/// isotropic point noise whose variance is estimated from the residuals
/// (`s² = N lambda_min / (N - 2)`): `var(alpha) = s² / (N lambda_max)`,
/// `cov(alpha, d) = t var(alpha)`, `var(d) = s² / N + t² var(alpha)`, where `t`
/// is the centroid's coordinate along the line from the foot of the normal.
pub fn line_from_moments(
    moments: &Moments,
    first: &Point2<f64>,
    last: &Point2<f64>,
) -> Option<LineSegment> {
    if moments.n < 2 {
        return None;
    }
    let eigen = moments.eigen();
    line_from_eigen(moments, &eigen, first, last)
}

/// As [`line_from_moments`] with the eigen decomposition already computed.
pub fn line_from_eigen(
    moments: &Moments,
    eigen: &SymmetricEigen2,
    first: &Point2<f64>,
    last: &Point2<f64>,
) -> Option<LineSegment> {
    let finite = moments.mean.x.is_finite()
        && moments.mean.y.is_finite()
        && eigen.lambda_max.is_finite()
        && eigen.lambda_min.is_finite();
    if moments.n < 2 || !finite || eigen.lambda_max <= 0.0 {
        return None;
    }
    let line = LineSegment::through(moments.mean, eigen.major, *first, *last);
    let n = moments.n as f64;
    let s2 = if moments.n > 2 { eigen.lambda_min * n / (n - 2.0) } else { 0.0 };
    let var_alpha = s2 / (n * eigen.lambda_max);
    let tangent = Vector2::new(-line.alpha().sin(), line.alpha().cos());
    let t = tangent.dot(&line.centroid().coords);
    let covariance =
        Matrix2::new(var_alpha, t * var_alpha, t * var_alpha, s2 / n + t * t * var_alpha);
    Some(line.with_statistics(moments.n, s2.sqrt(), covariance))
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::{Pose2, line_angle_diff};
    use proptest::prelude::*;
    use rand::{SeedableRng, rngs::StdRng};
    use rand_distr::{Distribution, Normal};

    #[test]
    fn horizontal_wall() {
        let pts: Vec<_> = (0..20).map(|i| Point2::new(i as f64 * 0.1 - 1.0, -2.0)).collect();
        let l = fit_pca(&pts).unwrap();
        assert!((l.alpha() + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((l.d() - 2.0).abs() < 1e-12);
        assert_eq!(l.residual_std(), 0.0);
        assert_eq!(l.n_points(), 20);
    }

    #[test]
    fn wall_through_sensor_x_axis() {
        // Points along the x axis itself: the line passes through the origin.
        let pts: Vec<_> = (1..30).map(|i| Point2::new(i as f64 * 0.1, 0.0)).collect();
        let l = fit_pca(&pts).unwrap();
        assert_eq!(l.d(), 0.0);
        assert!((l.alpha().abs() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn slope_intercept_fit_agrees_with_the_full_fit() {
        let mut rng = StdRng::seed_from_u64(3);
        let noise = Normal::new(0.0, 0.05).unwrap();
        for slope in [-3.0, -0.5, 0.0, 0.2, 4.0] {
            let pts: Vec<_> = (0..60)
                .map(|i| {
                    let x = i as f64 * 0.05;
                    Point2::new(x, slope * x + 1.0 + noise.sample(&mut rng))
                })
                .collect();
            let a = fit_pca_slope_intercept(&pts).unwrap();
            let b = fit_pca(&pts).unwrap().slope_intercept().unwrap();
            assert!((a.m - b.m).abs() < 1e-9 && (a.n - b.n).abs() < 1e-9, "{a:?} {b:?}");
        }
        let vertical: Vec<_> = (0..5).map(|i| Point2::new(1.0, i as f64)).collect();
        assert!(fit_pca_slope_intercept(&vertical).is_none());
        assert!(fit_pca_slope_intercept(&[Point2::new(1.0, 1.0); 4]).is_none());
    }

    #[test]
    fn degenerate_inputs() {
        assert!(fit_pca(&[]).is_none());
        assert!(fit_pca(&[Point2::new(1.0, 1.0)]).is_none());
        assert!(
            fit_pca(&[Point2::new(1.0, 1.0); 5]).is_none(),
            "coincident points have no direction"
        );
        assert!(fit_pca(&[Point2::new(f64::NAN, 1.0), Point2::new(1.0, 1.0)]).is_none());
    }

    #[test]
    fn covariance_matches_monte_carlo() {
        // Wall 2 m long, 3 m away, sigma 2 cm orthogonal noise, 100 points.
        let mut rng = StdRng::seed_from_u64(7);
        let noise = Normal::new(0.0, 0.02).unwrap();
        let (mut sa, mut sd, mut pred_a, mut pred_d) = (0.0, 0.0, 0.0, 0.0);
        let runs = 2000;
        for _ in 0..runs {
            let pts: Vec<_> = (0..100)
                .map(|i| Point2::new(3.0 + noise.sample(&mut rng), -1.0 + 0.02 * i as f64 + 0.5))
                .collect();
            let l = fit_pca(&pts).unwrap();
            let a = line_angle_diff(l.alpha(), 0.0);
            sa += a * a;
            sd += (l.d() - 3.0).powi(2);
            pred_a += l.covariance()[(0, 0)];
            pred_d += l.covariance()[(1, 1)];
        }
        let ratio_a = sa / pred_a;
        let ratio_d = sd / pred_d;
        assert!((0.85..1.15).contains(&ratio_a), "alpha variance ratio {ratio_a}");
        assert!((0.85..1.15).contains(&ratio_d), "d variance ratio {ratio_d}");
    }

    /// Points along a line of direction `angle` from a random start.
    fn collinear() -> impl Strategy<Value = (Vec<Point2<f64>>, f64)> {
        (-3.2f64..3.2, -20.0f64..20.0, -20.0f64..20.0, 3usize..200, 0.001f64..0.5).prop_map(
            |(angle, cx, cy, n, step)| {
                let dir = Vector2::new(angle.cos(), angle.sin());
                let pts = (0..n).map(|i| Point2::new(cx, cy) + dir * (i as f64 * step)).collect();
                (pts, angle)
            },
        )
    }

    proptest! {
        #[test]
        fn recovers_collinear_points((pts, angle) in collinear()) {
            let l = fit_pca(&pts).unwrap();
            prop_assert!(line_angle_diff(l.direction_angle(), angle).abs() < 1e-9);
            for p in &pts {
                prop_assert!(l.signed_distance(p).abs() < 1e-9);
            }
            prop_assert!(l.residual_std() < 1e-6);
        }

        #[test]
        fn invariant_under_rigid_transform(
            seed in 0u64..1000, x in -30.0f64..30.0, y in -30.0f64..30.0, h in -3.2f64..3.2
        ) {
            let mut rng = StdRng::seed_from_u64(seed);
            let noise = Normal::new(0.0, 0.03).unwrap();
            let pts: Vec<_> = (0..50)
                .map(|i| Point2::new(i as f64 * 0.05, 1.0 + 0.3 * i as f64 * 0.05 + noise.sample(&mut rng)))
                .collect();
            let pose = Pose2::new(x, y, h);
            let moved: Vec<_> = pts.iter().map(|p| pose.transform_point(p)).collect();
            let a = fit_pca(&pts).unwrap().transformed(&pose);
            let b = fit_pca(&moved).unwrap();
            prop_assert!(line_angle_diff(a.alpha(), b.alpha()).abs() < 1e-9);
            prop_assert!((a.d() - b.d()).abs() < 1e-8);
            prop_assert!((a.start() - b.start()).norm() < 1e-8 && (a.end() - b.end()).norm() < 1e-8);
            prop_assert!((a.residual_std() - b.residual_std()).abs() < 1e-9);
        }
    }
}
