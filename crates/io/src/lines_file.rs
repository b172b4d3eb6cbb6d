//! Writers (and a reader) for detected lines and line maps, as JSON or CSV.

use crate::{IoError, write_atomic};
use pcaline_geometry::LineSegment;
use pcaline_mapping::{LineMap, MapRecord};
use serde::Serialize;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// The lines of one scan, in the sensor frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScanLines {
    /// Index of the scan in its file, from 0.
    pub scan: usize,
    /// Line or message number in the file.
    pub position: usize,
    /// Time, seconds.
    pub stamp_s: Option<f64>,
    /// The range noise the detector's thresholds used for this scan, when
    /// it uses one (the paper's detector does not).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise: Option<NoiseRecord>,
    /// The lines.
    pub lines: Vec<LineRecord>,
}

/// The range noise a detection used, for output.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NoiseRecord {
    /// Sigma below `far_from_m`, metres.
    pub near_sigma_m: f64,
    /// Sigma at and beyond `far_from_m`, metres.
    pub far_sigma_m: f64,
    /// Where the far band starts, metres (`null` when it never does).
    pub far_from_m: Option<f64>,
    /// Whether the sigmas were estimated from the scan (else the
    /// configuration's, the sensor profile's datasheet).
    pub estimated: bool,
    /// The range grid step found or known, metres, when estimated.
    pub range_step_m: Option<f64>,
}

/// One line, for output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LineRecord {
    /// Normal angle, radians.
    pub alpha_rad: f64,
    /// Distance from the origin, metres.
    pub d_m: f64,
    /// First endpoint.
    pub start: [f64; 2],
    /// Last endpoint.
    pub end: [f64; 2],
    /// Length, metres.
    pub length_m: f64,
    /// Points fitted.
    pub n_points: usize,
    /// Residual standard deviation, metres.
    pub residual_std_m: f64,
    /// First beam, when known.
    pub first_beam: Option<u32>,
    /// Last beam, when known.
    pub last_beam: Option<u32>,
    /// The residual in noise sigmas, when the straightness is known.
    pub residual_ratio: Option<f64>,
    /// The runs test's z of the residual signs, when known.
    pub runs_z: Option<f64>,
    /// The bow (sagitta of the residuals' parabola), metres, when known.
    pub bow_m: Option<f64>,
}

impl LineRecord {
    /// The record of a line, with its beam range when known.
    pub fn new(l: &LineSegment, beams: Option<(u32, u32)>) -> Self {
        LineRecord {
            alpha_rad: l.alpha(),
            d_m: l.d(),
            start: [l.start().x, l.start().y],
            end: [l.end().x, l.end().y],
            length_m: l.length(),
            n_points: l.n_points(),
            residual_std_m: l.residual_std(),
            first_beam: beams.map(|b| b.0),
            last_beam: beams.map(|b| b.1),
            residual_ratio: None,
            runs_z: None,
            bow_m: None,
        }
    }

    /// The same record with the line's straightness statistic: residual in
    /// noise sigmas, runs z, bow in metres (`pcaline_fitting::Straightness`).
    pub fn with_straightness(self, residual_ratio: f64, runs_z: f64, bow_m: f64) -> Self {
        LineRecord {
            residual_ratio: Some(residual_ratio),
            runs_z: Some(runs_z),
            bow_m: Some(bow_m),
            ..self
        }
    }
}

/// Writes any serialisable value as compact JSON, atomically.
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<(), IoError> {
    write_atomic(path, &json_bytes(path, value)?)
}

/// `value` as compact JSON, for `path` (named in the error).
pub fn json_bytes<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<Vec<u8>, IoError> {
    serde_json::to_vec(value).map_err(|e| IoError::parse(path, None, format!("cannot encode: {e}")))
}

/// How [`LinesWriter`] writes the lines of a log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum LinesFormat {
    /// A JSON array of [`ScanLines`], one scan per line of text (so the
    /// output can also be read line by line).
    Json,
    /// JSON Lines: one [`ScanLines`] object per line, nothing around them.
    JsonLines,
    /// CSV, one row per line, with a header row.
    Csv,
}

