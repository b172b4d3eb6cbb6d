//! [`fit_lines`]: the fitting half of the paper's section 2 in one call,
//! from sub-clusters to lines: corner-refined boundaries, a PCA fit of each
//! piece with the eigenvalue-ratio test (eq. 3-6), the merge of adjacent
//! collinear pieces (eq. 7), and the final tests of each line.

use crate::{
    FitConfig, Moments, Piece, Straightness, is_elongated, line_from_eigen, merge_adjacent,
    refine_boundaries, straightness,
};
use pcaline_geometry::{LineSegment, RangeNoise, ScanPoints};
use std::ops::Range;

/// A fitted line and the points it was fitted from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectedLine {
    /// The line in the sensor frame.
    pub line: LineSegment,
    /// Moments of the fitted points, sensor frame (for maps that refine lines).
    pub moments: Moments,
    /// Index of the first point in the scan's points.
    pub first_point: usize,
    /// Index of the last point, inclusive. Smaller than `first_point` only for
    /// a line that wraps around the end of a closed 360° scan.
    pub last_point: usize,
    /// Beam index of the first point.
    pub first_beam: u32,
    /// Beam index of the last point.
    pub last_beam: u32,
    /// How straight the points under the line are: residual against the
    /// noise the thresholds used (the UTM-30LX-EW datasheet for the paper's
    /// detector, which uses none) and the runs test of the residual signs.
    pub straightness: Straightness,
}

impl DetectedLine {
    /// Indices of the line's points in the scan's points, in scan order
    /// (wrapping for a line across the seam of a closed scan). Includes
    /// points of rejected pieces lying between merged pieces.
    pub fn point_indices(&self, n_points: usize) -> impl Iterator<Item = usize> + use<> {
        let (first, last) = (self.first_point, self.last_point);
        let len = if last >= first { last - first + 1 } else { n_points - first + last + 1 };
        (0..len).map(move |k| (first + k) % n_points.max(1))
    }
}

/// The lines [`fit_lines`] found, with its scratch buffers. Keep one
/// across scans: once warm, fitting allocates nothing.
#[derive(Debug, Clone, Default)]
pub struct LineFits {
    /// The lines, in scan order.
    pub lines: Vec<DetectedLine>,
    pieces: Vec<Piece>,
}

