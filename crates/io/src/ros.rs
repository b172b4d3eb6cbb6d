//! ROS logs: ROS 1 bags (format 2.0, via `rosbag`), ROS 2 bags (sqlite3
//! `.db3`, via `rusqlite` with the bundled SQLite), and MCAP (via `mcap`),
//! yielding every `sensor_msgs/LaserScan` (optionally of one topic).

use crate::laserscan_codec::{decode_laserscan_cdr, decode_laserscan_ros1};
use crate::{IoError, LogRecord, ScanRecord};
use std::collections::{BTreeSet, HashMap};
use std::ops::ControlFlow;
use std::path::Path;

const ROS1_TYPE: &str = "sensor_msgs/LaserScan";
const ROS2_TYPE: &str = "sensor_msgs/msg/LaserScan";

fn scan_record(scan: pcaline_geometry::Scan, position: usize) -> LogRecord {
    LogRecord::Scan(ScanRecord { scan, pose: None, odometry: None, position, sensor: None })
}

/// Streams the LaserScans of a ROS 1 bag; errors name the message number.
///
/// The bag header's index position is checked against the file length
/// first (the `rosbag` crate slices without checking, and panics on a
/// truncated bag); any other panic inside the decoder becomes an error
/// naming the file.
pub fn read_ros1_bag(
    path: &Path,
    topic: Option<&str>,
    visit: &mut dyn FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    check_ros1_header(path)?;
    let run = std::panic::AssertUnwindSafe(|| read_ros1_checked(path, topic, visit));
    std::panic::catch_unwind(run).unwrap_or_else(|_| {
        Err(IoError::parse(path, None, "corrupt ROS 1 bag (the bag decoder failed on it)"))
    })
}

/// Reads the bag header record and checks that its index position lies in the file.
fn check_ros1_header(path: &Path) -> Result<(), IoError> {
    use std::io::Read;
    let bad = |m: &str| IoError::parse(path, None, m.to_string());
    let mut file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let len = file.metadata().map_err(|e| IoError::io(path, e))?.len();
    let mut head = vec![0u8; 4096.min(len as usize)];
    file.read_exact(&mut head).map_err(|e| IoError::io(path, e))?;
    let rest = head
        .strip_prefix(b"#ROSBAG V2.0\n".as_slice())
        .ok_or_else(|| bad("not a ROS 1 bag (format 2.0)"))?;
    let u32_at = |b: &[u8], k: usize| {
        b.get(k..k + 4).map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as usize)
    };
    let header_len = u32_at(rest, 0).ok_or_else(|| bad("truncated bag header"))?;
    let header = rest.get(4..4 + header_len).ok_or_else(|| bad("truncated bag header"))?;
    let mut k = 0;
    while let Some(field_len) = u32_at(header, k) {
        let field =
            header.get(k + 4..k + 4 + field_len).ok_or_else(|| bad("corrupt bag header"))?;
        if let Some(v) = field.strip_prefix(b"index_pos=".as_slice()) {
            let pos = v.get(..8).map(|s| u64::from_le_bytes(s.try_into().unwrap_or([0; 8])));
            return match pos {
                Some(p) if p > 0 && p < len => Ok(()),
                Some(0) => Err(bad(
                    "the bag was not closed: it has no index (reindex it with rosbag reindex)",
                )),
                _ => Err(bad("the bag's index lies beyond the end of the file (truncated bag)")),
            };
        }
        k += 4 + field_len;
    }
    Err(bad("the bag header has no index position"))
}

