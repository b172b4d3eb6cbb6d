//! ROS logs: ROS 1 bags (format 2.0, via `rosbag`), ROS 2 bags (sqlite3
//! `.db3`, via `rusqlite` with the bundled SQLite), and MCAP (via `mcap`),
//! yielding every `sensor_msgs/LaserScan` and `sensor_msgs/MultiEchoLaserScan`
//! (its first echoes; optionally of one topic); and
//! their `nav_msgs/Odometry` topic by topic, the scans' frame and the
//! static transforms ([`read_ros_motion`]).

use crate::laserscan_codec::{
    Echo, decode_laserscan_cdr, decode_laserscan_ros1, decode_multiecho_cdr, decode_multiecho_ros1,
    laserscan_frame,
};
use crate::odometry_codec::{decode_odometry_cdr, decode_odometry_ros1};
use crate::tf_codec::{decode_tf_cdr, decode_tf_ros1};
use crate::{IoError, LogFormat, LogRecord, OdometryRecord, ScanRecord};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::ops::ControlFlow;
use std::path::Path;

const ROS1_TYPE: &str = "sensor_msgs/LaserScan";
const ROS2_TYPE: &str = "sensor_msgs/msg/LaserScan";
const ROS1_MULTIECHO: &str = "sensor_msgs/MultiEchoLaserScan";
const ROS2_MULTIECHO: &str = "sensor_msgs/msg/MultiEchoLaserScan";
const ROS1_ODOMETRY: &str = "nav_msgs/Odometry";
const ROS2_ODOMETRY: &str = "nav_msgs/msg/Odometry";
const ROS1_TF: &str = "tf2_msgs/TFMessage";
const ROS2_TF: &str = "tf2_msgs/msg/TFMessage";

/// Messages a pass over a ROS log takes: one type (its ROS 1 and ROS 2
/// names), optionally of one topic. A pass takes several at once.
#[derive(Clone, Copy)]
struct Wanted<'a> {
    ros1_type: &'a str,
    ros2_type: &'a str,
    topic: Option<&'a str>,
}

/// How a message is serialized.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    /// ROS 2's CDR (ROS 2 bags, MCAP channels of encoding `cdr`).
    Cdr,
    /// ROS 1's (ROS 1 bags, MCAP channels of encoding `ros1`, as MCAP files
    /// converted from ROS 1 bags have them).
    Ros1,
}

/// A wanted message, as a pass gives it to its visitor.
struct Message<'m> {
    /// The file it is in (a bag directory's `.db3` or `.mcap` file, else
    /// the log).
    file: &'m Path,
    topic: &'m str,
    /// Which of the pass's [`Wanted`] it is (their index).
    kind: usize,
    /// A 1-based message number, or a ROS 2 message id.
    position: usize,
    encoding: Encoding,
    data: &'m [u8],
}

/// Called with each wanted message, in the file's order.
type Visit<'v> = dyn FnMut(Message<'_>) -> Result<ControlFlow<()>, IoError> + 'v;

/// What a pass saw: the topics of each wanted type (whatever the topic
/// asked for), and whether the visitor stopped it.
struct Pass {
    topics: Vec<BTreeSet<String>>,
    stopped: bool,
}

impl Pass {
    fn new(wanted: &[Wanted<'_>]) -> Self {
        Pass { topics: vec![BTreeSet::new(); wanted.len()], stopped: false }
    }
}

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
    echo: Echo,
    visit: &mut dyn FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    read_scans(path, topic, echo, visit, ros1_messages, "message")
}

/// A pass over the messages of one type of a ROS log.
type MessagePass = fn(&Path, &[Wanted<'_>], &mut Visit<'_>) -> Result<Pass, IoError>;

/// The scans of a pass (`messages`): LaserScans, and MultiEchoLaserScans
/// as the scan of each beam's `echo`; each decode error names its
/// `label` (message number or id). Returns the scans read; a `topic` asked
/// for that no scan channel has is an error, unless `visit` stopped the
/// pass early.
fn read_scans(
    path: &Path,
    topic: Option<&str>,
    echo: Echo,
    visit: &mut dyn FnMut(LogRecord) -> ControlFlow<()>,
    messages: MessagePass,
    label: &str,
) -> Result<usize, IoError> {
    let wanted = scan_types(topic);
    let mut count = 0;
    let mut pass = messages(path, &wanted, &mut |m| {
        let (scan, name) = match (m.kind, m.encoding) {
            (0, Encoding::Cdr) => (decode_laserscan_cdr(m.data), "LaserScan"),
            (0, Encoding::Ros1) => (decode_laserscan_ros1(m.data), "LaserScan"),
            (_, Encoding::Cdr) => (decode_multiecho_cdr(m.data, echo), "MultiEchoLaserScan"),
            (_, Encoding::Ros1) => (decode_multiecho_ros1(m.data, echo), "MultiEchoLaserScan"),
        };
        let scan = scan.map_err(|e| {
            IoError::parse(m.file, None, format!("{label} {}: {name}: {e}", m.position))
        })?;
        count += 1;
        Ok(visit(scan_record(scan, m.position)))
    })?;
    if !pass.stopped {
        let multiecho = std::mem::take(&mut pass.topics[1]);
        pass.topics[0].extend(multiecho);
        topic_exists(path, topic, &pass.topics[0])?;
    }
    Ok(count)
}

/// The scan messages of a pass, of `topic` when given: LaserScans (kind
/// 0) and MultiEchoLaserScans (kind 1).
fn scan_types(topic: Option<&str>) -> [Wanted<'_>; 2] {
    [
        Wanted { ros1_type: ROS1_TYPE, ros2_type: ROS2_TYPE, topic },
        Wanted { ros1_type: ROS1_MULTIECHO, ros2_type: ROS2_MULTIECHO, topic },
    ]
}

/// The wanted messages of a ROS 1 bag, in chunk order (see
/// [`read_ros1_bag`] for the checks).
fn ros1_messages(
    path: &Path,
    wanted: &[Wanted<'_>],
    visit: &mut Visit<'_>,
) -> Result<Pass, IoError> {
    check_ros1_header(path)?;
    let run = std::panic::AssertUnwindSafe(|| read_ros1_checked(path, wanted, visit));
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
    wanted: &[Wanted<'_>],
    visit: &mut Visit<'_>,
) -> Result<Pass, IoError> {
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
    // Each connection's topic and kind, when it is of a wanted type and topic.
    let mut connections: HashMap<u32, Option<(String, usize)>> = HashMap::new();
    let mut pass = Pass::new(wanted);
    let mut index = 0usize;
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
                    let kind = wanted.iter().position(|w| w.ros1_type == c.tp);
                    if let Some(k) = kind {
                        pass.topics[k].insert(c.topic.to_string());
                    }
                    let taken = kind.filter(|k| wanted[*k].topic.is_none_or(|t| t == c.topic));
                    connections.insert(c.id, taken.map(|k| (c.topic.to_string(), k)));
                }
                rosbag::MessageRecord::MessageData(m) => {
                    index += 1;
                    let Some(Some((topic, kind))) = connections.get(&m.conn_id) else { continue };
                    let message = Message {
                        file: path,
                        topic,
                        kind: *kind,
                        position: index,
                        encoding: Encoding::Ros1,
                        data: m.data,
                    };
                    if visit(message)?.is_break() {
                        pass.stopped = true;
                        return Ok(pass);
                    }
                }
            }
        }
    }
    Ok(pass)
}

