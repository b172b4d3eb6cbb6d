//! Merge of adjacent collinear line pieces (paper eq. 7), refitting from the
//! kept [`Moments`] so each merge is O(1), repeated until nothing merges.

use crate::{Moments, SymmetricEigen2};
use pcaline_geometry::{RangeNoise, line_angle_diff};

/// A fitted piece of a scan: the moments of its points and the indices of its
/// first and last point in the scan's point array.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Piece {
    /// Moments of the points fitted.
    pub moments: Moments,
    /// Index of the first point.
    pub first: usize,
    /// Index of the last point (inclusive).
    pub last: usize,
    /// The level-1 cluster the piece came from; pieces of different clusters
    /// are separated by a gap in the scan and never merge.
    pub cluster: usize,
}

/// When two adjacent pieces are the same line.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum MergeRule {
    /// The paper's eq. 7: the two directions differ by less than `alpha_t_rad`
    /// and both lie within `alpha_t_rad` of the segment joining the centroids
    /// (all compared as undirected lines, modulo 180°).
    Angles {
        /// The angular threshold `alpha_T` in radians (paper: 0.05°).
        alpha_t_rad: f64,
    },
    /// A statistical test: merge when forcing one line through both pieces
    /// increases the sum of squared orthogonal residuals by no more than
    /// `max_chi2` noise variances. For two pieces of one straight wall the
    /// increase is `sigma² chi²(2)` (two more parameters), so a `chi²(2)`
    /// quantile is the natural threshold (13.8 is its 99.9% point). The noise
    /// variance is the larger of the model's at the joint centroid's range (the
    /// sensor is at the frame origin) and the pieces' pooled residual variance,
    /// so a sensor noisier than its model does not fragment walls. Unlike a
    /// test on the joint residual alone, a short piece across a corner cannot
    /// hide in a long wall's average.
    ResidualIncrease {
        /// Largest allowed increase, in noise variances.
        max_chi2: f64,
        /// The sensor's range noise.
        noise: RangeNoise,
    },
    /// Never merge.
    Never,
}

impl MergeRule {
    /// True when pieces with moments `a` and `b` are the same line.
    pub fn accepts(&self, a: &Moments, b: &Moments) -> bool {
        match *self {
            MergeRule::Never => false,
            MergeRule::Angles { alpha_t_rad } => {
                let (ea, eb) = (a.eigen(), b.eigen());
                let angle = |e: &SymmetricEigen2| e.major.y.atan2(e.major.x);
                let (a1, a2) = (angle(&ea), angle(&eb));
                let cc = b.mean - a.mean;
                let acc = cc.y.atan2(cc.x);
                line_angle_diff(a1, a2).abs() < alpha_t_rad
                    && line_angle_diff(a1, acc).abs() < alpha_t_rad
                    && line_angle_diff(a2, acc).abs() < alpha_t_rad
            }
            MergeRule::ResidualIncrease { max_chi2, noise } => {
                if a.n < 2 || b.n < 2 {
                    return false;
                }
                let joint = a.merge(b);
                let sse = |m: &Moments| m.eigen().lambda_min * m.n as f64;
                let (sse_a, sse_b) = (sse(a), sse(b));
                let increase = sse(&joint) - sse_a - sse_b;
                let dof = joint.n.saturating_sub(4).max(1) as f64;
                let pooled = (sse_a + sse_b) / dof;
                let model = noise.sigma_at(joint.mean.coords.norm()).powi(2);
                increase <= max_chi2 * model.max(pooled)
            }
        }
    }
}

