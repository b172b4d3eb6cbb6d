//! Scans of a small simulated room for the unit tests of this crate.

use pcaline_geometry::{Point2, Pose2, Scan, Vector2};
use pcaline_sim::{Wall, World};

/// A 6 x 4 m room seen from `pose`, 361 beams over 270°, exact ranges (the
/// simulator's ray casting).
pub(crate) fn room_scan(pose: &Pose2) -> Scan {
    let corners = [(-3.0, -2.0), (3.0, -2.0), (3.0, 2.0), (-3.0, 2.0)];
    let walls = (0..4)
        .map(|k| {
            let ((x1, y1), (x2, y2)) = (corners[k], corners[(k + 1) % 4]);
            Wall { a: Point2::new(x1, y1), b: Point2::new(x2, y2), shape: 0 }
        })
        .collect();
    let world = World::new(walls);
    let (angle_min, increment) = (-135f64.to_radians(), 270f64.to_radians() / 360.0);
    let origin = Point2::new(pose.x(), pose.y());
    let ranges = (0..361)
        .map(|i| {
            let a = pose.heading() + angle_min + increment * i as f64;
            let hit = world.cast(&origin, &Vector2::new(a.cos(), a.sin()), 30.0);
            hit.map_or(f32::NAN, |h| h.distance_m as f32)
        })
        .collect();
    Scan::new(angle_min as f32, increment as f32, 0.05, 30.0, ranges)
}
