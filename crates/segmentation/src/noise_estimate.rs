//! Estimating the range noise of a scan from the scan itself, so that the
//! noise-aware thresholds follow the sensor actually in use rather than its
//! datasheet.
//!
//! For three consecutive beams `i - 1, i, i + 1` hitting one flat surface,
//! the chord through the outer two points crosses the middle beam at
//! `r_hat = 2 r_(i-1) r_(i+1) cos(dtheta) / (r_(i-1) + r_(i+1))`, exactly,
//! whatever the incidence. With independent range noise `sigma` the residual
//! `r_i - r_hat` has standard deviation `sigma sqrt(3 / 2)` to first order.
//! Corners, edges and clutter give large residuals; the median absolute
//! residual ignores them as long as most triples lie on surfaces.

use pcaline_geometry::{ConfigError, RangeNoise, ScanPoints};

/// How the range noise is estimated from each scan.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct NoiseEstimation {
    /// Fewest triples a range band needs for its sigma to be estimated; a
    /// band with fewer keeps the nominal sigma.
    pub min_samples: usize,
    /// The estimate stays at or above `nominal * min_scale`. The triples
    /// measure the white noise from beam to beam; lines also carry what is
    /// not white (walls that are not flat, incidence-dependent bias), which
    /// the datasheet's figure covers: on the real UTM-30LX-EW bag the
    /// estimate is about 3 mm while lines scatter 6 mm about their fits, and
    /// thresholds at the estimate reject real walls. 1 (the standard): the
    /// estimate only ever raises the noise above the nominal.
    pub min_scale: f64,
    /// The estimate stays at or below `nominal * max_scale` (a scan of
    /// foliage is not a noisier sensor).
    pub max_scale: f64,
    /// Smallest sigma the estimate may give, metres (range quantisation
    /// and noise-free simulations otherwise give zero thresholds).
    pub floor_m: f64,
}

impl NoiseEstimation {
    /// 30 triples a band; between the nominal noise and 4 times it; at least 1 mm.
    pub const fn standard() -> Self {
        NoiseEstimation { min_samples: 30, min_scale: 1.0, max_scale: 4.0, floor_m: 0.001 }
    }

    /// Checks every value.
    pub fn validate(&self) -> Result<(), ConfigError> {
        ConfigError::check(
            self.min_samples >= 3,
            "segmentation.noise_estimation.min_samples",
            self.min_samples as f64,
            "must be >= 3",
        )?;
        ConfigError::check(
            self.min_scale >= 0.0 && self.min_scale <= 1.0,
            "segmentation.noise_estimation.min_scale",
            self.min_scale,
            "must be in [0, 1]",
        )?;
        ConfigError::check(
            self.max_scale >= 1.0 && self.max_scale.is_finite(),
            "segmentation.noise_estimation.max_scale",
            self.max_scale,
            "must be finite and >= 1",
        )?;
        ConfigError::check(
            self.floor_m >= 0.0 && self.floor_m.is_finite(),
            "segmentation.noise_estimation.floor_m",
            self.floor_m,
            "must be finite and >= 0",
        )
    }
}

/// Reusable buffers of [`estimate_range_noise`].
#[derive(Debug, Clone, Default)]
pub struct NoiseScratch {
    near: Vec<f64>,
    far: Vec<f64>,
}

/// Most triples examined per scan: beyond a few hundred the median is
/// already within a few percent, so longer scans are subsampled evenly.
const MAX_TRIPLES: usize = 256;

/// The range noise of the scan whose valid returns are `points`: the
/// nominal model `nominal` with each of its two range bands' sigma replaced
/// by the scan's estimate (module docs) when the band has enough triples of
/// consecutive beams. At most 256 triples, evenly spread, are examined.
///
/// ```
/// use pcaline_geometry::{BearingTable, RangeNoise, Scan, ScanPoints};
/// use pcaline_segmentation::{NoiseEstimation, NoiseScratch, estimate_range_noise};
/// // A wall 2 m ahead with ranges alternately 2 cm long and short.
/// let inc = 0.25f32.to_radians();
/// let ranges: Vec<f32> = (0..200)
///     .map(|i| {
///         let b = -0.4 + i as f32 * inc;
///         2.0 / b.cos() + if i % 2 == 0 { 0.02 } else { -0.02 }
///     })
///     .collect();
/// let mut points = ScanPoints::default();
/// points.fill_from(&Scan::new(-0.4, inc, 0.1, 30.0, ranges), &mut BearingTable::default());
/// let nominal = RangeNoise::constant(0.01);
/// let mut scratch = NoiseScratch::default();
/// let noise = estimate_range_noise(&points, &nominal, &NoiseEstimation::standard(), &mut scratch);
/// // Residuals of +-6 cm: 1.4826 * 0.06 / sqrt(1.5) = 7.3 cm, clamped to 4 x 1 cm.
/// assert!((noise.sigma_at(2.0) - 0.04).abs() < 1e-9);
/// ```
pub fn estimate_range_noise(
    points: &ScanPoints,
    nominal: &RangeNoise,
    estimation: &NoiseEstimation,
    scratch: &mut NoiseScratch,
) -> RangeNoise {
    let (near, far) = (&mut scratch.near, &mut scratch.far);
    near.clear();
    far.clear();
    let n = points.len();
    let stride = (n / MAX_TRIPLES).max(1);
    let (xs, beams, angles) = (&points.range_m, &points.beam, &points.angle_rad);
    // The half step is nearly always the scan's increment: cache its cosine.
    let (mut last_step, mut cos_step) = (f64::NAN, 1.0);
    let mut i = 1;
    while i + 1 < n {
        let (a, r, b) = (xs[i - 1], xs[i], xs[i + 1]);
        if beams[i] == beams[i - 1] + 1 && beams[i + 1] == beams[i] + 1 {
            let step = 0.5 * (angles[i + 1] - angles[i - 1]).abs();
            // Steps differ in their last bits from beam to beam.
            if (step - last_step).abs() > 1e-12 || last_step.is_nan() {
                (last_step, cos_step) = (step, step.cos());
            }
            let residual = (r - 2.0 * a * b * cos_step / (a + b)).abs();
            if residual.is_finite() {
                if r < nominal.far_from_m { near.push(residual) } else { far.push(residual) }
            }
        }
        i += stride;
    }
    let mut noise = *nominal;
    if let Some(sigma) = band_sigma(near, nominal.near_sigma_m, estimation) {
        noise.near_sigma_m = sigma;
    }
    if let Some(sigma) = band_sigma(far, nominal.far_sigma_m, estimation) {
        noise.far_sigma_m = sigma;
    }
    noise
}

