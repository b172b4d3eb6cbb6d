//! [`segment`]: both clustering levels of the paper's section 2.1 on one
//! scan's points in one call: the seam of a 360° scan, the level-1
//! break-points (eq. 2) and the level-2 rule inside each kept cluster.

use crate::{
    Level2Rule, SegmentationConfig, derivative_peak_split, level1_clusters, seam_start,
    split_at_farthest,
};
use pcaline_geometry::{Scan, ScanPoints};
use std::ops::Range;

/// What [`segment`] found, with its scratch buffers. Keep one across scans:
/// once its vectors have grown to the largest scan, segmenting allocates
/// nothing.
#[derive(Debug, Clone, Default)]
pub struct Segments {
    /// Level-1 break-points: indices of the points that begin a cluster.
    pub level1_breaks: Vec<usize>,
    /// Level-1 clusters with at least
    /// [`SegmentationConfig::min_cluster_points`] points, in scan order.
    pub clusters: Vec<Range<usize>>,
    /// Level-2 sub-clusters in scan order; those of each kept cluster tile
    /// it exactly (no point is dropped at a split).
    pub sub_clusters: Vec<Range<usize>>,
    /// A closed (360°) scan without any level-1 break-point, read as one
    /// cluster: its first and last sub-clusters are neighbours across the
    /// seam (a merge may join them).
    pub ring_without_break: bool,
    derivative_scratch: Vec<[f64; 2]>,
    split_stack: Vec<Range<usize>>,
}

/// Segments `points`, the valid returns of `scan` (as
/// [`ScanPoints::fill_from`] makes them, deskewed or not): level-1 clusters
/// by the break rule, then level-2 sub-clusters by the configured rule.
///
/// For a closed scan ([`Scan::is_closed`]) the points are first rotated to
/// start at a level-1 break-point, so that no cluster crosses the ±180°
/// seam; with no break-point at all the ring stays as it is and
/// [`Segments::ring_without_break`] is set.
///
/// Edge cases: no points, or fewer than the minimum cluster size, give no
/// cluster; invalid returns are never points, so nothing here sees a NaN.
///
/// ```
/// use pcaline_geometry::{BearingTable, Scan, ScanPoints};
/// use pcaline_segmentation::{SegmentationConfig, Segments, segment};
///
/// // Two walls 1 m apart in depth: a level-1 break between them.
/// let ranges: Vec<f32> = (0..100).map(|i| if i < 50 { 2.0 } else { 3.0 }).collect();
/// let scan = Scan::new(-0.5, 0.01, 0.1, 30.0, ranges);
/// let mut points = ScanPoints::default();
/// points.fill_from(&scan, &mut BearingTable::default());
/// let mut segments = Segments::default();
/// segment(&scan, &mut points, &SegmentationConfig::default(), &mut segments);
/// assert_eq!(segments.clusters, vec![0..50, 50..100]);
/// ```
pub fn segment(
    scan: &Scan,
    points: &mut ScanPoints,
    config: &SegmentationConfig,
    out: &mut Segments,
) {
    out.ring_without_break = false;
    if scan.is_closed() {
        match seam_start(points, &config.level1) {
            Some(start) => {
                let turn = std::f64::consts::TAU * f64::from(scan.angle_increment).signum();
                points.rotate_start(start, turn);
            }
            None => out.ring_without_break = points.len() >= config.min_cluster_points,
        }
    }

    level1_clusters(
        points,
        &config.level1,
        config.min_cluster_points,
        &mut out.level1_breaks,
        &mut out.clusters,
    );

    out.sub_clusters.clear();
    for cluster in &out.clusters {
        match config.level2 {
            Level2Rule::DerivativePeaks { sign } => derivative_peak_split(
                points,
                cluster.clone(),
                sign,
                &mut out.derivative_scratch,
                &mut out.sub_clusters,
            ),
            Level2Rule::SplitAtFarthest { sigma_factor, min_distance_m, noise } => {
                split_at_farthest(
                    points,
                    cluster.clone(),
                    &noise,
                    sigma_factor,
                    min_distance_m,
                    &mut out.split_stack,
                    &mut out.sub_clusters,
                )
            }
            Level2Rule::None => out.sub_clusters.push(cluster.clone()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::BearingTable;

    fn segmented(scan: &Scan, config: &SegmentationConfig) -> (ScanPoints, Segments) {
        let mut points = ScanPoints::default();
        points.fill_from(scan, &mut BearingTable::default());
        let mut segments = Segments::default();
        segment(scan, &mut points, config, &mut segments);
        (points, segments)
    }

    #[test]
    fn sub_clusters_tile_the_kept_clusters() {
        // A corner, then a gap, then a far wall.
        let ranges: Vec<f32> = (0..300)
            .map(|i| {
                let b = -1.0 + i as f64 * 0.005;
                if i < 200 {
                    (1.5 / b.cos()).min(2.0 / b.sin().abs().max(1e-3)) as f32
                } else {
                    6.0
                }
            })
            .collect();
        let scan = Scan::new(-1.0, 0.005, 0.1, 30.0, ranges);
        for config in [SegmentationConfig::paper(), SegmentationConfig::default()] {
            let (points, s) = segmented(&scan, &config);
            assert!(!s.clusters.is_empty());
            let mut subs = s.sub_clusters.iter();
            for c in &s.clusters {
                let mut at = c.start;
                for sub in subs.by_ref() {
                    assert_eq!(sub.start, at);
                    at = sub.end;
                    if at == c.end {
                        break;
                    }
                }
                assert_eq!(at, c.end);
            }
            assert!(s.clusters.last().is_some_and(|c| c.end <= points.len()));
            assert!(!s.ring_without_break);
        }
    }

    #[test]
    fn a_closed_room_without_breaks_is_one_ring() {
        // A circle of radius 2 m around the sensor, 720 beams over a turn.
        let n = 720;
        let inc = std::f32::consts::TAU / n as f32;
        let scan = Scan::new(-std::f32::consts::PI, inc, 0.1, 30.0, vec![2.0; n]);
        assert!(scan.is_closed());
        let (_, s) = segmented(&scan, &SegmentationConfig::default());
        assert!(s.ring_without_break);
        assert_eq!(s.clusters, vec![0..n]);
    }

    #[test]
    fn no_points_no_clusters() {
        let scan = Scan::new(0.0, 0.01, 0.1, 30.0, vec![f32::NAN; 50]);
        let (points, s) = segmented(&scan, &SegmentationConfig::default());
        assert!(points.is_empty() && s.clusters.is_empty() && s.sub_clusters.is_empty());
    }
}
