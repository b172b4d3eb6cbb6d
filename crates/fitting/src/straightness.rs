//! The straightness statistic of a fitted line: is the surface under it
//! straight, or a chord of a curve?
//!
//! Three numbers: the residual standard deviation in units of the range
//! noise (about 1 on a straight wall); the Wald-Wolfowitz runs test on the
//! signs of the residuals in scan order; and the bow, the sagitta of the
//! parabola that best fits the residuals along the line. On a straight wall
//! with white noise the signs alternate at random (z near 0) and the bow is
//! noise; a chord of an arc has residuals of one sign in its middle and the
//! other at its ends (three runs, a z of -5 or less on 40 points) and bows by
//! the arc's sagitta. Real walls have texture: on the shared real logs the
//! runs test alone refuses a third to nine tenths of the lines, so the test
//! refuses a line only when it also bows by more than the noise explains.

use pcaline_geometry::{LineSegment, Point2, RangeNoise};

/// How straight the points under a line are.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Straightness {
    /// The line's residual standard deviation divided by the range noise at
    /// its range (the norm of its centroid, the sensor at the origin): about
    /// 1 on a straight wall. `inf` with zero noise and a non-zero residual,
    /// 0 with both zero.
    pub residual_ratio: f64,
    /// The runs test's z score of the residual signs, in scan order: about
    /// N(0, 1) for white residuals, strongly negative when residuals keep one
    /// sign over long stretches. 0 with fewer than 10 points or only one
    /// sign.
    pub runs_z: f64,
    /// The sagitta of the parabola fitted to the residuals along the line,
    /// metres: how far the surface under the line's middle lies from the
    /// chord through its ends, signed (positive: away from the sensor side
    /// of the line's normal). 0 with fewer than 5 points.
    pub bow_m: f64,
}

/// The straightness of `line` over `points` (its points in scan order) with
/// range noise `noise`. A residual of exactly zero counts as negative in the
/// runs test. Non-finite points or lines give non-finite sums, reported as a
/// bow of 0.
///
/// ```
/// use pcaline_fitting::{fit_pca, straightness};
/// use pcaline_geometry::{Point2, RangeNoise};
/// let noise = RangeNoise::constant(0.01);
/// // A flat wall whose residuals alternate: many runs, z > 0.
/// let flat: Vec<_> = (0..40).map(|i| Point2::new(3.0 + if i % 2 == 0 { 0.01 } else { -0.01 }, 0.05 * i as f64)).collect();
/// let s = straightness(&flat, &fit_pca(&flat).unwrap(), &noise);
/// assert!(s.runs_z > 3.0 && (s.residual_ratio - 1.0).abs() < 0.05);
/// // A chord of an arc of radius 4 m: three runs.
/// let arc: Vec<_> = (0..40).map(|i| { let t = -0.25 + 0.5 * i as f64 / 39.0; Point2::new(4.0 * t.cos(), 4.0 * t.sin()) }).collect();
/// let s = straightness(&arc, &fit_pca(&arc).unwrap(), &noise);
/// assert!(s.runs_z < -5.0 && s.residual_ratio > 3.0);
/// assert!((s.bow_m - 4.0 * (1.0 - 0.25f64.cos())).abs() < 0.01); // the sagitta
/// ```
pub fn straightness<'a>(
    points: impl IntoIterator<Item = &'a Point2<f64>>,
    line: &LineSegment,
    noise: &RangeNoise,
) -> Straightness {
    let normal = line.normal();
    let tangent = pcaline_geometry::Vector2::new(-normal.y, normal.x);
    let centre = line.centroid().coords.dot(&tangent);
    let inv_half = 2.0 / line.length().max(1e-9);
    // Signs as 0 or 1 (2: none yet), counted without branches: on white
    // residuals a sign change is a coin flip no predictor guesses.
    let (mut positive, mut runs, mut last) = (0usize, 0usize, 2u8);
    // Normal equations of r = a + b u + c u², u in [-1, 1] along the line:
    // sums of u^0..u^4 and of r, r u, r u².
    let (mut su, mut sr) = ([0.0f64; 5], [0.0f64; 3]);
    let mut n = 0usize;
    for p in points {
        let r = p.coords.dot(&normal) - line.d();
        let u = (p.coords.dot(&tangent) - centre) * inv_half;
        let u2 = u * u;
        su[1] += u;
        su[2] += u2;
        su[3] += u2 * u;
        su[4] += u2 * u2;
        sr[0] += r;
        sr[1] += r * u;
        sr[2] += r * u2;
        n += 1;
        let sign = u8::from(r > 0.0);
        positive += usize::from(sign);
        runs += usize::from(sign != last);
        last = sign;
    }
    su[0] = n as f64;
    let signed = n;
    let negative = signed - positive;
    let sigma = noise.sigma_at(line.centroid().coords.norm());
    let residual_ratio = if line.residual_std() == 0.0 { 0.0 } else { line.residual_std() / sigma };
    // The parabola's value at the ends minus at the middle is c; the surface
    // under the middle lies -c from the chord.
    let bow_m = if n >= 5 {
        let m = pcaline_geometry::Matrix3::new(
            su[0], su[1], su[2], su[1], su[2], su[3], su[2], su[3], su[4],
        );
        m.try_inverse()
            .map_or(0.0, |inv| -(inv[(2, 0)] * sr[0] + inv[(2, 1)] * sr[1] + inv[(2, 2)] * sr[2]))
    } else {
        0.0
    };
    let bow_m = if bow_m.is_finite() { bow_m } else { 0.0 };
    Straightness { residual_ratio, runs_z: runs_z(positive, negative, runs), bow_m }
}

