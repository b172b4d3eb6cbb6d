//! Level-2 clustering (paper eq. 2a/2b): inside a level-1 cluster, new
//! break-points at the local peaks of the derivatives `dx/dtheta` and
//! `dy/dtheta` that exceed their mean plus standard deviation over the cluster.

use pcaline_geometry::ScanPoints;
use std::ops::Range;

/// Which values of the derivatives the peak rule compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum DerivativeSign {
    /// As printed in eq. 2a/2b: the signed derivative against its signed mean
    /// plus standard deviation (peaks of decreasing coordinates are never found).
    Signed,
    /// The absolute derivative against the mean plus standard deviation of the
    /// absolute values: finds steep changes in either direction.
    Absolute,
}

/// Splits `cluster` at the peaks of `dx/dtheta` and `dy/dtheta` (eq. 2a/2b),
/// appending the sub-clusters to `out` in order. The sub-clusters cover the
/// cluster exactly: no point is dropped at a split.
///
/// The derivative at point `k` is the backward difference
/// `(x_k - x_{k-1}) / (theta_k - theta_{k-1})`, so a peak at `k` makes `k` the
/// first point of a new sub-cluster. The threshold is the mean plus the
/// *standard deviation* over the cluster, as the paper's text says (the
/// printed formula omits the square root, which would make the threshold
/// depend on the unit of length). A peak is a value above the threshold that
/// is greater than its left neighbour and not smaller than its right one; the
/// first and last derivative have only one neighbour and are never peaks.
/// Clusters of fewer than 4 points (fewer than 3 derivatives) are not split.
/// `scratch` is a reused buffer.
pub fn derivative_peak_split(
    points: &ScanPoints,
    cluster: Range<usize>,
    sign: DerivativeSign,
    scratch: &mut Vec<[f64; 2]>,
    out: &mut Vec<Range<usize>>,
) {
    let n = cluster.len();
    if n < 4 {
        out.push(cluster);
        return;
    }
    scratch.clear();
    for k in cluster.start + 1..cluster.end {
        let dtheta = points.angle_rad[k] - points.angle_rad[k - 1];
        let d = points.xy[k] - points.xy[k - 1];
        let (dx, dy) = if dtheta != 0.0 { (d.x / dtheta, d.y / dtheta) } else { (0.0, 0.0) };
        scratch.push(match sign {
            DerivativeSign::Signed => [dx, dy],
            DerivativeSign::Absolute => [dx.abs(), dy.abs()],
        });
    }
    let m = scratch.len() as f64;
    let mut thresholds = [0.0; 2];
    for (axis, t) in thresholds.iter_mut().enumerate() {
        let mean = scratch.iter().map(|v| v[axis]).sum::<f64>() / m;
        let var = scratch.iter().map(|v| (v[axis] - mean).powi(2)).sum::<f64>() / (m - 1.0);
        *t = mean + var.sqrt();
    }
    let mut start = cluster.start;
    for (idx, v) in scratch.iter().enumerate() {
        let is_peak = |axis: usize| {
            let x = v[axis];
            x > thresholds[axis]
                && idx > 0
                && x > scratch[idx - 1][axis]
                && scratch.get(idx + 1).is_some_and(|next| x >= next[axis])
        };
        if is_peak(0) || is_peak(1) {
            let k = cluster.start + 1 + idx;
            out.push(start..k);
            start = k;
        }
    }
    out.push(start..cluster.end);
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::{BearingTable, Scan};

    fn corner_scan() -> ScanPoints {
        // A wall at x = 2 seen from -40° to 0°, then a wall at y = 1 beyond the corner.
        let inc = 0.5f64.to_radians();
        let ranges: Vec<f32> = (0..160)
            .map(|i| {
                let a = -40f64.to_radians() + i as f64 * inc;
                let rx = if a.cos() > 1e-9 { 2.0 / a.cos() } else { f64::INFINITY };
                let ry = if a.sin() > 1e-9 { 1.0 / a.sin() } else { f64::INFINITY };
                rx.min(ry) as f32
            })
            .collect();
        let scan = Scan::new(-40f32.to_radians(), inc as f32, 0.1, 30.0, ranges);
        let mut p = ScanPoints::default();
        p.fill_from(&scan, &mut BearingTable::default());
        p
    }

    #[test]
    fn sub_clusters_cover_the_cluster() {
        let p = corner_scan();
        for sign in [DerivativeSign::Signed, DerivativeSign::Absolute] {
            let mut out = vec![];
            derivative_peak_split(&p, 0..p.len(), sign, &mut vec![], &mut out);
            assert_eq!(out.first().unwrap().start, 0);
            assert_eq!(out.last().unwrap().end, p.len());
            for w in out.windows(2) {
                assert_eq!(w[0].end, w[1].start, "no point dropped at a split");
            }
        }
    }

    #[test]
    fn absolute_rule_breaks_near_the_corner() {
        let p = corner_scan();
        // The corner is where the wall x = 2 meets y = 1: bearing atan(1/2).
        let corner = p.angle_rad.iter().position(|&a| a > 0.5f64.atan()).unwrap();
        let mut out = vec![];
        derivative_peak_split(&p, 0..p.len(), DerivativeSign::Absolute, &mut vec![], &mut out);
        assert!(
            out.iter().any(|r| (r.start as i64 - corner as i64).abs() <= 2),
            "break-points {out:?}, corner at {corner}"
        );
    }

    #[test]
    fn tiny_cluster_is_not_split() {
        let p = corner_scan();
        let mut out = vec![];
        derivative_peak_split(&p, 3..6, DerivativeSign::Signed, &mut vec![], &mut out);
        assert_eq!(out, vec![3..6]);
    }
}