fn read_ros1_checked(
    path: &Path,
    topic: Option<&str>,
    visit: &mut dyn FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    let bag = rosbag::RosBag::new(path).map_err(|e| IoError::io(path, e))?;
    let bad = |msg: String| IoError::parse(path, None, msg);
    // Chunks are read at the positions the index gives (as the ROS tools
    // do), so records between chunks that the sequential iterator rejects
    // do not stop the read.
    let mut positions = Vec::new();
    for record in bag.index_records() {
        match record.map_err(|e| bad(format!("index section: {e}")))? {
            rosbag::IndexRecord::ChunkInfo(info) => positions.push(info.chunk_pos),
            _ => continue,
        }
    }
    if positions.is_empty() {
        return Err(bad("no chunk in the index (an unindexed or truncated bag)".into()));
    }
    positions.sort_unstable();
    let mut connections: HashMap<u32, bool> = HashMap::new();
    let mut scan_topics = BTreeSet::new();
    let (mut index, mut count) = (0usize, 0usize);
    for (k, pos) in positions.iter().enumerate() {
        let mut records = bag.chunk_records();
        records.seek(*pos).map_err(|e| bad(format!("chunk {} at byte {pos}: {e}", k + 1)))?;
        let chunk = match records.next() {
            Some(Ok(rosbag::ChunkRecord::Chunk(chunk))) => chunk,
            Some(Err(e)) => return Err(bad(format!("chunk {} at byte {pos}: {e}", k + 1))),
            _ => return Err(bad(format!("no chunk at byte {pos} where the index puts one"))),
        };
        for msg in chunk.messages() {
            let msg = msg.map_err(|e| bad(format!("after message {index}: {e}")))?;
            match msg {
                rosbag::MessageRecord::Connection(c) => {
                    if c.tp == ROS1_TYPE {
                        scan_topics.insert(c.topic.to_string());
                    }
                    let wanted = c.tp == ROS1_TYPE && topic.is_none_or(|t| t == c.topic);
                    connections.insert(c.id, wanted);
                }
                rosbag::MessageRecord::MessageData(m) => {
                    index += 1;
                    if connections.get(&m.conn_id) != Some(&true) {
                        continue;
                    }
                    let scan = decode_laserscan_ros1(m.data)
                        .map_err(|e| bad(format!("message {index}: LaserScan: {e}")))?;
                    count += 1;
                    if visit(scan_record(scan, index)).is_break() {
                        return Ok(count);
                    }
                }
            }
        }
    }
    topic_exists(path, topic, &scan_topics)?;
    Ok(count)
}

/// A `topic` asked for that no LaserScan channel has is an error listing
/// the LaserScan topics that do exist.
fn topic_exists(
    path: &Path,
    topic: Option<&str>,
    scan_topics: &BTreeSet<String>,
) -> Result<(), IoError> {
    match topic {
        Some(t) if !scan_topics.contains(t) => Err(IoError::parse(
            path,
            None,
            format!(
                "no LaserScan on topic {t:?} (LaserScan topics: {})",
                if scan_topics.is_empty() {
                    "none".to_string()
                } else {
                    scan_topics.iter().cloned().collect::<Vec<_>>().join(", ")
                }
            ),
        )),
        _ => Ok(()),
    }
}

/// The `.db3` files of a ROS 2 bag: the file itself, or the `.db3` files of
/// a bag directory in name order.
fn ros2_files(path: &Path) -> Result<Vec<std::path::PathBuf>, IoError> {
    if path.is_dir() {
        let mut files: Vec<_> = std::fs::read_dir(path)
            .map_err(|e| IoError::io(path, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "db3"))
            .collect();
        files.sort();
        if files.is_empty() {
            return Err(IoError::parse(path, None, "a ROS 2 bag directory without .db3 files"));
        }
        Ok(files)
    } else {
        Ok(vec![path.to_path_buf()])
    }
}

/// Streams the LaserScans of a ROS 2 sqlite3 bag (a `.db3` file or a bag
/// directory), in message id order, 512 rows at a time.
pub fn read_ros2_bag(
    path: &Path,
    topic: Option<&str>,
    visit: &mut dyn FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    let mut count = 0;
    let mut scan_topics = BTreeSet::new();
    for file in ros2_files(path)? {
        let sql = |e: rusqlite::Error| IoError::parse(&file, None, format!("sqlite: {e}"));
        let db = rusqlite::Connection::open_with_flags(
            &file,
            rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY,
        )
        .map_err(sql)?;
        let mut topics = db.prepare("SELECT id, name, type FROM topics").map_err(sql)?;
        let scans: Vec<(i64, String)> = topics
            .query_map([], |r| {
                Ok((r.get::<_, i64>(0)?, r.get::<_, String>(1)?, r.get::<_, String>(2)?))
            })
            .map_err(sql)?
            .filter_map(Result::ok)
            .filter(|(_, _, ty)| ty == ROS2_TYPE)
            .map(|(id, name, _)| (id, name))
            .collect();
        scan_topics.extend(scans.iter().map(|(_, name)| name.clone()));
        let wanted: Vec<i64> = scans
            .iter()
            .filter(|(_, name)| topic.is_none_or(|t| t == name))
            .map(|(id, _)| *id)
            .collect();
        if wanted.is_empty() {
            continue;
        }
        let list = wanted.iter().map(i64::to_string).collect::<Vec<_>>().join(",");
        let mut page = db
            .prepare(&format!(
                "SELECT id, data FROM messages WHERE topic_id IN ({list}) AND id > ?1 ORDER BY id LIMIT 512"
            ))
            .map_err(sql)?;
        let mut last = i64::MIN;
        loop {
            let rows: Vec<(i64, Vec<u8>)> = page
                .query_map([last], |r| Ok((r.get(0)?, r.get(1)?)))
                .map_err(sql)?
                .collect::<Result<_, _>>()
                .map_err(sql)?;
            if rows.is_empty() {
                break;
            }
            for (id, data) in rows {
                last = id;
                let scan = decode_laserscan_cdr(&data).map_err(|e| {
                    IoError::parse(&file, None, format!("message id {id}: LaserScan: {e}"))
                })?;
                count += 1;
                if visit(scan_record(scan, id as usize)).is_break() {
                    return Ok(count);
                }
            }
        }
    }
    topic_exists(path, topic, &scan_topics)?;
    Ok(count)
}

