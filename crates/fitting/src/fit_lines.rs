//! [`fit_lines`]: the fitting half of the paper's section 2 in one call,
//! from sub-clusters to lines: corner-refined boundaries, a PCA fit of each
//! piece with the eigenvalue-ratio test (eq. 3-6), the merge of adjacent
//! collinear pieces (eq. 7), and the final tests of each line.

use crate::{
    FitConfig, KinkTest, Moments, Piece, RunSums, Straightness, best_split, edge_on_ends,
    is_elongated, line_from_eigen, merge_adjacent, refine_boundaries, straightness,
};
use pcaline_geometry::{LineSegment, Point2, RangeNoise, ScanPoints};
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
    /// Lines still to be tested for a kink: first and last point, moments.
    pending: Vec<(usize, usize, Moments)>,
    /// Scratch of [`best_split`].
    suffix: Vec<RunSums>,
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
/// with [`FitConfig::kink_test`], a line whose points two lines fit
/// significantly better is cut in two ([`best_split`]), again for each
/// part; with [`FitConfig::edge_on_ends`], the end runs of a line that lie
/// on another surface seen edge-on are dropped ([`edge_on_ends`]) and the
/// rest tested again; each line is kept when it has enough points and length, passes
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
    for i in 0..out.pieces.len() {
        let piece = out.pieces[i];
        out.pending.clear();
        out.pending.push((piece.first, piece.last, piece.moments));
        while let Some((first, last, moments)) = out.pending.pop() {
            // One eigen decomposition serves the fit and the orientation test.
            let eigen = moments.eigen();
            let Some(line) = line_from_eigen(&moments, &eigen, &xy[first], &xy[last]) else {
                continue;
            };
            // The straightness pass is made once: before the kink test
            // when there is one (its screen), else only for lines that
            // pass the cheaper tests.
            let mut measured = None;
            if let Some(test) = &config.kink_test {
                let s = straightness_over(xy, first, last, &line, &reference_noise);
                measured = Some(s);
                let cut = (s.runs_z < test.max_runs_z)
                    .then(|| {
                        kink_cut(
                            first,
                            last,
                            &moments,
                            &line,
                            xy,
                            config,
                            &reference_noise,
                            test,
                            &mut out.suffix,
                        )
                    })
                    .flatten();
                if let Some(k) = cut {
                    // Right part first onto the stack, so the left one is
                    // finished first and the lines stay in scan order.
                    out.pending.push((k, last, Moments::from_points(&xy[k..=last])));
                    out.pending.push((first, k - 1, Moments::from_points(&xy[first..k])));
                    continue;
                }
            }
            // A line the tests below reject whatever its ends is not
            // walked: cutting them leaves fewer points and less spread.
            if let Some(test) = &config.edge_on_ends
                && last >= first
                && moments.n == last - first + 1
                && moments.n >= config.min_line_points
                && !config.orientation_test.is_some_and(|t| t.rejects_every_part(&moments, &eigen))
            {
                let sigma = reference_noise.sigma_at(line.centroid().coords.norm());
                let (start, end) = edge_on_ends(&xy[first..=last], &moments, sigma, test);
                if start + end > 0 {
                    // The rest tested again; the ends, returns of a surface
                    // seen edge-on, make no line.
                    let (lo, hi) = (first + start, last - end);
                    out.pending.push((lo, hi, Moments::from_points(&xy[lo..=hi])));
                    continue;
                }
            }
            if line.n_points() < config.min_line_points
                || line.length() < config.min_line_length_m
                || config.orientation_test.is_some_and(|t| !t.accepts(&moments, &eigen))
            {
                continue;
            }
            let straightness = measured
                .unwrap_or_else(|| straightness_over(xy, first, last, &line, &reference_noise));
            let sigma = reference_noise.sigma_at(line.centroid().coords.norm());
            if config.straightness_test.is_some_and(|t| !t.accepts(&straightness, sigma)) {
                continue;
            }
            out.lines.push(DetectedLine {
                line,
                moments,
                first_point: first,
                last_point: last,
                first_beam: points.beam[first],
                last_beam: points.beam[last],
                straightness,
            });
        }
    }
}

/// The straightness of `line` over points `first..=last` of `xy`, in scan
/// order (wrapping past the end of a closed scan when `last < first`).
fn straightness_over(
    xy: &[Point2<f64>],
    first: usize,
    last: usize,
    line: &LineSegment,
    noise: &RangeNoise,
) -> Straightness {
    if last >= first {
        straightness(&xy[first..=last], line, noise)
    } else {
        straightness(xy[first..].iter().chain(&xy[..=last]), line, noise)
    }
}

