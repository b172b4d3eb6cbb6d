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

/// Where a sensor sits on the vehicle, in the plane: its pose, and whether
/// its frame is mirrored (a LIDAR mounted upside down sees the plane with
/// its y axis flipped: its bearings turn the other way). It also keeps the
/// mount's rotation in space, whose tilt ([`PlanarMount::tilt_rad`]) the
/// plane drops.
///
/// A point `p` of the sensor's frame lies at `vehicle_from_sensor` applied
/// to `p`, with `p.y` negated first when `mirrored`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct PlanarMount {
    /// The sensor's pose on the vehicle; its heading is the sensor's x axis.
    pub vehicle_from_sensor: Pose2,
    /// The sensor's frame is mirrored.
    pub mirrored: bool,
    /// The rotation in space, a unit quaternion `[x, y, z, w]`.
    rotation_xyzw: [f64; 4],
}

impl PlanarMount {
    /// A level mount of pose `vehicle_from_sensor`, mirrored (rolled by
    /// 180° about the sensor's x axis) or not.
    pub fn new(vehicle_from_sensor: Pose2, mirrored: bool) -> Self {
        let (s, c) = (0.5 * vehicle_from_sensor.heading()).sin_cos();
        let rotation_xyzw = if mirrored { [c, s, 0.0, 0.0] } else { [0.0, 0.0, s, c] };
        PlanarMount { vehicle_from_sensor, mirrored, rotation_xyzw }
    }

    /// The mount of `transform`'s child in its parent.
    pub(crate) fn of(transform: &FrameTransform) -> Self {
        PlanarMount {
            rotation_xyzw: transform.rotation_xyzw,
            ..PlanarMount::new(transform.parent_from_child, transform.upside_down)
        }
    }

    /// How far the sensor's scan plane is tilted from the vehicle's plane,
    /// radians in [0, pi/2]: the angle between the sensor's z axis and the
    /// vehicle's z axis (or its opposite, for a mirrored mount). 0 for a
    /// level mount; the mapping projects a tilted scan to the plane as it
    /// is, so its ranges come out up to `1 / cos(tilt)` long.
    pub fn tilt_rad(&self) -> f64 {
        let [x, y, _, _] = self.rotation_xyzw;
        // The rotation's (z, z) entry.
        (1.0 - 2.0 * (x * x + y * y)).abs().min(1.0).acos()
    }

    /// `self` then `other`: `other`'s pose is mirrored into `self`'s frame
    /// when `self` is mirrored.
    pub(crate) fn compose(&self, other: &PlanarMount) -> Self {
        let o = other.vehicle_from_sensor;
        let o = if self.mirrored { Pose2::new(o.x(), -o.y(), -o.heading()) } else { o };
        PlanarMount {
            vehicle_from_sensor: self.vehicle_from_sensor.compose(&o),
            mirrored: self.mirrored != other.mirrored,
            rotation_xyzw: quaternion_product(&self.rotation_xyzw, &other.rotation_xyzw),
        }
    }

    /// The vehicle's mount on the sensor.
    fn inverse(&self) -> Self {
        let [x, y, z, w] = self.rotation_xyzw;
        let rotation_xyzw = [-x, -y, -z, w];
        let p = self.vehicle_from_sensor;
        if !self.mirrored {
            return PlanarMount { rotation_xyzw, ..PlanarMount::new(p.inverse(), false) };
        }
        // q = M R(-h) (p - t) = R(h) M p - R(h) M t for a mirror M.
        let (s, c) = p.heading().sin_cos();
        let (x, y) = (p.x(), -p.y());
        PlanarMount {
            rotation_xyzw,
            ..PlanarMount::new(Pose2::new(-(c * x - s * y), -(s * x + c * y), p.heading()), true)
        }
    }
}