impl LinesFormat {
    /// Appends one scan's lines to `out` as [`LinesWriter`] writes them in
    /// this format, without what goes between scans (the JSON array's
    /// commas): a JSON object, a JSON object and a newline, or CSV rows.
    /// Fails only when `out` does.
    pub fn encode(self, scan: &ScanLines, out: &mut impl Write) -> std::io::Result<()> {
        match self {
            // serde_json keeps the kind of a failed write (a broken pipe stays one).
            LinesFormat::Json => serde_json::to_writer(out, scan).map_err(std::io::Error::from),
            LinesFormat::JsonLines => {
                serde_json::to_writer(&mut *out, scan).map_err(std::io::Error::from)?;
                out.write_all(b"\n")
            }
            LinesFormat::Csv => write_csv_rows(out, scan),
        }
    }
}

/// The CSV header of [`LinesFormat::Csv`].
const LINES_CSV_HEADER: &str = "scan,position,stamp_s,alpha_rad,d_m,start_x,start_y,end_x,end_y,length_m,n_points,residual_std_m,first_beam,last_beam,residual_ratio,runs_z,bow_m\n";

/// Streams the lines of a log, scan by scan, to a writer: memory does not
/// grow with the log. [`LinesWriter::finish`] closes the JSON array; a
/// writer dropped before it leaves the JSON unterminated (write to an
/// [`crate::AtomicFile`] to leave nothing instead).
///
/// Edge cases: a log without scans is `[]` in JSON and the header alone in
/// CSV; a non-finite value is `null` in JSON and empty in CSV.
#[derive(Debug)]
pub struct LinesWriter<W: Write> {
    out: W,
    format: LinesFormat,
    scans: usize,
}

impl<W: Write> LinesWriter<W> {
    /// Starts the output. Nothing is written before the first scan or
    /// [`LinesWriter::finish`], so an output abandoned before either is empty.
    pub fn new(out: W, format: LinesFormat) -> Self {
        LinesWriter { out, format, scans: 0 }
    }

    fn start(&mut self) -> std::io::Result<()> {
        match self.format {
            LinesFormat::Json => self.out.write_all(b"["),
            LinesFormat::JsonLines => Ok(()),
            LinesFormat::Csv => self.out.write_all(LINES_CSV_HEADER.as_bytes()),
        }
    }

    /// Writes one scan's lines.
    pub fn write(&mut self, scan: &ScanLines) -> std::io::Result<()> {
        let mut body = Vec::new();
        self.format.encode(scan, &mut body)?;
        self.write_encoded(&body)
    }

    /// Writes one scan's lines already encoded by [`LinesFormat::encode`]
    /// in this writer's format (so that scans can be encoded on several
    /// threads and written in order): the same bytes as
    /// [`LinesWriter::write`] of the scan.
    pub fn write_encoded(&mut self, body: &[u8]) -> std::io::Result<()> {
        if self.scans == 0 {
            self.start()?;
        }
        if self.format == LinesFormat::Json {
            self.out.write_all(if self.scans == 0 { b"\n" } else { b",\n" })?;
        }
        self.out.write_all(body)?;
        self.scans += 1;
        Ok(())
    }

    /// Scans written so far.
    pub fn scans(&self) -> usize {
        self.scans
    }

    /// The writer.
    pub fn get_ref(&self) -> &W {
        &self.out
    }

    /// Ends the output (`]` in JSON), flushes, and returns the writer.
    pub fn finish(mut self) -> std::io::Result<W> {
        if self.scans == 0 {
            self.start()?;
        }
        if self.format == LinesFormat::Json {
            self.out.write_all(b"\n]\n")?;
        }
        self.out.flush()?;
        Ok(self.out)
    }
}

/// Lines of many scans as JSON ([`LinesFormat::Json`]).
pub fn lines_to_json(scans: &[ScanLines]) -> String {
    lines_to_text(scans, LinesFormat::Json)
}

/// Lines of many scans as CSV, one row per line ([`LinesFormat::Csv`]).
pub fn lines_to_csv(scans: &[ScanLines]) -> String {
    lines_to_text(scans, LinesFormat::Csv)
}

