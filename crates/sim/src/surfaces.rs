//! Collinear surfaces: walls drawn as several segments end to end along one
//! straight line are one surface to a sensor, and to the evaluation.

use crate::Wall;
use std::collections::HashMap;

/// Tolerance of the surface test: shared endpoints and distances from the
/// line within 1 µm, directions within 1 µrad.
const TOLERANCE: f64 = 1e-6;

/// The surface of each wall: walls that share an endpoint and lie on one
/// straight line get the same id (the smallest wall index of the surface),
/// transitively, so a wall drawn as ten collinear segments is one surface.
/// Walls meeting at any angle, however small, stay apart; zero-length walls
/// are surfaces of their own.
///
/// ```
/// use pcaline_geometry::Point2;
/// use pcaline_sim::{Wall, collinear_surfaces};
/// let w = |a: [f64; 2], b: [f64; 2]| Wall { a: Point2::new(a[0], a[1]), b: Point2::new(b[0], b[1]), shape: 0 };
/// let walls = [w([0.0, 0.0], [1.0, 0.0]), w([1.0, 0.0], [3.0, 0.0]), w([3.0, 0.0], [3.0, 2.0])];
/// assert_eq!(collinear_surfaces(&walls), vec![0, 0, 2]);
/// ```
pub fn collinear_surfaces(walls: &[Wall]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..walls.len() as u32).collect();
    let key = |p: &pcaline_geometry::Point2<f64>| {
        ((p.x / TOLERANCE).round() as i64, (p.y / TOLERANCE).round() as i64)
    };
    let mut at: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
    for (i, w) in walls.iter().enumerate() {
        if (w.b - w.a).norm() < TOLERANCE {
            continue;
        }
        at.entry(key(&w.a)).or_default().push(i as u32);
        at.entry(key(&w.b)).or_default().push(i as u32);
    }
    for ends in at.values() {
        for (k, &i) in ends.iter().enumerate() {
            for &j in &ends[k + 1..] {
                if i != j && collinear(&walls[i as usize], &walls[j as usize]) {
                    let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                    let (lo, hi) = (ri.min(rj), ri.max(rj));
                    parent[hi as usize] = lo;
                }
            }
        }
    }
    (0..walls.len() as u32).map(|i| root(&mut parent, i)).collect()
}

/// Both walls lie on one line: parallel directions, and the other wall's
/// endpoints on this wall's line.
fn collinear(a: &Wall, b: &Wall) -> bool {
    let (da, db) = ((a.b - a.a).normalize(), (b.b - b.a).normalize());
    let cross = |u: &pcaline_geometry::Vector2<f64>, v: &pcaline_geometry::Vector2<f64>| {
        u.x * v.y - u.y * v.x
    };
    cross(&da, &db).abs() < TOLERANCE
        && cross(&da, &(b.a - a.a)).abs() < TOLERANCE
        && cross(&da, &(b.b - a.a)).abs() < TOLERANCE
}

/// The root of `i` in the union-find forest, halving the path.
fn root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[parent[i as usize] as usize];
        parent[i as usize] = p;
        i = p;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::Point2;

    fn wall(a: [f64; 2], b: [f64; 2]) -> Wall {
        Wall { a: Point2::new(a[0], a[1]), b: Point2::new(b[0], b[1]), shape: 0 }
    }

    #[test]
    fn joins_chains_in_any_order_and_direction_but_not_bends() {
        // A straight wall drawn as four pieces, listed out of order and with
        // one reversed, then a piece bent by 0.01°.
        let bend = 0.01f64.to_radians();
        let walls = [
            wall([2.0, 1.0], [3.0, 1.0]),
            wall([1.0, 1.0], [0.0, 1.0]),
            wall([1.0, 1.0], [2.0, 1.0]),
            wall([3.0, 1.0], [4.0, 1.0]),
            wall([4.0, 1.0], [5.0, 1.0 + bend.tan()]),
            wall([0.0, 1.0], [0.0, 1.0]),
        ];
        assert_eq!(collinear_surfaces(&walls), vec![0, 0, 0, 0, 4, 5]);
        // Parallel walls that do not touch stay apart.
        let apart = [wall([0.0, 0.0], [1.0, 0.0]), wall([2.0, 0.0], [3.0, 0.0])];
        assert_eq!(collinear_surfaces(&apart), vec![0, 1]);
    }
}
