//! Level-1 clustering (paper, section 2): a break-point wherever the distance
//! between consecutive valid points exceeds a threshold; clusters of too few
//! points are dropped.

use crate::BreakRule;
use pcaline_geometry::{RangeNoise, ScanPoints, Vector2};
use std::ops::Range;

/// True when consecutive points `i` and `j` of `points` are separated by a
/// level-1 break-point under `rule`. `delta_angle_rad` is the absolute bearing
/// difference between the two points (several beams when invalid returns lie
/// between them).
#[inline]
pub fn is_break(
    points: &ScanPoints,
    i: usize,
    j: usize,
    delta_angle_rad: f64,
    rule: &BreakRule,
) -> bool {
    farther_than(
        points,
        i,
        j,
        rule.threshold_m(points.range_m[i], points.range_m[j], delta_angle_rad),
    )
}

/// Whether points `i` and `j` lie farther apart than `threshold_m`.
#[inline(always)]
fn farther_than(points: &ScanPoints, i: usize, j: usize, threshold_m: f64) -> bool {
    (points.xy[j] - points.xy[i]).norm_squared() > threshold_m * threshold_m
}

/// Splits the points into level-1 clusters.
///
/// `breaks` receives the index of every point that begins a new cluster
/// (including point 0 when there are points); `clusters` receives the clusters
/// of at least `min_points` points, as index ranges. Both are cleared first.
/// Points are assumed in scan order; for a closed scan rotate them first
/// ([`seam_start`]) so that no cluster crosses the array's ends.
pub fn level1_clusters(
    points: &ScanPoints,
    rule: &BreakRule,
    min_points: usize,
    breaks: &mut Vec<usize>,
    clusters: &mut Vec<Range<usize>>,
) {
    breaks.clear();
    clusters.clear();
    let n = points.len();
    if n == 0 {
        return;
    }
    breaks.push(0);
    let mut cut = Cuts { breaks, clusters, start: 0, min_points };
    // One tight loop per rule, so the rule is matched once, not per point.
    let xy = &points.xy;
    match *rule {
        BreakRule::Fixed { dth_m } => {
            let t2 = dth_m * dth_m;
            for j in 1..n {
                if (xy[j] - xy[j - 1]).norm_squared() > t2 {
                    cut.at(j);
                }
            }
        }
        BreakRule::Adaptive { lambda_rad, sigma_factor, noise, grazing } => {
            let mut cached = CachedRule::new(rule);
            // Slices of one length `n`: no bounds checks at `j - 1` and `j`.
            let (angle, range) = (&points.angle_rad[..n], &points.range_m[..n]);
            let xy = &xy[..n];
            let regular = |a: usize, b: usize| (angle[b] - angle[a]).abs() <= 0.5 * lambda_rad;
            // Blocks of up to 64 pairs: a first loop without branches (one
            // the compiler vectorises) flags the pairs that may break, those
            // farther apart than the threshold of the scan's usual step or
            // at another step; the second visits only those.
            let mut j0 = 1;
            while j0 < n {
                let len = (n - j0).min(BLOCK);
                let mut bits = cached.flag_block(xy, range, angle, j0, len);
                while bits != 0 {
                    let j = j0 + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    let step = (angle[j] - angle[j - 1]).abs();
                    let threshold = cached.threshold(range[j - 1], range[j], step);
                    if (xy[j] - xy[j - 1]).norm_squared() <= threshold * threshold {
                        continue;
                    }
                    if grazing
                        && j >= 2
                        && regular(j - 2, j - 1)
                        && regular(j - 1, j)
                        && continues_line(points, j, sigma_factor, &noise)
                    {
                        if cut.start == j - 1 {
                            // Three points on one grazing line: the break before
                            // the middle one was wrong too.
                            cut.undo_last();
                        }
                        continue;
                    }
                    cut.at(j);
                }
                j0 += len;
            }
        }
    }
    cut.finish(n);
}

/// The level-1 cuts made so far.
struct Cuts<'a> {
    breaks: &'a mut Vec<usize>,
    clusters: &'a mut Vec<Range<usize>>,
    start: usize,
    min_points: usize,
}

