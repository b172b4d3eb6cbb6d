//! The LIDAR's mount a log implies when it stores two poses with each scan:
//! the sensor's (`world_from_sensor`) and the vehicle's odometry pose
//! (`world_from_vehicle`). CARMEN `FLASER` and `ROBOTLASER1` lines do: the
//! laser pose is the robot pose moved by the laser's offset on the robot.
//! When every pair differs by the same rigid transform, that transform is
//! the mount (`vehicle_from_sensor`); the vehicle's poses as the source
//! and this mount place the scans where the log's laser poses put them.
//!
//! A log whose two poses are a corrected and a raw estimate (some
//! GMapping outputs) differs by a transform that drifts: no mount.
//!
//! A ROS log says it in its static transforms instead (`/tf_static`): the
//! chain from the odometry's child frame to the scans' frame
//! ([`mount_from_transforms`]).

use crate::FrameTransform;
use pcaline_geometry::{Pose2, wrap_angle};

/// The pose pairs of a mount agree with the first to within this, metres ...
pub const MOUNT_AGREEMENT_M: f64 = 0.005;
/// ... and this, radians (0.1°).
pub const MOUNT_AGREEMENT_RAD: f64 = 0.001_745;
/// A mount closer than this to the identity, metres ...
pub const MOUNT_TRIVIAL_M: f64 = 0.01;
/// ... and this, radians (0.5°), is no mount: the two poses are one.
pub const MOUNT_TRIVIAL_RAD: f64 = 0.008_727;
/// A mount farther than this from the vehicle's origin is not believed, metres.
pub const MOUNT_MAX_M: f64 = 2.0;
/// Pose pairs needed to call their transform a mount.
pub const MOUNT_MIN_PAIRS: usize = 3;

/// The mount (`vehicle_from_sensor`) that `pairs` of
/// `(world_from_vehicle, world_from_sensor)` imply, or `None`.
///
/// It is the first pair's `vehicle⁻¹ ∘ sensor`, returned when at least
/// [`MOUNT_MIN_PAIRS`] pairs are given, every pair's transform agrees with
/// it within [`MOUNT_AGREEMENT_M`] and [`MOUNT_AGREEMENT_RAD`], it is not
/// the identity (at least [`MOUNT_TRIVIAL_M`] or [`MOUNT_TRIVIAL_RAD`] from
/// it) and it lies within [`MOUNT_MAX_M`] of the vehicle. Edge cases: a
/// non-finite pose, too few pairs, transforms that drift from pair to pair
/// (a corrected and a raw estimate), or two poses that are one give `None`.
///
/// ```
/// use pcaline_geometry::Pose2;
/// use pcaline_io::mount_from_pose_pairs;
/// let mount = Pose2::new(0.3, 0.0, 0.0); // a laser 30 cm ahead
/// let pairs: Vec<(Pose2, Pose2)> = (0..10)
///     .map(|i| Pose2::new(i as f64, 0.5 * i as f64, 0.2 * i as f64))
///     .map(|vehicle| (vehicle, vehicle.compose(&mount)))
///     .collect();
/// let found = mount_from_pose_pairs(&pairs).unwrap();
/// assert!((found.x() - 0.3).abs() < 1e-9 && found.y().abs() < 1e-9);
/// // The same poses twice: no mount.
/// let same: Vec<_> = pairs.iter().map(|(v, _)| (*v, *v)).collect();
/// assert!(mount_from_pose_pairs(&same).is_none());
/// ```
pub fn mount_from_pose_pairs(pairs: &[(Pose2, Pose2)]) -> Option<Pose2> {
    if pairs.len() < MOUNT_MIN_PAIRS {
        return None;
    }
    let mut mounts = pairs.iter().map(|(vehicle, sensor)| vehicle.between(sensor));
    let first = mounts.next()?;
    if !first.is_finite() {
        return None;
    }
    let agree = |m: Pose2| {
        let d = first.between(&m);
        d.is_finite()
            && d.x().hypot(d.y()) <= MOUNT_AGREEMENT_M
            && wrap_angle(d.heading()).abs() <= MOUNT_AGREEMENT_RAD
    };
    if !mounts.all(agree) {
        return None;
    }
    let offset_m = first.x().hypot(first.y());
    let trivial =
        offset_m < MOUNT_TRIVIAL_M && wrap_angle(first.heading()).abs() < MOUNT_TRIVIAL_RAD;
    (!trivial && offset_m <= MOUNT_MAX_M).then_some(first)
}

