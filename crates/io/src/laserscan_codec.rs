//! `sensor_msgs/LaserScan` and `sensor_msgs/MultiEchoLaserScan` decoding:
//! ROS 2 CDR and ROS 1 serialization. (And CDR encoding, to write MCAP and
//! bag files for tests and examples.)
//!
//! Both layouts: `Header` (stamp, frame_id), then `angle_min`, `angle_max`,
//! `angle_increment`, `time_increment`, `scan_time`, `range_min`,
//! `range_max` (float32), then `ranges` and `intensities` (float32
//! sequences). ROS 2 CDR starts with a 4-byte encapsulation header (byte 1
//! is 1 for little-endian) and aligns each primitive to its size, counted
//! from the end of that header; its `Header` has no `seq` and its time is
//! `int32 sec, uint32 nanosec`. ROS 1 is packed little-endian with a
//! `uint32 seq` first.
//!
//! A `MultiEchoLaserScan` (a UTM-30LX-EW's `echoes` from `urg_node`, a
//! SICK LMS5xx's) has the same fields, but `ranges` and `intensities` are
//! sequences of `LaserEcho`, each a float32 sequence of the beam's returns,
//! nearest first. One echo of each beam is its range, chosen by [`Echo`]
//! (the first by default; an empty beam is no return), with that echo's
//! intensity; [`decode_multiecho_cdr`] and [`decode_multiecho_ros1`].

use crate::ros_cursor::Cursor;
use pcaline_geometry::Scan;

/// Which return of a `MultiEchoLaserScan`'s beam becomes its range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Echo {
    /// The nearest return, the beam's first echo (the default): the first
    /// surface the beam met.
    #[default]
    First,
    /// The farthest, the beam's last echo: past glass, dust, rain or
    /// foliage.
    Last,
    /// The return of the highest intensity; the first when the beam's
    /// intensities are missing or not one per echo.
    Strongest,
}

impl Echo {
    /// Every choice, in the order of [`Echo::names`].
    pub const ALL: [Echo; 3] = [Echo::First, Echo::Last, Echo::Strongest];

    /// The names the command line and configuration use: `first`, `last`,
    /// `strongest`.
    pub fn names() -> [&'static str; 3] {
        Echo::ALL.map(Echo::name)
    }

    /// This choice's name.
    pub fn name(self) -> &'static str {
        match self {
            Echo::First => "first",
            Echo::Last => "last",
            Echo::Strongest => "strongest",
        }
    }

    /// The index of the chosen echo among a beam's `ranges` (nearest
    /// first) and their `intensities`; `None` for a beam without echoes.
    fn pick(self, ranges: &[f32], intensities: &[f32]) -> Option<usize> {
        let last = ranges.len().checked_sub(1)?;
        Some(match self {
            Echo::First => 0,
            Echo::Last => last,
            Echo::Strongest if intensities.len() == ranges.len() => {
                intensities
                    .iter()
                    .enumerate()
                    .fold(
                        (0, f32::NEG_INFINITY),
                        |best, (k, v)| if *v > best.1 { (k, *v) } else { best },
                    )
                    .0
            }
            Echo::Strongest => 0,
        })
    }
}

