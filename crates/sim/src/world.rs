//! [`World`]: the wall segments of a scene and ray casting against them, with a
//! uniform grid walk ([`crate::wall_grid`]) to find candidate walls and a
//! closed-form ray/segment test in `f64` for the exact hit.

use crate::wall_grid::WallGrid;
use pcaline_geometry::{Point2, Vector2};

/// One straight wall segment of the world.
#[derive(Debug, Clone, PartialEq)]
pub struct Wall {
    /// Start point, world frame, metres.
    pub a: Point2<f64>,
    /// End point, world frame, metres.
    pub b: Point2<f64>,
    /// Index of the scene shape (wall polyline or obstacle) it belongs to.
    pub shape: usize,
}

/// A ray hit: which wall, how far, where.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Index of the wall in [`World::walls`].
    pub wall: u32,
    /// Distance from the ray origin along the unit direction, metres.
    pub distance_m: f64,
    /// The hit point, world frame.
    pub point: Point2<f64>,
}

/// The walls of a scene, indexed for ray casting.
#[derive(Debug, Clone)]
pub struct World {
    walls: Vec<Wall>,
    surfaces: Vec<u32>,
    grid: WallGrid,
}

impl World {
    /// Indexes `walls`. Zero-length walls are kept but never hit.
    pub fn new(walls: Vec<Wall>) -> Self {
        let ends: Vec<_> = walls.iter().map(|w| (w.a, w.b)).collect();
        let grid = WallGrid::new(&ends);
        let surfaces = crate::collinear_surfaces(&walls);
        World { walls, surfaces, grid }
    }

    /// The walls.
    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    /// The surface of each wall ([`crate::collinear_surfaces`]): walls drawn
    /// end to end along one line share the smallest of their indices.
    pub fn surfaces(&self) -> &[u32] {
        &self.surfaces
    }

    /// The nearest wall hit by the ray from `origin` along the unit vector
    /// `dir` within `max_distance_m`, or `None`.
    pub fn cast(
        &self,
        origin: &Point2<f64>,
        dir: &Vector2<f64>,
        max_distance_m: f64,
    ) -> Option<Hit> {
        self.cast_hinted(origin, dir, max_distance_m, None)
    }

    /// As [`World::cast`], testing wall `hint` first. Consecutive beams of a
    /// scan mostly hit the same wall: its distance bounds the search, so the
    /// grid walk stops at the cell that wall is hit in.
    pub fn cast_hinted(
        &self,
        origin: &Point2<f64>,
        dir: &Vector2<f64>,
        max_distance_m: f64,
        hint: Option<u32>,
    ) -> Option<Hit> {
        let mut best_t = max_distance_m;
        let mut best_wall = None;
        if let Some(h) = hint
            && let Some(w) = self.walls.get(h as usize)
            && let Some(t) = ray_segment(origin, dir, w)
            && t <= best_t
        {
            best_t = t;
            best_wall = Some(h);
        }
        self.grid.walk(origin, dir, best_t, |candidates| {
            for &w in candidates {
                if let Some(t) = ray_segment(origin, dir, &self.walls[w as usize])
                    && t < best_t
                {
                    best_t = t;
                    best_wall = Some(w);
                }
            }
            best_t
        });
        best_wall.map(|wall| Hit { wall, distance_m: best_t, point: origin + dir * best_t })
    }

    /// The nearest hit by testing every wall (no index): the reference the
    /// indexed [`World::cast`] is checked against.
    pub fn cast_brute_force(
        &self,
        origin: &Point2<f64>,
        dir: &Vector2<f64>,
        max_distance_m: f64,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        for (i, w) in self.walls.iter().enumerate() {
            if let Some(t) = ray_segment(origin, dir, w)
                && t <= max_distance_m
                && best.is_none_or(|b| t < b.distance_m)
            {
                best = Some(Hit { wall: i as u32, distance_m: t, point: origin + dir * t });
            }
        }
        best
    }
}

