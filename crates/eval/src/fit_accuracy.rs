//! Fit accuracy against the Cramer-Rao bound, and consistency of the fitted
//! (alpha, d) covariance (normalised estimation error squared), by Monte Carlo.
//!
//! A wall of `n` points spaced `spacing_m` along a line at a random pose,
//! with Gaussian noise `sigma_m` across it (the model under which PCA is the
//! maximum-likelihood estimator). The bound for the orientation is
//! `sigma / sqrt(sum t_i²)` (`t_i` along the line from the centroid, about
//! `sqrt(12 / n) sigma / L`) and for the offset of the line at its centroid
//! `sigma / sqrt(n)`.

use pcaline_fitting::fit_pca;
use pcaline_geometry::{Matrix2, Point2, Vector2, line_angle_diff};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};

/// One wall setting.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct FitAccuracy {
    /// Points.
    pub n: usize,
    /// Wall length, metres.
    pub length_m: f64,
    /// Noise across the wall, metres.
    pub sigma_m: f64,
    /// Runs.
    pub runs: usize,
    /// Standard deviation of the orientation error, radians.
    pub std_alpha_rad: f64,
    /// Its Cramer-Rao bound, radians.
    pub crb_alpha_rad: f64,
    /// Standard deviation of the offset at the centroid, metres.
    pub std_offset_m: f64,
    /// Its Cramer-Rao bound, metres.
    pub crb_offset_m: f64,
    /// Mean normalised estimation error squared of (alpha, d) with the
    /// fitted covariance: `2 (n - 2) / (n - 4)` for a consistent covariance
    /// whose noise variance is estimated from the residuals.
    pub mean_nees: f64,
}

/// Runs `runs` fits of a wall of `n` points over `length_m` with noise `sigma_m`.
pub fn fit_accuracy(n: usize, length_m: f64, sigma_m: f64, runs: usize, seed: u64) -> FitAccuracy {
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma_m).expect("sigma is finite");
    let spacing = length_m / (n.max(2) - 1) as f64;
    let (mut sa, mut so, mut nees) = (0.0, 0.0, 0.0);
    let mut pts = Vec::with_capacity(n);
    let mut used = 0usize;
    for _ in 0..runs {
        // A random wall pose, 1-10 m from the sensor.
        let angle = rng.random_range(-3.1..3.1);
        let dir = Vector2::new(f64::cos(angle), f64::sin(angle));
        let normal = Vector2::new(-dir.y, dir.x);
        let centre = Point2::new(rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0));
        pts.clear();
        for i in 0..n {
            let t = (i as f64 - (n - 1) as f64 / 2.0) * spacing;
            pts.push(centre + dir * t + normal * noise.sample(&mut rng));
        }
        let Some(line) = fit_pca(&pts) else { continue };
        let truth = pcaline_geometry::LineSegment::through(centre, dir, centre - dir, centre + dir);
        let da = line_angle_diff(line.alpha(), truth.alpha());
        let offset = truth.signed_distance(&line.centroid());
        // d of the fit against the true line's d in the truth's normal
        // convention: for a line near the origin the fit's normal may point
        // the other way (alpha + pi, d -> -d), which also flips the sign of
        // the covariance's cross term.
        let same_normal = (line.alpha() - truth.alpha()).cos() >= 0.0;
        let dd = if same_normal { line.d() - truth.d() } else { -line.d() - truth.d() };
        let e = Vector2::new(da, dd);
        let mut p: Matrix2<f64> = line.covariance();
        if !same_normal {
            p[(0, 1)] = -p[(0, 1)];
            p[(1, 0)] = -p[(1, 0)];
        }
        if let Some(inv) = p.try_inverse() {
            nees += (e.transpose() * inv * e)[(0, 0)];
        }
        sa += da * da;
        so += offset * offset;
        used += 1;
    }
    let m = used.max(1) as f64;
    let sum_t2: f64 = (0..n).map(|i| ((i as f64 - (n - 1) as f64 / 2.0) * spacing).powi(2)).sum();
    FitAccuracy {
        n,
        length_m,
        sigma_m,
        runs: used,
        std_alpha_rad: (sa / m).sqrt(),
        crb_alpha_rad: sigma_m / sum_t2.sqrt(),
        std_offset_m: (so / m).sqrt(),
        crb_offset_m: sigma_m / (n as f64).sqrt(),
        mean_nees: nees / m,
    }
}

/// Accuracy and consistency of the unweighted (PCA) and the weighted fit
/// (Pfister et al.) under range-and-bearing noise, by Monte Carlo.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct RangeBearingAccuracy {
    /// Beams on the wall.
    pub n: usize,
    /// Runs.
    pub runs: usize,
    /// Orientation error std of the unweighted fit, radians.
    pub std_alpha_pca_rad: f64,
    /// Orientation error std of the weighted fit, radians.
    pub std_alpha_weighted_rad: f64,
    /// The Cramer-Rao bound of the orientation (weighted information at the truth), radians.
    pub crb_alpha_rad: f64,
    /// Mean NEES of the unweighted fit with its range-and-bearing covariance (2 when consistent).
    pub nees_pca: f64,
    /// Mean NEES of the weighted fit with its covariance (2 when consistent).
    pub nees_weighted: f64,
}

