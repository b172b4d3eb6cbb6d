//! [`FoxgloveMcapWriter`]: scans, detected lines, the line map and poses,
//! scan by scan, as one MCAP file that Foxglove opens directly.
//!
//! Messages are JSON with the Foxglove schemas in `schemas/foxglove/`
//! (encoding `jsonschema`; Foxglove picks its renderer by the schema name),
//! in zstd-compressed chunks. The file is streamed: each message is written
//! as it comes and nothing grows with the log but the chunk index (one entry
//! per ~1 MiB chunk), so a log of millions of scans is written in constant
//! memory. It is an [`AtomicFile`]: nothing is at the target until
//! [`FoxgloveMcapWriter::finish`] succeeds.
//!
//! Topics ([`Topic`]) and frames:
//!
//! | topic | schema | frame |
//! |---|---|---|
//! | `/scan` | `foxglove.LaserScan` | `sensor` |
//! | `/lines` | `foxglove.SceneUpdate` | `sensor` |
//! | `/map` | `foxglove.SceneUpdate` | `world` |
//! | `/tf` | `foxglove.FrameTransform` | `world` to `sensor`, `source`, `truth` |
//! | `/pose/source`, `/pose/corrected`, `/truth/pose` | `foxglove.PoseInFrame` | `world` |
//! | `/truth/walls` | `foxglove.SceneUpdate` | `world` |
//!
//! The `sensor` frame follows the corrected pose ([`PoseKind::Corrected`]),
//! or the log's own pose where nothing corrects it (`pcaline detect`).

use crate::{AtomicFile, IoError};
use pcaline_geometry::{LineSegment, Pose2, Scan};
use pcaline_mapping::{LineMap, LineStatus};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The fixed frame of maps, trajectories and true walls.
pub const FRAME_WORLD: &str = "world";
/// The sensor's frame at its corrected pose: scans and detected lines.
pub const FRAME_SENSOR: &str = "sensor";

/// The Foxglove schemas, as written in each file's schema records.
const SCHEMAS: [(&str, &str); 4] = [
    ("foxglove.LaserScan", include_str!("../schemas/foxglove/LaserScan.json")),
    ("foxglove.SceneUpdate", include_str!("../schemas/foxglove/SceneUpdate.json")),
    ("foxglove.FrameTransform", include_str!("../schemas/foxglove/FrameTransform.json")),
    ("foxglove.PoseInFrame", include_str!("../schemas/foxglove/PoseInFrame.json")),
];

/// The JSON Schema of a Foxglove message type written by this module
/// (`"foxglove.LaserScan"`, ...); `None` for any other name.
pub fn foxglove_schema(name: &str) -> Option<&'static str> {
    SCHEMAS.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

/// A channel of the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Topic {
    /// `/scan`: each input scan (`foxglove.LaserScan`).
    Scan,
    /// `/lines`: each scan's detected lines (`foxglove.SceneUpdate`).
    Lines,
    /// `/map`: the line map (`foxglove.SceneUpdate`).
    Map,
    /// `/tf`: the frames `sensor`, `source` and `truth` in `world`
    /// (`foxglove.FrameTransform`).
    Transforms,
    /// `/pose/source`: the localization source's pose (`foxglove.PoseInFrame`).
    SourcePose,
    /// `/pose/corrected`: the corrected pose (`foxglove.PoseInFrame`).
    CorrectedPose,
    /// `/truth/pose`: the true pose of a simulated run (`foxglove.PoseInFrame`).
    TruePose,
    /// `/truth/walls`: the walls of a simulated scene (`foxglove.SceneUpdate`).
    TrueWalls,
}

impl Topic {
    /// Every topic, in channel order.
    pub const ALL: [Topic; 8] = [
        Topic::Scan,
        Topic::Lines,
        Topic::Map,
        Topic::Transforms,
        Topic::SourcePose,
        Topic::CorrectedPose,
        Topic::TruePose,
        Topic::TrueWalls,
    ];