/// Fits the lines of one segmented scan.
///
/// `points` are the scan's points; `clusters` its level-1 clusters and
/// `sub_clusters` the level-2 pieces that tile them, in scan order (as
/// `pcaline_segmentation::segment` gives them). The boundaries between
/// sub-clusters of one cluster are first moved to the corner
/// ([`refine_boundaries`], [`FitConfig::corner_window`]), in place. Each
/// piece of at least [`FitConfig::min_points`] points that passes the
/// elongation test (eq. 5) and the residual test is fitted by PCA; adjacent
/// pieces of one cluster merge under [`FitConfig::merge`] (eq. 7), across
/// the seam when `ring_without_break` (a closed scan read as one cluster);
/// each merged line is kept when it has enough points and length, passes
/// the orientation test, and, when configured, the straightness test
/// against `noise` (the UTM-30LX-EW datasheet's when `None`).
///
/// Edge cases: sub-clusters outside `points`, or not inside a cluster, are
/// skipped; no sub-clusters give no lines.
///
/// ```
/// use pcaline_fitting::{FitConfig, LineFits, fit_lines};
/// use pcaline_geometry::{BearingTable, Scan, ScanPoints};
///
/// // A wall 2 m ahead, one cluster and one piece.
/// let ranges: Vec<f32> = (0..101).map(|i| 2.0 / (-0.5f32 + i as f32 * 0.01).cos()).collect();
/// let scan = Scan::new(-0.5, 0.01, 0.1, 30.0, ranges);
/// let mut points = ScanPoints::default();
/// points.fill_from(&scan, &mut BearingTable::default());
/// let mut fits = LineFits::default();
/// fit_lines(&points, &[0..101], &mut [0..101], false, &FitConfig::default(), None, &mut fits);
/// assert_eq!(fits.lines.len(), 1);
/// assert!((fits.lines[0].line.d() - 2.0).abs() < 1e-6);
/// ```
pub fn fit_lines(
    points: &ScanPoints,
    clusters: &[Range<usize>],
    sub_clusters: &mut [Range<usize>],
    ring_without_break: bool,
    config: &FitConfig,
    noise: Option<&RangeNoise>,
    out: &mut LineFits,
) {
    let xy = &points.xy;
    // Corner refinement, cluster by cluster (sub-clusters tile clusters).
    let mut first_sub = 0;
    for cluster in clusters {
        let mut end = first_sub;
        while end < sub_clusters.len() && sub_clusters[end].end <= cluster.end {
            end += 1;
        }
        refine_boundaries(xy, &mut sub_clusters[first_sub..end], config.corner_window);
        first_sub = end;
    }

    out.pieces.clear();
    let mut cluster_id = 0;
    for sub in sub_clusters.iter() {
        while clusters.get(cluster_id).is_some_and(|c| c.end < sub.end) {
            cluster_id += 1;
        }
        if sub.len() < config.min_points || sub.end > xy.len() || cluster_id >= clusters.len() {
            continue;
        }
        let moments = Moments::from_points(&xy[sub.clone()]);
        let eigen = moments.eigen();
        if is_elongated(&eigen, config.eth)
            && config.residual_test.is_none_or(|t| t.accepts(&moments, &eigen))
        {
            out.pieces.push(Piece {
                moments,
                first: sub.start,
                last: sub.end - 1,
                cluster: cluster_id,
            });
        }
    }

    merge_adjacent(&mut out.pieces, &config.merge, ring_without_break);

    out.lines.clear();
    let reference_noise = noise.copied().unwrap_or(RangeNoise::utm30lx());
    for piece in &out.pieces {
        let (first, last) = (xy[piece.first], xy[piece.last]);
        // One eigen decomposition serves the fit and the orientation test.
        let eigen = piece.moments.eigen();
        let Some(line) = line_from_eigen(&piece.moments, &eigen, &first, &last) else { continue };
        if line.n_points() < config.min_line_points
            || line.length() < config.min_line_length_m
            || config.orientation_test.is_some_and(|t| !t.accepts(&piece.moments, &eigen))
        {
            continue;
        }
        // The line's points in scan order, wrapping past the end of a
        // closed scan.
        let straightness = if piece.last >= piece.first {
            straightness(&xy[piece.first..=piece.last], &line, &reference_noise)
        } else {
            let wrapped = xy[piece.first..].iter().chain(&xy[..=piece.last]);
            straightness(wrapped, &line, &reference_noise)
        };
        let sigma = reference_noise.sigma_at(line.centroid().coords.norm());
        if config.straightness_test.is_some_and(|t| !t.accepts(&straightness, sigma)) {
            continue;
        }
        out.lines.push(DetectedLine {
            line,
            moments: piece.moments,
            first_point: piece.first,
            last_point: piece.last,
            first_beam: points.beam[piece.first],
            last_beam: points.beam[piece.last],
            straightness,
        });
    }
}

#[cfg(test)]
// One cluster is a slice of one range, not a vector of its indices.
#[allow(clippy::single_range_in_vec_init)]
mod tests {
    use super::*;
    use pcaline_geometry::{BearingTable, Scan};

    fn points_of(ranges: Vec<f32>) -> ScanPoints {
        let scan = Scan::new(-0.5, 0.01, 0.1, 30.0, ranges);
        let mut points = ScanPoints::default();
        points.fill_from(&scan, &mut BearingTable::default());
        points
    }

    #[test]
    fn collinear_pieces_merge_into_one_line() {
        let points = points_of((0..101).map(|i| 2.0 / (-0.5f32 + i as f32 * 0.01).cos()).collect());
        let mut fits = LineFits::default();
        let mut subs = [0..40, 40..70, 70..101];
        fit_lines(&points, &[0..101], &mut subs, false, &FitConfig::default(), None, &mut fits);
        assert_eq!(fits.lines.len(), 1);
        let l = &fits.lines[0];
        assert_eq!((l.first_point, l.last_point, l.first_beam, l.last_beam), (0, 100, 0, 100));
        assert_eq!(l.point_indices(101).count(), 101);
    }

    #[test]
    fn pieces_of_different_clusters_never_merge() {
        let points = points_of((0..101).map(|i| 2.0 / (-0.5f32 + i as f32 * 0.01).cos()).collect());
        let mut fits = LineFits::default();
        let mut subs = [0..50, 50..101];
        fit_lines(
            &points,
            &[0..50, 50..101],
            &mut subs,
            false,
            &FitConfig::default(),
            None,
            &mut fits,
        );
        assert_eq!(fits.lines.len(), 2);
    }

    #[test]
    fn ranges_outside_the_points_are_skipped() {
        let points = points_of(vec![2.0; 20]);
        let mut fits = LineFits::default();
        fit_lines(&points, &[0..500], &mut [0..500], false, &FitConfig::default(), None, &mut fits);
        assert!(fits.lines.is_empty());
        fit_lines(&points, &[], &mut [], false, &FitConfig::default(), None, &mut fits);
        assert!(fits.lines.is_empty());
    }
}