/// The pose of frame `sensor` in frame `vehicle` through the tree of
/// `transforms` (each child's pose in its parent; a transform may be
/// walked either way), or `None` when no chain joins them. The same frame
/// gives the identity. Frame names are compared without a leading `/`.
/// Of several chains, the one with fewest transforms is taken; a
/// non-finite result is `None`.
///
/// ```
/// use pcaline_geometry::Pose2;
/// use pcaline_io::{FrameTransform, mount_from_transforms};
/// let t = |p: &str, c: &str, x: f64| FrameTransform {
///     parent: p.into(),
///     child: c.into(),
///     parent_from_child: Pose2::new(x, 0.0, 0.0),
///     stamp_s: 0.0,
/// };
/// let tree = [t("base_footprint", "base_link", 0.1), t("base_link", "laser", 0.2)];
/// let m = mount_from_transforms(&tree, "base_footprint", "/laser").unwrap();
/// assert!((m.x() - 0.3).abs() < 1e-12);
/// assert!(mount_from_transforms(&tree, "laser", "camera").is_none());
/// ```
pub fn mount_from_transforms(
    transforms: &[FrameTransform],
    vehicle: &str,
    sensor: &str,
) -> Option<Pose2> {
    let (vehicle, sensor) = (vehicle.trim_start_matches('/'), sensor.trim_start_matches('/'));
    // Breadth-first from the vehicle: each frame reached with its pose in
    // the vehicle's frame.
    let mut reached: Vec<(&str, Pose2)> = vec![(vehicle, Pose2::identity())];
    let mut next = 0;
    while next < reached.len() {
        let (frame, vehicle_from_frame) = reached[next];
        next += 1;
        if frame == sensor {
            return vehicle_from_frame.is_finite().then_some(vehicle_from_frame);
        }
        for t in transforms {
            let step = if t.parent == frame {
                Some((t.child.as_str(), t.parent_from_child))
            } else if t.child == frame {
                Some((t.parent.as_str(), t.parent_from_child.inverse()))
            } else {
                None
            };
            if let Some((other, frame_from_other)) = step
                && reached.iter().all(|(f, _)| *f != other)
            {
                reached.push((other, vehicle_from_frame.compose(&frame_from_other)));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(n: usize) -> Vec<Pose2> {
        (0..n).map(|i| Pose2::new(0.7 * i as f64, (0.3 * i as f64).sin(), 0.4 * i as f64)).collect()
    }

    #[test]
    fn a_chain_walked_both_ways_composes() {
        let t = |p: &str, c: &str, pose: Pose2| FrameTransform {
            parent: p.into(),
            child: c.into(),
            parent_from_child: pose,
            stamp_s: 0.0,
        };
        // odom -> base_link -> plate -> laser, with the laser's frame turned.
        let tree = [
            t("odom", "base_link", Pose2::new(5.0, 5.0, 1.0)),
            t("base_link", "plate", Pose2::new(0.1, 0.0, 0.5)),
            t("plate", "laser", Pose2::new(0.2, 0.05, -0.5)),
        ];
        let m = mount_from_transforms(&tree, "base_link", "laser").unwrap();
        let want = Pose2::new(0.1, 0.0, 0.5).compose(&Pose2::new(0.2, 0.05, -0.5));
        let d = want.between(&m);
        assert!(d.x().hypot(d.y()) < 1e-12 && d.heading().abs() < 1e-12, "{m:?}");
        // The other way round: the inverse.
        let back = mount_from_transforms(&tree, "laser", "base_link").unwrap();
        let d = m.inverse().between(&back);
        assert!(d.x().hypot(d.y()) < 1e-12, "{back:?}");
        assert_eq!(mount_from_transforms(&tree, "laser", "laser"), Some(Pose2::identity()));
        assert_eq!(mount_from_transforms(&[], "base_link", "laser"), None);
    }

    #[test]
    fn a_laser_behind_and_turned_is_found() {
        let mount = Pose2::new(-0.2, 0.05, std::f64::consts::PI);
        let pairs: Vec<_> = path(20).into_iter().map(|v| (v, v.compose(&mount))).collect();
        let m = mount_from_pose_pairs(&pairs).unwrap();
        let d = mount.between(&m);
        assert!(d.x().hypot(d.y()) < 1e-9 && wrap_angle(d.heading()).abs() < 1e-9, "{m:?}");
    }

    #[test]
    fn a_drifting_difference_is_no_mount() {
        // A corrected pose and a raw one: their difference grows.
        let pairs: Vec<_> = path(20)
            .into_iter()
            .enumerate()
            .map(|(i, v)| (v, v.compose(&Pose2::new(0.3 + 0.002 * i as f64, 0.0, 0.0))))
            .collect();
        assert!(mount_from_pose_pairs(&pairs).is_none());
        let turning: Vec<_> = path(20)
            .into_iter()
            .enumerate()
            .map(|(i, v)| (v, v.compose(&Pose2::new(0.3, 0.0, 0.001 * i as f64))))
            .collect();
        assert!(mount_from_pose_pairs(&turning).is_none());
    }

    #[test]
    fn too_few_far_or_broken_pairs_are_no_mount() {
        let mount = Pose2::new(0.3, 0.0, 0.0);
        let pairs: Vec<_> = path(20).into_iter().map(|v| (v, v.compose(&mount))).collect();
        assert!(mount_from_pose_pairs(&pairs[..2]).is_none());
        assert!(mount_from_pose_pairs(&pairs[..3]).is_some());
        let far: Vec<_> =
            path(5).into_iter().map(|v| (v, v.compose(&Pose2::new(2.5, 0.0, 0.0)))).collect();
        assert!(mount_from_pose_pairs(&far).is_none());
        let mut broken = pairs.clone();
        broken[0].1 = Pose2::new(f64::NAN, 0.0, 0.0);
        assert!(mount_from_pose_pairs(&broken).is_none());
        broken = pairs.clone();
        broken[7].1 = Pose2::new(f64::INFINITY, 0.0, 0.0);
        assert!(mount_from_pose_pairs(&broken).is_none());
        // Within the agreement: noise of a millimetre still reads as one mount.
        let noisy: Vec<_> = path(20)
            .into_iter()
            .enumerate()
            .map(|(i, v)| (v, v.compose(&Pose2::new(0.3 + 0.001 * (i % 2) as f64, 0.0, 0.0))))
            .collect();
        assert!(mount_from_pose_pairs(&noisy).is_some());
    }
}