/// A wall `x cos(0.3) + y sin(0.3) = 4 m` seen from the origin by beams 0.25°
/// apart from -0.6 to 1.2 rad (ranges 4-14 m, oblique incidence), range noise
/// as the UTM-30LX-EW's datasheet (10 mm below 10 m, 30 mm beyond) and
/// bearing noise `sigma_bearing_rad`; covariances evaluated at the estimates.
pub fn range_bearing_accuracy(
    sigma_bearing_rad: f64,
    runs: usize,
    seed: u64,
) -> RangeBearingAccuracy {
    use pcaline_fitting::{fit_weighted, pca_covariance, point_covariance};
    use pcaline_geometry::polar_to_cartesian;
    use rand_distr::StandardNormal;
    let (phi, d) = (0.3, 4.0);
    let step = 0.25f64.to_radians();
    let truth: Vec<(f64, f64)> = (0..=((1.8 / step) as usize))
        .map(|i| -0.6 + i as f64 * step)
        .map(|b| (d / (b - phi).cos(), b))
        .collect();
    let sigma_r = |r: f64| if r < 10.0 { 0.01 } else { 0.03 };
    let mut rng = StdRng::seed_from_u64(seed);
    let (mut nees_pca, mut nees_w, mut sq_pca, mut sq_w, mut used) = (0.0, 0.0, 0.0, 0.0, 0usize);
    let nees = |alpha: f64, dd: f64, c: &Matrix2<f64>| {
        let e = Vector2::new(line_angle_diff(alpha, phi), dd - d);
        c.try_inverse().map(|inv| (e.transpose() * inv * e)[(0, 0)])
    };
    let (mut pts, mut covs) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        pts.clear();
        covs.clear();
        for &(r, b) in &truth {
            let nr: f64 = StandardNormal.sample(&mut rng);
            let nb: f64 = StandardNormal.sample(&mut rng);
            let (rm, bm) = (r + sigma_r(r) * nr, b + sigma_bearing_rad * nb);
            pts.push(polar_to_cartesian(rm, bm));
            covs.push(point_covariance(rm, bm, sigma_r(rm), sigma_bearing_rad));
        }
        let (Some(pca), Some(w)) = (fit_pca(&pts), fit_weighted(&pts, &covs, 3)) else { continue };
        let Some(cov_pca) = pca_covariance(&pca, &pts, &covs) else { continue };
        let (Some(a), Some(b)) =
            (nees(pca.alpha(), pca.d(), &cov_pca), nees(w.alpha(), w.d(), &w.covariance()))
        else {
            continue;
        };
        nees_pca += a;
        nees_w += b;
        sq_pca += line_angle_diff(pca.alpha(), phi).powi(2);
        sq_w += line_angle_diff(w.alpha(), phi).powi(2);
        used += 1;
    }
    // The bound: the weighted information at the true points.
    let exact: Vec<_> = truth.iter().map(|&(r, b)| polar_to_cartesian(r, b)).collect();
    let exact_covs: Vec<_> =
        truth.iter().map(|&(r, b)| point_covariance(r, b, sigma_r(r), sigma_bearing_rad)).collect();
    let crb =
        fit_weighted(&exact, &exact_covs, 1).map_or(f64::NAN, |l| l.covariance()[(0, 0)].sqrt());
    let m = used.max(1) as f64;
    RangeBearingAccuracy {
        n: truth.len(),
        runs: used,
        std_alpha_pca_rad: (sq_pca / m).sqrt(),
        std_alpha_weighted_rad: (sq_w / m).sqrt(),
        crb_alpha_rad: crb,
        nees_pca: nees_pca / m,
        nees_weighted: nees_w / m,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pca_attains_the_bound_and_its_covariance_is_consistent() {
        for (n, len, sigma) in [(40, 1.0, 0.01), (100, 3.0, 0.03), (25, 1.0, 0.03)] {
            let r = fit_accuracy(n, len, sigma, 4000, 5);
            assert!((r.std_alpha_rad / r.crb_alpha_rad - 1.0).abs() < 0.1, "{r:?}");
            assert!((r.std_offset_m / r.crb_offset_m - 1.0).abs() < 0.1, "{r:?}");
            // The noise variance is estimated from n - 2 residual degrees of
            // freedom, so the mean NEES is Hotelling's 2 (n - 2) / (n - 4), not 2.
            let expected = 2.0 * (n as f64 - 2.0) / (n as f64 - 4.0);
            assert!((r.mean_nees / expected - 1.0).abs() < 0.1, "{r:?} (expected {expected:.2})");
        }
    }

    #[test]
    fn range_and_bearing_covariances_are_consistent_and_weighting_helps() {
        let r = range_bearing_accuracy(0.05f64.to_radians(), 2000, 3);
        assert!((r.nees_pca / 2.0 - 1.0).abs() < 0.1, "{r:?}");
        assert!((r.nees_weighted / 2.0 - 1.0).abs() < 0.1, "{r:?}");
        assert!(r.std_alpha_weighted_rad < r.std_alpha_pca_rad, "{r:?}");
        assert!((r.std_alpha_weighted_rad / r.crb_alpha_rad - 1.0).abs() < 0.1, "{r:?}");
    }
}