/// A `topic` asked for that no scan channel has is an error listing the
/// scan topics (LaserScan and MultiEchoLaserScan) that do exist.
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
                "no LaserScan or MultiEchoLaserScan on topic {t:?} (scan topics: {})",
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

/// The files of a bag: the file itself, or the files of a bag directory
/// (ROS 2 writes a directory of `.db3` or `.mcap` files, split by size or
/// time) whose names end with one of `suffixes` (case-insensitive), in
/// name order.
fn bag_files(path: &Path, suffixes: &[&str]) -> Result<Vec<std::path::PathBuf>, IoError> {
    if !path.is_dir() {
        return Ok(vec![path.to_path_buf()]);
    }
    let mut files: Vec<_> = std::fs::read_dir(path)
        .map_err(|e| IoError::io(path, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && suffixes.iter().any(|s| has_suffix(p, s)))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(IoError::parse(
            path,
            None,
            format!("a bag directory without {} files", suffixes.join(" or ")),
        ));
    }
    Ok(files)
}

/// Whether the name of `file` ends with `suffix` (such as `.db3.zstd`),
/// case-insensitive.
fn has_suffix(file: &Path, suffix: &str) -> bool {
    let name = file.file_name().map(|n| n.to_string_lossy().to_ascii_lowercase());
    name.is_some_and(|n| n.ends_with(suffix))
}

/// The files of the directory `dir` whose extension is `ext`
/// (case-insensitive), in name order.
pub(crate) fn files_with_extension(
    dir: &Path,
    ext: &str,
) -> Result<Vec<std::path::PathBuf>, IoError> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .map_err(|e| IoError::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case(ext)))
        .collect();
    files.sort();
    Ok(files)
}

/// Streams the LaserScans of a ROS 2 sqlite3 bag (a `.db3` file or a bag
/// directory), in message id order, 512 rows at a time.
pub fn read_ros2_bag(
    path: &Path,
    topic: Option<&str>,
    echo: Echo,
    visit: &mut dyn FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    read_scans(path, topic, echo, visit, ros2_messages, "message id")
}

/// The first bytes of a zstd frame. A CDR message starts with its
/// encapsulation header (`00 01 00 00` or `00 00 00 00`), never with these.
const ZSTD_MAGIC: [u8; 4] = [0x28, 0xB5, 0x2F, 0xFD];

/// A compressed message that decompresses to more than this is refused
/// (a corrupt or hostile frame must not fill the memory), bytes.
const MAX_MESSAGE_BYTES: u64 = 1 << 28;

/// A message as stored, or decompressed when rosbag2 compressed it
/// (`--compression-mode message --compression-format zstd`).
fn message_bytes(data: &[u8]) -> Result<std::borrow::Cow<'_, [u8]>, String> {
    use std::io::Read;
    if !data.starts_with(&ZSTD_MAGIC) {
        return Ok(std::borrow::Cow::Borrowed(data));
    }
    let mut out = Vec::new();
    zstd::stream::read::Decoder::new(data)
        .and_then(|d| d.take(MAX_MESSAGE_BYTES + 1).read_to_end(&mut out))
        .map_err(|e| format!("zstd: {e}"))?;
    if out.len() as u64 > MAX_MESSAGE_BYTES {
        return Err(format!("zstd: decompresses to more than {MAX_MESSAGE_BYTES} bytes"));
    }
    Ok(std::borrow::Cow::Owned(out))
}

/// A ROS 2 bag file ready for SQLite: the file itself, or, for a file
/// rosbag2 compressed whole (`.db3.zstd`, `--compression-mode file`), a
/// temporary copy decompressed beside the system's other temporary files,
/// removed when this is dropped (and by [`crate::remove_temporary_files`]
/// on an interrupt).
#[derive(Debug)]
struct Db3File {
    path: std::path::PathBuf,
    temporary: bool,
}

impl Db3File {
    fn open(file: &Path) -> Result<Self, IoError> {
        if !is_compressed_db3(file) {
            return Ok(Db3File { path: file.to_path_buf(), temporary: false });
        }
        static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let k = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let name = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let path = std::env::temp_dir().join(format!("pcaline-{}-{k}-{name}", std::process::id()));
        crate::atomic::register(&path);
        let out = Db3File { path, temporary: true };
        #[cfg(test)]
        DECOMPRESSIONS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let input = std::fs::File::open(file).map_err(|e| IoError::io(file, e))?;
        let mut output = std::fs::File::create(&out.path).map_err(|e| IoError::io(&out.path, e))?;
        zstd::stream::copy_decode(input, &mut output)
            .map_err(|e| IoError::parse(file, None, format!("zstd: {e}")))?;
        Ok(out)
    }
}

impl Drop for Db3File {
    fn drop(&mut self) {
        if self.temporary {
            let _ = std::fs::remove_file(&self.path);
            crate::atomic::unregister(&self.path);
        }
    }
}

/// The decompressed copies in use, by compressed file: each is made once
/// and shared while something holds it (a pass over the bag, or a
/// [`DecompressedBag`]).
static COPIES: std::sync::Mutex<Vec<(std::path::PathBuf, std::sync::Weak<Db3File>)>> =
    std::sync::Mutex::new(Vec::new());

/// Copies decompressed so far (for the tests).
#[cfg(test)]
static DECOMPRESSIONS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

impl Db3File {
    /// [`Db3File::open`], sharing a decompressed copy of `file` that is
    /// still held.
    fn shared(file: &Path) -> Result<std::sync::Arc<Db3File>, IoError> {
        if !is_compressed_db3(file) {
            return Db3File::open(file).map(std::sync::Arc::new);
        }
        let mut copies = COPIES.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        copies.retain(|(_, copy)| copy.strong_count() > 0);
        if let Some(copy) = copies.iter().filter(|(p, _)| p == file).find_map(|(_, c)| c.upgrade())
        {
            return Ok(copy);
        }
        let copy = std::sync::Arc::new(Db3File::open(file)?);
        copies.push((file.to_path_buf(), std::sync::Arc::downgrade(&copy)));
        Ok(copy)
    }
}

