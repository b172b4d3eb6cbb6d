//! Recursive split (iterative end-point fit), the segmentation of the
//! split-and-merge extractors and pcaline's noise-aware level-2 variant: a
//! cluster is split at the point farthest from the chord joining its ends while
//! that distance exceeds a multiple of the range noise.

use pcaline_geometry::{RangeNoise, ScanPoints};
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
    stack.push(cluster);
    while let Some(r) = stack.pop() {
        match farthest_split(points, &r, noise, sigma_factor, min_distance_m) {
            Some(k) => {
                // Depth-first, left first: output stays in scan order.
                stack.push(k..r.end);
                stack.push(r.start..k);
            }
            None => out.push(r),
        }
    }
}

/// The index at which `r` splits, if any.
fn farthest_split(
    points: &ScanPoints,
    r: &Range<usize>,
    noise: &RangeNoise,
    sigma_factor: f64,
    min_distance_m: f64,
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
    let mut best = (0.0f64, 0usize);
    // The inner points, zipped: no bounds checks in the loop.
    let inner = r.start + 1..r.end - 1;
    let inner_points = points.xy[inner.clone()].iter().zip(&points.range_m[inner.clone()]);
    for (k, (p, &range)) in inner.zip(inner_points) {
        let v = p - a;
        let dist = if len > 1e-12 { (chord.x * v.y - chord.y * v.x).abs() } else { v.norm() };
        let scale = if range < noise.far_from_m { inv_near } else { inv_far };
        let excess = dist * scale;
        if excess > best.0 {
            best = (excess, k);
        }
    }
    let best = (if len > 1e-12 { best.0 / len } else { best.0 }, best.1);
    (best.0 > 1.0).then_some(best.1)
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
}