impl Cuts<'_> {
    /// A break before point `j`.
    fn at(&mut self, j: usize) {
        self.breaks.push(j);
        if j - self.start >= self.min_points {
            self.clusters.push(self.start..j);
        }
        self.start = j;
    }

    /// Takes back the last break (its cluster, if kept, reopens).
    fn undo_last(&mut self) {
        if self.breaks.len() < 2 {
            return;
        }
        self.breaks.pop();
        let previous = *self.breaks.last().unwrap_or(&0);
        if self.clusters.last().is_some_and(|c| c.start == previous && c.end == self.start) {
            self.clusters.pop();
        }
        self.start = previous;
    }

    fn finish(&mut self, n: usize) {
        if n - self.start >= self.min_points {
            self.clusters.push(self.start..n);
        }
    }
}

/// Whether point `j` continues the line through points `j - 2` and `j - 1`
/// (a wall seen at grazing incidence, whose points are farther apart than
/// any break threshold): its distance from that line is within
/// `sigma_factor` standard deviations of the prediction, given the range
/// noise `noise` of the three points projected across the line, and the
/// spacings of the two steps differ by less than half (a doorway seen
/// edge-on, a far wall collinear with a near one, is a jump in spacing).
///
/// ```
/// use pcaline_geometry::{BearingTable, RangeNoise, Scan, ScanPoints};
/// use pcaline_segmentation::continues_line;
/// // A wall 1 m to the side, seen 80-84° off its normal: 0.1-0.2 m apart.
/// let angle_min = 80f32.to_radians() - std::f32::consts::FRAC_PI_2;
/// let inc = 1f32.to_radians();
/// let ranges: Vec<f32> =
///     (0..5).map(|i| 1.0 / (angle_min + i as f32 * inc).cos().abs()).collect();
/// let mut p = ScanPoints::default();
/// p.fill_from(&Scan::new(angle_min, inc, 0.1, 30.0, ranges), &mut BearingTable::default());
/// assert!(continues_line(&p, 4, 3.0, &RangeNoise::constant(0.01)));
/// ```
pub fn continues_line(
    points: &ScanPoints,
    j: usize,
    sigma_factor: f64,
    noise: &RangeNoise,
) -> bool {
    if j < 2 || j >= points.len() {
        return false;
    }
    let (a, b, c) = (points.xy[j - 2], points.xy[j - 1], points.xy[j]);
    let (s1, s2) = ((b - a).norm(), (c - b).norm());
    if !(s1 > 0.0 && s2 > 0.0) {
        return false;
    }
    let slack = sigma_factor * noise.sigma_at(points.range_m[j]);
    if s1.max(s2) > 1.5 * s1.min(s2) + slack {
        return false;
    }
    let u = (b - a) / s1;
    let normal = Vector2::new(-u.y, u.x);
    // Noise of each point across the line: its range noise times the cosine
    // between its beam and the line's normal.
    let across = |k: usize| {
        let r = points.range_m[k];
        noise.sigma_at(r) * (normal.dot(&points.xy[k].coords) / r).abs()
    };
    let lever = s2 / s1;
    let predicted_var = across(j).powi(2)
        + (across(j - 1) * (1.0 + lever)).powi(2)
        + (across(j - 2) * lever).powi(2);
    let distance = normal.dot(&(c - b)).abs();
    // The floor covers the f32 rounding of noise-free ranges.
    distance <= sigma_factor * predicted_var.sqrt() + 1e-6 * points.range_m[j]
}

/// For a closed (360°) scan: the index of a point that begins a level-1
/// cluster when the scan is read as a ring, so that rotating the points to
/// start there keeps a wall across the ±180° seam in one cluster.
///
/// Returns `None` when the ring has no break-point at all (a closed room seen
/// whole) or has fewer than 2 points; then the seam is bridged later by the
/// merge step instead.
pub fn seam_start(points: &ScanPoints, rule: &BreakRule) -> Option<usize> {
    let n = points.len();
    if n < 2 {
        return None;
    }
    let last = n - 1;
    let wrap_gap = std::f64::consts::TAU - (points.angle_rad[last] - points.angle_rad[0]).abs();
    if is_break(points, last, 0, wrap_gap.abs(), rule) {
        return Some(0);
    }
    let mut cached = CachedRule::new(rule);
    (1..n).find(|&j| {
        let d_angle = (points.angle_rad[j] - points.angle_rad[j - 1]).abs();
        cached.is_break(points, j - 1, j, d_angle)
    })
}

