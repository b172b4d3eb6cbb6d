//! CARMEN logs (`.clf`, `.log`): `FLASER`, `ROBOTLASER1`, `ODOM`, and
//! `RAWLASER1` in a log without the first two ([`RawLaserScans`]); `PARAM`
//! lines are read apart, for the front laser's mount
//! ([`front_laser_params`]); `NEFF`, `SYNC` and other messages are skipped;
//! `#` starts a comment.
//! Streams line by line: a long log is never held in memory.
//!
//! `FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp`:
//! the line does not carry the field of view. 180 beams mean 1° from -90°,
//! 181 beams 1° from -90° to +90°, 361 beams 0.5° from -90°; any other count
//! needs an explicit field of view ([`CarmenOptions::fov_rad`]), spread over
//! the beams symmetric about the x axis. "No return" is written as the
//! sensor's maximum (81.91 in CSAIL, 81.83 in Intel): ranges at or beyond
//! [`CarmenOptions::max_range_m`] become +inf.

use crate::{IoError, LogRecord, OdometryRecord, ScanRecord};
use pcaline_geometry::{Pose2, Scan, SensorProfile};
use std::f64::consts::PI;
use std::fmt::Display;
use std::io::BufRead;
use std::path::{Path, PathBuf};

/// Options of the CARMEN reader.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct CarmenOptions {
    /// Field of view for `FLASER` lines, radians; `None` infers it from the
    /// beam count (180: 180° in 1° steps from -90°; 181: 180° with both ends;
    /// 361: 180° in 0.5° steps).
    pub fov_rad: Option<f64>,
    /// Ranges at or above this are "no return" (+inf), metres.
    pub max_range_m: f64,
    /// Offset added to the log's timestamps, seconds.
    pub time_offset_s: f64,
    /// Whether `RAWLASER1` lines are scans.
    pub raw_laser: RawLaserScans,
}

impl Default for CarmenOptions {
    fn default() -> Self {
        CarmenOptions {
            fov_rad: None,
            max_range_m: 80.0,
            time_offset_s: 0.0,
            raw_laser: RawLaserScans::WhenNoPosedScans,
        }
    }
}

impl CarmenOptions {
    /// The options with [`RawLaserScans::WhenNoPosedScans`] decided for the
    /// log at `path`: [`RawLaserScans::Always`] when it has no posed scan
    /// message ([`has_posed_scans`], which reads up to the first one), else
    /// [`RawLaserScans::Never`]. Decided once, the log's later reads do not
    /// look through it again. Other choices are kept as they are.
    pub fn decided_for(mut self, path: &Path) -> Result<Self, IoError> {
        if self.raw_laser == RawLaserScans::WhenNoPosedScans {
            self.raw_laser =
                if has_posed_scans(path)? { RawLaserScans::Never } else { RawLaserScans::Always };
        }
        Ok(self)
    }
}

/// Whether the `RAWLASER1` lines of a CARMEN log are read as scans.
///
/// CARMEN's logger writes the front laser twice when the robot module runs:
/// as `RAWLASER1` (the driver's message, no pose) and as `FLASER` or
/// `ROBOTLASER1` (the same scan with the robot's pose). A log of a laser
/// alone has only `RAWLASER1`, its motion, if any, in `ODOM` lines. Reading
/// both kinds would give every scan twice, so by default a log's
/// `RAWLASER1` lines are scans only when it has no posed scan message.
/// `RAWLASER2`-`4` (other lasers, such as a rear one) are never read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum RawLaserScans {
    /// `RAWLASER1` lines are scans when the log has no `FLASER` or
    /// `ROBOTLASER1` line. [`CarmenReader::open`] looks through the file
    /// for one ([`has_posed_scans`]), stopping at the first; over a stream
    /// ([`CarmenReader::new`]), which cannot be looked through first, this
    /// is [`RawLaserScans::Never`].
    #[default]
    WhenNoPosedScans,
    /// `RAWLASER1` lines are skipped.
    Never,
    /// `RAWLASER1` lines are scans, beside any `FLASER` or `ROBOTLASER1`.
    Always,
}

/// Whether the CARMEN log at `path` has a posed scan message (a line whose
/// first field is `FLASER` or `ROBOTLASER1`); reads up to the first one.
/// Lines that are not UTF-8 text are passed over here: the reader reports
/// them.
pub fn has_posed_scans(path: &Path) -> Result<bool, IoError> {
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let mut input = std::io::BufReader::with_capacity(1 << 16, file);
    let mut line = Vec::new();
    loop {
        line.clear();
        if input.read_until(b'\n', &mut line).map_err(|e| IoError::io(path, e))? == 0 {
            return Ok(false);
        }
        if matches!(first_field(&line), b"FLASER" | b"ROBOTLASER1") {
            return Ok(true);
        }
    }
}