/// The Wald-Wolfowitz z score of `runs` runs among `positive` and
/// `negative` signs; 0 when undefined or with fewer than 10 signs.
fn runs_z(positive: usize, negative: usize, runs: usize) -> f64 {
    let (p, m) = (positive as f64, negative as f64);
    let n = p + m;
    if n < 10.0 || positive == 0 || negative == 0 {
        return 0.0;
    }
    let mean = 2.0 * p * m / n + 1.0;
    let variance = 2.0 * p * m * (2.0 * p * m - n) / (n * n * (n - 1.0));
    if variance <= 0.0 { 0.0 } else { (runs as f64 - mean) / variance.sqrt() }
}

/// Refuses a line that is not straight: it bows by more than
/// `max_bow_sigmas` noise sigmas and its runs test's z is below
/// `max_runs_z` (the chord of a curved surface). Either alone keeps the line:
/// textured real walls fail the runs test with bows within the noise, and a
/// short noisy wall can bow by chance with random signs.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct StraightnessTest {
    /// The largest bow still kept, in noise sigmas at the line's range.
    pub max_bow_sigmas: f64,
    /// The largest (most negative) runs z score still kept.
    pub max_runs_z: f64,
}

impl StraightnessTest {
    /// Keeps a line unless its bow exceeds `max_bow_sigmas` noise sigmas and
    /// its runs z lies below `max_runs_z` (see [`StraightnessTest::accepts`]).
    pub const fn new(max_bow_sigmas: f64, max_runs_z: f64) -> Self {
        StraightnessTest { max_bow_sigmas, max_runs_z }
    }

    /// A bow above 2 sigmas with runs z below -3 (one straight wall in 700
    /// with white residuals fails the runs test alone). A chord bowing by
    /// 2 sigmas lies about 0.6 sigma (rms) from its surface.
    pub const fn standard() -> Self {
        StraightnessTest { max_bow_sigmas: 2.0, max_runs_z: -3.0 }
    }

    /// True when the line with `straightness`, whose noise at its range is
    /// `sigma_m`, is kept.
    pub fn accepts(&self, straightness: &Straightness, sigma_m: f64) -> bool {
        !(straightness.bow_m.abs() > self.max_bow_sigmas * sigma_m
            && straightness.runs_z < self.max_runs_z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit_pca;
    use rand::{SeedableRng, rngs::StdRng};
    use rand_distr::{Distribution, Normal};

    /// White noise on a straight wall: z is about standard normal (mean
    /// within 0.15, sd within 0.15 of 1 over 400 walls), the ratio about 1,
    /// and the standard test keeps at least 99% of walls.
    #[test]
    fn white_noise_on_a_straight_wall_is_straight() {
        let mut rng = StdRng::seed_from_u64(11);
        let normal = Normal::new(0.0, 0.02).unwrap();
        let noise = RangeNoise::constant(0.02);
        let (mut zs, mut kept) = (Vec::new(), 0);
        for _ in 0..400 {
            let pts: Vec<_> = (0..60)
                .map(|i| Point2::new(5.0 + normal.sample(&mut rng), -1.5 + 0.05 * i as f64))
                .collect();
            let s = straightness(&pts, &fit_pca(&pts).unwrap(), &noise);
            assert!((s.residual_ratio - 1.0).abs() < 0.35, "{s:?}");
            // The bow's standard error is about 3.35 sigma / sqrt(60).
            assert!(s.bow_m.abs() < 5.0 * 0.43 * 0.02, "{s:?}");
            kept += usize::from(StraightnessTest::standard().accepts(&s, 0.02));
            zs.push(s.runs_z);
        }
        let mean = zs.iter().sum::<f64>() / zs.len() as f64;
        let sd = (zs.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / zs.len() as f64).sqrt();
        assert!(mean.abs() < 0.15 && (sd - 1.0).abs() < 0.15, "mean {mean}, sd {sd}");
        assert!(kept >= 396, "{kept} of 400 kept");
    }

    #[test]
    fn the_chord_of_a_noisy_arc_is_refused() {
        let mut rng = StdRng::seed_from_u64(3);
        let normal = Normal::new(0.0, 0.01).unwrap();
        // An arc of radius 3 m over 40°, 1 cm noise: sagitta 18 cm.
        let pts: Vec<_> = (0..80)
            .map(|i| {
                let t = (-20.0 + 40.0 * i as f64 / 79.0f64).to_radians();
                let r = 3.0 + normal.sample(&mut rng);
                Point2::new(r * t.cos(), r * t.sin())
            })
            .collect();
        let s = straightness(&pts, &fit_pca(&pts).unwrap(), &RangeNoise::constant(0.01));
        // Sagitta 3 (1 - cos 20°) = 18 cm, the middle behind the chord.
        assert!((s.bow_m - 0.181).abs() < 0.02, "{s:?}");
        assert!(!StraightnessTest::standard().accepts(&s, 0.01), "{s:?}");
        assert_eq!(runs_z(3, 0, 1), 0.0);
        assert_eq!(runs_z(3, 3, 2), 0.0);
    }
}