/// The Hamilton product `a b` of quaternions `[x, y, z, w]`: rotation `b`,
/// then `a`.
fn quaternion_product(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    let ([ax, ay, az, aw], [bx, by, bz, bw]) = (*a, *b);
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// The mount of frame `sensor` in frame `vehicle` through the tree of
/// `transforms` (each child's pose in its parent; a transform may be
/// walked either way), or `None` when no chain joins them. The same frame
/// gives the identity. Frame names are compared without a leading `/`.
/// Of several chains, the one with fewest transforms is taken; a
/// non-finite result is `None`. A transform whose child is upside down
/// ([`FrameTransform::upside_down`]) mirrors what lies beyond it.
///
/// ```
/// use pcaline_geometry::Pose2;
/// use pcaline_io::{FrameTransform, mount_from_transforms};
/// let t = |p: &str, c: &str, x: f64| FrameTransform::planar(p, c, Pose2::new(x, 0.0, 0.0), 0.0);
/// let tree = [t("base_footprint", "base_link", 0.1), t("base_link", "laser", 0.2)];
/// let m = mount_from_transforms(&tree, "base_footprint", "/laser").unwrap();
/// assert!((m.vehicle_from_sensor.x() - 0.3).abs() < 1e-12 && !m.mirrored);
/// assert!(mount_from_transforms(&tree, "laser", "camera").is_none());
/// ```
pub fn mount_from_transforms(
    transforms: &[FrameTransform],
    vehicle: &str,
    sensor: &str,
) -> Option<PlanarMount> {
    let (vehicle, sensor) = (vehicle.trim_start_matches('/'), sensor.trim_start_matches('/'));
    // Breadth-first from the vehicle: each frame reached with its mount on
    // the vehicle.
    let mut reached: Vec<(&str, PlanarMount)> =
        vec![(vehicle, PlanarMount::new(Pose2::identity(), false))];
    let mut next = 0;
    while next < reached.len() {
        let (frame, vehicle_from_frame) = reached[next];
        next += 1;
        if frame == sensor {
            return vehicle_from_frame
                .vehicle_from_sensor
                .is_finite()
                .then_some(vehicle_from_frame);
        }
        for t in transforms {
            let step = if t.parent == frame {
                Some((t.child.as_str(), PlanarMount::of(t)))
            } else if t.child == frame {
                Some((t.parent.as_str(), PlanarMount::of(t).inverse()))
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
        let t = |p: &str, c: &str, pose: Pose2| FrameTransform::planar(p, c, pose, 0.0);
        // odom -> base_link -> plate -> laser, with the laser's frame turned.
        let tree = [
            t("odom", "base_link", Pose2::new(5.0, 5.0, 1.0)),
            t("base_link", "plate", Pose2::new(0.1, 0.0, 0.5)),
            t("plate", "laser", Pose2::new(0.2, 0.05, -0.5)),
        ];
        let m = mount_from_transforms(&tree, "base_link", "laser").unwrap().vehicle_from_sensor;
        let want = Pose2::new(0.1, 0.0, 0.5).compose(&Pose2::new(0.2, 0.05, -0.5));
        let d = want.between(&m);
        assert!(d.x().hypot(d.y()) < 1e-12 && d.heading().abs() < 1e-12, "{m:?}");
        // The other way round: the inverse.
        let back = mount_from_transforms(&tree, "laser", "base_link").unwrap().vehicle_from_sensor;
        let d = m.inverse().between(&back);
        assert!(d.x().hypot(d.y()) < 1e-12, "{back:?}");
        assert_eq!(
            mount_from_transforms(&tree, "laser", "laser"),
            Some(PlanarMount::new(Pose2::identity(), false))
        );
        assert_eq!(mount_from_transforms(&[], "base_link", "laser"), None);
    }

    /// A point of an upside-down laser's frame, carried to the vehicle by
    /// the mount found, lands where the 3D rotations put it, on chains with
    /// the flip at either end, walked either way.
    #[test]
    fn an_upside_down_laser_is_a_mirrored_mount() {
        // The 3D rotation of a transform, applied to a point of the plane.
        let place = |t: &FrameTransform, p: [f64; 2]| {
            let (s, c) = t.parent_from_child.heading().sin_cos();
            let y = if t.upside_down { -p[1] } else { p[1] };
            let o = &t.parent_from_child;
            [o.x() + c * p[0] - s * y, o.y() + s * p[0] + c * y]
        };
        let apply = |m: &PlanarMount, p: [f64; 2]| {
            let y = if m.mirrored { -p[1] } else { p[1] };
            let q = m.vehicle_from_sensor.transform_point(&pcaline_geometry::Point2::new(p[0], y));
            [q.x, q.y]
        };
        let t = |parent: &str, child: &str, pose: Pose2, upside_down: bool| {
            if upside_down {
                FrameTransform::rolled_over(parent, child, pose, 0.0)
            } else {
                FrameTransform::planar(parent, child, pose, 0.0)
            }
        };
        let (a, b) = (Pose2::new(0.3, -0.1, 0.4), Pose2::new(0.05, 0.2, -1.1));
        for flips in [[true, false], [false, true], [true, true]] {
            let tree = [t("base", "plate", a, flips[0]), t("plate", "laser", b, flips[1])];
            let m = mount_from_transforms(&tree, "base", "laser").unwrap();
            assert_eq!(m.mirrored, flips[0] != flips[1], "{flips:?}");
            let p = [1.5, -0.7];
            let want = place(&tree[0], place(&tree[1], p));
            let got = apply(&m, p);
            assert!((want[0] - got[0]).hypot(want[1] - got[1]) < 1e-12, "{flips:?}");
            // Walked the other way: the inverse.
            let back = mount_from_transforms(&tree, "laser", "base").unwrap();
            let round = apply(&back, got);
            assert!((round[0] - p[0]).hypot(round[1] - p[1]) < 1e-12, "{flips:?}: {back:?}");
        }
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

    /// The tilt of a chain is that of the composed rotations: two opposite
    /// pitches cancel, an upside-down mount is level, and walking the chain
    /// backwards gives the same tilt.
    #[test]
    fn the_tilt_of_a_chain_is_that_of_its_rotations() {
        let pitch = |p: &str, c: &str, deg: f64| {
            let h = 0.5 * deg.to_radians();
            FrameTransform::from_3d(p, c, [0.1, 0.0, 0.3], [0.0, h.sin(), 0.0, h.cos()], 0.0)
                .unwrap()
        };
        let roll_over =
            FrameTransform::rolled_over("plate", "laser", Pose2::new(0.0, 0.0, 1.0), 0.0);
        let cases = [
            (vec![pitch("base", "laser", 10.0)], 10.0),
            (vec![pitch("base", "plate", 10.0), pitch("plate", "laser", -10.0)], 0.0),
            (vec![pitch("base", "plate", 4.0), pitch("plate", "laser", 3.0)], 7.0),
            (vec![pitch("base", "plate", 0.0), roll_over.clone()], 0.0),
            (vec![pitch("base", "plate", 5.0), roll_over], 5.0),
        ];
        for (tree, want_deg) in cases {
            for (from, to) in [("base", "laser"), ("laser", "base")] {
                let m = mount_from_transforms(&tree, from, to).unwrap();
                assert!((m.tilt_rad().to_degrees() - want_deg).abs() < 1e-9, "{tree:?}: {m:?}");
            }
        }
        assert_eq!(PlanarMount::new(Pose2::new(1.0, 2.0, 3.0), true).tilt_rad(), 0.0);
    }
}