    /// The topic's name.
    pub fn name(self) -> &'static str {
        match self {
            Topic::Scan => "/scan",
            Topic::Lines => "/lines",
            Topic::Map => "/map",
            Topic::Transforms => "/tf",
            Topic::SourcePose => "/pose/source",
            Topic::CorrectedPose => "/pose/corrected",
            Topic::TruePose => "/truth/pose",
            Topic::TrueWalls => "/truth/walls",
        }
    }

    /// The Foxglove schema name of the topic's messages.
    pub fn schema(self) -> &'static str {
        match self {
            Topic::Scan => "foxglove.LaserScan",
            Topic::Lines | Topic::Map | Topic::TrueWalls => "foxglove.SceneUpdate",
            Topic::Transforms => "foxglove.FrameTransform",
            Topic::SourcePose | Topic::CorrectedPose | Topic::TruePose => "foxglove.PoseInFrame",
        }
    }

    fn index(self) -> usize {
        Topic::ALL.iter().position(|t| *t == self).unwrap_or(0)
    }
}

/// Which pose: each has its topic and its frame in `/tf`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum PoseKind {
    /// The localization source (odometry, or the log's own pose): frame
    /// `source`, topic `/pose/source`.
    Source,
    /// The corrected pose: frame `sensor` (scans and lines follow it), topic
    /// `/pose/corrected`.
    Corrected,
    /// The true pose of a simulated run: frame `truth`, topic `/truth/pose`.
    Truth,
    /// The log's own pose where nothing corrects it (`pcaline detect`):
    /// frame `sensor`, topic `/pose/source`.
    SensorFromLog,
}

impl PoseKind {
    fn frame(self) -> &'static str {
        match self {
            PoseKind::Source => "source",
            PoseKind::Corrected | PoseKind::SensorFromLog => FRAME_SENSOR,
            PoseKind::Truth => "truth",
        }
    }

    fn topic(self) -> Topic {
        match self {
            PoseKind::Source | PoseKind::SensorFromLog => Topic::SourcePose,
            PoseKind::Corrected => Topic::CorrectedPose,
            PoseKind::Truth => Topic::TruePose,
        }
    }
}

/// A message time: nanoseconds since the epoch of the log's clock.
///
/// Edge cases: [`Stamp::from_seconds`] refuses NaN, infinite and negative
/// times, and times from 2^32 s (the year 2106, Foxglove's `u32` seconds).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub struct Stamp(pub u64);

impl Stamp {
    /// A time in seconds, if it is finite, not negative and fits.
    pub fn from_seconds(t_s: f64) -> Option<Stamp> {
        let ns = (t_s * 1e9).round();
        (ns.is_finite() && ns >= 0.0 && t_s < 4_294_967_296.0).then_some(Stamp(ns as u64))
    }

    fn time(self) -> Time {
        Time { sec: (self.0 / 1_000_000_000) as u32, nsec: (self.0 % 1_000_000_000) as u32 }
    }
}

/// Messages written per topic, from [`FoxgloveMcapWriter::finish`].
pub type TopicCounts = BTreeMap<&'static str, u64>;

/// Streams Foxglove messages into an MCAP file (module docs: topics, frames).
///
/// Each `write_*` call writes its messages at once. Channels are added on
/// first use, so a file holds only the topics that were written.
pub struct FoxgloveMcapWriter {
    path: PathBuf,
    writer: mcap::Writer<AtomicFile>,
    schema_ids: [Option<u16>; 4],
    channel_ids: [Option<u16>; Topic::ALL.len()],
    sequence: u32,
    counts: [u64; Topic::ALL.len()],
    buffer: Vec<u8>,
}

impl std::fmt::Debug for FoxgloveMcapWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FoxgloveMcapWriter").field("path", &self.path).finish_non_exhaustive()
    }
}