/// Streams the CDR LaserScans of an MCAP file.
pub fn read_mcap(
    path: &Path,
    topic: Option<&str>,
    visit: &mut dyn FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    // No record is longer than the file: a corrupt length must not become an
    // allocation of exabytes.
    let len = file.metadata().map_err(|e| IoError::io(path, e))?.len();
    let options = mcap::sans_io::LinearReaderOptions::default()
        .with_record_length_limit(usize::try_from(len).unwrap_or(usize::MAX));
    let reader = mcap::io::MessageReader::new_with_options(std::io::BufReader::new(file), options);
    let mut count = 0;
    let mut scan_topics = BTreeSet::new();
    for (index, message) in reader.enumerate() {
        let message = message
            .map_err(|e| IoError::parse(path, None, format!("after message {index}: {e}")))?;
        let ch = &message.channel;
        let is_scan =
            ch.schema.as_ref().is_some_and(|s| s.name == ROS2_TYPE) && ch.message_encoding == "cdr";
        if is_scan && !scan_topics.contains(&ch.topic) {
            scan_topics.insert(ch.topic.clone());
        }
        if !is_scan || topic.is_some_and(|t| t != ch.topic) {
            continue;
        }
        let scan = decode_laserscan_cdr(&message.data).map_err(|e| {
            IoError::parse(path, None, format!("message {}: LaserScan: {e}", index + 1))
        })?;
        count += 1;
        if visit(scan_record(scan, index + 1)).is_break() {
            return Ok(count);
        }
    }
    topic_exists(path, topic, &scan_topics)?;
    Ok(count)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode_laserscan_cdr;
    use pcaline_geometry::Scan;
    use std::collections::BTreeMap;

    #[test]
    fn mcap_round_trip_with_topic_filter() {
        let path = std::env::temp_dir().join(format!("pcaline-{}.mcap", std::process::id()));
        let scans: Vec<Scan> = (0..5)
            .map(|k| {
                Scan::new(-1.0, 0.01, 0.1, 30.0, vec![1.0 + k as f32; 200]).with_stamp(k as f64)
            })
            .collect();
        {
            let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
            let mut w = mcap::Writer::new(file).unwrap();
            let schema = w.add_schema(ROS2_TYPE, "ros2msg", b"").unwrap();
            let scan_ch = w.add_channel(schema, "/scan", "cdr", &BTreeMap::new()).unwrap();
            let other = w.add_channel(schema, "/other", "cdr", &BTreeMap::new()).unwrap();
            for (k, s) in scans.iter().enumerate() {
                let data = encode_laserscan_cdr(s, "laser");
                let header = mcap::records::MessageHeader {
                    channel_id: scan_ch,
                    sequence: k as u32,
                    log_time: k as u64,
                    publish_time: k as u64,
                };
                w.write_to_known_channel(&header, &data).unwrap();
                let header = mcap::records::MessageHeader { channel_id: other, ..header };
                w.write_to_known_channel(&header, &data).unwrap();
            }
            w.finish().unwrap();
        }
        let mut got = Vec::new();
        let n = read_mcap(&path, Some("/scan"), &mut |r| {
            if let LogRecord::Scan(s) = r {
                got.push(s.scan);
            }
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(n, 5);
        assert_eq!(got, scans);
        let all = read_mcap(&path, None, &mut |_| ControlFlow::Continue(())).unwrap();
        assert_eq!(all, 10);
        // A topic no LaserScan channel has: an error listing those that exist.
        let e = read_mcap(&path, Some("/nope"), &mut |_| ControlFlow::Continue(())).unwrap_err();
        assert!(
            e.to_string()
                .contains("no LaserScan on topic \"/nope\" (LaserScan topics: /other, /scan)"),
            "{e}"
        );
        std::fs::remove_file(&path).unwrap();
    }
}