/// Where to cut the line through points `first..=last` with `moments` in
/// two under `test` (the index of the first point of the right part), when
/// the moments hold every point between its ends (no rejected piece inside,
/// not across the seam of a closed scan).
#[allow(clippy::too_many_arguments)]
fn kink_cut(
    first: usize,
    last: usize,
    moments: &Moments,
    line: &LineSegment,
    xy: &[Point2<f64>],
    config: &FitConfig,
    noise: &RangeNoise,
    test: &KinkTest,
    suffix: &mut Vec<RunSums>,
) -> Option<usize> {
    if last < first || moments.n != last - first + 1 {
        return None;
    }
    let sigma = noise.sigma_at(line.centroid().coords.norm());
    let (k, chi2) = best_split(&xy[first..=last], config.min_points, sigma, suffix)?;
    (chi2 > test.min_chi2).then_some(first + k)
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

    /// A wall's front face (x = 2) and its 10 cm end face, as one piece:
    /// the kink test cuts the end face off, which is then too short to be
    /// a line, and the wall comes out exact; without it the line is tilted.
    #[test]
    fn a_wall_and_its_end_face_are_cut_apart_by_the_kink_test() {
        let mut points = ScanPoints::default();
        let front = (0..40).map(|k| Point2::new(2.0, -3.0 + 0.0625 * k as f64));
        let cap = (0..12).map(|j| Point2::new(2.0 + 0.1 * j as f64 / 11.0, -0.5));
        for (i, p) in front.chain(cap).enumerate() {
            points.xy.push(p);
            points.range_m.push(p.coords.norm());
            points.angle_rad.push(p.y.atan2(p.x));
            points.beam.push(i as u32);
        }
        let n = points.len();
        let mut fits = LineFits::default();
        let mut config = FitConfig::default();
        fit_lines(&points, &[0..n], &mut [0..n], false, &config, None, &mut fits);
        assert_eq!(fits.lines.len(), 1);
        assert!(fits.lines[0].line.alpha().abs() > 0.5f64.to_radians(), "{:?}", fits.lines[0].line);
        config.kink_test = Some(KinkTest::standard());
        // Noise-free points have runs of one sign wherever they bend.
        fit_lines(&points, &[0..n], &mut [0..n], false, &config, None, &mut fits);
        assert_eq!(fits.lines.len(), 1, "{:#?}", fits.lines);
        let l = &fits.lines[0];
        assert!(l.line.alpha().abs() < 1e-9 && (l.line.d() - 2.0).abs() < 1e-9, "{:?}", l.line);
        assert_eq!((l.first_point, l.last_point, l.moments.n), (0, 39, 40));
    }

    /// A wall seen by beams 0.25° apart up to its end, then 7 beams on its
    /// 10 cm face seen nearly edge-on: with the edge-on test the face's
    /// returns leave the line, which then lies on the wall.
    #[test]
    fn an_end_face_seen_edge_on_leaves_the_wall_line() {
        use std::f64::consts::FRAC_PI_4;
        let mut points = ScanPoints::default();
        for i in 0..47u32 {
            let b = FRAC_PI_4 + (f64::from(i) - 39.0) * 0.25f64.to_radians();
            let r = if b <= FRAC_PI_4 + 1e-9 { 1.5 / b.cos() } else { 1.5 / b.sin() };
            points.xy.push(Point2::new(r * b.sin(), r * b.cos()));
            points.range_m.push(r);
            points.angle_rad.push(b);
            points.beam.push(i);
        }
        let n = points.len();
        let mut fits = LineFits::default();
        let mut config = FitConfig::default();
        fit_lines(&points, &[0..n], &mut [0..n], false, &config, None, &mut fits);
        assert_eq!(fits.lines.len(), 1);
        assert_eq!(fits.lines[0].last_point, 46);
        config.edge_on_ends = Some(crate::EdgeOnEnds::standard());
        fit_lines(&points, &[0..n], &mut [0..n], false, &config, None, &mut fits);
        assert_eq!(fits.lines.len(), 1, "{:#?}", fits.lines);
        let l = &fits.lines[0];
        assert_eq!((l.first_point, l.last_point, l.moments.n), (0, 39, 40));
        assert!((l.line.d() - 1.5).abs() < 1e-9, "{:?}", l.line);
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