/// Map lines are drawn by status: confirmed red, tentative orange, not
/// straight grey.
const MAP_COLOURS: [(LineStatus, &str, Color); 3] = [
    (LineStatus::Confirmed, "confirmed", Color { r: 0.84, g: 0.15, b: 0.16, a: 1.0 }),
    (LineStatus::Tentative, "tentative", Color { r: 1.0, g: 0.6, b: 0.0, a: 0.8 }),
    (LineStatus::NotStraight, "not-straight", Color { r: 0.5, g: 0.5, b: 0.5, a: 0.8 }),
];
const LINE_COLOUR: Color = Color { r: 0.1, g: 0.75, b: 0.2, a: 1.0 };
const WALL_COLOUR: Color = Color { r: 0.7, g: 0.7, b: 0.7, a: 1.0 };

impl FoxgloveMcapWriter {
    /// Starts the file at `path` (written to a temporary file beside it).
    pub fn create(path: &Path) -> Result<Self, IoError> {
        let file = AtomicFile::create(path)?;
        let options = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .chunk_size(Some(1 << 20))
            .profile("")
            .library(concat!("pcaline ", env!("CARGO_PKG_VERSION")));
        let writer = options.create(file).map_err(|e| mcap_error(path, e))?;
        Ok(FoxgloveMcapWriter {
            path: path.to_path_buf(),
            writer,
            schema_ids: [None; 4],
            channel_ids: [None; Topic::ALL.len()],
            sequence: 0,
            counts: [0; Topic::ALL.len()],
            buffer: Vec::with_capacity(1 << 14),
        })
    }

    /// Writes `scan` on `/scan`, in the `sensor` frame. Invalid returns
    /// (NaN, infinite, outside `range_min..range_max`) are written as 0,
    /// which Foxglove draws at the sensor: JSON has no NaN.
    pub fn write_scan(&mut self, stamp: Stamp, scan: &Scan) -> Result<(), IoError> {
        let n = scan.ranges.len();
        let last = scan.angle_min as f64 + scan.angle_increment as f64 * n.saturating_sub(1) as f64;
        let message = LaserScan {
            timestamp: stamp.time(),
            frame_id: FRAME_SENSOR,
            pose: FoxPose::identity(),
            start_angle: scan.angle_min as f64,
            end_angle: last,
            ranges: RangeList { ranges: &scan.ranges, min: scan.range_min, max: scan.range_max },
            intensities: FiniteList(scan.intensities.as_deref().unwrap_or(&[])),
        };
        self.write(Topic::Scan, stamp, &message)
    }