/// The front laser's mount on the robot that the `PARAM` lines of the CARMEN
/// log at `path` give: `robot_frontlaser_offset` (forward, metres),
/// `robot_frontlaser_side_offset` (left, metres) and
/// `robot_frontlaser_angular_offset` (radians), as CARMEN's robot module
/// and GMapping read them. A parameter written twice takes its last value;
/// one that is absent is 0. `None` when the log sets none of the three.
///
/// `FLASER` and `ROBOTLASER1` lines carry the laser's pose and the robot's,
/// which give the mount scan by scan; this is for logs whose scans carry no
/// pose (`RAWLASER1` with `ODOM` lines). Reads the whole file.
///
/// # Errors
///
/// The file cannot be read, or one of the three has a value that is not a
/// finite number (the error names the line and the parameter).
///
/// ```
/// use pcaline_io::front_laser_params;
/// let path = std::env::temp_dir().join("pcaline-doc-front-laser-params.log");
/// std::fs::write(&path, "PARAM robot_frontlaser_offset 0.25 host 0\nODOM 0 0 0 0 0 0 1 host 1\n").unwrap();
/// let mount = front_laser_params(&path).unwrap().unwrap();
/// assert_eq!((mount.x(), mount.y(), mount.heading()), (0.25, 0.0, 0.0));
/// std::fs::remove_file(&path).unwrap();
/// ```
pub fn front_laser_params(path: &Path) -> Result<Option<Pose2>, IoError> {
    const NAMES: [&str; 3] = [
        "robot_frontlaser_offset",
        "robot_frontlaser_side_offset",
        "robot_frontlaser_angular_offset",
    ];
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let mut input = std::io::BufReader::with_capacity(1 << 16, file);
    let mut line = Vec::new();
    let mut values: [Option<f64>; 3] = [None; 3];
    let mut line_no = 0;
    loop {
        line.clear();
        if input.read_until(b'\n', &mut line).map_err(|e| IoError::io(path, e))? == 0 {
            break;
        }
        line_no += 1;
        if first_field(&line) != b"PARAM" {
            continue;
        }
        // Lines that are not UTF-8 text are the reader's to report.
        let Ok(text) = std::str::from_utf8(&line) else { continue };
        let mut fields = text.split_ascii_whitespace().skip(1);
        let Some(k) = fields.next().and_then(|name| NAMES.iter().position(|n| *n == name)) else {
            continue;
        };
        let value = fields.next().and_then(|v| v.parse::<f64>().ok()).filter(|v| v.is_finite());
        values[k] = Some(value.ok_or_else(|| {
            IoError::parse(path, Some(line_no), format!("PARAM {}: not a finite number", NAMES[k]))
        })?);
    }
    Ok(values.iter().any(Option::is_some).then(|| {
        let [x, y, yaw] = values.map(|v| v.unwrap_or(0.0));
        Pose2::new(x, y, yaw)
    }))
}

/// The first whitespace-separated field of a line (empty for a blank line).
pub(crate) fn first_field(line: &[u8]) -> &[u8] {
    let start = line.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(line.len());
    let rest = &line[start..];
    let end = rest.iter().position(u8::is_ascii_whitespace).unwrap_or(rest.len());
    &rest[..end]
}

/// 10^k for k up to 15: all exact in an `f64`.
const POWERS_OF_TEN: [f64; 16] =
    [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15];

/// A plain decimal of at most 15 digits (`-12.345`, `7`, `.5`), parsed
/// exactly as `str::parse::<f64>` parses it; `None` for anything else
/// (exponents, `inf`, `nan`, more digits, whitespace), which the caller
/// hands to `str::parse`. Most CARMEN fields are such decimals, and this is
/// several times faster.
fn short_decimal(s: &[u8]) -> Option<f64> {
    let (value, end) = leading_decimal(s);
    if end == s.len() { value } else { None }
}

/// The field at the start of `s` (up to ASCII whitespace or the end) read
/// as a plain decimal of at most 15 digits, and where the field ends: one
/// pass finds both. The value is `None` when the field is anything else.
/// Exact (Clinger's fast path): the digits as an integer below 2^53 and a
/// power of ten up to 10^15 are both exact `f64`s, and IEEE division
/// rounds their quotient correctly.
fn leading_decimal(s: &[u8]) -> (Option<f64>, usize) {
    let negative = s.first() == Some(&b'-');
    let mut i = usize::from(negative || s.first() == Some(&b'+'));
    let (mut mantissa, mut digits, mut decimals) = (0u64, 0usize, 0usize);
    let (mut point, mut plain) = (false, true);
    while i < s.len() {
        match s[i] {
            c @ b'0'..=b'9' => {
                // Wraps only past 19 digits, which are not plain anyway.
                mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(c - b'0'));
                digits += 1;
                decimals += usize::from(point);
            }
            b'.' if !point => point = true,
            c if c.is_ascii_whitespace() => break,
            _ => plain = false,
        }
        i += 1;
    }
    if !(plain && (1..=15).contains(&digits)) {
        return (None, i);
    }
    let v = mantissa as f64 / POWERS_OF_TEN[decimals];
    (Some(if negative { -v } else { v }), i)
}

