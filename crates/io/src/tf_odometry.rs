//! The odometry a ROS log keeps in its transform tree (`/tf`) when it has no
//! `nav_msgs/Odometry` topic: the moving transform nearest the scans'
//! frame, as REP 105 lays the tree out (`odom -> base_link -> laser`).
//!
//! From the scans' frame the tree is walked up, parent by parent. A
//! transform that never changes (any `/tf_static` one, or a `/tf` one
//! published again and again with the same pose, as ROS 1's
//! `static_transform_publisher` does) is part of the mount; the first one
//! that moves is the odometry: its child is the vehicle, its parent the
//! odometry's frame. A `map -> odom` correction above it is not used.

use crate::{FrameTransform, OdometryRecord, PlanarMount};
use pcaline_geometry::Pose2;

/// The odometry found in a transform tree ([`odometry_from_transforms`]).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct TfOdometry {
    /// The odometry's frame (the moving transform's parent, `odom`).
    pub parent: String,
    /// The vehicle's frame (its child, `base_link`).
    pub child: String,
    /// The vehicle's pose in the odometry's frame at each `/tf` message of
    /// the transform, in the file's order; `position` is the message's.
    pub records: Vec<OdometryRecord>,
    /// The scans' frame on the vehicle: the unchanging transforms from the
    /// vehicle down to the scans' frame.
    pub mount: PlanarMount,
}

/// Transforms of one parent and child that differ by less than this, metres
/// and radians, are one unchanging transform.
const UNCHANGING: f64 = 1e-9;

