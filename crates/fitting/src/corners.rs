//! Corner refinement: move each break-point between two adjacent pieces so
//! that the points around it go to the line they fit best. A split at the
//! point farthest from a chord (or at a derivative peak) lands on the corner
//! point itself, which then tilts the short side's line.

use crate::Moments;
use pcaline_geometry::Point2;
use std::ops::Range;

/// Refines the boundaries between consecutive pieces of one cluster.
///
/// `pieces` must be contiguous (`pieces[j].end == pieces[j + 1].start`). For
/// each boundary, each side is fitted without its `window` points nearest the
/// boundary; the boundary then moves, within those `2 window` points, to the
/// index that minimises the squared distances of the window's points to their
/// side's line. Pieces too short to fit without the window (fewer than
/// `window + 3` points) keep their boundary. Pieces never lose all points.
///
/// ```
/// use pcaline_fitting::refine_boundaries;
/// use pcaline_geometry::Point2;
/// // A corner at (1, 0): points along y = 0, then along x = 1.
/// let mut pts: Vec<_> = (0..10).map(|i| Point2::new(i as f64 * 0.1, 0.0)).collect();
/// pts.extend((1..10).map(|i| Point2::new(1.0, i as f64 * 0.1)));
/// // A split two points early: points 8 and 9 lie on y = 0 but start the second piece.
/// let mut pieces = vec![0..8, 8..19];
/// refine_boundaries(&pts, &mut pieces, 2);
/// assert_eq!(pieces, vec![0..10, 10..19]);
/// ```
pub fn refine_boundaries(points: &[Point2<f64>], pieces: &mut [Range<usize>], window: usize) {
    if window == 0 {
        return;
    }
    for j in 1..pieces.len() {
        let (left, right) = (pieces[j - 1].clone(), pieces[j].clone());
        if left.end != right.start
            || left.len() < window + 3
            || right.len() < window + 3
            || right.end > points.len()
        {
            continue;
        }
        let lm = Moments::from_points(&points[left.start..left.end - window]);
        let rm = Moments::from_points(&points[right.start + window..right.end]);
        let (le, re) = (lm.eigen(), rm.eigen());
        let dist2 = |m: &Moments, major: &pcaline_geometry::Vector2<f64>, p: &Point2<f64>| {
            let v = p - m.mean;
            let c = v.x * major.y - v.y * major.x;
            c * c
        };
        let (w0, w1) = (left.end - window, right.start + window);
        // cost(s) = sum_{i < s} dL(i)² + sum_{i >= s} dR(i)², for s in w0..=w1.
        let mut cost: f64 = (w0..w1).map(|i| dist2(&rm, &re.major, &points[i])).sum();
        let mut best = (cost, w0);
        for s in w0 + 1..=w1 {
            let p = &points[s - 1];
            cost += dist2(&lm, &le.major, p) - dist2(&rm, &re.major, p);
            if cost < best.0 - 1e-15 {
                best = (cost, s);
            }
        }
        pieces[j - 1].end = best.1;
        pieces[j].start = best.1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corner() -> Vec<Point2<f64>> {
        let mut pts: Vec<_> = (0..20).map(|i| Point2::new(i as f64 * 0.05, 0.0)).collect();
        pts.extend((1..20).map(|i| Point2::new(0.95, i as f64 * 0.05)));
        pts
    }

    #[test]
    fn boundary_moves_to_the_corner_from_either_side() {
        let pts = corner();
        for start in [17, 18, 19, 20, 21, 22] {
            let mut pieces = vec![0..start, start..pts.len()];
            refine_boundaries(&pts, &mut pieces, 3);
            // Point 19 is the corner vertex itself, on both lines: either side is right.
            assert!((19..=20).contains(&pieces[0].end), "from {start}: {pieces:?}");
            assert_eq!(pieces[0].end, pieces[1].start);
        }
    }

    #[test]
    fn short_pieces_and_gaps_are_left_alone() {
        let pts = corner();
        let mut pieces = vec![0..4, 4..pts.len()];
        refine_boundaries(&pts, &mut pieces, 3);
        assert_eq!(pieces, vec![0..4, 4..pts.len()]);
        let mut pieces = vec![0..10, 12..pts.len()];
        refine_boundaries(&pts, &mut pieces, 3);
        assert_eq!(pieces, vec![0..10, 12..pts.len()]);
        refine_boundaries(&pts, &mut [], 3);
    }
}
