//! Recursive split (iterative end-point fit), the segmentation of the
//! split-and-merge extractors and pcaline's noise-aware level-2 variant: a
//! cluster is split at the point farthest from the chord joining its ends while
//! that distance exceeds a multiple of the range noise.

use pcaline_geometry::{Point2, RangeNoise, ScanPoints, Vector2};
use std::ops::Range;

/// Splits `cluster` recursively at the point farthest from the chord between
/// the first and last point, while that point's distance exceeds
/// `max(sigma_factor * sigma(range), min_distance_m)`; appends the resulting
/// sub-clusters to `out` in order. The farthest point begins the right-hand
/// sub-cluster; the sub-clusters cover the cluster exactly.
///
/// `stack` is a reused buffer. Clusters of fewer than 3 points are not split.
pub fn split_at_farthest(
    points: &ScanPoints,
    cluster: Range<usize>,
    noise: &RangeNoise,
    sigma_factor: f64,
    min_distance_m: f64,
    stack: &mut Vec<Range<usize>>,
    out: &mut Vec<Range<usize>>,
) {
    stack.clear();
    // A cluster wholly in one range band has one threshold for every point,
    // and its split needs no per-point band test.
    let ranges = &points.range_m[cluster.clone()];
    let one_band = ranges.iter().all(|&r| r < noise.far_from_m)
        || ranges.iter().all(|&r| r >= noise.far_from_m);
    stack.push(cluster);
    while let Some(r) = stack.pop() {
        match farthest_split(points, &r, noise, sigma_factor, min_distance_m, one_band) {
            Some(k) => {
                // Depth-first, left first: output stays in scan order.
                stack.push(k..r.end);
                stack.push(r.start..k);
            }
            None => out.push(r),
        }
    }
}

/// The index at which `r` splits, if any. `one_band`: every point of `r`
/// lies in the range band of its first.
fn farthest_split(
    points: &ScanPoints,
    r: &Range<usize>,
    noise: &RangeNoise,
    sigma_factor: f64,
    min_distance_m: f64,
    one_band: bool,
) -> Option<usize> {
    if r.len() < 3 {
        return None;
    }
    let a = points.xy[r.start];
    let b = points.xy[r.end - 1];
    let chord = b - a;
    let len = chord.norm();
    // Maximise distance / threshold without a division per point: the
    // threshold takes one of two values (near and far noise).
    let inv = |sigma: f64| 1.0 / (sigma_factor * sigma).max(min_distance_m).max(1e-12);
    let (inv_near, inv_far) = (inv(noise.near_sigma_m), inv(noise.far_sigma_m));
    let scale_at = |range: f64| if range < noise.far_from_m { inv_near } else { inv_far };
    // The inner points, zipped with their scales: no bounds checks in the
    // loop, and no band test per point where the band is one.
    let inner = r.start + 1..r.end - 1;
    let best = if one_band {
        let scale = scale_at(points.range_m[r.start]);
        farthest(&points.xy[inner.clone()], std::iter::repeat(scale), a, chord, len)
    } else {
        let scales = points.range_m[inner.clone()].iter().map(|&range| scale_at(range));
        farthest(&points.xy[inner.clone()], scales, a, chord, len)
    };
    let best = (if len > 1e-12 { best.0 / len } else { best.0 }, r.start + 1 + best.1);
    (best.0 > 1.0).then_some(best.1)
}

/// The largest scaled distance of `points` from the chord from `a` (its
/// length `len` times the distance; the distance from `a` for a chord of
/// zero length), and the offset of its point in `points` (the first of
/// equals; 0 and offset 0 when none exceeds 0).
fn farthest(
    points: &[Point2<f64>],
    scales: impl Iterator<Item = f64>,
    a: Point2<f64>,
    chord: Vector2<f64>,
    len: f64,
) -> (f64, usize) {
    let mut best = (0.0f64, 0usize);
    for (k, (p, scale)) in points.iter().zip(scales).enumerate() {
        let v = p - a;
        let dist = if len > 1e-12 { (chord.x * v.y - chord.y * v.x).abs() } else { v.norm() };
        let excess = dist * scale;
        if excess > best.0 {
            best = (excess, k);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::{BearingTable, Scan};

    #[test]
    fn splits_a_corner_only() {
        // Wall x = 2 then wall y = 1: one split near the corner.
        let inc = 0.5f64.to_radians();
        let ranges: Vec<f32> = (0..160)
            .map(|i| {
                let a = -40f64.to_radians() + i as f64 * inc;
                let rx = 2.0 / a.cos();
                let ry = if a.sin() > 1e-9 { 1.0 / a.sin() } else { f64::INFINITY };
                rx.min(ry) as f32
            })
            .collect();
        let scan = Scan::new(-40f32.to_radians(), inc as f32, 0.1, 30.0, ranges);
        let mut p = ScanPoints::default();
        p.fill_from(&scan, &mut BearingTable::default());
        let mut out = vec![];
        split_at_farthest(
            &p,
            0..p.len(),
            &RangeNoise::constant(0.01),
            3.0,
            0.0,
            &mut vec![],
            &mut out,
        );
        assert_eq!(out.len(), 2, "{out:?}");
        assert_eq!(out[0].start, 0);
        assert_eq!(out[0].end, out[1].start);
        assert_eq!(out[1].end, p.len());
        let corner = p.angle_rad.iter().position(|&a| a > 0.5f64.atan()).unwrap();
        assert!((out[1].start as i64 - corner as i64).abs() <= 1);
    }

    /// A wall 2 m ahead whose ranges cross `far_from_m` (3 m) part-way,
    /// with a 5 cm bump: beyond 3 m the threshold (3 x 50 mm) leaves it,
    /// before 3 m (3 x 1 mm) it splits there, and a cluster wholly in one
    /// band splits as it would with that band's threshold throughout.
    #[test]
    fn each_point_is_judged_by_its_own_band() {
        let inc = 0.5f64.to_radians();
        let mut noise = RangeNoise::constant(0.001);
        (noise.far_sigma_m, noise.far_from_m) = (0.05, 3.0);
        let wall = |bump_at: f64| -> ScanPoints {
            let ranges: Vec<f32> = (0..200)
                .map(|i| {
                    let a = i as f64 * inc;
                    let r = 2.0 / a.cos();
                    let bump = if (r - bump_at).abs() < 0.05 { 0.05 } else { 0.0 };
                    (r - bump) as f32
                })
                .collect();
            let scan = Scan::new(0.0, inc as f32, 0.1, 30.0, ranges);
            let mut p = ScanPoints::default();
            p.fill_from(&scan, &mut BearingTable::default());
            p
        };
        let split = |p: &ScanPoints, cluster: std::ops::Range<usize>| {
            let mut out = vec![];
            split_at_farthest(p, cluster, &noise, 3.0, 0.0, &mut vec![], &mut out);
            out
        };
        let far_bump = wall(3.5);
        let crossing = far_bump.range_m.iter().position(|&r| r >= 3.0).unwrap();
        assert!(crossing > 10 && crossing + 10 < far_bump.len());
        // Both bands, the bump beyond 3 m: one piece.
        assert_eq!(split(&far_bump, 0..far_bump.len()).len(), 1);
        // Both bands, the bump before 3 m: split.
        let near_bump = wall(2.5);
        assert!(split(&near_bump, 0..near_bump.len()).len() > 1);
        // The far part alone (one band): the bump stays; the near part
        // alone with its bump: split.
        assert_eq!(split(&far_bump, crossing..far_bump.len()).len(), 1);
        assert!(split(&near_bump, 0..crossing).len() > 1);
    }
}