/// The odometry in the transform tree of a ROS log: walking up from
/// `sensor` (the scans' frame), the first transform of `dynamic` (`/tf`)
/// whose pose changes; each comes with the number of its message. `statics`
/// (`/tf_static`) and unchanging `/tf` transforms on the way make the
/// mount.
///
/// Edge cases: `None` when the walk reaches a frame with no parent before a
/// moving transform (no odometry in the tree). Frame names are compared without a
/// leading `/`. A frame with several parents takes the first transform
/// found for it (`/tf_static` first); a cycle ends the walk.
///
/// ```
/// use pcaline_geometry::Pose2;
/// use pcaline_io::{FrameTransform, odometry_from_transforms};
/// let t = |parent: &str, child: &str, pose: Pose2, stamp_s: f64| {
///     FrameTransform::planar(parent, child, pose, stamp_s)
/// };
/// let statics = [t("base_link", "laser", Pose2::new(0.2, 0.0, 0.0), 0.0)];
/// let moving = [
///     (1, t("odom", "base_link", Pose2::new(0.0, 0.0, 0.0), 1.0)),
///     (2, t("odom", "base_link", Pose2::new(0.5, 0.0, 0.1), 2.0)),
/// ];
/// let found = odometry_from_transforms(&statics, &moving, "laser").unwrap();
/// assert_eq!((found.parent.as_str(), found.child.as_str()), ("odom", "base_link"));
/// assert_eq!(found.records.len(), 2);
/// assert_eq!(found.mount.vehicle_from_sensor, Pose2::new(0.2, 0.0, 0.0));
/// ```
pub fn odometry_from_transforms(
    statics: &[FrameTransform],
    dynamic: &[(usize, FrameTransform)],
    sensor: &str,
) -> Option<TfOdometry> {
    // Names compared without their leading `/`, and without copying them.
    fn name(s: &str) -> &str {
        s.trim_start_matches('/')
    }
    let mut frame: &str = name(sensor);
    // The frame's pose in the frames walked up so far: frame_from_sensor.
    let mut frame_from_sensor = PlanarMount::new(Pose2::identity(), false);
    for _ in 0..=statics.len() + dynamic.len() {
        if let Some(t) = statics.iter().find(|t| name(&t.child) == frame) {
            frame_from_sensor = PlanarMount::of(t).compose(&frame_from_sensor);
            frame = name(&t.parent);
            continue;
        }
        let (_, first) = dynamic.iter().find(|(_, t)| name(&t.child) == frame)?;
        let parent = name(&first.parent);
        let of_edge: Vec<&(usize, FrameTransform)> = dynamic
            .iter()
            .filter(|(_, t)| name(&t.child) == frame && name(&t.parent) == parent)
            .collect();
        let moves = of_edge.iter().any(|(_, t)| {
            let d = first.parent_from_child.between(&t.parent_from_child);
            d.x().abs() > UNCHANGING || d.y().abs() > UNCHANGING || d.heading().abs() > UNCHANGING
        });
        if !moves {
            frame_from_sensor = PlanarMount::of(first).compose(&frame_from_sensor);
            frame = parent;
            continue;
        }
        let records = of_edge
            .iter()
            .map(|(position, t)| OdometryRecord {
                pose: t.parent_from_child,
                stamp_s: t.stamp_s,
                position: *position,
            })
            .collect();
        return Some(TfOdometry {
            parent: parent.to_string(),
            child: frame.to_string(),
            records,
            mount: frame_from_sensor,
        });
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(parent: &str, child: &str, pose: Pose2, stamp_s: f64) -> FrameTransform {
        FrameTransform::planar(parent, child, pose, stamp_s)
    }

    /// REP 105's tree with ROS 1's habits: the laser's mount published on
    /// `/tf` again and again, a `map -> odom` correction above the
    /// odometry, and another robot's frames beside it.
    #[test]
    fn the_first_moving_transform_above_the_scans_is_the_odometry() {
        let mount = Pose2::new(0.3, -0.1, 0.2);
        let plate = Pose2::new(0.05, 0.0, 0.0);
        let statics = [t("/base_link", "plate", plate, 0.0)];
        let mut dynamic = Vec::new();
        for k in 0..5 {
            let s = f64::from(k);
            dynamic.push(t("plate", "laser", mount, s));
            dynamic.push(t("odom", "base_link", Pose2::new(s, 0.0, 0.1 * s), s));
            dynamic.push(t("map", "odom", Pose2::new(0.0, 0.01 * s, 0.0), s));
            dynamic.push(t("odom", "other_base", Pose2::new(-s, 0.0, 0.0), s));
        }
        let dynamic: Vec<(usize, FrameTransform)> =
            dynamic.into_iter().enumerate().map(|(k, t)| (k + 10, t)).collect();
        let found = odometry_from_transforms(&statics, &dynamic, "/laser").unwrap();
        assert_eq!((found.parent.as_str(), found.child.as_str()), ("odom", "base_link"));
        let xs: Vec<f64> = found.records.iter().map(|r| r.pose.x()).collect();
        assert_eq!(xs, [0.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(found.records[1].position, 15);
        assert_eq!(found.records[1].stamp_s, 1.0);
        let want = plate.compose(&mount);
        let d = found.mount.vehicle_from_sensor.between(&want);
        assert!(d.x().hypot(d.y()) < 1e-12 && d.heading().abs() < 1e-12, "{found:?}");
    }

    /// No moving transform above the scans, no parent, or a cycle: no
    /// odometry. The scans' own frame may be the one that moves.
    #[test]
    fn a_tree_without_odometry_gives_none() {
        let still = [(1, t("base_link", "laser", Pose2::new(0.1, 0.0, 0.0), 1.0))];
        assert_eq!(odometry_from_transforms(&[], &still, "laser"), None);
        assert_eq!(odometry_from_transforms(&[], &[], "laser"), None);
        let cycle =
            [t("a", "laser", Pose2::identity(), 0.0), t("laser", "a", Pose2::identity(), 0.0)];
        assert_eq!(odometry_from_transforms(&cycle, &[], "laser"), None);
        let moving = [
            (1, t("odom", "laser", Pose2::identity(), 0.0)),
            (2, t("odom", "laser", Pose2::new(1.0, 0.0, 0.0), 1.0)),
        ];
        let found = odometry_from_transforms(&[], &moving, "laser").unwrap();
        let mount = found.mount.vehicle_from_sensor;
        assert_eq!((found.child.as_str(), mount), ("laser", Pose2::identity()));
    }
}