/// Distance along the ray `origin + t dir` (t > 0) to the segment `wall`, if
/// they intersect. Closed form: solve `origin + t dir = a + s (b - a)`.
#[inline]
fn ray_segment(origin: &Point2<f64>, dir: &Vector2<f64>, wall: &Wall) -> Option<f64> {
    let e = wall.b - wall.a;
    let denom = dir.x * e.y - dir.y * e.x;
    if denom.abs() < 1e-15 {
        return None; // parallel (or zero-length)
    }
    let w = wall.a - origin;
    let t = (w.x * e.y - w.y * e.x) / denom;
    let s = (w.x * dir.y - w.y * dir.x) / denom;
    (t > 1e-9 && (0.0..=1.0).contains(&s)).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn wall(ax: f64, ay: f64, bx: f64, by: f64) -> Wall {
        Wall { a: Point2::new(ax, ay), b: Point2::new(bx, by), shape: 0 }
    }

    #[test]
    fn nearest_wall_wins() {
        let w = World::new(vec![wall(5.0, -1.0, 5.0, 1.0), wall(3.0, -1.0, 3.0, 1.0)]);
        let hit = w.cast(&Point2::origin(), &Vector2::new(1.0, 0.0), 30.0).unwrap();
        assert_eq!(hit.wall, 1);
        assert!((hit.distance_m - 3.0).abs() < 1e-12);
        assert!(w.cast(&Point2::origin(), &Vector2::new(-1.0, 0.0), 30.0).is_none());
        assert!(w.cast(&Point2::origin(), &Vector2::new(1.0, 0.0), 2.0).is_none());
        assert!(
            World::new(vec![]).cast(&Point2::origin(), &Vector2::new(1.0, 0.0), 30.0).is_none()
        );
    }

    #[test]
    fn rays_along_grid_lines_and_from_outside_find_the_nearest_wall() {
        // A row of walls at x = 0, 1, 2, ... (cell boundaries of some grid),
        // cast along them, across them, and from outside the grid.
        let walls: Vec<_> = (0..10).map(|i| wall(i as f64, 0.0, i as f64, 3.0)).collect();
        let world = World::new(walls);
        for (origin, dir) in [
            (Point2::new(-5.0, 1.5), Vector2::new(1.0, 0.0)),
            (Point2::new(20.0, 1.5), Vector2::new(-1.0, 0.0)),
            (Point2::new(4.0, -5.0), Vector2::new(0.0, 1.0)),
            (Point2::new(4.5, 10.0), Vector2::new(0.0, -1.0)),
            (Point2::new(0.5, 0.5), Vector2::new(0.6, 0.8)),
        ] {
            let a = world.cast(&origin, &dir, 30.0).map(|h| h.distance_m);
            let b = world.cast_brute_force(&origin, &dir, 30.0).map(|h| h.distance_m);
            assert_eq!(a, b, "{origin:?} {dir:?}");
        }
        assert!(world.cast(&Point2::new(4.5, 10.0), &Vector2::new(0.0, -1.0), 30.0).is_none());
        // Degenerate rays end, and hit nothing.
        let nan = f64::NAN;
        for (origin, dir) in [
            (Point2::new(nan, 1.0), Vector2::new(1.0, 0.0)),
            (Point2::new(0.5, 1.0), Vector2::new(nan, 0.0)),
            (Point2::new(0.5, 1.0), Vector2::new(nan, nan)),
            (Point2::new(0.5, 1.0), Vector2::new(0.0, 0.0)),
        ] {
            assert!(world.cast(&origin, &dir, f64::INFINITY).is_none(), "{origin:?} {dir:?}");
        }
        let far = world.cast(&Point2::new(-5.0, 1.5), &Vector2::new(1.0, 0.0), f64::INFINITY);
        assert_eq!(far.map(|h| h.wall), Some(0));
    }

    proptest! {
        #[test]
        fn indexed_cast_matches_brute_force(
            walls in prop::collection::vec((-20.0f64..20.0, -20.0f64..20.0, -3.0f64..3.0, -3.0f64..3.0), 1..60),
            angle in -3.2f64..3.2,
            axis_aligned in any::<bool>(),
            (ox, oy) in (-30.0f64..30.0, -30.0f64..30.0),
        ) {
            let world = World::new(walls.iter().map(|&(x, y, dx, dy)| wall(x, y, x + dx, y + dy)).collect());
            let angle = if axis_aligned { (angle / std::f64::consts::FRAC_PI_2).round() * std::f64::consts::FRAC_PI_2 } else { angle };
            let dir = Vector2::new(angle.cos(), angle.sin());
            for origin in [Point2::new(0.5, 0.25), Point2::new(ox, oy)] {
                let b = world.cast_brute_force(&origin, &dir, 30.0);
                for hint in [None, Some(0), Some(walls.len() as u32 - 1), Some(u32::MAX)] {
                    let a = world.cast_hinted(&origin, &dir, 30.0, hint);
                    match (a, b) {
                        (None, None) => {}
                        (Some(a), Some(b)) => prop_assert!((a.distance_m - b.distance_m).abs() < 1e-9),
                        _ => prop_assert!(false, "{a:?} vs {b:?}"),
                    }
                }
            }
        }
    }
}