fn lines_to_text(scans: &[ScanLines], format: LinesFormat) -> String {
    let write = || -> std::io::Result<Vec<u8>> {
        let mut w = LinesWriter::new(Vec::new(), format);
        for s in scans {
            w.write(s)?;
        }
        w.finish()
    };
    // Writing to memory cannot fail, and the records are valid UTF-8.
    String::from_utf8(write().unwrap_or_default()).unwrap_or_default()
}

fn write_csv_rows(out: &mut impl Write, scan: &ScanLines) -> std::io::Result<()> {
    let opt = |v: Option<u32>| v.map(|b| b.to_string()).unwrap_or_default();
    let optf =
        |v: Option<f64>| v.filter(|x| x.is_finite()).map(|x| x.to_string()).unwrap_or_default();
    for l in &scan.lines {
        writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            scan.scan,
            scan.position,
            optf(scan.stamp_s),
            l.alpha_rad,
            l.d_m,
            l.start[0],
            l.start[1],
            l.end[0],
            l.end[1],
            l.length_m,
            l.n_points,
            l.residual_std_m,
            opt(l.first_beam),
            opt(l.last_beam),
            optf(l.residual_ratio),
            optf(l.runs_z),
            optf(l.bow_m)
        )?;
    }
    Ok(())
}

/// Writes a map as JSON (the [`MapRecord`] form, loadable with [`read_map`]).
pub fn write_map_json(path: &Path, map: &LineMap) -> Result<(), IoError> {
    write_atomic(path, &map_json_bytes(path, map)?)
}

/// A map as the JSON of [`write_map_json`], for `path` (named in the error).
pub fn map_json_bytes(path: &Path, map: &LineMap) -> Result<Vec<u8>, IoError> {
    serde_json::to_vec_pretty(&MapRecord::from_map(map))
        .map_err(|e| IoError::parse(path, None, format!("cannot encode the map: {e}")))
}

/// Writes a map as CSV, one row per map line.
pub fn write_map_csv(path: &Path, map: &LineMap) -> Result<(), IoError> {
    write_atomic(path, map_csv_text(map).as_bytes())
}

/// A map as the CSV of [`write_map_csv`].
pub fn map_csv_text(map: &LineMap) -> String {
    let mut s = String::from(
        "id,alpha_rad,d_m,start_x,start_y,end_x,end_y,length_m,n_points,observations,residual_std_m\n",
    );
    for m in map.lines() {
        let l = &m.line;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{}",
            m.id.0,
            l.alpha(),
            l.d(),
            l.start().x,
            l.start().y,
            l.end().x,
            l.end().y,
            l.length(),
            l.n_points(),
            m.observations,
            l.residual_std()
        );
    }
    s
}

/// Reads a map written by [`write_map_json`].
pub fn read_map(path: &Path) -> Result<LineMap, IoError> {
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, e))?;
    let record: MapRecord = serde_json::from_str(&text)
        .map_err(|e| IoError::parse(path, Some(e.line()), e.to_string()))?;
    record.to_map().map_err(|e| IoError::Invalid {
        path: path.to_path_buf(),
        item: "config".into(),
        message: e.to_string(),
    })
}

/// A named series of poses; `None` where a record has no pose of that name.
pub type PoseSeries = (String, Vec<Option<pcaline_geometry::Pose2>>);