    /// Writes one scan's detected lines on `/lines`, in the `sensor` frame:
    /// the previous scan's lines are deleted, then one entity per line, its
    /// metadata the line's index in the scan (`id`), `n_points` and
    /// `residual_std_m`. Lines with a non-finite endpoint are skipped.
    pub fn write_lines<'a>(
        &mut self,
        stamp: Stamp,
        lines: impl IntoIterator<Item = &'a LineSegment>,
    ) -> Result<(), IoError> {
        let entities = lines
            .into_iter()
            .enumerate()
            .filter(|(_, l)| finite_segment(l))
            .map(|(k, l)| {
                let ends = [[l.start().x, l.start().y], [l.end().x, l.end().y]];
                let mut e = Entity::lines(
                    stamp,
                    FRAME_SENSOR,
                    format!("line-{k}"),
                    &ends,
                    0.04,
                    LINE_COLOUR,
                );
                // Drawn with the sensor as it moves, until the next scan's lines.
                e.frame_locked = true;
                e.metadata = vec![
                    KeyValue::new("id", k.to_string()),
                    KeyValue::new("n_points", l.n_points().to_string()),
                    KeyValue::new("residual_std_m", format!("{:.4}", l.residual_std())),
                ];
                e
            })
            .collect();
        self.write_scene(Topic::Lines, stamp, entities)
    }

    /// Writes the whole line map on `/map`, in the `world` frame, replacing
    /// the last: one entity per status (`confirmed`, `tentative`,
    /// `not-straight`), each a line list coloured apart, its metadata the
    /// line count. Lines with a non-finite endpoint are skipped.
    pub fn write_map(&mut self, stamp: Stamp, map: &LineMap) -> Result<(), IoError> {
        let mut entities = Vec::with_capacity(MAP_COLOURS.len());
        for (status, name, colour) in MAP_COLOURS {
            let ends: Vec<[f64; 2]> = map
                .lines()
                .iter()
                .filter(|m| m.status == status && finite_segment(&m.line))
                .flat_map(|m| {
                    [[m.line.start().x, m.line.start().y], [m.line.end().x, m.line.end().y]]
                })
                .collect();
            let mut e =
                Entity::lines(stamp, FRAME_WORLD, format!("map-{name}"), &ends, 0.05, colour);
            e.metadata = vec![
                KeyValue::new("status", name.to_string()),
                KeyValue::new("lines", (ends.len() / 2).to_string()),
            ];
            entities.push(e);
        }
        self.write_scene(Topic::Map, stamp, entities)
    }

    /// Writes the true walls of a simulated scene on `/truth/walls`, in the
    /// `world` frame, as one line list.
    pub fn write_walls(&mut self, stamp: Stamp, walls: &[[[f64; 2]; 2]]) -> Result<(), IoError> {
        let ends: Vec<[f64; 2]> = walls
            .iter()
            .filter(|w| w.iter().flatten().all(|v| v.is_finite()))
            .flat_map(|w| [w[0], w[1]])
            .collect();
        let mut entity =
            Entity::lines(stamp, FRAME_WORLD, "walls".into(), &ends, 0.08, WALL_COLOUR);
        entity.metadata = vec![KeyValue::new("walls", (ends.len() / 2).to_string())];
        self.write_scene(Topic::TrueWalls, stamp, vec![entity])
    }

    /// Writes `pose` (`world_from_sensor`) as a transform on `/tf` (frame
    /// `sensor`, `source` or `truth` in `world`) and as a pose on its topic.
    /// A non-finite pose is not written.
    pub fn write_pose(
        &mut self,
        stamp: Stamp,
        kind: PoseKind,
        pose: &Pose2,
    ) -> Result<(), IoError> {
        if !(pose.x().is_finite() && pose.y().is_finite() && pose.heading().is_finite()) {
            return Ok(());
        }
        let p = FoxPose::of(pose);
        let transform = FrameTransform {
            timestamp: stamp.time(),
            parent_frame_id: FRAME_WORLD,
            child_frame_id: kind.frame(),
            translation: p.position,
            rotation: p.orientation,
        };
        self.write(Topic::Transforms, stamp, &transform)?;
        let in_frame = PoseInFrame { timestamp: stamp.time(), frame_id: FRAME_WORLD, pose: p };
        self.write(kind.topic(), stamp, &in_frame)
    }

    /// Ends the file: writes the summary, syncs and renames it over the
    /// target. Returns the messages written per topic name.
    pub fn finish(mut self) -> Result<TopicCounts, IoError> {
        let path = self.path.clone();
        self.writer.finish().map_err(|e| mcap_error(&path, e))?;
        let counts = Topic::ALL
            .iter()
            .zip(self.counts)
            .filter(|(_, n)| *n > 0)
            .map(|(t, n)| (t.name(), n))
            .collect();
        self.writer.into_inner().commit()?;
        Ok(counts)
    }

    fn write_scene(
        &mut self,
        topic: Topic,
        stamp: Stamp,
        entities: Vec<Entity>,
    ) -> Result<(), IoError> {
        let update = SceneUpdate {
            deletions: vec![Deletion { timestamp: stamp.time(), kind: 1, id: String::new() }],
            entities,
        };
        self.write(topic, stamp, &update)
    }

    fn channel(&mut self, topic: Topic) -> Result<u16, IoError> {
        if let Some(id) = self.channel_ids[topic.index()] {
            return Ok(id);
        }
        let k = SCHEMAS.iter().position(|(n, _)| *n == topic.schema()).unwrap_or(0);
        let schema = match self.schema_ids[k] {
            Some(id) => id,
            None => {
                let (name, text) = SCHEMAS[k];
                let id = self
                    .writer
                    .add_schema(name, "jsonschema", text.as_bytes())
                    .map_err(|e| mcap_error(&self.path, e))?;
                self.schema_ids[k] = Some(id);
                id
            }
        };
        let id = self
            .writer
            .add_channel(schema, topic.name(), "json", &BTreeMap::new())
            .map_err(|e| mcap_error(&self.path, e))?;
        self.channel_ids[topic.index()] = Some(id);
        Ok(id)
    }

    fn write<T: Serialize>(
        &mut self,
        topic: Topic,
        stamp: Stamp,
        message: &T,
    ) -> Result<(), IoError> {
        let channel_id = self.channel(topic)?;
        self.buffer.clear();
        serde_json::to_writer(&mut self.buffer, message)
            .map_err(|e| IoError::parse(&self.path, None, format!("cannot encode: {e}")))?;
        self.sequence = self.sequence.wrapping_add(1);
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time: stamp.0,
            publish_time: stamp.0,
        };
        self.writer
            .write_to_known_channel(&header, &self.buffer)
            .map_err(|e| mcap_error(&self.path, e))?;
        self.counts[topic.index()] += 1;
        Ok(())
    }
}

