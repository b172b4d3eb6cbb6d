//! `nav_msgs/Odometry` decoding: ROS 2 CDR and ROS 1 serialization, down to
//! what a planar localization source needs, the stamp and the pose. (And
//! CDR encoding, to write MCAP and bag files for tests and examples.)
//!
//! Layout: `Header` (stamp, frame_id), `child_frame_id`, then
//! `PoseWithCovariance` (position x, y, z and orientation x, y, z, w as
//! float64, then 36 float64 of covariance) and `TwistWithCovariance`, which
//! are not read. The pose is the child frame (the vehicle, `base_link`) in
//! the header's frame (`odom`); the heading is the quaternion's yaw.

use crate::ros_cursor::Cursor;
use crate::tf_codec::frame_name;
use pcaline_geometry::Pose2;

/// What a planar source takes from a `nav_msgs/Odometry`.
#[derive(Debug, Clone, PartialEq)]
pub struct OdometryMessage {
    /// The header's stamp, seconds.
    pub stamp_s: f64,
    /// The child frame's planar pose in the header's frame.
    pub pose: Pose2,
    /// The child frame (the vehicle's, `base_link`), without a leading `/`.
    pub child_frame_id: String,
}

/// The yaw of the unit quaternion `(x, y, z, w)`, radians: the rotation
/// about z of its projection on the plane (a tilted vehicle's heading).
fn yaw(x: f64, y: f64, z: f64, w: f64) -> f64 {
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

/// The pose after the header and child frame, shared by both layouts.
fn pose(c: &mut Cursor<'_>) -> Result<Pose2, String> {
    let x = c.f64("pose.pose.position.x")?;
    let y = c.f64("pose.pose.position.y")?;
    let _z = c.f64("pose.pose.position.z")?;
    let mut q = [0.0; 4];
    for (v, name) in q.iter_mut().zip(["x", "y", "z", "w"]) {
        *v = c.f64(name)?;
    }
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(norm > 0.5 && norm < 1.5) {
        return Err(format!("pose.pose.orientation is not a unit quaternion (norm {norm})"));
    }
    Ok(Pose2::new(x, y, yaw(q[0], q[1], q[2], q[3])))
}

/// Decodes a ROS 2 `nav_msgs/msg/Odometry` in CDR (with its encapsulation
/// header) to its stamp, seconds, and planar pose. Errors say what was
/// being read where; an orientation far from a unit quaternion (norm
/// outside 0.5-1.5, as an all-zero one) is an error.
///
/// ```
/// use pcaline_geometry::Pose2;
/// use pcaline_io::{decode_odometry_cdr, encode_odometry_cdr};
/// let bytes = encode_odometry_cdr(12.5, &Pose2::new(1.0, -2.0, 0.3), "odom", "base_link");
/// let m = decode_odometry_cdr(&bytes).unwrap();
/// assert_eq!((m.stamp_s, m.child_frame_id.as_str()), (12.5, "base_link"));
/// assert!((m.pose.heading() - 0.3).abs() < 1e-12 && m.pose.x() == 1.0);
/// ```
pub fn decode_odometry_cdr(data: &[u8]) -> Result<OdometryMessage, String> {
    let mut c = Cursor::cdr(data)?;
    let (stamp_s, _frame) = c.header()?;
    let child_frame_id = frame_name(&c.string("child_frame_id")?);
    Ok(OdometryMessage { stamp_s, pose: pose(&mut c)?, child_frame_id })
}

/// Decodes a ROS 1 `nav_msgs/Odometry` to its stamp and planar pose (as
/// [`decode_odometry_cdr`]).
pub fn decode_odometry_ros1(data: &[u8]) -> Result<OdometryMessage, String> {
    let mut c = Cursor::ros1(data);
    let (stamp_s, _frame) = c.header()?;
    let child_frame_id = frame_name(&c.string("child_frame_id")?);
    Ok(OdometryMessage { stamp_s, pose: pose(&mut c)?, child_frame_id })
}

/// Encodes a little-endian CDR `nav_msgs/msg/Odometry` of the planar pose
/// `pose` at `stamp_s` (zero covariances and twist).
pub fn encode_odometry_cdr(
    stamp_s: f64,
    pose: &Pose2,
    frame_id: &str,
    child_frame_id: &str,
) -> Vec<u8> {
    let mut out = vec![0u8, 1, 0, 0];
    let pad = |out: &mut Vec<u8>, n: usize| {
        while !(out.len() - 4).is_multiple_of(n) {
            out.push(0);
        }
    };
    let sec = stamp_s.floor();
    out.extend_from_slice(&(sec as i32).to_le_bytes());
    out.extend_from_slice(&(((stamp_s - sec) * 1e9).round() as u32).to_le_bytes());
    for name in [frame_id, child_frame_id] {
        pad(&mut out, 4);
        out.extend_from_slice(&(name.len() as u32 + 1).to_le_bytes());
        out.extend_from_slice(name.as_bytes());
        out.push(0);
    }
    pad(&mut out, 8);
    let (s, c) = (0.5 * pose.heading()).sin_cos();
    // Position, orientation (a turn about z), the pose's covariance, then
    // the twist (linear, angular) and its covariance.
    let values = [pose.x(), pose.y(), 0.0, 0.0, 0.0, s, c];
    for v in values.into_iter().chain(std::iter::repeat_n(0.0, 36 + 6 + 36)) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn cdr_round_trip_and_alignment() {
        // Frame names of every length mod 8 move the doubles' alignment.
        for frame in ["", "o", "od", "odom", "odom_frame", "map_odometry"] {
            let p = Pose2::new(-3.25, 7.5, -2.9);
            let bytes = encode_odometry_cdr(1234.75, &p, frame, "base_link");
            let m = decode_odometry_cdr(&bytes).unwrap();
            let (t, q) = (m.stamp_s, m.pose);
            assert_eq!(t, 1234.75, "{frame:?}");
            assert_eq!(m.child_frame_id, "base_link");
            assert_eq!((q.x(), q.y()), (p.x(), p.y()), "{frame:?}");
            assert!((q.heading() - p.heading()).abs() < 1e-12, "{frame:?}");
        }
    }

    #[test]
    fn ros1_layout_is_packed() {
        let mut data = Vec::new();
        data.extend_from_slice(&7u32.to_le_bytes()); // seq
        data.extend_from_slice(&100u32.to_le_bytes());
        data.extend_from_slice(&500_000_000u32.to_le_bytes());
        for name in ["odom", "base_link"] {
            data.extend_from_slice(&(name.len() as u32).to_le_bytes());
            data.extend_from_slice(name.as_bytes());
        }
        // A quarter turn: z = sin(pi/4), w = cos(pi/4).
        let h = std::f64::consts::FRAC_PI_4;
        for v in [2.0, 3.0, 0.0, 0.0, 0.0, h.sin(), h.cos()] {
            data.extend_from_slice(&f64::to_le_bytes(v));
        }
        let m = decode_odometry_ros1(&data).unwrap();
        let (t, p) = (m.stamp_s, m.pose);
        assert_eq!(t, 100.5);
        assert_eq!((p.x(), p.y()), (2.0, 3.0));
        assert!((p.heading() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn a_tilted_quaternion_keeps_its_yaw_and_a_zero_one_is_an_error() {
        // Yaw 0.4 then roll 0.3: q = q_z(0.4) * q_x(0.3).
        let (sz, cz) = (0.2f64).sin_cos();
        let (sx, cx) = (0.15f64).sin_cos();
        let (x, y, z, w) = (cz * sx, sz * sx, sz * cx, cz * cx);
        assert!((yaw(x, y, z, w) - 0.4).abs() < 1e-12);
        let mut bytes = encode_odometry_cdr(1.0, &Pose2::identity(), "odom", "base");
        let n = bytes.len();
        // The quaternion's w is the 7th double of the pose: zero it.
        let w_at = n - 8 * (36 + 6 + 36) - 8;
        bytes[w_at..w_at + 8].copy_from_slice(&0f64.to_le_bytes());
        let e = decode_odometry_cdr(&bytes).unwrap_err();
        assert!(e.contains("unit quaternion"), "{e}");
        let e = decode_odometry_cdr(&bytes[..40]).unwrap_err();
        assert!(e.contains("truncated"), "{e}");
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(data in prop::collection::vec(any::<u8>(), 0..300)) {
            let _ = decode_odometry_cdr(&data);
            let _ = decode_odometry_ros1(&data);
        }
    }
}