/// The whitespace-separated fields of a line, taken left to right without
/// collecting them: the fast path of `FLASER` lines. Whitespace is what
/// `str::split_ascii_whitespace` splits at, so the fields are the same.
struct Fields<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Fields<'a> {
    /// The next field, or `None` at the end of the line.
    fn next_field(&mut self) -> Option<&'a [u8]> {
        let b = self.bytes;
        let mut i = self.at;
        while i < b.len() && b[i].is_ascii_whitespace() {
            i += 1;
        }
        let start = i;
        while i < b.len() && !b[i].is_ascii_whitespace() {
            i += 1;
        }
        self.at = i;
        (i > start).then(|| &b[start..i])
    }

    /// The next field as a number, read as [`CarmenReader::num`] reads it;
    /// `None` at the end of the line or when it is not a number. A plain
    /// decimal is read in the same pass that finds the field's end
    /// ([`leading_decimal`]; this runs for every range of a log); anything
    /// else goes to `str::parse`.
    fn number(&mut self) -> Option<f64> {
        let b = self.bytes;
        let mut start = self.at;
        while start < b.len() && b[start].is_ascii_whitespace() {
            start += 1;
        }
        let (value, length) = leading_decimal(&b[start..]);
        self.at = start + length;
        if length == 0 {
            return None;
        }
        value.or_else(|| std::str::from_utf8(&b[start..self.at]).ok()?.parse().ok())
    }
}

/// The name of a pose's field in errors: `x`, or `odom_x` under `odom`.
struct PoseField<'a> {
    what: &'a str,
    axis: &'static str,
}

impl Display for PoseField<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.what.is_empty() {
            f.write_str(self.axis)
        } else {
            write!(f, "{}_{}", self.what, self.axis)
        }
    }
}

/// A streaming reader of a CARMEN log.
pub struct CarmenReader<R> {
    input: R,
    path: PathBuf,
    options: CarmenOptions,
    line_no: usize,
    buf: String,
}

impl CarmenReader<std::io::BufReader<std::fs::File>> {
    /// Opens a CARMEN log file. With [`RawLaserScans::WhenNoPosedScans`]
    /// the file is first looked through for a posed scan message.
    pub fn open(path: &Path, options: CarmenOptions) -> Result<Self, IoError> {
        let options = resolve_raw_laser(path, options)?;
        let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
        Ok(Self::new(std::io::BufReader::new(file), path, options))
    }
}

/// `options` with [`RawLaserScans::WhenNoPosedScans`] decided for the log
/// at `path` ([`CarmenOptions::decided_for`]).
pub(crate) fn resolve_raw_laser(
    path: &Path,
    options: CarmenOptions,
) -> Result<CarmenOptions, IoError> {
    options.decided_for(path)
}

impl<R: BufRead> CarmenReader<R> {
    /// A reader over any buffered input; `path` names it in errors.
    /// [`RawLaserScans::WhenNoPosedScans`] is [`RawLaserScans::Never`]
    /// here: a stream cannot be looked through first.
    pub fn new(input: R, path: &Path, options: CarmenOptions) -> Self {
        CarmenReader { input, path: path.to_path_buf(), options, line_no: 0, buf: String::new() }
    }

    /// The reader with its line numbers counted from `first_line` (1-based)
    /// instead of 1: for input that starts within a log.
    pub(crate) fn starting_at_line(mut self, first_line: usize) -> Self {
        self.line_no = first_line.saturating_sub(1);
        self
    }

    fn err(&self, message: impl Into<String>) -> IoError {
        IoError::parse(&self.path, Some(self.line_no), message)
    }

    fn parse_line(&self, line: &str) -> Result<Option<LogRecord>, IoError> {
        if let Some(rest) = line.strip_prefix("FLASER ")
            && let Some(record) = self.flaser_fast(rest)
        {
            return Ok(Some(record));
        }
        let mut fields = line.split_ascii_whitespace();
        let Some(kind) = fields.next() else { return Ok(None) };
        if kind.starts_with('#') {
            return Ok(None);
        }
        let rest: Vec<&str> = fields.collect();
        match kind {
            "FLASER" => self.flaser(&rest).map(Some),
            "ROBOTLASER1" => self.robotlaser(&rest).map(Some),
            "ODOM" => self.odom(&rest).map(Some),
            "RAWLASER1" if self.options.raw_laser == RawLaserScans::Always => {
                self.rawlaser(&rest).map(Some)
            }
            _ => Ok(None), // PARAM, NEFF, SYNC, RAWLASER*, ...: not used
        }
    }

    /// Field `i` as a number; `what` names it in errors (formatted only for
    /// an error: this runs for every range of a log).
    fn num(&self, fields: &[&str], i: usize, what: impl Display) -> Result<f64, IoError> {
        let s = fields.get(i).ok_or_else(|| self.err(format!("truncated line: no {what}")))?;
        match short_decimal(s.as_bytes()) {
            Some(v) => Ok(v),
            None => {
                s.parse::<f64>().map_err(|_| self.err(format!("{what} is not a number: {s:?}")))
            }
        }
    }