/// The fields after the header, shared by both layouts; the ranges and
/// intensities are read by `beams` (a value a beam, or a choice of each
/// beam's echoes).
fn body(
    c: &mut Cursor<'_>,
    stamp_s: f64,
    beams: impl FnOnce(&mut Cursor<'_>) -> Result<(Vec<f32>, Vec<f32>), String>,
) -> Result<Scan, String> {
    let angle_min = c.f32("angle_min")?;
    let _angle_max = c.f32("angle_max")?;
    let angle_increment = c.f32("angle_increment")?;
    let time_increment = c.f32("time_increment")?;
    let _scan_time = c.f32("scan_time")?;
    let range_min = c.f32("range_min")?;
    let range_max = c.f32("range_max")?;
    let (ranges, intensities) = beams(c)?;
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
    body(&mut c, stamp_s, one_value_a_beam)
}

/// A LaserScan's `ranges` and `intensities`.
fn one_value_a_beam(c: &mut Cursor<'_>) -> Result<(Vec<f32>, Vec<f32>), String> {
    Ok((c.f32_seq("ranges")?, c.f32_seq("intensities")?))
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
    body(&mut c, stamp_s, one_value_a_beam)
}

/// A sequence of `LaserEcho`: each beam's echoes.
fn echo_lists(c: &mut Cursor<'_>, what: &str) -> Result<Vec<Vec<f32>>, String> {
    let n = c.u32(what)? as usize;
    // Each echo list is at least its 4-byte count: a corrupt count must not
    // become a huge allocation.
    if n.saturating_mul(4) > c.remaining() {
        return Err(format!("{what}: {n} beams do not fit in the message"));
    }
    (0..n).map(|_| c.f32_seq(what)).collect()
}

/// A MultiEchoLaserScan's `ranges` and `intensities` as the `echo` of each
/// beam: its range, NaN (no return) for a beam without echoes, and that
/// echo's intensity (NaN when the beam has none for it; no intensities
/// when the message has none).
fn chosen_echoes(c: &mut Cursor<'_>, echo: Echo) -> Result<(Vec<f32>, Vec<f32>), String> {
    let ranges = echo_lists(c, "ranges")?;
    let intensities = echo_lists(c, "intensities")?;
    let none: &[f32] = &[];
    let mut out = (Vec::with_capacity(ranges.len()), Vec::new());
    for (b, beam) in ranges.iter().enumerate() {
        let own = intensities.get(b).map_or(none, Vec::as_slice);
        let k = echo.pick(beam, own);
        out.0.push(k.map_or(f32::NAN, |k| beam[k]));
        if !intensities.is_empty() {
            out.1.push(k.and_then(|k| own.get(k)).copied().unwrap_or(f32::NAN));
        }
    }
    Ok(out)
}

/// Decodes a ROS 2 `sensor_msgs/msg/MultiEchoLaserScan` in CDR as the scan
/// of each beam's `echo` (the first: the nearest return), with its
/// intensity. Errors say what was being read where.
///
/// ```
/// use pcaline_geometry::Scan;
/// use pcaline_io::{Echo, decode_multiecho_cdr, encode_multiecho_cdr};
/// let echoes = vec![vec![2.0, 5.0], vec![], vec![3.0]];
/// let data = encode_multiecho_cdr(-1.0, 0.01, 0.1, 30.0, 4.5, &echoes, &[], "laser");
/// let scan = decode_multiecho_cdr(&data, Echo::First).unwrap();
/// assert_eq!(scan.ranges[0], 2.0);
/// assert!(scan.ranges[1].is_nan()); // no echo: no return
/// assert_eq!((scan.ranges[2], scan.stamp_s), (3.0, Some(4.5)));
/// assert_eq!(decode_multiecho_cdr(&data, Echo::Last).unwrap().ranges[0], 5.0);
/// ```
pub fn decode_multiecho_cdr(data: &[u8], echo: Echo) -> Result<Scan, String> {
    let mut c = Cursor::cdr(data)?;
    let (stamp_s, _frame) = c.header()?;
    body(&mut c, stamp_s, |c| chosen_echoes(c, echo))
}

/// Decodes a ROS 1 `sensor_msgs/MultiEchoLaserScan`, as
/// [`decode_multiecho_cdr`] does.
pub fn decode_multiecho_ros1(data: &[u8], echo: Echo) -> Result<Scan, String> {
    let mut c = Cursor::ros1(data);
    let (stamp_s, _frame) = c.header()?;
    body(&mut c, stamp_s, |c| chosen_echoes(c, echo))
}

/// Encodes a little-endian CDR `sensor_msgs/msg/MultiEchoLaserScan` of
/// `echoes` (each beam's ranges, nearest first) and their `intensities`
/// (each beam's, or none at all when empty), for tests and examples.
#[allow(clippy::too_many_arguments)]
pub fn encode_multiecho_cdr(
    angle_min: f32,
    angle_increment: f32,
    range_min: f32,
    range_max: f32,
    stamp_s: f64,
    echoes: &[Vec<f32>],
    intensities: &[Vec<f32>],
    frame_id: &str,
) -> Vec<u8> {
    let mut out = encode_scan_fields(
        stamp_s,
        frame_id,
        [angle_min, angle_increment, range_min, range_max],
        echoes.len(),
    );
    for lists in [echoes, intensities] {
        out.extend_from_slice(&(lists.len() as u32).to_le_bytes());
        for beam in lists {
            out.extend_from_slice(&(beam.len() as u32).to_le_bytes());
            for v in beam {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    out
}

/// The encapsulation header, the message header and the seven float32
/// fields that LaserScan and MultiEchoLaserScan share, in little-endian CDR,
/// for a scan of `beams` beams (no time increment or scan time).
fn encode_scan_fields(
    stamp_s: f64,
    frame_id: &str,
    [angle_min, angle_increment, range_min, range_max]: [f32; 4],
    beams: usize,
) -> Vec<u8> {
    let mut out = vec![0u8, 1, 0, 0];
    let sec = stamp_s.floor();
    out.extend_from_slice(&(sec as i32).to_le_bytes());
    out.extend_from_slice(&(((stamp_s - sec) * 1e9).round() as u32).to_le_bytes());
    out.extend_from_slice(&(frame_id.len() as u32 + 1).to_le_bytes());
    out.extend_from_slice(frame_id.as_bytes());
    out.push(0);
    while !(out.len() - 4).is_multiple_of(4) {
        out.push(0);
    }
    let angle_max = angle_min + angle_increment * beams.saturating_sub(1) as f32;
    for v in [angle_min, angle_max, angle_increment, 0.0, 0.0, range_min, range_max] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// Encodes a scan as a little-endian CDR `sensor_msgs/msg/LaserScan`.
pub fn encode_laserscan_cdr(scan: &Scan, frame_id: &str) -> Vec<u8> {
    let mut out = encode_scan_fields(
        scan.stamp_s.unwrap_or(0.0),
        frame_id,
        [scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max],
        scan.ranges.len(),
    );
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

    /// Each beam's first echo is its range, a beam without one no return;
    /// truncation is an error naming the field; the ROS 1 layout reads the
    /// same beams.
    #[test]
    fn multiecho_takes_each_beams_first_echo() {
        let echoes = vec![vec![1.5, 7.0, 9.0], vec![], vec![2.5], vec![f32::INFINITY, 3.0]];
        let data = encode_multiecho_cdr(-0.5, 0.25, 0.02, 30.0, 12.25, &echoes, &[], "laser01");
        let scan = decode_multiecho_cdr(&data, Echo::First).unwrap();
        assert_eq!((scan.angle_min, scan.angle_increment), (-0.5, 0.25));
        assert_eq!((scan.range_min, scan.range_max, scan.stamp_s), (0.02, 30.0, Some(12.25)));
        assert_eq!(scan.ranges.len(), 4);
        assert_eq!((scan.ranges[0], scan.ranges[2], scan.ranges[3]), (1.5, 2.5, f32::INFINITY));
        assert!(scan.ranges[1].is_nan() && scan.intensities.is_none());
        let e = decode_multiecho_cdr(&data[..data.len() - 12], Echo::First).unwrap_err();
        assert!(e.contains("ranges") || e.contains("intensities"), "{e}");
        // ROS 1: a seq before the stamp, no encapsulation header, packed
        // (a frame name of 7 bytes leaves no CDR padding to take out).
        let mut ros1 = 7u32.to_le_bytes().to_vec();
        ros1.extend_from_slice(&data[4..]);
        let back = decode_multiecho_ros1(&ros1, Echo::First).unwrap();
        assert_eq!(back.ranges[0], 1.5);
        assert!(back.ranges[1].is_nan());
    }

    /// The last echo, and the strongest with its intensity; a beam whose
    /// intensities do not match its echoes keeps its first.
    #[test]
    fn multiecho_takes_the_last_or_the_strongest_echo() {
        let echoes = vec![vec![1.5, 7.0, 9.0], vec![], vec![2.5, 4.0], vec![3.0, 6.0]];
        let intensities = vec![vec![10.0, 80.0, 20.0], vec![], vec![5.0], vec![70.0, 60.0]];
        let data = encode_multiecho_cdr(-0.5, 0.25, 0.02, 30.0, 1.0, &echoes, &intensities, "l");
        let last = decode_multiecho_cdr(&data, Echo::Last).unwrap();
        assert_eq!((last.ranges[0], last.ranges[2], last.ranges[3]), (9.0, 4.0, 6.0));
        assert!(last.ranges[1].is_nan());
        let i = last.intensities.unwrap();
        assert_eq!((i[0], i[3]), (20.0, 60.0));
        assert!(i[1].is_nan() && i[2].is_nan()); // beam 2 has no intensity for its last echo
        let strongest = decode_multiecho_cdr(&data, Echo::Strongest).unwrap();
        assert_eq!(
            (strongest.ranges[0], strongest.ranges[2], strongest.ranges[3]),
            (7.0, 2.5, 3.0)
        );
        assert_eq!(strongest.intensities.unwrap()[0], 80.0);
        assert_eq!(Echo::names(), ["first", "last", "strongest"]);
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(data in prop::collection::vec(any::<u8>(), 0..300)) {
            let _ = decode_laserscan_cdr(&data);
            let _ = decode_laserscan_ros1(&data);
            for echo in Echo::ALL {
                let _ = decode_multiecho_cdr(&data, echo);
                let _ = decode_multiecho_ros1(&data, echo);
            }
        }
    }
}