fn mcap_error(path: &Path, e: mcap::McapError) -> IoError {
    match e {
        mcap::McapError::Io(io) => IoError::io(path, io),
        other => IoError::parse(path, None, format!("writing MCAP: {other}")),
    }
}

fn finite_segment(l: &LineSegment) -> bool {
    [l.start().x, l.start().y, l.end().x, l.end().y].iter().all(|v| v.is_finite())
}

// The Foxglove messages, as serde writes them (field names are Foxglove's).

#[derive(Debug, Clone, Copy, Serialize, Default)]
struct Time {
    sec: u32,
    nsec: u32,
}

impl Time {
    const ZERO: Time = Time { sec: 0, nsec: 0 };
}

#[derive(Debug, Clone, Copy, Serialize)]
struct Vector3 {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Debug, Clone, Copy, Serialize)]
struct Quaternion {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

#[derive(Debug, Clone, Copy, Serialize)]
struct FoxPose {
    position: Vector3,
    orientation: Quaternion,
}

impl FoxPose {
    fn identity() -> Self {
        FoxPose {
            position: Vector3 { x: 0.0, y: 0.0, z: 0.0 },
            orientation: Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 1.0 },
        }
    }

    /// A planar pose: a rotation about z by the heading.
    fn of(p: &Pose2) -> Self {
        let half = 0.5 * p.heading();
        FoxPose {
            position: Vector3 { x: p.x(), y: p.y(), z: 0.0 },
            orientation: Quaternion { x: 0.0, y: 0.0, z: half.sin(), w: half.cos() },
        }
    }
}

#[derive(Debug, Clone, Copy, Serialize)]
struct Color {
    r: f64,
    g: f64,
    b: f64,
    a: f64,
}

#[derive(Debug, Clone, Copy, Serialize)]
struct Point3 {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Debug, Serialize)]
struct KeyValue {
    key: &'static str,
    value: String,
}

impl KeyValue {
    fn new(key: &'static str, value: String) -> Self {
        KeyValue { key, value }
    }
}

#[derive(Debug, Serialize)]
struct LinePrimitive {
    /// 2: LINE_LIST, a segment per pair of points.
    #[serde(rename = "type")]
    kind: u8,
    pose: FoxPose,
    thickness: f64,
    scale_invariant: bool,
    points: Vec<Point3>,
    color: Color,
    colors: [Color; 0],
    indices: [u32; 0],
}

impl LinePrimitive {
    /// Segments from pairs of points, `thickness_m` wide in the world.
    fn list(ends: &[[f64; 2]], thickness_m: f64, color: Color) -> Self {
        LinePrimitive {
            kind: 2,
            pose: FoxPose::identity(),
            thickness: thickness_m,
            scale_invariant: false,
            points: ends.iter().map(|p| Point3 { x: p[0], y: p[1], z: 0.0 }).collect(),
            color,
            colors: [],
            indices: [],
        }
    }
}