    /// Three numbers from field `i` on as a pose; `what` prefixes the field
    /// names in errors (`odom` -> `odom_x`, `odom_y`, `odom_theta`).
    fn pose(&self, fields: &[&str], i: usize, what: &str) -> Result<Pose2, IoError> {
        let name = |axis: &'static str| PoseField { what, axis };
        Ok(Pose2::new(
            self.num(fields, i, name("x"))?,
            self.num(fields, i + 1, name("y"))?,
            self.num(fields, i + 2, name("theta"))?,
        ))
    }

    /// `fields` must be exactly `expected` long: a count that does not match
    /// its line would shift the pose, odometry and stamp into the wrong
    /// columns.
    fn exact(&self, fields: &[&str], expected: usize, layout: impl Display) -> Result<(), IoError> {
        if fields.len() == expected {
            return Ok(());
        }
        Err(self.err(format!(
            "{} fields after the message name, expected {expected} ({layout})",
            fields.len()
        )))
    }

    fn count(&self, fields: &[&str], i: usize, what: &str) -> Result<usize, IoError> {
        let v = self.num(fields, i, what)?;
        if !is_count(v) {
            return Err(self.err(format!("{what} is not a count: {v}")));
        }
        Ok(v as usize)
    }

    /// A range as the log writes it, metres: at or beyond the maximum (the
    /// log's "no return") or NaN, +inf.
    fn range(&self, r: f64) -> f32 {
        if r >= self.options.max_range_m || r.is_nan() { f32::INFINITY } else { r as f32 }
    }

    fn ranges(&self, fields: &[&str], start: usize, n: usize) -> Result<Vec<f32>, IoError> {
        (0..n)
            .map(|k| {
                Ok(self.range(self.num(fields, start + k, format_args!("range {}", k + 1))?))
            })
            .collect()
    }

    /// A `FLASER` line in one pass over its bytes, when it is well formed:
    /// every number a number, the field count right, the field of view
    /// known. `None` for anything else, which [`Self::flaser`] then reads
    /// (and reports) field by field; both give the same record.
    fn flaser_fast(&self, after_name: &str) -> Option<LogRecord> {
        let mut f = Fields { bytes: after_name.as_bytes(), at: 0 };
        let n = f.number().filter(|v| is_count(*v))? as usize;
        let frame = self.flaser_frame(n)?;
        let mut ranges = Vec::with_capacity(n);
        for _ in 0..n {
            ranges.push(self.range(f.number()?));
        }
        let mut v = [0.0; 7];
        for x in &mut v {
            *x = f.number()?;
        }
        // hostname and logger_timestamp, then nothing.
        f.next_field()?;
        f.next_field()?;
        if f.next_field().is_some() {
            return None;
        }
        let pose = Pose2::new(v[0], v[1], v[2]);
        let odom = Pose2::new(v[3], v[4], v[5]);
        Some(self.flaser_record(frame, ranges, pose, odom, v[6]))
    }

    fn flaser(&self, f: &[&str]) -> Result<LogRecord, IoError> {
        let n = self.count(f, 0, "beam count")?;
        let ranges = self.ranges(f, 1, n)?;
        let p = 1 + n;
        let pose = self.pose(f, p, "")?;
        let odom = self.pose(f, p + 3, "odom")?;
        let stamp = self.num(f, p + 6, "ipc_timestamp")?;
        let frame = self.flaser_frame(n).ok_or_else(|| {
            self.err(format!(
                "FLASER with {n} beams: the field of view is ambiguous, give it (--fov)"
            ))
        })?;
        self.exact(
            f,
            n + 10,
            format_args!(
                "FLASER {n} ranges x y theta odom_x odom_y odom_theta ipc_timestamp hostname \
                 logger_timestamp"
            ),
        )?;
        Ok(self.flaser_record(frame, ranges, pose, odom, stamp))
    }

    /// The first beam's angle and the angle step of a `FLASER` line of `n`
    /// beams, radians; `None` when the count leaves them ambiguous and no
    /// field of view was given.
    fn flaser_frame(&self, n: usize) -> Option<(f64, f64)> {
        match self.options.fov_rad {
            Some(fov) if n > 1 => Some((-fov / 2.0, fov / (n - 1) as f64)),
            Some(fov) => Some((0.0, fov)),
            None => match n {
                180 | 181 => Some((-PI / 2.0, PI / 180.0)),
                361 => Some((-PI / 2.0, PI / 360.0)),
                _ => None,
            },
        }
    }

