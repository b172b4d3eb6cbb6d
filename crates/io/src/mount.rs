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

#[cfg(test)]
mod tests {
    use super::*;

    fn path(n: usize) -> Vec<Pose2> {
        (0..n).map(|i| Pose2::new(0.7 * i as f64, (0.3 * i as f64).sin(), 0.4 * i as f64)).collect()
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
