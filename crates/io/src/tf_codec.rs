//! `tf2_msgs/TFMessage` decoding (ROS 2 CDR and ROS 1), projected to the
//! plane: each `geometry_msgs/TransformStamped` becomes the planar pose of
//! its child frame in its parent frame. (And CDR encoding, for tests.)
//!
//! Layout: a sequence of `TransformStamped`, each a `Header` (stamp,
//! frame_id: the parent), `child_frame_id`, then the translation (x, y, z)
//! and the rotation (x, y, z, w) as float64.

use crate::ros_cursor::Cursor;
use pcaline_geometry::Pose2;

/// One transform of a `tf2_msgs/TFMessage`: its rotation as read, and its
/// projection to the plane, which is what the mapping uses.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameTransform {
    /// The parent frame (the header's `frame_id`), without a leading `/`.
    pub parent: String,
    /// The child frame, without a leading `/`.
    pub child: String,
    /// The child frame's pose in the parent's: x, y and the rotation's yaw
    /// (z and the tilt dropped).
    pub parent_from_child: Pose2,
    /// The header's stamp, seconds (0 in a static transform, as a rule).
    pub stamp_s: f64,
    /// The child's z axis points down in the parent's frame (a LIDAR
    /// mounted upside down, rolled by 180°): in the plane the child frame
    /// is mirrored (its y flipped) before `parent_from_child`, whose
    /// heading is then the child's x axis, places it.
    pub upside_down: bool,
    /// The rotation as read, a unit quaternion `[x, y, z, w]`: what the
    /// plane drops of it is the tilt ([`crate::PlanarMount::tilt_rad`]).
    pub rotation_xyzw: [f64; 4],
}

impl FrameTransform {
    /// A transform in the plane: a turn of `parent_from_child`'s heading
    /// about z, the child level.
    pub fn planar(
        parent: impl Into<String>,
        child: impl Into<String>,
        parent_from_child: Pose2,
        stamp_s: f64,
    ) -> Self {
        let (s, c) = (0.5 * parent_from_child.heading()).sin_cos();
        FrameTransform {
            parent: parent.into(),
            child: child.into(),
            parent_from_child,
            stamp_s,
            upside_down: false,
            rotation_xyzw: [0.0, 0.0, s, c],
        }
    }

    /// A transform whose child is upside down: `Rz(heading) Rx(pi)`, the
    /// child's x axis along `parent_from_child`'s heading and its z axis
    /// pointing down.
    pub fn rolled_over(
        parent: impl Into<String>,
        child: impl Into<String>,
        parent_from_child: Pose2,
        stamp_s: f64,
    ) -> Self {
        let (s, c) = (0.5 * parent_from_child.heading()).sin_cos();
        FrameTransform {
            upside_down: true,
            rotation_xyzw: [c, s, 0.0, 0.0],
            ..Self::planar(parent, child, parent_from_child, stamp_s)
        }
    }

    /// A transform as a message gives it: the child's origin at
    /// `translation_m` (x, y, z) and rotated by `rotation_xyzw`, whose
    /// length must lie within 0.5 and 1.5 of one (`None` otherwise, or when
    /// it is not finite). Its planar pose is x, y and the yaw of the
    /// rotation's x axis; `rotation_xyzw` keeps the rotation normalized.
    pub fn from_3d(
        parent: impl Into<String>,
        child: impl Into<String>,
        translation_m: [f64; 3],
        rotation_xyzw: [f64; 4],
        stamp_s: f64,
    ) -> Option<Self> {
        let norm = rotation_xyzw.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(norm > 0.5 && norm < 1.5) {
            return None;
        }
        let [qx, qy, qz, qw] = rotation_xyzw;
        let yaw = (2.0 * (qw * qz + qx * qy)).atan2(1.0 - 2.0 * (qy * qy + qz * qz));
        Some(FrameTransform {
            parent: parent.into(),
            child: child.into(),
            parent_from_child: Pose2::new(translation_m[0], translation_m[1], yaw),
            stamp_s,
            // The rotation's (z, z) entry: the child's z axis along the parent's.
            upside_down: 1.0 - 2.0 * (qx * qx + qy * qy) < 0.0,
            rotation_xyzw: rotation_xyzw.map(|v| v / norm),
        })
    }
}

/// A frame name as ROS 1 and ROS 2 write it, compared without its leading `/`.
pub(crate) fn frame_name(name: &str) -> String {
    name.trim_start_matches('/').to_string()
}

/// The transforms after the count, shared by both layouts.
fn transforms(c: &mut Cursor<'_>) -> Result<Vec<FrameTransform>, String> {
    let n = c.u32("transforms")? as usize;
    // Each transform is at least 7 doubles: a corrupt count must not
    // become a huge allocation.
    if n.saturating_mul(56) > c.remaining() {
        return Err(format!("transforms: {n} do not fit in the message"));
    }
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let (stamp_s, parent) = c.header()?;
        let child = frame_name(&c.string("child_frame_id")?);
        let mut v = [0.0; 7];
        for x in &mut v {
            *x = c.f64("transform")?;
        }
        let t = FrameTransform::from_3d(
            parent,
            child,
            [v[0], v[1], v[2]],
            [v[3], v[4], v[5], v[6]],
            stamp_s,
        )
        .ok_or_else(|| format!("transform {k}: the rotation is not a unit quaternion"))?;
        out.push(t);
    }
    Ok(out)
}