/// Pairs of points a level-1 block covers (one bit each of a `u64`).
const BLOCK: usize = 64;

/// A rule with its angular factor cached: in a scan, consecutive valid beams
/// are almost always one increment apart, so the trigonometry runs once for
/// the scan's usual step (the first pair's) and once per other distinct
/// step, instead of once per point. A step within 1e-12 rad of the usual one
/// takes its factor.
struct CachedRule<'a> {
    rule: &'a BreakRule,
    /// The usual step and its factor (NaN until the first pair).
    usual_step: f64,
    usual_factor: f64,
    /// The last other step and its factor.
    step: f64,
    factor: f64,
}

impl<'a> CachedRule<'a> {
    fn new(rule: &'a BreakRule) -> Self {
        CachedRule { rule, usual_step: f64::NAN, usual_factor: 0.0, step: f64::NAN, factor: 0.0 }
    }

    /// The factor of a bearing step of `step` radians.
    #[inline(always)]
    fn factor(&mut self, step: f64) -> f64 {
        if self.usual_step.is_nan() {
            self.usual_step = step;
            self.usual_factor = self.rule.angular_factor(step);
        }
        if (step - self.usual_step).abs() <= 1e-12 {
            return self.usual_factor;
        }
        if (step - self.step).abs() > 1e-12 || self.step.is_nan() {
            self.step = step;
            self.factor = self.rule.angular_factor(step);
        }
        self.factor
    }

    /// The break threshold between points at ranges `r_i` and `r_j`,
    /// `step` radians apart, metres.
    #[inline(always)]
    fn threshold(&mut self, r_i: f64, r_j: f64, step: f64) -> f64 {
        let factor = self.factor(step);
        self.rule.threshold_with_factor(r_i, r_j, factor)
    }

    #[inline(always)]
    fn is_break(&mut self, points: &ScanPoints, i: usize, j: usize, step: f64) -> bool {
        let t = self.threshold(points.range_m[i], points.range_m[j], step);
        farther_than(points, i, j, t)
    }

