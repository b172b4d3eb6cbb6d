//! `sensor_msgs/LaserScan` decoding: ROS 2 CDR and ROS 1 serialization.
//! (And CDR encoding, to write MCAP and bag files for tests and examples.)
//!
//! Both layouts: `Header` (stamp, frame_id), then `angle_min`, `angle_max`,
//! `angle_increment`, `time_increment`, `scan_time`, `range_min`,
//! `range_max` (float32), then `ranges` and `intensities` (float32
//! sequences). ROS 2 CDR starts with a 4-byte encapsulation header (byte 1
//! is 1 for little-endian) and aligns each primitive to its size, counted
//! from the end of that header; its `Header` has no `seq` and its time is
//! `int32 sec, uint32 nanosec`. ROS 1 is packed little-endian with a
//! `uint32 seq` first.

use crate::ros_cursor::Cursor;
use pcaline_geometry::Scan;

/// The fields after the header, shared by both layouts.
fn body(c: &mut Cursor<'_>, stamp_s: f64) -> Result<Scan, String> {
    let angle_min = c.f32("angle_min")?;
    let _angle_max = c.f32("angle_max")?;
    let angle_increment = c.f32("angle_increment")?;
    let time_increment = c.f32("time_increment")?;
    let _scan_time = c.f32("scan_time")?;
    let range_min = c.f32("range_min")?;
    let range_max = c.f32("range_max")?;
    let ranges = c.f32_seq("ranges")?;
    let intensities = c.f32_seq("intensities")?;
    let mut scan =
        Scan::new(angle_min, angle_increment, range_min, range_max, ranges).with_stamp(stamp_s);
    if !intensities.is_empty() {
        scan.intensities = Some(intensities);
    }
    if time_increment.is_finite() && time_increment != 0.0 {
        scan.time_increment_s = Some(f64::from(time_increment.abs()));
    }
    Ok(scan)
}

/// Decodes a ROS 2 `sensor_msgs/msg/LaserScan` in CDR (with its
/// encapsulation header). Errors say what was being read where.
pub fn decode_laserscan_cdr(data: &[u8]) -> Result<Scan, String> {
    let mut c = Cursor::cdr(data)?;
    let (stamp_s, _frame) = c.header()?;
    body(&mut c, stamp_s)
}

/// The `frame_id` of a LaserScan (the header alone is read), without a
/// leading `/`: CDR, or ROS 1 with `ros1`.
pub(crate) fn laserscan_frame(data: &[u8], ros1: bool) -> Result<String, String> {
    let mut c = if ros1 { Cursor::ros1(data) } else { Cursor::cdr(data)? };
    Ok(c.header()?.1)
}

/// Decodes a ROS 1 `sensor_msgs/LaserScan`.
pub fn decode_laserscan_ros1(data: &[u8]) -> Result<Scan, String> {
    let mut c = Cursor::ros1(data);
    let (stamp_s, _frame) = c.header()?;
    body(&mut c, stamp_s)
}

/// Encodes a scan as a little-endian CDR `sensor_msgs/msg/LaserScan`.
pub fn encode_laserscan_cdr(scan: &Scan, frame_id: &str) -> Vec<u8> {
    let mut out = vec![0u8, 1, 0, 0];
    let pad = |out: &mut Vec<u8>, n: usize| {
        while !(out.len() - 4).is_multiple_of(n) {
            out.push(0);
        }
    };
    let stamp = scan.stamp_s.unwrap_or(0.0);
    let sec = stamp.floor();
    out.extend_from_slice(&(sec as i32).to_le_bytes());
    out.extend_from_slice(&(((stamp - sec) * 1e9).round() as u32).to_le_bytes());
    out.extend_from_slice(&(frame_id.len() as u32 + 1).to_le_bytes());
    out.extend_from_slice(frame_id.as_bytes());
    out.push(0);
    pad(&mut out, 4);
    let n = scan.ranges.len();
    let angle_max = scan.angle_min + scan.angle_increment * n.saturating_sub(1) as f32;
    for v in
        [scan.angle_min, angle_max, scan.angle_increment, 0.0, 0.0, scan.range_min, scan.range_max]
    {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for seq in [&scan.ranges[..], scan.intensities.as_deref().unwrap_or(&[])] {
        out.extend_from_slice(&(seq.len() as u32).to_le_bytes());
        for v in seq {
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
    fn cdr_round_trip() {
        let mut scan =
            Scan::new(-2.35, 0.0043, 0.02, 60.0, vec![1.0, f32::INFINITY, 2.5]).with_stamp(17.25);
        scan.intensities = Some(vec![3.0, 4.0, 5.0]);
        let bytes = encode_laserscan_cdr(&scan, "laser");
        let back = decode_laserscan_cdr(&bytes).unwrap();
        assert_eq!(back, scan);
    }

    #[test]
    fn truncation_is_an_error_naming_the_field() {
        let bytes = encode_laserscan_cdr(&Scan::new(0.0, 0.1, 0.0, 10.0, vec![1.0; 10]), "f");
        let e = decode_laserscan_cdr(&bytes[..bytes.len() - 10]).unwrap_err();
        assert!(e.contains("ranges") || e.contains("intensities"), "{e}");
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(data in prop::collection::vec(any::<u8>(), 0..300)) {
            let _ = decode_laserscan_cdr(&data);
            let _ = decode_laserscan_ros1(&data);
        }
    }
}
