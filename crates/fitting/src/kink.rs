//! [`best_split`]: the one-line-or-two test of a fitted line's points (a
//! likelihood-ratio test with the range noise), and [`KinkTest`], its
//! configuration.
//!
//! Beyond the paper. Level 2 cuts a cluster where one point lies far from
//! the chord; a jog smaller than that threshold is never cut, however many
//! points show it. A wall's 10 cm end face seen head-on is such a jog: at
//! 30 mm noise its points lie 0-10 cm from the long face's line, within the
//! split threshold, and the two faces came out as one line tilted by 2-5°.
//! The residual sums see it: the two-line fit lowers the sum of squared
//! residuals by many noise variances, where a straight wall lowers it by
//! about two (the second line's two parameters).

use pcaline_geometry::Point2;

/// When a fitted line is cut in two ([`best_split`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct KinkTest {
    /// A line is cut where two lines fit its points best, when that lowers
    /// the sum of squared orthogonal residuals by more than this many noise
    /// variances (a likelihood ratio; for a straight wall, about chi² with
    /// two degrees of freedom at each cut position).
    pub min_chi2: f64,
    /// Only lines whose residual signs run together (runs test z below
    /// this, [`crate::Straightness::runs_z`]) are tested: a kink leaves
    /// long runs of one sign, white noise does not, and the test's pass
    /// over the points is then spent on the few lines that may need it.
    pub max_runs_z: f64,
}

impl KinkTest {
    /// A cut when the two lines lower the residual sum by more than
    /// `min_chi2` noise variances, tested on lines whose runs z lies below
    /// `max_runs_z`.
    pub const fn new(min_chi2: f64, max_runs_z: f64) -> Self {
        KinkTest { min_chi2, max_runs_z }
    }

    /// 30 noise variances: for one straight wall of 1000 points, the
    /// largest of the 1000 cut positions' chi²(2) statistics passes 30 with
    /// a probability below 1e-3 (Bonferroni: 1000 e^-15); the end face of a
    /// 10 cm thick wall with 10 points on it, 5 cm off on average at 30 mm
    /// noise, scores about 25 noise variances per 10 points. Lines with a
    /// runs z below -2 are tested (2% of straight walls).
    pub const fn standard() -> Self {
        KinkTest { min_chi2: 30.0, max_runs_z: -2.0 }
    }
}

/// Raw sums of one run of points, about an origin near them: count, x, y,
/// x², xy, y².
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RunSums {
    n: f64,
    x: f64,
    y: f64,
    xx: f64,
    xy: f64,
    yy: f64,
}

impl RunSums {
    #[inline]
    pub(crate) fn add(&mut self, x: f64, y: f64) {
        self.n += 1.0;
        self.x += x;
        self.y += y;
        self.xx += x * x;
        self.xy += x * y;
        self.yy += y * y;
    }

    /// The sums of the points of `moments` about their mean.
    pub(crate) fn about_mean(moments: &crate::Moments) -> RunSums {
        RunSums {
            n: moments.n as f64,
            x: 0.0,
            y: 0.0,
            xx: moments.sxx,
            xy: moments.sxy,
            yy: moments.syy,
        }
    }

    /// The sums of the points in `self` but not in `part` (a run within it,
    /// about the same origin).
    #[inline]
    pub(crate) fn minus(&self, part: &RunSums) -> RunSums {
        RunSums {
            n: self.n - part.n,
            x: self.x - part.x,
            y: self.y - part.y,
            xx: self.xx - part.xx,
            xy: self.xy - part.xy,
            yy: self.yy - part.yy,
        }
    }

    /// Sum of squared orthogonal residuals about the best line through
    /// the run: the smaller eigenvalue of its centred scatter matrix.
    #[inline]
    pub(crate) fn residual_sum(&self) -> f64 {
        let inv = 1.0 / self.n;
        let sxx = self.xx - self.x * self.x * inv;
        let sxy = self.xy - self.x * self.y * inv;
        let syy = self.yy - self.y * self.y * inv;
        let half_diff = 0.5 * (sxx - syy);
        (0.5 * (sxx + syy) - (half_diff * half_diff + sxy * sxy).sqrt()).max(0.0)
    }
}