    /// Bit `k` set for each pair `(j - 1, j)`, `j = j0 + k < j0 + len`, that
    /// is a break under the usual step's threshold or lies at another step
    /// (`len <= 64`, `j0 >= 1`, `j0 + len <= ` the slices' length). A pair
    /// whose bit is clear is no break.
    #[inline(always)]
    fn flag_block(
        &mut self,
        xy: &[pcaline_geometry::Point2<f64>],
        range: &[f64],
        angle: &[f64],
        j0: usize,
        len: usize,
    ) -> u64 {
        let every_pair = if len == BLOCK { u64::MAX } else { (1u64 << len) - 1 };
        let BreakRule::Adaptive { sigma_factor, noise, .. } = *self.rule else {
            return every_pair;
        };
        // The first call sets the usual step, from the scan's first pair.
        self.factor((angle[j0] - angle[j0 - 1]).abs());
        let (usual, factor) = (self.usual_step, self.usual_factor);
        if factor == f64::NEG_INFINITY {
            // Even the usual step is a wide gap: every pair to the slow path.
            return every_pair;
        }
        let (near, far, far_from) =
            (sigma_factor * noise.near_sigma_m, sigma_factor * noise.far_sigma_m, noise.far_from_m);
        let (xy, range, angle) =
            (&xy[j0 - 1..j0 + len], &range[j0 - 1..j0 + len], &angle[j0 - 1..j0 + len]);
        let mut flags = [false; BLOCK];
        for (k, flag) in flags[..len].iter_mut().enumerate() {
            let (r_i, r_j) = (range[k], range[k + 1]);
            let slack = if r_i.max(r_j) < far_from { near } else { far };
            let threshold = r_i.min(r_j) * factor + slack;
            let d = xy[k + 1] - xy[k];
            let other_step = ((angle[k + 1] - angle[k]).abs() - usual).abs() > 1e-12;
            *flag = (d.x * d.x + d.y * d.y > threshold * threshold) | other_step;
        }
        // Eight flags (bytes of 0 or 1) at a time into eight bits: the
        // multiplication gathers byte `i`'s low bit into bit `56 + i`.
        let mut bits = 0u64;
        for (c, chunk) in flags.chunks_exact(8).enumerate() {
            let bytes = u64::from_le_bytes(std::array::from_fn(|i| u8::from(chunk[i])));
            bits |= (bytes.wrapping_mul(0x0102_0408_1020_4080) >> 56) << (8 * c);
        }
        bits
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::{BearingTable, Scan};

    fn points_of(scan: &Scan) -> ScanPoints {
        let mut p = ScanPoints::default();
        p.fill_from(scan, &mut BearingTable::default());
        p
    }

    #[test]
    fn depth_jump_is_a_break_and_small_clusters_drop() {
        // 10 beams at 2 m, 3 beams at 4 m, 10 beams at 2 m.
        let mut ranges = vec![2.0f32; 10];
        ranges.extend([4.0; 3]);
        ranges.extend([2.0; 10]);
        let scan = Scan::new(0.0, 0.25f32.to_radians(), 0.1, 30.0, ranges);
        let p = points_of(&scan);
        let (mut b, mut c) = (vec![], vec![]);
        level1_clusters(&p, &BreakRule::paper(), 5, &mut b, &mut c);
        assert_eq!(b, vec![0, 10, 13]);
        assert_eq!(c, vec![0..10, 13..23]);
    }

    #[test]
    fn empty_and_tiny_inputs() {
        let (mut b, mut c) = (vec![1], vec![0..1, 2..3]);
        level1_clusters(&ScanPoints::default(), &BreakRule::paper(), 5, &mut b, &mut c);
        assert!(b.is_empty() && c.is_empty());
        let p = points_of(&Scan::new(0.0, 0.01, 0.1, 30.0, vec![1.0]));
        level1_clusters(&p, &BreakRule::paper(), 5, &mut b, &mut c);
        assert_eq!(b, vec![0]);
        assert!(c.is_empty());
        assert_eq!(seam_start(&p, &BreakRule::paper()), None);
    }

    #[test]
    fn a_wide_gap_of_invalid_beams_breaks_the_cluster() {
        // A straight wall at 2 m with 30 missing beams (7.5°) in the middle.
        let inc = 0.25f64.to_radians();
        let ranges: Vec<f32> = (0..200)
            .map(|i| {
                let a = -25f64.to_radians() + i as f64 * inc;
                if (80..110).contains(&i) { f32::NAN } else { (2.0 / a.cos()) as f32 }
            })
            .collect();
        let scan = Scan::new(-25f32.to_radians(), inc as f32, 0.1, 30.0, ranges);
        let p = points_of(&scan);
        let (mut b, mut c) = (vec![], vec![]);
        level1_clusters(&p, &BreakRule::adaptive_utm30lx(), 5, &mut b, &mut c);
        assert_eq!(c.len(), 2, "{c:?}");
        // A narrow gap (3 beams) does not break it.
        let ranges: Vec<f32> = (0..200)
            .map(|i| {
                let a = -25f64.to_radians() + i as f64 * inc;
                if (80..83).contains(&i) { f32::NAN } else { (2.0 / a.cos()) as f32 }
            })
            .collect();
        let p = points_of(&Scan::new(-25f32.to_radians(), inc as f32, 0.1, 30.0, ranges));
        level1_clusters(&p, &BreakRule::adaptive_utm30lx(), 5, &mut b, &mut c);
        assert_eq!(c.len(), 1, "{c:?}");
    }

    #[test]
    fn adaptive_threshold_keeps_far_grazing_wall_together() {
        // A wall seen at 25 m: spacing 0.25° * 25 m = 11 cm, grazing makes it larger.
        let rule = BreakRule::adaptive_utm30lx();
        assert!(rule.threshold_m(25.0, 25.5, 0.25f64.to_radians()) > 0.3);
        // Near points: a 15 cm gap at 1 m is a real break.
        assert!(rule.threshold_m(1.0, 1.0, 0.25f64.to_radians()) < 0.15);
    }

    /// Ranges of a wall `y = 1` (1 m to the left of the sensor) for bearings
    /// `from_deg`, `from_deg + step_deg`, ...
    fn side_wall(from_deg: f32, step_deg: f32, n: usize) -> Vec<f32> {
        (0..n).map(|i| 1.0 / (from_deg + i as f32 * step_deg).to_radians().sin()).collect()
    }

    fn adaptive(grazing: bool) -> BreakRule {
        BreakRule::Adaptive {
            lambda_rad: 10f64.to_radians(),
            sigma_factor: 3.0,
            noise: pcaline_geometry::RangeNoise::constant(0.01),
            grazing,
        }
    }

    #[test]
    fn a_wall_seen_at_grazing_incidence_stays_one_cluster() {
        // Bearings 4°..30° at 0.25°: incidence 86° down to 60°, spacing 0.25 m
        // down to 1.5 cm, beyond the adaptive threshold below ~10°.
        let scan = Scan::new(
            4f32.to_radians(),
            0.25f32.to_radians(),
            0.1,
            30.0,
            side_wall(4.0, 0.25, 105),
        );
        let p = points_of(&scan);
        let (mut b, mut c) = (vec![], vec![]);
        level1_clusters(&p, &adaptive(true), 5, &mut b, &mut c);
        assert_eq!(c, vec![0..105], "breaks {b:?}");
        level1_clusters(&p, &adaptive(false), 5, &mut b, &mut c);
        assert!(c.len() == 1 && c[0].start > 10, "without it the far end breaks up: {c:?}");
    }

    #[test]
    fn grazing_continuation_still_breaks_at_depth_jumps_and_spacing_jumps() {
        let mut ranges = side_wall(4.0, 0.25, 60);
        // A step back by 0.5 m in the middle (an object edge): a break.
        for r in &mut ranges[30..] {
            *r += 0.5;
        }
        let scan = Scan::new(4f32.to_radians(), 0.25f32.to_radians(), 0.1, 30.0, ranges);
        let p = points_of(&scan);
        let (mut b, mut c) = (vec![], vec![]);
        level1_clusters(&p, &adaptive(true), 5, &mut b, &mut c);
        assert!(b.contains(&30), "{b:?}");
        // The same line on both sides of four beams with no return (a
        // doorway seen edge-on): the spacing jumps, so a break.
        let mut ranges = side_wall(4.0, 0.25, 30);
        for r in &mut ranges[10..14] {
            *r = f32::NAN;
        }
        let scan = Scan::new(4f32.to_radians(), 0.25f32.to_radians(), 0.1, 30.0, ranges);
        let p = points_of(&scan);
        level1_clusters(&p, &adaptive(true), 5, &mut b, &mut c);
        assert!(b.contains(&10), "{b:?}");
        assert!(!continues_line(&p, 10, 3.0, &pcaline_geometry::RangeNoise::constant(0.01)));
        assert!(continues_line(&p, 9, 3.0, &pcaline_geometry::RangeNoise::constant(0.01)));
    }

    proptest::proptest! {
        /// The blocks' branch-free screen misses no break: without the
        /// grazing continuation, the breaks are exactly the pairs the rule
        /// breaks one by one, across block boundaries, gaps of invalid
        /// beams (another bearing step) and a first pair over a gap.
        #[test]
        fn blocks_find_the_breaks_the_rule_finds_pair_by_pair(
            ranges in proptest::collection::vec(
                proptest::prop_oneof![8 => 0.5f32..3.0, 1 => proptest::strategy::Just(f32::NAN)],
                0..300,
            ),
        ) {
            let scan = Scan::new(-2.0, 0.25f32.to_radians(), 0.1, 30.0, ranges);
            let p = points_of(&scan);
            let rule = adaptive(false);
            let (mut b, mut c) = (vec![], vec![]);
            level1_clusters(&p, &rule, 5, &mut b, &mut c);
            let mut expected: Vec<usize> = (1..p.len())
                .filter(|&j| {
                    let step = (p.angle_rad[j] - p.angle_rad[j - 1]).abs();
                    is_break(&p, j - 1, j, step, &rule)
                })
                .collect();
            if !p.is_empty() {
                expected.insert(0, 0);
            }
            proptest::prop_assert_eq!(b, expected);
        }
    }
}