#[derive(Debug, Serialize, Default)]
struct Entity {
    timestamp: Time,
    frame_id: &'static str,
    id: String,
    lifetime: Time,
    frame_locked: bool,
    metadata: Vec<KeyValue>,
    arrows: [(); 0],
    cubes: [(); 0],
    spheres: [(); 0],
    cylinders: [(); 0],
    lines: Vec<LinePrimitive>,
    triangles: [(); 0],
    texts: [(); 0],
    models: [(); 0],
}

impl Entity {
    /// An entity of one line list (segments from pairs of `ends`) in
    /// `frame`, kept until replaced or deleted, placed in the fixed frame;
    /// no metadata.
    fn lines(
        stamp: Stamp,
        frame: &'static str,
        id: String,
        ends: &[[f64; 2]],
        thickness_m: f64,
        color: Color,
    ) -> Self {
        Entity {
            timestamp: stamp.time(),
            frame_id: frame,
            id,
            lifetime: Time::ZERO,
            frame_locked: false,
            lines: vec![LinePrimitive::list(ends, thickness_m, color)],
            ..Entity::default()
        }
    }
}

#[derive(Debug, Serialize)]
struct Deletion {
    timestamp: Time,
    /// 1: ALL, every entity of the topic.
    #[serde(rename = "type")]
    kind: u8,
    id: String,
}

#[derive(Debug, Serialize)]
struct SceneUpdate {
    deletions: Vec<Deletion>,
    entities: Vec<Entity>,
}

#[derive(Serialize)]
struct LaserScan<'a> {
    timestamp: Time,
    frame_id: &'static str,
    pose: FoxPose,
    start_angle: f64,
    end_angle: f64,
    ranges: RangeList<'a>,
    intensities: FiniteList<'a>,
}

/// Ranges with the invalid ones (non-finite, outside `min..=max`) written
/// as 0, without a copy.
struct RangeList<'a> {
    ranges: &'a [f32],
    min: f32,
    max: f32,
}

impl Serialize for RangeList<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let valid = |r: f32| r.is_finite() && r >= self.min && r <= self.max;
        s.collect_seq(self.ranges.iter().map(|&r| if valid(r) { r } else { 0.0 }))
    }
}

/// Values with the non-finite ones written as 0, without a copy.
struct FiniteList<'a>(&'a [f32]);

impl Serialize for FiniteList<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.0.iter().map(|&v| if v.is_finite() { v } else { 0.0 }))
    }
}

#[derive(Debug, Serialize)]
struct FrameTransform {
    timestamp: Time,
    parent_frame_id: &'static str,
    child_frame_id: &'static str,
    translation: Vector3,
    rotation: Quaternion,
}

#[derive(Debug, Serialize)]
struct PoseInFrame {
    timestamp: Time,
    frame_id: &'static str,
    pose: FoxPose,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_refuse_what_does_not_fit() {
        assert_eq!(Stamp::from_seconds(1.5), Some(Stamp(1_500_000_000)));
        assert_eq!(Stamp::from_seconds(0.0), Some(Stamp(0)));
        for bad in [f64::NAN, f64::INFINITY, -1.0, 4_294_967_296.0] {
            assert_eq!(Stamp::from_seconds(bad), None, "{bad}");
        }
        let t = Stamp(3_000_000_007).time();
        assert_eq!((t.sec, t.nsec), (3, 7));
    }

    #[test]
    fn every_topic_has_a_schema() {
        for t in Topic::ALL {
            let text = foxglove_schema(t.schema()).unwrap();
            let v: serde_json::Value = serde_json::from_str(text).unwrap();
            assert_eq!(v["title"], t.schema(), "{}", t.name());
        }
        assert_eq!(foxglove_schema("foxglove.Log"), None);
    }

    #[test]
    fn a_heading_is_a_rotation_about_z() {
        let p = FoxPose::of(&Pose2::new(1.0, 2.0, std::f64::consts::FRAC_PI_2));
        let q = p.orientation;
        assert!((q.z - (0.5f64).sqrt()).abs() < 1e-12 && (q.w - (0.5f64).sqrt()).abs() < 1e-12);
        assert_eq!((p.position.x, p.position.y, p.position.z), (1.0, 2.0, 0.0));
    }
}
