//! Scans as JSON or CSV.
//!
//! JSON: one scan object, an array of them, or one object per line (JSON
//! Lines). A scan object is either pcaline's form
//! `{"angle_min", "angle_increment", "range_min", "range_max", "ranges",
//! "intensities"?, "stamp_s"?, "odometry"?}` (radians, metres; `null` or a
//! missing value in `ranges` is no return; `odometry` the vehicle's pose
//! `[x_m, y_m, heading_rad]`), or the form of the laser_line_extraction
//! examples, `{"ranges": [...], "bearings": [...]}` with evenly spaced
//! bearings (then `range_min` is 0 and `range_max` unbounded).
//!
//! CSV: a header line, then one scan per line:
//! `stamp_s,angle_min,angle_increment,range_min,range_max,r0,r1,...`
//! (empty, `nan` or `inf` cells are no return; lines may have different
//! beam counts). With `odom_x,odom_y,odom_heading` after `range_max` in the
//! header, each line carries the vehicle's odometry pose there (metres,
//! radians), before its ranges.

use crate::{IoError, LogRecord, ScanRecord};
use pcaline_geometry::{Pose2, Scan};
use serde::{Deserialize, Serialize};
use std::io::BufRead;
use std::ops::ControlFlow;
use std::path::Path;

/// pcaline's JSON form of a scan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScanJson {
    /// Bearing of the first beam, radians.
    pub angle_min: f32,
    /// Angle between beams, radians.
    pub angle_increment: f32,
    /// Smallest valid range, metres.
    pub range_min: f32,
    /// Largest range, metres.
    pub range_max: f32,
    /// Ranges, metres; `null` is no return.
    pub ranges: Vec<Option<f32>>,
    /// Intensities.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intensities: Option<Vec<f32>>,
    /// Time, seconds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stamp_s: Option<f64>,
    /// The vehicle's odometry pose when the scan was taken, `[x_m, y_m,
    /// heading_rad]`: the source `pcaline map` takes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub odometry: Option<[f64; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BearingsJson {
    ranges: Vec<Option<f32>>,
    bearings: Vec<f64>,
}

#[derive(Debug)]
enum AnyScan {
    Full(ScanJson),
    Bearings(BearingsJson),
}

impl AnyScan {
    /// The scan of a JSON value: the bearings form when it has `bearings`,
    /// else pcaline's form. The error names the field (`ranges[3]: invalid
    /// type: string "NaN", expected f32`, `unknown field \`foo\``).
    fn from_value(value: serde_json::Value) -> Result<AnyScan, String> {
        use serde_json::Value;
        let kind = match &value {
            Value::Object(o) => {
                let bearings = o.contains_key("bearings");
                let named = |e: serde_path_to_error::Error<serde_json::Error>| {
                    let at = e.path().to_string();
                    if at == "." { e.inner().to_string() } else { format!("{at}: {}", e.inner()) }
                };
                return if bearings {
                    serde_path_to_error::deserialize(value).map(AnyScan::Bearings).map_err(named)
                } else {
                    serde_path_to_error::deserialize(value).map(AnyScan::Full).map_err(named)
                };
            }
            Value::Null => "null",
            Value::Bool(_) => "a boolean",
            Value::Number(_) => "a number",
            Value::String(_) => "a string",
            Value::Array(_) => "an array",
        };
        Err(format!("expected a scan object, found {kind}"))
    }
}

/// Where the newlines a reader has given out are, for the line of each
/// value of a JSON stream.
#[derive(Debug, Default, Clone, Copy)]
struct Newlines {
    /// Bytes given out.
    read: usize,
    /// Newlines among them.
    count: usize,
    /// Offset of the last one.
    last_at: Option<usize>,
}

impl Newlines {
    /// The 1-based line of the byte before `offset` (a value's end, as
    /// `StreamDeserializer::byte_offset` gives it): serde_json may have read
    /// one byte past the value (the newline after `null` or a number).
    fn line_ending_at(&self, offset: usize) -> usize {
        let past = self.last_at.is_some_and(|at| at >= offset) as usize;
        self.count - past + 1
    }
}

/// A reader that records [`Newlines`].
struct LineCounting<R> {
    inner: R,
    newlines: std::rc::Rc<std::cell::Cell<Newlines>>,
}

impl<R: std::io::Read> std::io::Read for LineCounting<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let mut seen = self.newlines.get();
        for (k, b) in buf[..n].iter().enumerate() {
            if *b == b'\n' {
                seen.count += 1;
                seen.last_at = Some(seen.read + k);
            }
        }
        seen.read += n;
        self.newlines.set(seen);
        Ok(n)
    }
}