    /// The scan record of a `FLASER` line, its fields read; `stamp` as the
    /// log writes it (before the time offset).
    fn flaser_record(
        &self,
        (angle_min, increment): (f64, f64),
        ranges: Vec<f32>,
        pose: Pose2,
        odom: Pose2,
        stamp: f64,
    ) -> LogRecord {
        let scan = Scan::new(
            angle_min as f32,
            increment as f32,
            0.0,
            self.options.max_range_m as f32,
            ranges,
        )
        .with_stamp(stamp + self.options.time_offset_s);
        LogRecord::Scan(ScanRecord {
            scan,
            pose: Some(pose),
            odometry: Some(odom),
            position: self.line_no,
            sensor: None,
        })
    }

    /// The laser header and ranges that `ROBOTLASER1` and `RAWLASER1`
    /// share (`laser_type start_angle fov angular_res max_range accuracy
    /// remission_mode n r1..rn m rem1..remm`): the scan, without its stamp,
    /// and the index of the first field after the remissions.
    fn laser_fields(&self, f: &[&str]) -> Result<(Scan, usize), IoError> {
        let start = self.num(f, 1, "start_angle")?;
        let res = self.num(f, 3, "angular_res")?;
        let max_range = self.num(f, 4, "max_range")?;
        let n = self.count(f, 7, "beam count")?;
        let max = if max_range > 0.0 {
            max_range.min(self.options.max_range_m)
        } else {
            self.options.max_range_m
        };
        let ranges: Vec<f32> = self
            .ranges(f, 8, n)?
            .into_iter()
            .map(|r| if f64::from(r) >= max { f32::INFINITY } else { r })
            .collect();
        let m = self.count(f, 8 + n, "remission count")?;
        let scan = Scan::new(start as f32, res as f32, 0.0, max as f32, ranges);
        Ok((scan, 9 + n + m))
    }

    /// `RAWLASER1`: the laser header, ranges and remissions, then
    /// `ipc_timestamp hostname logger_timestamp`; no pose.
    fn rawlaser(&self, f: &[&str]) -> Result<LogRecord, IoError> {
        let (scan, p) = self.laser_fields(f)?;
        let stamp = self.num(f, p, "ipc_timestamp")? + self.options.time_offset_s;
        self.exact(
            f,
            p + 3,
            format_args!(
                "RAWLASER1 with {} ranges and {} remissions: 7 header fields, the counts, \
                 ipc_timestamp hostname logger_timestamp",
                scan.len(),
                p - 9 - scan.len()
            ),
        )?;
        Ok(LogRecord::Scan(ScanRecord {
            scan: scan.with_stamp(stamp),
            pose: None,
            odometry: None,
            position: self.line_no,
            sensor: carmen_laser_type(self.num(f, 0, "laser_type")?),
        }))
    }

    fn robotlaser(&self, f: &[&str]) -> Result<LogRecord, IoError> {
        let (scan, p) = self.laser_fields(f)?;
        let (n, m) = (scan.len(), p - 9 - scan.len());
        let laser = self.pose(f, p, "laser")?;
        let robot = self.pose(f, p + 3, "robot")?;
        let stamp = self.num(f, p + 11, "ipc_timestamp")? + self.options.time_offset_s;
        self.exact(
            f,
            n + m + 23,
            format_args!(
                "ROBOTLASER1 with {n} ranges and {m} remissions: 7 header fields, the counts, \
                 laser and robot poses, 5 velocities and safety fields, ipc_timestamp hostname \
                 logger_timestamp"
            ),
        )?;
        Ok(LogRecord::Scan(ScanRecord {
            scan: scan.with_stamp(stamp),
            pose: Some(laser),
            odometry: Some(robot),
            position: self.line_no,
            sensor: carmen_laser_type(self.num(f, 0, "laser_type")?),
        }))
    }

    fn odom(&self, f: &[&str]) -> Result<LogRecord, IoError> {
        let pose = self.pose(f, 0, "")?;
        let stamp = self.num(f, 6, "ipc_timestamp")? + self.options.time_offset_s;
        self.exact(f, 9, "ODOM x y theta tv rv accel ipc_timestamp hostname logger_timestamp")?;
        Ok(LogRecord::Odometry(OdometryRecord { pose, stamp_s: stamp, position: self.line_no }))
    }
}

impl<R: BufRead> Iterator for CarmenReader<R> {
    type Item = Result<LogRecord, IoError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            self.buf.clear();
            self.line_no += 1;
            match self.input.read_line(&mut self.buf) {
                Ok(0) => return None,
                Ok(_) => {}
                Err(e) if e.kind() == std::io::ErrorKind::InvalidData => {
                    return Some(Err(self.err("not text (invalid UTF-8)")));
                }
                Err(e) => return Some(Err(IoError::io(&self.path, e))),
            }
            let line = std::mem::take(&mut self.buf);
            let parsed = self.parse_line(&line);
            self.buf = line;
            match parsed {
                Ok(Some(record)) => return Some(Ok(record)),
                Ok(None) => continue,
                Err(e) => return Some(Err(e)),
            }
        }
    }
}

/// Whether a field read as a number is a count: a whole number from 0 to a
/// million.
fn is_count(v: f64) -> bool {
    v >= 0.0 && v.fract() == 0.0 && v <= 1e6
}