/// Holds the decompressed copies of a ROS 2 bag's files that rosbag2
/// compressed whole (`.db3.zstd`), so that every pass over the bag while
/// this lives reads them instead of decompressing each file again. The
/// copies are removed when it is dropped (and on an interrupt, as every
/// temporary copy is).
#[derive(Debug)]
#[must_use = "the copies are removed when this is dropped"]
pub struct DecompressedBag {
    _copies: Vec<std::sync::Arc<Db3File>>,
}

/// Decompresses the `.db3.zstd` files of the ROS 2 bag at `path` (a file
/// or a bag folder) once, for as long as the result lives; a bag without
/// such files holds nothing. Errors name the file, as reading the bag
/// does.
pub fn keep_decompressed(path: &Path) -> Result<DecompressedBag, IoError> {
    let copies = bag_files(path, &[".db3", ".db3.zstd"])?
        .iter()
        .filter(|f| is_compressed_db3(f))
        .map(|f| Db3File::shared(f))
        .collect::<Result<_, _>>()?;
    Ok(DecompressedBag { _copies: copies })
}

/// A file rosbag2 compressed whole: `*.db3.zstd`.
pub(crate) fn is_compressed_db3(file: &Path) -> bool {
    has_suffix(file, ".db3.zstd")
}

/// The wanted messages of a ROS 2 bag, file by file in message id order;
/// rosbag2's zstd compression, of whole files or of each message, is
/// undone.
fn ros2_messages(
    path: &Path,
    wanted: &[Wanted<'_>],
    visit: &mut Visit<'_>,
) -> Result<Pass, IoError> {
    let mut pass = Pass::new(wanted);
    for file in bag_files(path, &[".db3", ".db3.zstd"])? {
        let sql = |e: rusqlite::Error| IoError::parse(&file, None, format!("sqlite: {e}"));
        let db_file = Db3File::shared(&file)?;
        let db = rusqlite::Connection::open_with_flags(
            &db_file.path,
            rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY,
        )
        .map_err(sql)?;
        let mut topics = db.prepare("SELECT id, name, type FROM topics").map_err(sql)?;
        let of_type: Vec<(i64, String, usize)> = topics
            .query_map([], |r| {
                Ok((r.get::<_, i64>(0)?, r.get::<_, String>(1)?, r.get::<_, String>(2)?))
            })
            .map_err(sql)?
            .filter_map(Result::ok)
            .filter_map(|(id, name, ty)| {
                wanted.iter().position(|w| w.ros2_type == ty).map(|k| (id, name, k))
            })
            .collect();
        for (_, name, k) in &of_type {
            pass.topics[*k].insert(name.clone());
        }
        let taken: HashMap<i64, (String, usize)> = of_type
            .into_iter()
            .filter(|(_, name, k)| wanted[*k].topic.is_none_or(|t| t == name))
            .map(|(id, name, k)| (id, (name, k)))
            .collect();
        if taken.is_empty() {
            continue;
        }
        let list = taken.keys().map(i64::to_string).collect::<Vec<_>>().join(",");
        let mut page = db
            .prepare(&format!(
                "SELECT id, topic_id, data FROM messages WHERE topic_id IN ({list}) AND id > ?1 ORDER BY id LIMIT 512"
            ))
            .map_err(sql)?;
        let mut last = i64::MIN;
        loop {
            let rows: Vec<(i64, i64, Vec<u8>)> = page
                .query_map([last], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
                .map_err(sql)?
                .collect::<Result<_, _>>()
                .map_err(sql)?;
            if rows.is_empty() {
                break;
            }
            for (id, topic_id, data) in rows {
                // Each page starts past the last id: a table whose ids do
                // not increase (a corrupt file) would page for ever.
                if id <= last {
                    return Err(IoError::parse(
                        &file,
                        None,
                        format!(
                            "messages table: message id {id} comes after id {last} (a corrupt database)"
                        ),
                    ));
                }
                last = id;
                let Some((topic, kind)) = taken.get(&topic_id) else { continue };
                let data = message_bytes(&data)
                    .map_err(|e| IoError::parse(&file, None, format!("message id {id}: {e}")))?;
                let message = Message {
                    file: &file,
                    topic,
                    kind: *kind,
                    position: id as usize,
                    encoding: Encoding::Cdr,
                    data: &data,
                };
                if visit(message)?.is_break() {
                    pass.stopped = true;
                    return Ok(pass);
                }
            }
        }
    }
    Ok(pass)
}

/// Streams the CDR LaserScans of an MCAP file, or of the `.mcap` files of a
/// ROS 2 bag directory in name order.
pub fn read_mcap(
    path: &Path,
    topic: Option<&str>,
    echo: Echo,
    visit: &mut dyn FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    read_scans(path, topic, echo, visit, mcap_messages, "message")
}

/// The wanted CDR messages of an MCAP file, in the file's order.
fn mcap_messages(
    path: &Path,
    wanted: &[Wanted<'_>],
    visit: &mut Visit<'_>,
) -> Result<Pass, IoError> {
    let mut pass = Pass::new(wanted);
    for file in bag_files(path, &[".mcap"])? {
        mcap_file_messages(&file, wanted, visit, &mut pass)?;
        if pass.stopped {
            break;
        }
    }
    Ok(pass)
}

/// [`mcap_messages`] of one MCAP file, adding to `pass`; positions count
/// the file's own messages.
fn mcap_file_messages(
    path: &Path,
    wanted: &[Wanted<'_>],
    visit: &mut Visit<'_>,
    pass: &mut Pass,
) -> Result<(), IoError> {
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    // No record is longer than the file: a corrupt length must not become an
    // allocation of exabytes.
    let len = file.metadata().map_err(|e| IoError::io(path, e))?.len();
    let options = mcap::sans_io::LinearReaderOptions::default()
        .with_record_length_limit(usize::try_from(len).unwrap_or(usize::MAX));
    each_mcap_message(path, file, options, |position, channel, data| {
        let schema = channel.schema.as_ref().map_or("", |s| s.name.as_str());
        let of_type =
            wanted.iter().enumerate().find_map(|(k, w)| match channel.message_encoding.as_str() {
                "cdr" if schema == w.ros2_type => Some((k, Encoding::Cdr)),
                "ros1" if schema == w.ros1_type => Some((k, Encoding::Ros1)),
                _ => None,
            });
        let Some((kind, encoding)) = of_type else { return Ok(ControlFlow::Continue(())) };
        if !pass.topics[kind].contains(&channel.topic) {
            pass.topics[kind].insert(channel.topic.clone());
        }
        if wanted[kind].topic.is_some_and(|t| t != channel.topic) {
            return Ok(ControlFlow::Continue(()));
        }
        let message = Message { file: path, topic: &channel.topic, kind, position, encoding, data };
        let flow = visit(message)?;
        if flow.is_break() {
            pass.stopped = true;
        }
        Ok(flow)
    })
}

/// Calls `f` with each message of the MCAP file `path` (opened as `file`),
/// its position in the file (counted from 1) and its channel, in file
/// order, until `f` breaks or fails.
///
/// It drives the crate's sans-io reader itself and parses only the records
/// a message needs: schemas, channels and messages. The crate's own
/// message reader parses every record, and its parser panics on some
/// malformed records of other kinds (mcap 0.26: an attachment whose body is
/// shorter than its header, found by the `mcap` fuzz target); those are now
/// skipped like the summary's indexes. Schemas and channels are linked with
/// the crate's checks ([`mcap::read::ChannelAccumulator`]: a redefinition
/// must match, a channel's schema must come first). The file is read to its
/// end magic, so a truncated file is an error after its last message.
fn each_mcap_message(
    path: &Path,
    file: std::fs::File,
    options: mcap::sans_io::LinearReaderOptions,
    mut f: impl FnMut(usize, &mcap::Channel<'static>, &[u8]) -> Result<ControlFlow<()>, IoError>,
) -> Result<(), IoError> {
    use mcap::records::op;
    use mcap::sans_io::{LinearReadEvent, LinearReader};
    use std::io::Read;
    let mut source = std::io::BufReader::new(file);
    let mut reader = LinearReader::new_with_options(options.with_emit_chunks(false));
    let mut channels = mcap::read::ChannelAccumulator::default();
    let mut messages = 0usize;
    let error = |messages: usize, e: mcap::McapError| {
        IoError::parse(path, None, format!("after message {messages}: {e}"))
    };
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| error(messages, e))? {
            LinearReadEvent::ReadRequest(need) => {
                let read = loop {
                    match source.read(reader.insert(need)) {
                        Ok(n) => break n,
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                        Err(e) => return Err(IoError::io(path, e)),
                    }
                };
                reader.notify_read(read);
            }
            LinearReadEvent::Record { opcode, data } => {
                if !matches!(opcode, op::SCHEMA | op::CHANNEL | op::MESSAGE) {
                    continue;
                }
                match mcap::parse_record(opcode, data).map_err(|e| error(messages, e))? {
                    mcap::records::Record::Schema { header, data } => channels
                        .add_schema_from_slice(header, &data)
                        .map_err(|e| error(messages, e))?,
                    mcap::records::Record::Channel(channel) => {
                        channels.add_channel(channel).map_err(|e| error(messages, e))?
                    }
                    mcap::records::Record::Message { header, data } => {
                        let Some(channel) = channels.get(header.channel_id) else {
                            let e =
                                mcap::McapError::UnknownChannel(header.sequence, header.channel_id);
                            return Err(error(messages, e));
                        };
                        messages += 1;
                        if f(messages, &channel, &data)?.is_break() {
                            return Ok(());
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(())
}

/// The odometry of a ROS log and what places its LIDAR on the vehicle
/// ([`read_ros_motion`]).
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct RosMotion {
    /// Each `nav_msgs/Odometry` topic's messages.
    pub odometry: BTreeMap<String, OdometryTrack>,
    /// The `frame_id` of the first scan message (of the topic asked for),
    /// without a leading `/`.
    pub scan_frame: Option<String>,
    /// Every transform on `/tf_static`.
    pub static_transforms: Vec<crate::FrameTransform>,
    /// Every LaserScan and MultiEchoLaserScan topic of the log (whatever
    /// topic was asked for).
    pub scan_topics: BTreeSet<String>,
    /// Every transform on `/tf`, in the file's order, each with the number
    /// of its message: where a log keeps its odometry when it has no
    /// `nav_msgs/Odometry` ([`crate::odometry_from_transforms`]).
    pub transforms: Vec<(usize, crate::FrameTransform)>,
}

/// The messages of one `nav_msgs/Odometry` topic.
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct OdometryTrack {
    /// The first message's `child_frame_id` (the vehicle's frame).
    pub child_frame_id: String,
    /// The poses in the file's order (positions as the scan readers give
    /// them).
    pub records: Vec<OdometryRecord>,
}

/// The `nav_msgs/Odometry` of a ROS log (ROS 1 bag, ROS 2 bag or MCAP) by
/// topic, the frame of its scans (of `scan_topic` when given), its scan
/// topics (LaserScan and MultiEchoLaserScan), and its `/tf_static` and
/// `/tf` transforms, in one pass over the log: what `pcaline map` needs to
/// use the odometry as the source and place the LIDAR on the vehicle.
/// Another format, or a log without them, gives them empty. Errors name the
/// file and the message; a pose or stamp that is not finite, or beyond
/// [`crate::MAX_COORDINATE_M`], is an error as in every reader.
pub fn read_ros_motion(
    path: &Path,
    format: LogFormat,
    scan_topic: Option<&str>,
) -> Result<RosMotion, IoError> {
    let mut motion = RosMotion::default();
    let messages: MessagePass = match format {
        LogFormat::Ros1Bag => ros1_messages,
        LogFormat::Ros2Bag => ros2_messages,
        LogFormat::Mcap => mcap_messages,
        _ => return Ok(motion),
    };
    // One pass: the odometry, the transforms (of `/tf_static` and `/tf`;
    // other TFMessage topics are not the transform tree), and the scans,
    // of which only the first is decoded, for its frame.
    const ODOMETRY: usize = 0;
    const TRANSFORMS: usize = 1;
    const SCANS: usize = 2;
    const MULTIECHO_SCANS: usize = 3;
    let [scans, multiecho] = scan_types(scan_topic);
    let wanted = [
        Wanted { ros1_type: ROS1_ODOMETRY, ros2_type: ROS2_ODOMETRY, topic: None },
        Wanted { ros1_type: ROS1_TF, ros2_type: ROS2_TF, topic: None },
        scans,
        multiecho,
    ];
    let mut pass = messages(path, &wanted, &mut |m| {
        let position = m.position;
        let error = |what: &str, e: String| {
            IoError::parse(m.file, None, format!("message {position}: {what}: {e}"))
        };
        match m.kind {
            ODOMETRY => {
                let decoded = match m.encoding {
                    Encoding::Cdr => decode_odometry_cdr(m.data),
                    Encoding::Ros1 => decode_odometry_ros1(m.data),
                };
                let o = decoded.map_err(|e| error("Odometry", e))?;
                let record = OdometryRecord { pose: o.pose, stamp_s: o.stamp_s, position };
                crate::check_record(&LogRecord::Odometry(record))
                    .map_err(|e| error("Odometry", e))?;
                let track = motion.odometry.entry(m.topic.to_string()).or_insert_with(|| {
                    OdometryTrack { child_frame_id: o.child_frame_id, records: Vec::new() }
                });
                track.records.push(record);
            }
            TRANSFORMS => {
                let dynamic = match m.topic.trim_start_matches('/') {
                    "tf_static" => false,
                    "tf" => true,
                    _ => return Ok(ControlFlow::Continue(())),
                };
                let decoded = match m.encoding {
                    Encoding::Cdr => decode_tf_cdr(m.data),
                    Encoding::Ros1 => decode_tf_ros1(m.data),
                };
                let t = decoded.map_err(|e| error("TFMessage", e))?;
                for transform in &t {
                    let record = OdometryRecord {
                        pose: transform.parent_from_child,
                        stamp_s: transform.stamp_s,
                        position,
                    };
                    crate::check_record(&LogRecord::Odometry(record))
                        .map_err(|e| error("TFMessage", e))?;
                }
                if dynamic {
                    motion.transforms.extend(t.into_iter().map(|t| (position, t)));
                } else {
                    motion.static_transforms.extend(t);
                }
            }
            // Both scan types begin with the same header.
            SCANS | MULTIECHO_SCANS if motion.scan_frame.is_none() => {
                let frame = laserscan_frame(m.data, m.encoding == Encoding::Ros1)
                    .map_err(|e| error("LaserScan", e))?;
                motion.scan_frame = Some(frame);
            }
            _ => {}
        }
        Ok(ControlFlow::Continue(()))
    })?;
    motion.scan_topics = std::mem::take(&mut pass.topics[SCANS]);
    motion.scan_topics.append(&mut pass.topics[MULTIECHO_SCANS]);
    Ok(motion)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode_laserscan_cdr;
    use pcaline_geometry::Scan;
    use std::collections::BTreeMap;

    /// A ROS 2 bag of rosbag2's tables: `topics` (name, type) with ids from
    /// 1, and `messages` (topic name, CDR data) with ids and timestamps in
    /// order.
    fn write_ros2_bag(path: &Path, topics: &[(&str, &str)], messages: &[(&str, Vec<u8>)]) {
        let db = rusqlite::Connection::open(path).unwrap();
        db.execute_batch(
            "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, \
             serialization_format TEXT, offered_qos_profiles TEXT); \
             CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER, \
             timestamp INTEGER, data BLOB);",
        )
        .unwrap();
        for (id, (name, ty)) in topics.iter().enumerate() {
            db.execute(
                "INSERT INTO topics VALUES (?1, ?2, ?3, 'cdr', '')",
                rusqlite::params![id as i64 + 1, name, ty],
            )
            .unwrap();
        }
        for (k, (topic, data)) in messages.iter().enumerate() {
            let topic_id = topics.iter().position(|(name, _)| name == topic).unwrap() as i64 + 1;
            db.execute(
                "INSERT INTO messages VALUES (?1, ?2, ?3, ?4)",
                rusqlite::params![k as i64 + 1, topic_id, k as i64, data],
            )
            .unwrap();
        }
    }

    /// Odometry of two topics beside the scans and a static transform, in an
    /// MCAP file and a ROS 2 bag: each topic's poses come back in order
    /// with its vehicle frame, the scans' frame and the transform too, and
    /// the scans read as before.
    #[test]
    fn odometry_is_read_topic_by_topic() {
        let dir = std::env::temp_dir().join(format!("pcaline-odom-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let pose = |k: usize| pcaline_geometry::Pose2::new(k as f64, 0.5, 0.1 * k as f64);
        let scan = Scan::new(-1.0, 0.01, 0.1, 30.0, vec![2.0; 100]).with_stamp(0.5);
        let laser = crate::FrameTransform::planar(
            "base_link",
            "laser",
            pcaline_geometry::Pose2::new(0.2, 0.0, 0.0),
            0.0,
        );
        let tf = ("/tf_static", crate::encode_tf_cdr(std::slice::from_ref(&laser)));
        let messages: Vec<(&str, Vec<u8>)> = std::iter::once(tf)
            .chain((0..4).flat_map(|k| {
                let t = k as f64 * 0.1;
                [
                    ("/odom", crate::encode_odometry_cdr(t, &pose(k), "odom", "base_link")),
                    ("/wheel", crate::encode_odometry_cdr(t, &pose(10 + k), "odom", "base")),
                    ("/scan", encode_laserscan_cdr(&scan, "/laser")),
                ]
            }))
            .collect();
        // MCAP.
        let mcap_path = dir.join("odom.mcap");
        {
            let file = std::io::BufWriter::new(std::fs::File::create(&mcap_path).unwrap());
            let mut w = mcap::Writer::new(file).unwrap();
            let scans = w.add_schema(ROS2_TYPE, "ros2msg", b"").unwrap();
            let odom = w.add_schema(ROS2_ODOMETRY, "ros2msg", b"").unwrap();
            let tf = w.add_schema(ROS2_TF, "ros2msg", b"").unwrap();
            let mut channels = BTreeMap::new();
            for (k, (topic, data)) in messages.iter().enumerate() {
                let schema = match *topic {
                    "/scan" => scans,
                    "/tf_static" => tf,
                    _ => odom,
                };
                let ch = *channels.entry(*topic).or_insert_with(|| {
                    w.add_channel(schema, topic, "cdr", &BTreeMap::new()).unwrap()
                });
                let header = mcap::records::MessageHeader {
                    channel_id: ch,
                    sequence: k as u32,
                    log_time: k as u64,
                    publish_time: k as u64,
                };
                w.write_to_known_channel(&header, data).unwrap();
            }
            w.finish().unwrap();
        }
        // ROS 2 bag: the rosbag2 tables.
        let db_path = dir.join("odom.db3");
        let topics = [
            ("/odom", ROS2_ODOMETRY),
            ("/wheel", ROS2_ODOMETRY),
            ("/scan", ROS2_TYPE),
            ("/tf_static", ROS2_TF),
        ];
        write_ros2_bag(&db_path, &topics, &messages);
        for (path, format) in [(&mcap_path, LogFormat::Mcap), (&db_path, LogFormat::Ros2Bag)] {
            let motion = read_ros_motion(path, format, None).unwrap();
            let tracks = &motion.odometry;
            assert_eq!(tracks.keys().collect::<Vec<_>>(), ["/odom", "/wheel"], "{format:?}");
            assert_eq!(motion.scan_frame.as_deref(), Some("laser"));
            assert_eq!(motion.static_transforms, std::slice::from_ref(&laser));
            assert_eq!(motion.scan_topics.iter().collect::<Vec<_>>(), ["/scan"]);
            for (topic, first, vehicle) in [("/odom", 0, "base_link"), ("/wheel", 10, "base")] {
                let t = &tracks[topic];
                assert_eq!(t.child_frame_id, vehicle);
                assert_eq!(t.records.len(), 4);
                for (k, r) in t.records.iter().enumerate() {
                    assert_eq!(r.pose.x(), pose(first + k).x(), "{format:?} {topic}");
                    assert!((r.stamp_s - k as f64 * 0.1).abs() < 1e-9);
                }
            }
            let mut scans = 0;
            crate::read_log(
                path,
                &crate::LogOptions { format: Some(format), ..Default::default() },
                |r| {
                    scans += usize::from(matches!(r, LogRecord::Scan(_)));
                    ControlFlow::Continue(())
                },
            )
            .unwrap();
            assert_eq!(scans, 4, "{format:?}");
        }
        // A ROS 2 bag directory of MCAP files (rosbag2's default storage
        // since Iron), split in two: detected as MCAP, read file by file.
        let bag = dir.join("mcap_bag");
        std::fs::create_dir_all(&bag).unwrap();
        std::fs::write(bag.join("metadata.yaml"), "rosbag2_bagfile_information: {}\n").unwrap();
        for name in ["mcap_bag_0.mcap", "mcap_bag_1.MCAP"] {
            std::fs::copy(&mcap_path, bag.join(name)).unwrap();
        }
        assert_eq!(LogFormat::detect(&bag).unwrap(), LogFormat::Mcap);
        let motion = read_ros_motion(&bag, LogFormat::Mcap, None).unwrap();
        assert_eq!(motion.odometry["/odom"].records.len(), 8);
        assert_eq!(motion.static_transforms.len(), 2);
        let mut stamps = Vec::new();
        crate::read_log(&bag, &crate::LogOptions::default(), |r| {
            if let LogRecord::Scan(s) = r {
                stamps.push(s.position);
            }
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(stamps.len(), 8);
        let empty = dir.join("empty_bag");
        std::fs::create_dir_all(&empty).unwrap();
        assert_eq!(LogFormat::detect(&empty).unwrap(), LogFormat::Ros2Bag);
        let e = read_ros_motion(&empty, LogFormat::Mcap, None).unwrap_err().to_string();
        assert!(e.contains("without .mcap files"), "{e}");
        // Other formats have no such messages.
        assert_eq!(read_ros_motion(&db_path, LogFormat::Json, None).unwrap(), RosMotion::default());
        // A broken odometry message is an error naming it.
        let db = rusqlite::Connection::open(&db_path).unwrap();
        db.execute("UPDATE messages SET data = x'00010000' WHERE id = 5", []).unwrap();
        drop(db);
        let e = read_ros_motion(&db_path, LogFormat::Ros2Bag, None).unwrap_err().to_string();
        assert!(e.contains("message 5: Odometry: truncated"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

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
        let n = read_mcap(&path, Some("/scan"), Echo::First, &mut |r| {
            if let LogRecord::Scan(s) = r {
                got.push(s.scan);
            }
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(n, 5);
        assert_eq!(got, scans);
        let all = read_mcap(&path, None, Echo::First, &mut |_| ControlFlow::Continue(())).unwrap();
        assert_eq!(all, 10);
        let motion = read_ros_motion(&path, LogFormat::Mcap, Some("/scan")).unwrap();
        assert_eq!(motion.scan_topics.iter().collect::<Vec<_>>(), ["/other", "/scan"]);
        // A topic no LaserScan channel has: an error listing those that exist.
        let e = read_mcap(&path, Some("/nope"), Echo::First, &mut |_| ControlFlow::Continue(()))
            .unwrap_err();
        assert!(
            e.to_string().contains(
                "no LaserScan or MultiEchoLaserScan on topic \"/nope\" (scan topics: /other, /scan)"
            ),
            "{e}"
        );
        std::fs::remove_file(&path).unwrap();
    }

    /// An attachment record whose body is shorter than its own header and
    /// CRC panicked the mcap crate's parser (mcap 0.26, found by the `mcap`
    /// fuzz target). The reader parses only schemas, channels and messages:
    /// such an attachment in a good file is skipped and its scans read; in
    /// the fuzzer's truncated file it is an error naming the file.
    #[test]
    fn an_attachment_shorter_than_its_header_is_skipped_not_a_panic() {
        let path = std::env::temp_dir().join(format!("pcaline-att-{}.mcap", std::process::id()));
        let scans: Vec<Scan> = (0..3)
            .map(|k| Scan::new(-1.0, 0.01, 0.1, 30.0, vec![2.0; 100]).with_stamp(k as f64))
            .collect();
        let mut bytes = Vec::new();
        {
            let mut w = mcap::Writer::new(std::io::Cursor::new(&mut bytes)).unwrap();
            let schema = w.add_schema(ROS2_TYPE, "ros2msg", b"").unwrap();
            let ch = w.add_channel(schema, "/scan", "cdr", &BTreeMap::new()).unwrap();
            for (k, s) in scans.iter().enumerate() {
                let header = mcap::records::MessageHeader {
                    channel_id: ch,
                    sequence: k as u32,
                    log_time: k as u64,
                    publish_time: k as u64,
                };
                w.write_to_known_channel(&header, &encode_laserscan_cdr(s, "laser")).unwrap();
            }
            w.finish().unwrap();
        }
        // After the magic (8 bytes) and the header record (opcode, u64
        // length, body): an attachment of two times, two empty strings and
        // a zero data length (32 bytes), with no room for its CRC.
        let header_len = u64::from_le_bytes(bytes[9..17].try_into().unwrap()) as usize;
        let at = 8 + 9 + header_len;
        let mut attachment = vec![mcap::records::op::ATTACHMENT];
        attachment.extend_from_slice(&32u64.to_le_bytes());
        attachment.extend_from_slice(&[0u8; 32]);
        bytes.splice(at..at, attachment);
        std::fs::write(&path, &bytes).unwrap();
        let mut got = Vec::new();
        read_mcap(&path, Some("/scan"), Echo::First, &mut |r| {
            if let LogRecord::Scan(s) = r {
                got.push(s.scan);
            }
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(got, scans);

        // The fuzzer's input: the magic, then such an attachment, then the
        // end of the file.
        let fuzzed: [u8; 58] = [
            137, 77, 67, 65, 80, 48, 13, 10, 9, 41, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0,
            0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 8, 0, 0, 0, 109, 99, 97, 112, 45, 112, 121, 116, 104,
            111, 110, 47, 49, 46, 0, 0, 0,
        ];
        std::fs::write(&path, fuzzed).unwrap();
        let e = read_mcap(&path, None, Echo::First, &mut |_| ControlFlow::Continue(()))
            .unwrap_err()
            .to_string();
        assert!(e.contains(&path.display().to_string()), "{e}");
        std::fs::remove_file(&path).unwrap();
    }

    /// A LaserScan in ROS 1's serialization (packed, little-endian).
    fn laserscan_ros1(scan: &Scan, frame_id: &str) -> Vec<u8> {
        let mut out = Vec::new();
        let stamp = scan.stamp_s.unwrap_or(0.0);
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&(stamp.floor() as u32).to_le_bytes());
        out.extend_from_slice(&((stamp.fract() * 1e9).round() as u32).to_le_bytes());
        out.extend_from_slice(&(frame_id.len() as u32).to_le_bytes());
        out.extend_from_slice(frame_id.as_bytes());
        let last = scan.angle_min + scan.angle_increment * (scan.len() - 1) as f32;
        for v in [scan.angle_min, last, scan.angle_increment, 0.0, 0.0] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for v in [scan.range_min, scan.range_max] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&(scan.len() as u32).to_le_bytes());
        for r in &scan.ranges {
            out.extend_from_slice(&r.to_le_bytes());
        }
        out.extend_from_slice(&0u32.to_le_bytes());
        out
    }

    /// MCAP files converted from ROS 1 bags keep ROS 1's serialization
    /// (channels of encoding `ros1`, schemas named as in ROS 1): they read
    /// as the same scans, and give the scans' frame.
    #[test]
    fn mcap_of_ros1_messages_reads_as_cdr() {
        let path = std::env::temp_dir().join(format!("pcaline-ros1-{}.mcap", std::process::id()));
        let scans: Vec<Scan> = (0..3)
            .map(|k| {
                let ranges = (0..50).map(|i| 1.0 + 0.01 * (i + k) as f32).collect();
                Scan::new(-1.0, 0.02, 0.1, 30.0, ranges).with_stamp(10.0 + 0.25 * k as f64)
            })
            .collect();
        {
            let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
            let mut w = mcap::Writer::new(file).unwrap();
            let ros1 = w.add_schema(ROS1_TYPE, "ros1msg", b"").unwrap();
            let ch = w.add_channel(ros1, "/scan", "ros1", &BTreeMap::new()).unwrap();
            // A CDR channel of the ROS 1 name is not a LaserScan channel.
            let odd = w.add_schema(ROS1_TYPE, "ros2msg", b"").unwrap();
            let wrong = w.add_channel(odd, "/cdr_named_as_ros1", "cdr", &BTreeMap::new()).unwrap();
            for (k, scan) in scans.iter().enumerate() {
                for (channel_id, data) in [
                    (ch, laserscan_ros1(scan, "/laser")),
                    (wrong, encode_laserscan_cdr(scan, "laser")),
                ] {
                    let header = mcap::records::MessageHeader {
                        channel_id,
                        sequence: k as u32,
                        log_time: k as u64,
                        publish_time: k as u64,
                    };
                    w.write_to_known_channel(&header, &data).unwrap();
                }
            }
            w.finish().unwrap();
        }
        let mut got = Vec::new();
        let n = read_mcap(&path, None, Echo::First, &mut |r| {
            if let LogRecord::Scan(s) = r {
                got.push(s.scan);
            }
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(n, 3);
        for (a, b) in got.iter().zip(&scans) {
            assert_eq!(
                (a.angle_min, a.angle_increment, &a.ranges),
                (b.angle_min, b.angle_increment, &b.ranges)
            );
            assert!((a.stamp_s.unwrap() - b.stamp_s.unwrap()).abs() < 1e-6);
        }
        let motion = read_ros_motion(&path, LogFormat::Mcap, None).unwrap();
        assert_eq!(motion.scan_frame.as_deref(), Some("laser"));
        std::fs::remove_file(&path).unwrap();
    }

    /// MultiEchoLaserScans (a UTM-30LX-EW's `echoes`) in a ROS 2 bag and
    /// in MCAP: read as the scans of each beam's first echo, with their
    /// frame and topic, and a topic asked for is looked for among both
    /// scan types.
    #[test]
    fn multiecho_scans_are_read_as_their_first_echoes() {
        let dir = std::env::temp_dir().join(format!("pcaline-echoes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let echoes = |k: usize| -> Vec<Vec<f32>> {
            (0..50).map(|i| if i == 7 { vec![] } else { vec![2.0 + k as f32, 9.0] }).collect()
        };
        let data = |k: usize| {
            crate::encode_multiecho_cdr(
                -1.0,
                0.01,
                0.1,
                30.0,
                k as f64 * 0.025,
                &echoes(k),
                &[],
                "laser",
            )
        };
        let mcap_path = dir.join("echoes.mcap");
        {
            let file = std::io::BufWriter::new(std::fs::File::create(&mcap_path).unwrap());
            let mut w = mcap::Writer::new(file).unwrap();
            let schema = w.add_schema(ROS2_MULTIECHO, "ros2msg", b"").unwrap();
            let ch = w.add_channel(schema, "/echoes", "cdr", &BTreeMap::new()).unwrap();
            for k in 0..3 {
                let header = mcap::records::MessageHeader {
                    channel_id: ch,
                    sequence: k as u32,
                    log_time: k as u64,
                    publish_time: k as u64,
                };
                w.write_to_known_channel(&header, &data(k)).unwrap();
            }
            w.finish().unwrap();
        }
        let db_path = dir.join("echoes.db3");
        let messages: Vec<(&str, Vec<u8>)> = (0..3).map(|k| ("/echoes", data(k))).collect();
        write_ros2_bag(&db_path, &[("/echoes", ROS2_MULTIECHO)], &messages);
        for (path, format) in [(&mcap_path, LogFormat::Mcap), (&db_path, LogFormat::Ros2Bag)] {
            let options = crate::LogOptions { format: Some(format), ..Default::default() };
            let mut got = Vec::new();
            crate::read_log(path, &options, |r| {
                if let LogRecord::Scan(s) = r {
                    got.push(s.scan);
                }
                ControlFlow::Continue(())
            })
            .unwrap();
            assert_eq!(got.len(), 3, "{format:?}");
            for (k, scan) in got.iter().enumerate() {
                assert_eq!(scan.ranges[0], 2.0 + k as f32, "{format:?}");
                assert!(scan.ranges[7].is_nan(), "{format:?}: a beam without echo");
            }
            // `--echo last`: each beam's farthest return.
            let last = crate::LogOptions { echo: Echo::Last, ..options.clone() };
            let mut ranges = Vec::new();
            crate::read_log(path, &last, |r| {
                if let LogRecord::Scan(s) = r {
                    ranges.push((s.scan.ranges[0], s.scan.ranges[7]));
                }
                ControlFlow::Continue(())
            })
            .unwrap();
            assert!(ranges.iter().all(|(r, none)| *r == 9.0 && none.is_nan()), "{ranges:?}");
            let motion = read_ros_motion(path, format, None).unwrap();
            assert_eq!(motion.scan_frame.as_deref(), Some("laser"));
            assert_eq!(motion.scan_topics.iter().collect::<Vec<_>>(), ["/echoes"]);
            let topic = crate::LogOptions { topic: Some("/echoes".into()), ..options.clone() };
            assert!(crate::read_log(path, &topic, |_| ControlFlow::Continue(())).is_ok());
            let wrong = crate::LogOptions { topic: Some("/scan".into()), ..options };
            let e = crate::read_log(path, &wrong, |_| ControlFlow::Continue(())).unwrap_err();
            assert!(e.to_string().contains("topics: /echoes"), "{e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A corrupt bag whose `messages` table gives its ids out of order
    /// (rowids 1, 6, 2 in one leaf page, as a fuzzer made one) is an error
    /// naming the ids, not an endless paging loop: the page after id 2
    /// would hold ids 6 and 2 again. Run on a thread, so that a regression
    /// fails instead of hanging the suite.
    #[test]
    fn a_messages_table_whose_ids_go_backwards_is_an_error_not_a_hang() {
        let dir = std::env::temp_dir().join(format!("pcaline-rowids-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("corrupt.db3");
        let scan = Scan::new(-1.0, 0.01, 0.1, 30.0, vec![2.0; 40]);
        let data = encode_laserscan_cdr(&scan, "laser");
        let messages: Vec<(&str, Vec<u8>)> = (0..3).map(|_| ("/scan", data.clone())).collect();
        write_ros2_bag(&path, &[("/scan", ROS2_TYPE)], &messages);
        // The table's leaf page: an 8-byte header, then one 2-byte cell
        // pointer per row; a cell starts with its payload size and its
        // rowid, one byte each for these small rows... unless the payload
        // is 128 bytes or more (two bytes). Rowids 1, 2, 3 become 1, 6, 2.
        let (page_size, root): (usize, usize) = {
            let db = rusqlite::Connection::open(&path).unwrap();
            let size: i64 = db.query_row("PRAGMA page_size", [], |r| r.get(0)).unwrap();
            let root: i64 = db
                .query_row("SELECT rootpage FROM sqlite_master WHERE name = 'messages'", [], |r| {
                    r.get(0)
                })
                .unwrap();
            (size as usize, root as usize)
        };
        let mut bytes = std::fs::read(&path).unwrap();
        let page = (root - 1) * page_size;
        assert_eq!(bytes[page], 0x0d, "a table leaf page");
        let cells = u16::from_be_bytes([bytes[page + 3], bytes[page + 4]]) as usize;
        assert_eq!(cells, 3);
        for (k, rowid) in [(1usize, 6u8), (2, 2)] {
            let at = page
                + u16::from_be_bytes([bytes[page + 8 + 2 * k], bytes[page + 9 + 2 * k]]) as usize;
            // Skip the payload-size varint.
            let mut i = at;
            while bytes[i] & 0x80 != 0 {
                i += 1;
            }
            assert_eq!(bytes[i + 1], k as u8 + 1, "rowid of cell {k}");
            bytes[i + 1] = rowid;
        }
        std::fs::write(&path, &bytes).unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let reader = path.clone();
        std::thread::spawn(move || {
            let mut n = 0;
            let r = read_ros2_bag(&reader, None, Echo::First, &mut |_| {
                n += 1;
                ControlFlow::Continue(())
            });
            let _ = tx.send(r.map(|_| n));
        });
        let result = rx.recv_timeout(std::time::Duration::from_secs(30)).expect("the read ends");
        let e = result.unwrap_err().to_string();
        assert!(e.contains("corrupt.db3") && e.contains("id 2 comes after id 6"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A ROS 2 bag as rosbag2 compresses it with zstd, each message or the
    /// whole file (`.db3.zstd`, alone or in a bag folder): the same scans
    /// as uncompressed, the temporary decompressed copy removed after the
    /// read, and a corrupt compressed message an error naming its id.
    #[test]
    fn zstd_compressed_ros2_bags_read_as_uncompressed() {
        let dir = std::env::temp_dir().join(format!("pcaline-zstd-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scans: Vec<Scan> = (0..3)
            .map(|k| {
                Scan::new(-1.0, 0.01, 0.1, 30.0, vec![1.0 + k as f32; 40]).with_stamp(k as f64)
            })
            .collect();
        let write_db = |path: &Path, compress: bool| {
            let messages: Vec<(&str, Vec<u8>)> = scans
                .iter()
                .map(|scan| {
                    let data = encode_laserscan_cdr(scan, "laser");
                    if !compress {
                        return ("/scan", data);
                    }
                    let data = zstd::stream::encode_all(&data[..], 3).unwrap();
                    assert!(data.starts_with(&ZSTD_MAGIC));
                    ("/scan", data)
                })
                .collect();
            write_ros2_bag(path, &[("/scan", ROS2_TYPE)], &messages);
        };
        let read = |path: &Path| -> Result<Vec<Vec<f32>>, IoError> {
            let mut got = Vec::new();
            read_ros2_bag(path, None, Echo::First, &mut |r| {
                if let LogRecord::Scan(s) = r {
                    got.push(s.scan.ranges);
                }
                ControlFlow::Continue(())
            })?;
            Ok(got)
        };
        let want: Vec<Vec<f32>> = scans.iter().map(|s| s.ranges.clone()).collect();
        let per_message = dir.join("per_message.db3");
        write_db(&per_message, true);
        assert_eq!(read(&per_message).unwrap(), want);
        let plain = dir.join("plain.db3");
        write_db(&plain, false);
        let folder = dir.join("bag");
        std::fs::create_dir_all(&folder).unwrap();
        let whole = folder.join("bag_0.db3.zstd");
        let bytes = zstd::stream::encode_all(&std::fs::read(&plain).unwrap()[..], 3).unwrap();
        std::fs::write(&whole, bytes).unwrap();
        assert_eq!(LogFormat::detect(&whole).unwrap(), LogFormat::Ros2Bag);
        assert_eq!(LogFormat::detect(&folder).unwrap(), LogFormat::Ros2Bag);
        assert_eq!(read(&whole).unwrap(), want);
        assert_eq!(read(&folder).unwrap(), want);
        let leftovers = || {
            std::fs::read_dir(std::env::temp_dir())
                .unwrap()
                .filter_map(|e| e.ok())
                .filter(|e| e.file_name().to_string_lossy().ends_with("-bag_0.db3"))
                .count()
        };
        assert_eq!(leftovers(), 0, "the decompressed copy stays behind");
        // Held, the copy is made once for every pass, and removed after.
        let copies = || DECOMPRESSIONS.load(std::sync::atomic::Ordering::Relaxed);
        let kept = keep_decompressed(&folder).unwrap();
        let made = copies();
        assert_eq!(read(&folder).unwrap(), want);
        assert_eq!(read(&whole).unwrap(), want);
        assert_eq!((copies(), leftovers()), (made, 1));
        drop(kept);
        assert_eq!(leftovers(), 0, "the kept copy stays behind");
        assert!(keep_decompressed(&plain).is_ok(), "nothing to keep");
        // A compressed message cut short: an error naming it.
        let db = rusqlite::Connection::open(&per_message).unwrap();
        db.execute("UPDATE messages SET data = substr(data, 1, 12) WHERE id = 2", []).unwrap();
        drop(db);
        let e = read(&per_message).unwrap_err().to_string();
        assert!(e.contains("message id 2") && e.contains("zstd"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
