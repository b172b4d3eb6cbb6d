//! [`World`]: the wall segments of a scene and ray casting against them, with a
//! parry2d BVH to find candidate walls and a closed-form ray/segment test in
//! `f64` for the exact hit.

use parry2d::bounding_volume::Aabb;
use parry2d::math::Vector as GlamVec;
use parry2d::partitioning::{Bvh, BvhBuildStrategy, TraversalAction};
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
    bvh: Bvh,
}

impl World {
    /// Indexes `walls`. Zero-length walls are kept but never hit.
    pub fn new(walls: Vec<Wall>) -> Self {
        let leaves: Vec<Aabb> = walls
            .iter()
            .map(|w| {
                let pad = 1e-4;
                Aabb::new(
                    GlamVec::new((w.a.x.min(w.b.x) - pad) as f32, (w.a.y.min(w.b.y) - pad) as f32),
                    GlamVec::new((w.a.x.max(w.b.x) + pad) as f32, (w.a.y.max(w.b.y) + pad) as f32),
                )
            })
            .collect();
        let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves);
        let surfaces = crate::collinear_surfaces(&walls);
        World { walls, surfaces, bvh }
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
    /// BVH traversal prunes almost everything else.
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
        // Slab test against node boxes in f32, with slack for the rounding;
        // the exact test of each candidate wall is in f64.
        let (ox, oy) = (origin.x as f32, origin.y as f32);
        let (ix, iy) = (1.0 / dir.x as f32, 1.0 / dir.y as f32);
        let slack = 1e-3f32;
        self.bvh.traverse(|node| {
            let (lo, hi) = (node.mins(), node.maxs());
            let (tx1, tx2) = ((lo.x - ox) * ix, (hi.x - ox) * ix);
            let (ty1, ty2) = ((lo.y - oy) * iy, (hi.y - oy) * iy);
            let enter = tx1.min(tx2).max(ty1.min(ty2)).max(0.0);
            let exit = tx1.max(tx2).min(ty1.max(ty2));
            if enter > exit + slack || enter > best_t as f32 + slack {
                return TraversalAction::Prune;
            }
            if let Some(leaf) = node.leaf_data()
                && let Some(t) = ray_segment(origin, dir, &self.walls[leaf as usize])
                && t < best_t
            {
                best_t = t;
                best_wall = Some(leaf);
            }
            TraversalAction::Continue
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

    proptest! {
        #[test]
        fn indexed_cast_matches_brute_force(
            walls in prop::collection::vec((-20.0f64..20.0, -20.0f64..20.0, -3.0f64..3.0, -3.0f64..3.0), 1..60),
            angle in -3.2f64..3.2,
        ) {
            let world = World::new(walls.iter().map(|&(x, y, dx, dy)| wall(x, y, x + dx, y + dy)).collect());
            let dir = Vector2::new(angle.cos(), angle.sin());
            let origin = Point2::new(0.5, 0.25);
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