impl From<&Scan> for ScanJson {
    fn from(s: &Scan) -> Self {
        ScanJson {
            angle_min: s.angle_min,
            angle_increment: s.angle_increment,
            range_min: s.range_min,
            range_max: s.range_max,
            ranges: s.ranges.iter().map(|r| r.is_finite().then_some(*r)).collect(),
            intensities: s.intensities.clone(),
            stamp_s: s.stamp_s,
            odometry: None,
        }
    }
}

/// The scan of a JSON object, and its odometry pose if it has one.
fn to_scan(any: AnyScan) -> Result<(Scan, Option<Pose2>), String> {
    let ranges =
        |v: Vec<Option<f32>>| v.into_iter().map(|r| r.unwrap_or(f32::INFINITY)).collect::<Vec<_>>();
    match any {
        AnyScan::Full(j) => {
            if let Some(i) = &j.intensities
                && i.len() != j.ranges.len()
            {
                return Err(format!("{} intensities for {} ranges", i.len(), j.ranges.len()));
            }
            let mut scan = Scan::new(
                j.angle_min,
                j.angle_increment,
                j.range_min,
                j.range_max,
                ranges(j.ranges),
            );
            scan.intensities = j.intensities;
            scan.stamp_s = j.stamp_s;
            Ok((scan, j.odometry.map(|[x, y, heading]| Pose2::new(x, y, heading))))
        }
        AnyScan::Bearings(b) => {
            let n = b.ranges.len();
            if b.bearings.len() != n {
                return Err(format!(
                    "{} bearings for {n} ranges (beam count mismatch)",
                    b.bearings.len()
                ));
            }
            if n < 2 {
                return Err("fewer than 2 beams: no bearing increment".into());
            }
            let inc = (b.bearings[n - 1] - b.bearings[0]) / (n - 1) as f64;
            for (k, a) in b.bearings.iter().enumerate() {
                if (a - (b.bearings[0] + inc * k as f64)).abs() > 1e-4 {
                    return Err(format!("bearing {k} is not evenly spaced"));
                }
            }
            let scan =
                Scan::new(b.bearings[0] as f32, inc as f32, 0.0, f32::INFINITY, ranges(b.ranges));
            Ok((scan, None))
        }
    }
}

/// Streams the scans of a JSON file: a top-level array is read whole; a
/// single object or JSON Lines stream object by object.
pub fn read_scan_json(
    path: &Path,
    visit: &mut dyn FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let mut reader = std::io::BufReader::new(file);
    // Blank lines before the first value are consumed here: their count
    // keeps line numbers right.
    let mut skipped_lines = 0;
    let first = loop {
        let buf = reader.fill_buf().map_err(|e| IoError::io(path, e))?;
        match buf.iter().position(|b| !b.is_ascii_whitespace()) {
            Some(k) => break Some(buf[k]),
            None if buf.is_empty() => break None,
            None => {
                let n = buf.len();
                skipped_lines += buf.iter().filter(|b| **b == b'\n').count();
                reader.consume(n);
            }
        }
    };
    let mut count = 0;
    let mut emit = |(scan, odometry): (Scan, Option<Pose2>), position: usize| {
        count += 1;
        visit(LogRecord::Scan(ScanRecord { scan, pose: None, odometry, position, sensor: None }))
    };
    let parse_err = |e: serde_json::Error| IoError::parse(path, Some(e.line()), e.to_string());
    match first {
        None => return Err(IoError::parse(path, Some(1), "empty file: no scan")),
        Some(b'[') => {
            let all: Vec<serde_json::Value> = serde_json::from_reader(reader).map_err(parse_err)?;
            for (i, value) in all.into_iter().enumerate() {
                let scan = AnyScan::from_value(value)
                    .and_then(to_scan)
                    .map_err(|m| IoError::parse(path, None, format!("scan {}: {m}", i + 1)))?;
                if emit(scan, i + 1).is_break() {
                    break;
                }
            }
        }
        Some(_) => {
            let newlines = std::rc::Rc::new(std::cell::Cell::new(Newlines::default()));
            let counting = LineCounting { inner: reader, newlines: newlines.clone() };
            let mut stream =
                serde_json::Deserializer::from_reader(counting).into_iter::<serde_json::Value>();
            let mut i = 0;
            while let Some(item) = stream.next() {
                let value = item.map_err(|e| {
                    IoError::parse(path, Some(e.line() + skipped_lines), e.to_string())
                })?;
                // The line the value ends on.
                let line = skipped_lines + newlines.get().line_ending_at(stream.byte_offset());
                i += 1;
                let scan = AnyScan::from_value(value)
                    .and_then(to_scan)
                    .map_err(|m| IoError::parse(path, Some(line), format!("scan {i}: {m}")))?;
                if emit(scan, i).is_break() {
                    break;
                }
            }
        }
    }
    Ok(count)
}

