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
        let da = line_angle_diff(line.alpha, truth.alpha);
        let offset = truth.signed_distance(&line.centroid);
        // d of the fit against the true line's d in the truth's normal
        // convention: for a line near the origin the fit's normal may point
        // the other way (alpha + pi, d -> -d), which also flips the sign of
        // the covariance's cross term.
        let same_normal = (line.alpha - truth.alpha).cos() >= 0.0;
        let dd = if same_normal { line.d - truth.d } else { -line.d - truth.d };
        let e = Vector2::new(da, dd);
        let mut p: Matrix2<f64> = line.covariance;
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
}