/// Named pose series from a trajectory file written by `pcaline run`
/// (`scans.json`) or `pcaline map` (`trajectory.json`): an array of objects
/// in which every field holding three numbers `[x, y, heading]` is a pose of
/// the series of that name (`true_pose`, `aided`, ...). Records without a
/// field leave a gap in its series. Series are in the order their names first
/// appear.
pub fn read_pose_series(path: &Path) -> Result<Vec<PoseSeries>, IoError> {
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, e))?;
    let value: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| IoError::parse(path, Some(e.line()), e.to_string()))?;
    let records = value
        .as_array()
        .ok_or_else(|| IoError::parse(path, Some(1), "expected an array of records"))?;
    let mut series: Vec<PoseSeries> = Vec::new();
    for (k, record) in records.iter().enumerate() {
        let Some(fields) = record.as_object() else {
            return Err(IoError::parse(path, None, format!("record {k} is not an object")));
        };
        for (name, v) in fields {
            let pose = v.as_array().filter(|a| a.len() == 3).and_then(|a| {
                let n: Vec<f64> = a.iter().filter_map(serde_json::Value::as_f64).collect();
                (n.len() == 3).then(|| pcaline_geometry::Pose2::new(n[0], n[1], n[2]))
            });
            let Some(pose) = pose else { continue };
            let index = match series.iter().position(|(s, _)| s == name) {
                Some(i) => i,
                None => {
                    series.push((name.clone(), Vec::new()));
                    series.len() - 1
                }
            };
            let s = &mut series[index].1;
            s.resize(k, None);
            s.push(Some(pose));
        }
    }
    for (_, s) in &mut series {
        s.resize(records.len(), None);
    }
    if series.is_empty() {
        return Err(IoError::parse(path, None, "no pose fields ([x, y, heading]) in the records"));
    }
    Ok(series)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan_lines(scan: usize, lines: usize) -> ScanLines {
        use pcaline_geometry::{Point2, Vector2};
        let line = LineSegment::through(
            Point2::new(1.0, 0.0),
            Vector2::new(0.0, 1.0),
            Point2::new(1.0, -1.0),
            Point2::new(1.0, 1.0),
        );
        ScanLines {
            scan,
            position: scan + 1,
            stamp_s: Some(scan as f64 * 0.025),
            noise: None,
            lines: (0..lines).map(|_| LineRecord::new(&line, Some((3, 12)))).collect(),
        }
    }

    #[test]
    fn streamed_lines_are_one_json_array_and_csv_rows() {
        assert_eq!(lines_to_json(&[]), "[\n]\n");
        let v: serde_json::Value = serde_json::from_str(&lines_to_json(&[])).unwrap();
        assert_eq!(v, serde_json::json!([]));
        let scans = [scan_lines(0, 2), scan_lines(1, 0), scan_lines(2, 1)];
        let text = lines_to_json(&scans);
        assert_eq!(text.lines().count(), 5, "one scan per line between the brackets");
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v.as_array().unwrap().len(), 3);
        assert_eq!(v[0]["lines"].as_array().unwrap().len(), 2);
        assert_eq!(v[2]["lines"][0]["first_beam"], 3);
        let csv = lines_to_csv(&scans);
        assert_eq!(csv.lines().count(), 1 + 3, "header and one row per line");
        assert!(csv.lines().nth(3).unwrap().starts_with("2,3,0.05,"));
        assert_eq!(lines_to_csv(&[]).lines().count(), 1);
        let mut w = LinesWriter::new(Vec::new(), LinesFormat::JsonLines);
        for s in &scans {
            w.write(s).unwrap();
        }
        let text = String::from_utf8(w.finish().unwrap()).unwrap();
        assert_eq!(text.lines().count(), 3);
        for (k, line) in text.lines().enumerate() {
            let v: serde_json::Value = serde_json::from_str(line).unwrap();
            assert_eq!(v["scan"], k);
        }
    }

    #[test]
    fn map_round_trip_and_csv() {
        let dir = std::env::temp_dir().join(format!("pcaline-map-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut map = LineMap::new(pcaline_mapping::MapConfig::default()).unwrap();
        let line = LineSegment::through(
            pcaline_geometry::Point2::new(3.0, 0.5),
            pcaline_geometry::Vector2::new(0.0, 1.0),
            pcaline_geometry::Point2::new(3.0, 0.0),
            pcaline_geometry::Point2::new(3.0, 1.0),
        );
        let pts: Vec<_> =
            (0..11).map(|i| pcaline_geometry::Point2::new(3.0, i as f64 * 0.1)).collect();
        let moments = pcaline_fitting::Moments::from_points(&pts);
        map.insert(&line, &moments);
        write_map_json(&dir.join("m.json"), &map).unwrap();
        let back = read_map(&dir.join("m.json")).unwrap();
        assert_eq!(back.len(), 1);
        write_map_csv(&dir.join("m.csv"), &map).unwrap();
        let csv = std::fs::read_to_string(dir.join("m.csv")).unwrap();
        assert_eq!(csv.lines().count(), 2);
        std::fs::write(dir.join("bad.json"), "{\n\"config\": 1}").unwrap();
        let e = read_map(&dir.join("bad.json")).unwrap_err().to_string();
        assert!(e.contains("bad.json:2"), "{e}");
    }
}