/// Streams the scans of a CSV file, line by line.
pub fn read_scan_csv(
    path: &Path,
    visit: &mut dyn FnMut(LogRecord) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let mut count = 0;
    // The first range's column: 8 when the header has the odometry's three.
    let mut first_range = 5;
    for (i, line) in std::io::BufReader::new(file).lines().enumerate() {
        let line_no = i + 1;
        let line =
            line.map_err(|e| IoError::parse(path, Some(line_no), format!("not text: {e}")))?;
        if line_no == 1 {
            if !line.trim_start().starts_with("stamp_s") {
                return Err(IoError::parse(
                    path,
                    Some(1),
                    "expected the header stamp_s,angle_min,angle_increment,range_min,range_max,r0,... \
                     (or ...,range_max,odom_x,odom_y,odom_heading,r0,...)",
                ));
            }
            let header: Vec<&str> = line.split(',').map(str::trim).collect();
            if header.get(5..8) == Some(&["odom_x", "odom_y", "odom_heading"][..]) {
                first_range = 8;
            }
            continue;
        }
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() < first_range {
            return Err(IoError::parse(
                path,
                Some(line_no),
                format!("{} columns, need at least {first_range}", cells.len()),
            ));
        }
        let num = |k: usize, name: &str| -> Result<f64, IoError> {
            cells[k].parse::<f64>().map_err(|_| {
                IoError::parse(
                    path,
                    Some(line_no),
                    format!("{name} is not a number: {:?}", cells[k]),
                )
            })
        };
        let stamp = num(0, "stamp_s")?;
        let (amin, inc, rmin, rmax) = (
            num(1, "angle_min")?,
            num(2, "angle_increment")?,
            num(3, "range_min")?,
            num(4, "range_max")?,
        );
        let odometry = if first_range == 8 {
            Some(Pose2::new(num(5, "odom_x")?, num(6, "odom_y")?, num(7, "odom_heading")?))
        } else {
            None
        };
        let ranges = cells[first_range..]
            .iter()
            .enumerate()
            .map(|(k, c)| {
                if c.is_empty() {
                    Ok(f32::INFINITY)
                } else {
                    c.parse::<f32>().map_err(|_| {
                        IoError::parse(path, Some(line_no), format!("r{k} is not a number: {c:?}"))
                    })
                }
            })
            .collect::<Result<Vec<f32>, _>>()?;
        let scan =
            Scan::new(amin as f32, inc as f32, rmin as f32, rmax as f32, ranges).with_stamp(stamp);
        count += 1;
        if visit(LogRecord::Scan(ScanRecord {
            scan,
            pose: None,
            odometry,
            position: line_no,
            sensor: None,
        }))
        .is_break()
        {
            break;
        }
    }
    Ok(count)
}