/// The sigma of one band from its absolute residuals, clamped about the
/// band's nominal sigma; `None` with too few residuals.
fn band_sigma(residuals: &mut [f64], nominal: f64, estimation: &NoiseEstimation) -> Option<f64> {
    if residuals.len() < estimation.min_samples {
        return None;
    }
    let mid = residuals.len() / 2;
    let (_, median, _) = residuals.select_nth_unstable_by(mid, f64::total_cmp);
    // Median |N(0, 1.5 sigma²)| = 0.6745 sqrt(1.5) sigma.
    let estimate = *median / (0.674_489_75 * 1.5f64.sqrt());
    let (lo, hi) = (nominal * estimation.min_scale, nominal * estimation.max_scale);
    Some(estimate.clamp(lo, hi).max(estimation.floor_m))
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::{BearingTable, Scan};
    use rand::{SeedableRng, rngs::StdRng};
    use rand_distr::{Distribution, Normal};

    /// A room-like scan: walls at 3 m and 12 m, corners between them.
    fn scan(sigma_near: f64, sigma_far: f64, seed: u64) -> ScanPoints {
        let mut rng = StdRng::seed_from_u64(seed);
        let inc = 0.25f64.to_radians();
        let ranges: Vec<f32> = (0..1081)
            .map(|i| {
                let b = -135f64.to_radians() + i as f64 * inc;
                // A 3 m wall across the front half, a 12 m wall behind.
                let (d, normal) = if b.abs() < 1.0 { (3.0, 0.0) } else { (12.0, b.signum() * 2.0) };
                let r = d / (b - normal).cos().abs();
                let sigma = if r < 10.0 { sigma_near } else { sigma_far };
                (r + Normal::new(0.0, sigma).unwrap().sample(&mut rng)) as f32
            })
            .collect();
        let mut p = ScanPoints::default();
        p.fill_from(
            &Scan::new(-135f32.to_radians(), inc as f32, 0.1, 60.0, ranges),
            &mut BearingTable::default(),
        );
        p
    }

    /// Unbiased over seeds (mean within 5%), and each scan's estimate within
    /// 20% (about 120 triples a band here, after subsampling).
    #[test]
    fn recovers_each_band_sigma() {
        let nominal = RangeNoise::utm30lx();
        let e = NoiseEstimation { min_scale: 0.25, ..NoiseEstimation::standard() };
        let mut scratch = NoiseScratch::default();
        for (near, far) in [(0.01, 0.03), (0.03, 0.03), (0.005, 0.02)] {
            let (mut sum_near, mut sum_far) = (0.0, 0.0);
            let seeds = 20;
            for seed in 1..=seeds {
                let n = estimate_range_noise(&scan(near, far, seed), &nominal, &e, &mut scratch);
                assert!((n.near_sigma_m / near - 1.0).abs() < 0.2, "{near} {far}: {n:?}");
                assert!((n.far_sigma_m / far - 1.0).abs() < 0.2, "{near} {far}: {n:?}");
                sum_near += n.near_sigma_m;
                sum_far += n.far_sigma_m;
            }
            let (mean_near, mean_far) = (sum_near / seeds as f64, sum_far / seeds as f64);
            assert!((mean_near / near - 1.0).abs() < 0.05, "{near}: mean {mean_near}");
            assert!((mean_far / far - 1.0).abs() < 0.05, "{far}: mean {mean_far}");
        }
    }

    #[test]
    fn too_few_samples_keep_the_nominal_and_the_bounds_hold() {
        let nominal = RangeNoise::constant(0.02);
        let e = NoiseEstimation::standard();
        let mut scratch = NoiseScratch::default();
        let empty = ScanPoints::default();
        assert_eq!(estimate_range_noise(&empty, &nominal, &e, &mut scratch), nominal);
        // Less noise than the nominal: the standard keeps the nominal.
        let n = estimate_range_noise(&scan(0.005, 0.005, 1), &nominal, &e, &mut scratch);
        assert_eq!(n.near_sigma_m, 0.02);
        // Noise-free walls, allowed below the nominal: the floor, not zero.
        let low = NoiseEstimation { min_scale: 0.0, ..e };
        let n = estimate_range_noise(&scan(0.0, 0.0, 1), &nominal, &low, &mut scratch);
        assert_eq!(n.near_sigma_m, 0.001);
        // Far more noise than the nominal: at most 4 times it.
        let n = estimate_range_noise(&scan(0.5, 0.5, 1), &nominal, &e, &mut scratch);
        assert_eq!(n.near_sigma_m, 0.08);
    }
}