/// Decodes a ROS 2 `tf2_msgs/msg/TFMessage` in CDR. Errors say what was
/// being read where.
///
/// ```
/// use pcaline_geometry::Pose2;
/// use pcaline_io::{FrameTransform, decode_tf_cdr, encode_tf_cdr};
/// let t = FrameTransform::planar("base_link", "laser", Pose2::new(0.2, 0.0, 0.1), 0.0);
/// let back = decode_tf_cdr(&encode_tf_cdr(&[t.clone()])).unwrap();
/// assert_eq!(back[0].child, "laser");
/// assert!((back[0].parent_from_child.heading() - 0.1).abs() < 1e-12);
/// ```
pub fn decode_tf_cdr(data: &[u8]) -> Result<Vec<FrameTransform>, String> {
    transforms(&mut Cursor::cdr(data)?)
}

/// Decodes a ROS 1 `tf2_msgs/TFMessage`.
pub fn decode_tf_ros1(data: &[u8]) -> Result<Vec<FrameTransform>, String> {
    transforms(&mut Cursor::ros1(data))
}

/// Encodes little-endian CDR `tf2_msgs/msg/TFMessage` of `transforms`
/// (each with its x, y, z = 0 and its `rotation_xyzw`; stamps in whole
/// nanoseconds, a negative or non-finite one as 0).
pub fn encode_tf_cdr(transforms: &[FrameTransform]) -> Vec<u8> {
    let mut out = vec![0u8, 1, 0, 0];
    let pad = |out: &mut Vec<u8>, n: usize| {
        while !(out.len() - 4).is_multiple_of(n) {
            out.push(0);
        }
    };
    out.extend_from_slice(&(transforms.len() as u32).to_le_bytes());
    for t in transforms {
        pad(&mut out, 4);
        let stamp = if t.stamp_s.is_finite() { t.stamp_s.max(0.0) } else { 0.0 };
        let sec = stamp.floor();
        let nanosec = (((stamp - sec) * 1e9).round() as u32).min(999_999_999);
        out.extend_from_slice(&(sec as i32).to_le_bytes());
        out.extend_from_slice(&nanosec.to_le_bytes());
        for name in [&t.parent, &t.child] {
            pad(&mut out, 4);
            out.extend_from_slice(&(name.len() as u32 + 1).to_le_bytes());
            out.extend_from_slice(name.as_bytes());
            out.push(0);
        }
        pad(&mut out, 8);
        let (p, q) = (&t.parent_from_child, &t.rotation_xyzw);
        for v in [p.x(), p.y(), 0.0, q[0], q[1], q[2], q[3]] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn two_transforms_round_trip_and_names_lose_their_slash() {
        let ts = [
            FrameTransform::planar("odom", "base", Pose2::new(1.0, 2.0, -0.5), 1234.5),
            FrameTransform::planar("/base", "laser_frame", Pose2::new(0.3, -0.1, 3.0), 0.0),
        ];
        let back = decode_tf_cdr(&encode_tf_cdr(&ts)).unwrap();
        assert_eq!(back.len(), 2);
        assert_eq!((back[1].parent.as_str(), back[1].child.as_str()), ("base", "laser_frame"));
        assert!((back[1].parent_from_child.heading() - 3.0).abs() < 1e-12);
        assert_eq!(back[0].parent_from_child.x(), 1.0);
        assert_eq!((back[0].stamp_s, back[1].stamp_s), (1234.5, 0.0));
    }

    #[test]
    fn ros1_layout_is_packed() {
        let mut data = 1u32.to_le_bytes().to_vec();
        data.extend_from_slice(&[0u8; 12]); // seq, secs, nsecs
        for name in ["/base_link", "laser"] {
            data.extend_from_slice(&(name.len() as u32).to_le_bytes());
            data.extend_from_slice(name.as_bytes());
        }
        for v in [0.25, 0.0, 0.1, 0.0, 0.0, 0.0, 1.0] {
            data.extend_from_slice(&f64::to_le_bytes(v));
        }
        let t = decode_tf_ros1(&data).unwrap();
        assert_eq!(t[0].parent, "base_link");
        assert_eq!(t[0].parent_from_child, Pose2::new(0.25, 0.0, 0.0));
        let e = decode_tf_ros1(&data[..data.len() - 4]).unwrap_err();
        assert!(e.contains("transform"), "{e}");
        let mut huge = data.clone();
        huge[..4].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode_tf_ros1(&huge).unwrap_err().contains("do not fit"));
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(data in prop::collection::vec(any::<u8>(), 0..300)) {
            let _ = decode_tf_cdr(&data);
            let _ = decode_tf_ros1(&data);
        }
    }
}