/// The best cut of `points` into two runs of at least `min_points` each:
/// the index `k` where `points[..k]` and `points[k..]` fitted by two lines
/// leave the smallest residual sum, with the drop from one line's residual
/// sum, divided by `sigma_m²`. `suffix` is scratch (cleared and refilled;
/// reuse it across calls to allocate nothing once warm). One pass each way
/// over raw sums about the first point.
///
/// Returns `None` for fewer than `2 * min_points` points, a `min_points`
/// below 2, a `sigma_m` that is not positive and finite, or non-finite
/// points.
///
/// ```
/// use pcaline_fitting::best_split;
/// use pcaline_geometry::Point2;
/// // A 2 m wall along y = 2 and its 10 cm end face seen head-on.
/// let mut pts: Vec<_> = (0..40).map(|i| Point2::new(0.05 * i as f64, 2.0)).collect();
/// pts.extend((1..=10).map(|i| Point2::new(2.0, 2.0 - 0.01 * i as f64)));
/// let (k, chi2) = best_split(&pts, 5, 0.01, &mut Vec::new()).unwrap();
/// assert_eq!(k, 40);
/// assert!(chi2 > 30.0);
/// ```
pub fn best_split(
    points: &[Point2<f64>],
    min_points: usize,
    sigma_m: f64,
    suffix: &mut Vec<RunSums>,
) -> Option<(usize, f64)> {
    let n = points.len();
    if min_points < 2 || n < 2 * min_points || !(sigma_m > 0.0 && sigma_m.is_finite()) {
        return None;
    }
    if !points.iter().all(|p| p.x.is_finite() && p.y.is_finite()) {
        return None;
    }
    let origin = points[0];
    // suffix[k] = sums of points[k..].
    suffix.clear();
    suffix.resize(n + 1, RunSums::default());
    for k in (0..n).rev() {
        let mut s = suffix[k + 1];
        s.add(points[k].x - origin.x, points[k].y - origin.y);
        suffix[k] = s;
    }
    let one_line = suffix[0].residual_sum();
    let mut prefix = RunSums::default();
    for p in &points[..min_points] {
        prefix.add(p.x - origin.x, p.y - origin.y);
    }
    let mut best = (min_points, f64::INFINITY);
    for k in min_points..=n - min_points {
        let two_lines = prefix.residual_sum() + suffix[k].residual_sum();
        if two_lines < best.1 {
            best = (k, two_lines);
        }
        prefix.add(points[k].x - origin.x, points[k].y - origin.y);
    }
    Some((best.0, (one_line - best.1) / (sigma_m * sigma_m)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{SeedableRng, rngs::StdRng};
    use rand_distr::{Distribution, Normal};

    #[test]
    fn a_straight_noisy_wall_stays_whole() {
        // 200 walls of 300 points at 1 cm noise: the statistic stays below
        // the standard threshold on every one.
        let mut rng = StdRng::seed_from_u64(7);
        let noise = Normal::new(0.0, 0.01).unwrap();
        let mut scratch = Vec::new();
        let mut worst = 0.0f64;
        for _ in 0..200 {
            let pts: Vec<_> = (0..300)
                .map(|i| Point2::new(0.01 * i as f64, 3.0 + noise.sample(&mut rng)))
                .collect();
            let (_, chi2) = best_split(&pts, 5, 0.01, &mut scratch).unwrap();
            worst = worst.max(chi2);
        }
        assert!(worst < KinkTest::standard().min_chi2, "{worst}");
        assert!(worst > 2.0, "{worst}");
    }

    #[test]
    fn a_corner_is_cut_at_the_corner() {
        let mut pts: Vec<_> = (0..30).map(|i| Point2::new(1.0, 0.05 * i as f64)).collect();
        pts.extend((1..20).map(|i| Point2::new(1.0 - 0.05 * i as f64, 1.45)));
        // The corner point lies on both walls: either side of it is exact.
        let (k, chi2) = best_split(&pts, 5, 0.01, &mut Vec::new()).unwrap();
        assert!(k == 29 || k == 30, "{k}");
        assert!(chi2 > 1000.0, "{chi2}");
    }

    #[test]
    fn too_few_points_or_a_bad_sigma_give_none() {
        let pts: Vec<_> = (0..9).map(|i| Point2::new(i as f64, 0.0)).collect();
        let mut s = Vec::new();
        assert_eq!(best_split(&pts, 5, 0.01, &mut s), None);
        assert!(best_split(&pts, 4, 0.01, &mut s).is_some());
        assert_eq!(best_split(&pts, 1, 0.01, &mut s), None);
        assert_eq!(best_split(&pts, 4, 0.0, &mut s), None);
        assert_eq!(best_split(&pts, 4, f64::NAN, &mut s), None);
        let mut bad = pts.clone();
        bad[3].x = f64::NAN;
        assert_eq!(best_split(&bad, 4, 0.01, &mut s), None);
    }
}