/// The profile of CARMEN's `laser_type` (`carmen_laser_laser_type_t`):
/// SICK LMS (0), PLS (1) and S300 (4) are [`SensorProfile::SickLms`], a
/// Hokuyo URG (2) is [`SensorProfile::Urg04lx`]; a simulated (3) or unknown
/// laser names none.
fn carmen_laser_type(code: f64) -> Option<SensorProfile> {
    match code {
        0.0 | 1.0 | 4.0 => Some(SensorProfile::SickLms),
        2.0 => Some(SensorProfile::Urg04lx),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast path gives `str::parse`'s bits, and leaves it what it
    /// cannot take.
    #[test]
    fn short_decimals_parse_as_std_parses_them() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..200_000 {
            let digits = (next() % 15 + 1) as usize;
            let mantissa = next() % 10u64.pow(digits as u32);
            let decimals = (next() % (digits as u64 + 1)) as usize;
            let text = format!("{mantissa:0digits$}");
            let (int, frac) = text.split_at(digits - decimals);
            let sign = ["", "-", "+"][(next() % 3) as usize];
            let s = format!("{sign}{int}.{frac}");
            assert_eq!(
                short_decimal(s.as_bytes()).map(f64::to_bits),
                Some(s.parse::<f64>().unwrap().to_bits()),
                "{s}"
            );
        }
        for s in ["12", "-0", "0.5", ".5", "5.", "81.9", "-1.5708", "123456789012345"] {
            assert_eq!(
                short_decimal(s.as_bytes()).map(f64::to_bits),
                Some(s.parse::<f64>().unwrap().to_bits()),
                "{s}"
            );
        }
        for s in
            ["", "-", ".", "1e3", "inf", "nan", "1.2.3", "1234567890123456", "--1", "0x1", " 1"]
        {
            assert_eq!(short_decimal(s.as_bytes()), None, "{s}");
        }
    }

    /// The one-pass `FLASER` reader gives the field-by-field reader's
    /// record, bit for bit, on every line it takes, and takes no line that
    /// reader rejects (which then reports it).
    #[test]
    fn the_fast_flaser_path_reads_as_the_general_one() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = move |m: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % m
        };
        let number = |next: &mut dyn FnMut(u64) -> u64| match next(12) {
            0 => "1e-1".to_string(),
            1 => "nan".to_string(),
            2 => "81.91".to_string(),
            3 => "x".to_string(),
            4 => "-0.5".to_string(),
            5 => "1109289934.123456".to_string(),
            6 => "12345678901234567890123.5".to_string(),
            7 => "+.5".to_string(),
            _ => format!("{}.{:03}", next(90), next(1000)),
        };
        let (mut taken, mut declined) = (0, 0);
        for _ in 0..3000 {
            let n = [180, 181, 361, 7, 0][next(5) as usize];
            let mut line = format!("FLASER {n}");
            let fields = n + 9 + [0, 0, 0, 1][next(4) as usize] - [0, 0, 0, 1][next(4) as usize];
            for _ in 0..fields {
                line.push(if next(20) == 0 { '\t' } else { ' ' });
                // Numbers only rarely unusual, so that most lines are taken.
                let unusual = next(400) == 0;
                line.push_str(&if unusual { number(&mut next) } else { format!("{}.5", next(9)) });
            }
            line.push('\n');
            let options = CarmenOptions {
                fov_rad: (next(2) == 0).then_some(3.0),
                time_offset_s: 0.25,
                ..Default::default()
            };
            let reader = CarmenReader::new(&b""[..], Path::new("t.clf"), options);
            let fields: Vec<&str> = line.split_ascii_whitespace().skip(1).collect();
            // Debug text, so that a NaN pose compares equal to itself; a
            // line the general reader rejects fails here if it is taken.
            let general = format!("{:?}", reader.flaser(&fields).map_err(|e| e.to_string()));
            match reader.flaser_fast(line.strip_prefix("FLASER ").unwrap()) {
                Some(record) => {
                    taken += 1;
                    assert_eq!(format!("{:?}", Ok::<_, String>(record)), general, "{line}");
                }
                None => declined += 1,
            }
        }
        assert!(taken > 500 && declined > 500, "taken {taken}, declined {declined}");
    }

    fn read(text: &str, options: CarmenOptions) -> Vec<Result<LogRecord, IoError>> {
        CarmenReader::new(text.as_bytes(), Path::new("t.clf"), options).collect()
    }

    #[test]
    fn flaser_odom_and_comments() {
        let mut line = String::from("FLASER 180");
        for i in 0..180 {
            line.push_str(if i == 5 { " 81.91" } else { " 2.5" });
        }
        line.push_str(" 1 2 0.5 1.1 2.1 0.6 12.5 host 12.6\n");
        let text = format!("# comment\nPARAM robot_x 1\nODOM 1 2 0.1 0 0 0 3.0 host 3.0\n{line}");
        let records = read(&text, CarmenOptions::default());
        assert_eq!(records.len(), 2);
        let LogRecord::Scan(s) = records[1].as_ref().unwrap() else { panic!() };
        assert_eq!(s.scan.len(), 180);
        assert_eq!(s.scan.ranges[5], f32::INFINITY);
        assert_eq!(s.scan.stamp_s, Some(12.5));
        assert!((f64::from(s.scan.angle_min) + PI / 2.0).abs() < 1e-6);
        assert_eq!(s.position, 4);
        assert_eq!(s.pose.unwrap().x(), 1.0);
        assert_eq!(s.odometry.unwrap().x(), 1.1);
    }

    /// `ROBOTLASER1` carries the laser type: SICK LMS (0) and Hokuyo URG (2)
    /// name their profiles, a simulated laser (3) none.
    #[test]
    fn robotlaser_names_its_sensor() {
        let line = |laser_type: u32| {
            let mut l = format!("ROBOTLASER1 {laser_type} -1.5708 3.1416 0.0175 81.9 0.01 0 180");
            l.push_str(&" 2.5".repeat(180));
            l.push_str(" 0 0 0 0 1 2 0.5 0 0 0 0 0 12.5 host 12.6\n");
            l
        };
        for (code, want) in
            [(0, Some(SensorProfile::SickLms)), (2, Some(SensorProfile::Urg04lx)), (3, None)]
        {
            let records = read(&line(code), CarmenOptions::default());
            let LogRecord::Scan(s) = records[0].as_ref().unwrap() else { panic!() };
            assert_eq!(s.sensor, want, "laser_type {code}");
            assert_eq!(s.scan.len(), 180);
        }
    }

    #[test]
    fn errors_name_the_line() {
        let e = read("ODOM 1 2\n", CarmenOptions::default()).remove(0).unwrap_err().to_string();
        assert_eq!(e, "t.clf:1: truncated line: no theta");
        let e = read("\n\nFLASER 2 1.0 x\n", CarmenOptions::default())
            .remove(0)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.clf:3: range 2 is not a number"), "{e}");
        let e = read("FLASER 360 1\n", CarmenOptions::default()).remove(0).unwrap_err().to_string();
        assert!(e.contains("truncated") || e.contains("ambiguous"), "{e}");
        let mut line = String::from("FLASER 360");
        line.push_str(&" 1.0".repeat(360));
        line.push_str(" 0 0 0 0 0 0 1 h 1\n");
        let e = read(&line, CarmenOptions::default()).remove(0).unwrap_err().to_string();
        assert!(e.contains("ambiguous"), "{e}");
        let ok = read(&line, CarmenOptions { fov_rad: Some(PI), ..Default::default() });
        assert!(ok[0].is_ok());
    }

    /// A count that does not match its line would read the pose, odometry
    /// and stamp from the wrong columns: extra or missing fields are errors.
    #[test]
    fn field_counts_must_match_the_message() {
        let flaser = |n: usize, extra: &str| {
            format!("FLASER {n}{} 1 2 0.5 1.1 2.1 0.6 12.5 host 12.6{extra}\n", " 2.5".repeat(n))
        };
        assert!(read(&flaser(180, ""), CarmenOptions::default())[0].is_ok());
        // One range too many, read as a count of 180: everything shifts.
        let shifted = flaser(181, "").replacen("FLASER 181", "FLASER 180", 1);
        let e = read(&shifted, CarmenOptions::default()).remove(0).unwrap_err().to_string();
        assert!(e.starts_with("t.clf:1: 191 fields after the message name, expected 190"), "{e}");
        let e = read(&flaser(180, " 7"), CarmenOptions::default()).remove(0).unwrap_err();
        assert!(e.to_string().contains("expected 190"), "{e}");
        let short = "FLASER 2 1 1 0 0 0 0 0 0 5.0\n";
        let o = CarmenOptions { fov_rad: Some(1.0), ..Default::default() };
        assert!(read(short, o).remove(0).unwrap_err().to_string().contains("expected 12"));
        let e = read("ODOM 1 2 0.1 0 0 0 3.0 host 3.0 extra\n", CarmenOptions::default())
            .remove(0)
            .unwrap_err();
        assert!(e.to_string().contains("expected 9"), "{e}");
    }

    /// A `RAWLASER1` line of `n` ranges of 2.5 m, two remissions, at 12.5 s.
    fn rawlaser(n: usize, extra: &str) -> String {
        let mut l = format!("RAWLASER1 2 -2.0944 4.18879 0.00613592 5.6 0.01 0 {n}");
        l.push_str(&" 2.5".repeat(n));
        l.push_str(&format!(" 2 7 7 12.5 host 12.6{extra}\n"));
        l
    }

    /// `RAWLASER1` is a scan without a pose when asked for
    /// ([`RawLaserScans::Always`]), skipped otherwise; a stream cannot be
    /// looked through, so there `WhenNoPosedScans` skips it.
    #[test]
    fn rawlaser_is_a_scan_without_a_pose_when_asked_for() {
        let text = format!("ODOM 1 2 0.1 0 0 0 3.0 host 3.0\n{}", rawlaser(683, ""));
        let always = CarmenOptions { raw_laser: RawLaserScans::Always, ..Default::default() };
        let records = read(&text, always);
        assert_eq!(records.len(), 2);
        let LogRecord::Scan(s) = records[1].as_ref().unwrap() else { panic!() };
        assert_eq!((s.scan.len(), s.scan.stamp_s, s.position), (683, Some(12.5), 2));
        assert_eq!((s.pose, s.odometry, s.sensor), (None, None, Some(SensorProfile::Urg04lx)));
        assert!((f64::from(s.scan.angle_min) + 2.0944).abs() < 1e-6);
        assert!((f64::from(s.scan.range_max) - 5.6).abs() < 1e-6);
        for skipping in [RawLaserScans::Never, RawLaserScans::WhenNoPosedScans] {
            let o = CarmenOptions { raw_laser: skipping, ..Default::default() };
            assert_eq!(read(&text, o).len(), 1, "{skipping:?}");
        }
        // The field count is checked: the stamp would be a remission.
        let e = read(&rawlaser(10, " 9"), always).remove(0).unwrap_err().to_string();
        assert!(e.starts_with("t.clf:1: 25 fields after the message name, expected 24"), "{e}");
        let e = read(&rawlaser(10, "").replace(" 2 7 7", " 2 7"), always).remove(0).unwrap_err();
        assert!(e.to_string().contains("ipc_timestamp"), "{e}");
    }

    /// Opened from a file, a log reads its `RAWLASER1` lines only when it
    /// has no `FLASER` or `ROBOTLASER1` line: CARMEN's logger writes the
    /// front laser as both, and every scan must come once.
    #[test]
    fn a_file_reads_rawlaser_only_without_posed_scans() {
        let mut flaser = String::from("FLASER 180");
        flaser.push_str(&" 2.5".repeat(180));
        flaser.push_str(" 1 2 0.5 1 2 0.5 12.5 host 12.6\n");
        let raw_only = format!("# a laser alone\n{}{}", rawlaser(5, ""), rawlaser(5, ""));
        let both = format!("{}{}{}", rawlaser(5, ""), flaser, rawlaser(5, ""));
        for (name, text, scans, posed) in [("raw", raw_only, 2, false), ("both", both, 1, true)] {
            let path = std::env::temp_dir()
                .join(format!("pcaline-carmen-{}-{name}.clf", std::process::id()));
            std::fs::write(&path, &text).unwrap();
            assert_eq!(has_posed_scans(&path).unwrap(), posed, "{name}");
            let records: Vec<_> = CarmenReader::open(&path, CarmenOptions::default())
                .unwrap()
                .collect::<Result<_, _>>()
                .unwrap();
            std::fs::remove_file(&path).unwrap();
            assert_eq!(records.len(), scans, "{name}");
            let posed_scans = records
                .iter()
                .filter(|r| matches!(r, LogRecord::Scan(s) if s.pose.is_some()))
                .count();
            assert_eq!(posed_scans, usize::from(posed), "{name}");
        }
        assert!(has_posed_scans(Path::new("/no/such/log.clf")).is_err());
    }

    /// The front laser's `PARAM` lines make its mount: the last value of
    /// each wins, an absent one is 0, other parameters and messages are
    /// passed over, and a value that is no number is an error naming the
    /// line and the parameter.
    #[test]
    fn param_lines_give_the_front_lasers_mount() {
        let write = |name: &str, text: &str| {
            let path = std::env::temp_dir()
                .join(format!("pcaline-carmen-param-{}-{name}.log", std::process::id()));
            std::fs::write(&path, text).unwrap();
            path
        };
        let text = format!(
            "PARAM robot_frontlaser_offset 0.1 host 0\n\
             PARAM robot_rearlaser_offset -0.3 host 0\n{}\
             PARAM robot_frontlaser_angular_offset 0.05 host 0\n\
             PARAM robot_frontlaser_offset 0.2 host 0\n",
            rawlaser(5, "")
        );
        let path = write("set", &text);
        let mount = front_laser_params(&path).unwrap().unwrap();
        assert_eq!((mount.x(), mount.y(), mount.heading()), (0.2, 0.0, 0.05));
        let none = write("none", "PARAM robot_rearlaser_offset -0.3 host 0\n");
        assert_eq!(front_laser_params(&none).unwrap(), None);
        let bad = write("bad", "# params\nPARAM robot_frontlaser_side_offset nan host 0\n");
        let e = front_laser_params(&bad).unwrap_err().to_string();
        assert!(e.contains(":2:") && e.contains("robot_frontlaser_side_offset"), "{e}");
        for p in [path, none, bad] {
            std::fs::remove_file(p).unwrap();
        }
    }
}