/// Merges adjacent pieces of the same cluster that `rule` accepts, refitting
/// from the merged moments, and repeats until no pair merges (eq. 7).
///
/// Pieces are visited in order; a merge never drops a piece's points, and a
/// single piece is returned unchanged. When `closed` is set (a 360° scan whose
/// first and last pieces are neighbours across the seam and in the same
/// cluster), the last piece may also merge into the first.
pub fn merge_adjacent(pieces: &mut Vec<Piece>, rule: &MergeRule, closed: bool) {
    if matches!(rule, MergeRule::Never) {
        return;
    }
    loop {
        let before = pieces.len();
        let mut write = 0;
        for read in 1..pieces.len() {
            let (cur, next) = (pieces[write], pieces[read]);
            if cur.cluster == next.cluster && rule.accepts(&cur.moments, &next.moments) {
                pieces[write] = Piece {
                    moments: cur.moments.merge(&next.moments),
                    first: cur.first,
                    last: next.last,
                    cluster: cur.cluster,
                };
            } else {
                write += 1;
                pieces[write] = next;
            }
        }
        pieces.truncate((write + 1).min(pieces.len()));
        if closed && pieces.len() >= 2 {
            let (first, last) = (pieces[0], pieces[pieces.len() - 1]);
            if first.cluster == last.cluster && rule.accepts(&last.moments, &first.moments) {
                pieces[0] = Piece {
                    moments: last.moments.merge(&first.moments),
                    first: last.first,
                    last: first.last,
                    cluster: first.cluster,
                };
                pieces.pop();
            }
        }
        if pieces.len() == before {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::Point2;

    fn piece(pts: &[Point2<f64>], first: usize, cluster: usize) -> Piece {
        Piece { moments: Moments::from_points(pts), first, last: first + pts.len() - 1, cluster }
    }

    fn wall(from: f64, to: f64, y: f64) -> Vec<Point2<f64>> {
        (0..10).map(|i| Point2::new(from + (to - from) * i as f64 / 9.0, y)).collect()
    }

    #[test]
    fn collinear_pieces_merge_and_others_do_not() {
        let rule = MergeRule::Angles { alpha_t_rad: 0.05f64.to_radians() };
        let mut v = vec![
            piece(&wall(0.0, 1.0, 2.0), 0, 0),
            piece(&wall(1.1, 2.0, 2.0), 10, 0),
            piece(&wall(2.1, 3.0, 2.0), 20, 0),
            piece(&wall(3.1, 4.0, 2.5), 30, 0), // parallel, offset: not the same line
        ];
        merge_adjacent(&mut v, &rule, false);
        assert_eq!(v.len(), 2);
        assert_eq!((v[0].first, v[0].last, v[0].moments.n), (0, 29, 30));
        assert_eq!((v[1].first, v[1].last), (30, 39));
    }

    #[test]
    fn single_piece_survives() {
        let mut v = vec![piece(&wall(0.0, 1.0, 2.0), 0, 0)];
        merge_adjacent(&mut v, &MergeRule::Angles { alpha_t_rad: 0.1 }, true);
        assert_eq!(v.len(), 1);
        let mut empty: Vec<Piece> = vec![];
        merge_adjacent(&mut empty, &MergeRule::Angles { alpha_t_rad: 0.1 }, true);
        assert!(empty.is_empty());
    }

    #[test]
    fn clusters_do_not_merge() {
        let mut v = vec![piece(&wall(0.0, 1.0, 2.0), 0, 0), piece(&wall(1.1, 2.0, 2.0), 10, 1)];
        merge_adjacent(&mut v, &MergeRule::Angles { alpha_t_rad: 0.1 }, false);
        assert_eq!(v.len(), 2);
    }

    #[test]
    fn angle_comparison_wraps() {
        // Directions near +90° and -90° are the same undirected line.
        let a: Vec<_> = (0..10).map(|i| Point2::new(2.0, i as f64 * 0.1)).collect();
        let b: Vec<_> = (0..10).map(|i| Point2::new(2.0, 2.0 - i as f64 * 0.1)).collect();
        let rule = MergeRule::Angles { alpha_t_rad: 0.01 };
        assert!(rule.accepts(&Moments::from_points(&a), &Moments::from_points(&b)));
    }

    #[test]
    fn residual_rule_uses_noise() {
        let rule =
            MergeRule::ResidualIncrease { max_chi2: 13.8, noise: RangeNoise::constant(0.01) };
        let a = Moments::from_points(&wall(0.0, 1.0, 2.0));
        assert!(rule.accepts(&a, &Moments::from_points(&wall(1.1, 2.0, 2.0))));
        assert!(!rule.accepts(&a, &Moments::from_points(&wall(1.1, 2.0, 2.1))));
        // A short tail around a corner does not hide in a long wall.
        let long: Vec<_> = (0..400).map(|i| Point2::new(i as f64 * 0.01, 2.0)).collect();
        let tail: Vec<_> = (0..12).map(|i| Point2::new(4.0, 2.0 - i as f64 * 0.015)).collect();
        assert!(!rule.accepts(&Moments::from_points(&long), &Moments::from_points(&tail)));
    }

    #[test]
    fn closed_scan_joins_across_seam() {
        let rule = MergeRule::Angles { alpha_t_rad: 0.01 };
        let mut v = vec![
            piece(&wall(1.1, 2.0, 2.0), 0, 0),
            piece(&wall(-2.0, -1.0, 1.0), 10, 0),
            piece(&wall(0.0, 1.0, 2.0), 20, 0),
        ];
        merge_adjacent(&mut v, &rule, true);
        assert_eq!(v.len(), 2);
        assert_eq!((v[0].first, v[0].last, v[0].moments.n), (20, 9, 20));
    }
}