/// Writes scans as CSV text (the form [`read_scan_csv`] reads).
pub fn scans_to_csv<'a>(scans: impl IntoIterator<Item = &'a Scan>) -> String {
    let mut out = String::from("stamp_s,angle_min,angle_increment,range_min,range_max,ranges...\n");
    for s in scans {
        out.push_str(&format!(
            "{},{},{},{},{}",
            s.stamp_s.unwrap_or(0.0),
            s.angle_min,
            s.angle_increment,
            s.range_min,
            s.range_max
        ));
        for r in &s.ranges {
            if r.is_finite() {
                out.push_str(&format!(",{r}"));
            } else {
                out.push(',');
            }
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn first_error(name: &str, text: &str) -> String {
        let path = std::env::temp_dir().join(format!("pcaline-{}-{name}", std::process::id()));
        std::fs::write(&path, text).unwrap();
        let result = read_scan_json(&path, &mut |_| ControlFlow::Continue(()));
        std::fs::remove_file(&path).unwrap();
        result.unwrap_err().to_string()
    }

    /// Each fault names its field and, in JSON Lines, its line (the
    /// untagged form said only "did not match any variant" at line 0).
    #[test]
    fn malformed_scans_name_the_field_and_the_line() {
        let good = r#"{"angle_min": -0.5, "angle_increment": 0.01, "range_min": 0.1, "range_max": 30.0, "ranges": [1.0, 2.0]}"#;
        let cases = [
            (
                r#"{"angle_min": -0.5, "angle_increment": 0.01, "range_min": 0.1, "range_max": 30.0, "ranges": [1.0], "colour": 1}"#,
                "unknown field `colour`",
            ),
            (
                r#"{"angle_min": -0.5, "angle_increment": 0.01, "range_min": 0.1, "range_max": 30.0}"#,
                "missing field `ranges`",
            ),
            (
                r#"{"angle_min": -0.5, "angle_increment": 0.01, "range_min": 0.1, "range_max": 30.0, "ranges": [1.0, "NaN"]}"#,
                "ranges[1]: invalid type: string \"NaN\"",
            ),
            (
                r#"{"angle_min": "-0.5", "angle_increment": 0.01, "range_min": 0.1, "range_max": 30.0, "ranges": [1.0]}"#,
                "angle_min: invalid type: string",
            ),
            (
                r#"{"angle_min": -0.5, "angle_increment": 0.01, "range_min": 0.1, "range_max": 30.0, "ranges": "1 2"}"#,
                "ranges: invalid type: string",
            ),
            ("null", "expected a scan object, found null"),
            ("3", "expected a scan object, found a number"),
            ("{}", "missing field"),
            (r#"{"ranges": [1.0, 2.0], "bearings": [0.0, "x"]}"#, "bearings[1]: invalid type"),
            (
                r#"{"angle_min": -0.5, "angle_increment": 0.01, "range_min": 0.1, "range_max": 30.0, "ranges": [1.0], "odometry": [1.0, 2.0]}"#,
                "odometry: invalid length 2",
            ),
        ];
        for (k, (bad, wanted)) in cases.iter().enumerate() {
            let e = first_error(&format!("bad{k}.jsonl"), &format!("{good}\n{good}\n{bad}\n"));
            assert!(e.contains(":3: scan 3: ") && e.contains(wanted), "{bad}: {e}");
            let e = first_error(&format!("bad{k}.json"), &format!("[{good}, {bad}]"));
            assert!(e.contains("scan 2: ") && e.contains(wanted), "{bad}: {e}");
        }
    }

    /// Every record of a CSV text, or the first error.
    fn read_csv(name: &str, text: &str) -> Result<Vec<ScanRecord>, String> {
        let path = std::env::temp_dir().join(format!("pcaline-{}-{name}", std::process::id()));
        std::fs::write(&path, text).unwrap();
        let mut records = Vec::new();
        let result = read_scan_csv(&path, &mut |r| {
            if let LogRecord::Scan(s) = r {
                records.push(s);
            }
            ControlFlow::Continue(())
        });
        std::fs::remove_file(&path).unwrap();
        result.map(|_| records).map_err(|e| e.to_string())
    }

    /// With the odometry's three columns in the header, each line's pose
    /// comes before its ranges; a cell that is not a number is named.
    #[test]
    fn csv_scans_may_carry_their_odometry() {
        let header =
            "stamp_s,angle_min,angle_increment,range_min,range_max,odom_x,odom_y,odom_heading";
        let records =
            read_csv("odom.csv", &format!("{header}\n1.5,-0.5,0.01,0.1,30,2,3,0.25,1.0,,2.5\n"))
                .unwrap();
        let s = &records[0];
        assert_eq!(s.odometry, Some(Pose2::new(2.0, 3.0, 0.25)));
        assert_eq!(s.scan.ranges, [1.0, f32::INFINITY, 2.5]);
        assert_eq!(s.scan.stamp_s, Some(1.5));
        let plain = read_csv(
            "plain.csv",
            "stamp_s,angle_min,angle_increment,range_min,range_max\n1,-0.5,0.01,0.1,30,2,3\n",
        )
        .unwrap();
        assert_eq!((plain[0].odometry, plain[0].scan.len()), (None, 2));
        let e = read_csv("bad-odom.csv", &format!("{header}\n1,-0.5,0.01,0.1,30,2,y,0,1\n"))
            .unwrap_err();
        assert!(e.contains(":2: odom_y is not a number"), "{e}");
        let e = read_csv("short.csv", &format!("{header}\n1,-0.5,0.01,0.1,30,2\n")).unwrap_err();
        assert!(e.contains("6 columns, need at least 8"), "{e}");
    }
}
