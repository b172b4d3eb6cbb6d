//! A log read in chunks that are parsed later, on any thread:
//! [`read_log_chunks`] reads in order and does as little as it can (in a
//! CARMEN log, only finding the ends of lines), and [`LogChunk::parse`] does
//! the rest. Parsing a text log costs about as much as detecting its lines;
//! split this way, it runs on every core instead of on the one thread that
//! reads.
//!
//! Invariant: the chunks' records, parsed in order, are [`read_log`]'s
//! records, with its checks and its errors at the same lines.
//!
//! [`read_log`]: crate::read_log

use crate::carmen::CarmenReader;
use crate::log::{LogFormat, LogOptions, check_record_in, read_log};
use crate::{CarmenOptions, IoError, LogRecord, RawLaserScans};
use std::io::BufRead;
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Arc;

/// A chunk of CARMEN text ends at this many bytes even with fewer scans,
/// so that a log of other messages does not grow it without bound.
const MAX_CHUNK_BYTES: usize = 4 << 20;

/// Consecutive records of a log, read but perhaps not yet parsed.
#[derive(Debug)]
pub struct LogChunk {
    content: Content,
}

#[derive(Debug)]
enum Content {
    /// Records already parsed and checked (the binary, JSON and CSV formats).
    Records { records: Vec<LogRecord>, scans: usize },
    /// Whole lines of the CARMEN log at `path`, the first of them line
    /// `first_line` (1-based), `scans` of them scan messages, to be read
    /// with `options`.
    CarmenLines {
        path: Arc<Path>,
        options: CarmenOptions,
        first_line: usize,
        scans: usize,
        text: Vec<u8>,
    },
}

impl LogChunk {
    /// The scans the chunk holds. Exact when it parses; a chunk that fails
    /// to parse ends the log at its error, so what follows does not count.
    pub fn scans(&self) -> usize {
        match &self.content {
            Content::Records { scans, .. } | Content::CarmenLines { scans, .. } => *scans,
        }
    }

    /// Gives the chunk's records to `visit` in log order until it breaks.
    /// Returns the error [`read_log`](crate::read_log) returns at the first
    /// record that fails (to parse, or [`check_record`](crate::check_record)),
    /// after every record before it.
    pub fn parse(self, mut visit: impl FnMut(LogRecord) -> ControlFlow<()>) -> Result<(), IoError> {
        match self.content {
            Content::Records { records, .. } => {
                for record in records {
                    if visit(record).is_break() {
                        break;
                    }
                }
            }
            Content::CarmenLines { path, options, first_line, text, .. } => {
                let lines =
                    CarmenReader::new(&text[..], &path, options).starting_at_line(first_line);
                for record in lines {
                    let record = record?;
                    check_record_in(&path, LogFormat::Carmen, &record)?;
                    if visit(record).is_break() {
                        break;
                    }
                }
            }
        }
        Ok(())
    }
}

/// Reads the log at `path` in order, in chunks of `scans_per_chunk` scans
/// (the last may hold fewer, and a CARMEN chunk ends early at a few MB),
/// calling `visit` with each until it breaks. A CARMEN log is only split
/// into lines here; the other formats are parsed as [`read_log`] parses
/// them. An error that stops the read comes after the chunk of every record
/// before it. Parse each chunk with [`LogChunk::parse`], on any thread: it
/// carries the file's name and the options for its reading and errors.
///
/// [`read_log`]: crate::read_log
pub fn read_log_chunks(
    path: &Path,
    options: &LogOptions,
    scans_per_chunk: usize,
    mut visit: impl FnMut(LogChunk) -> ControlFlow<()>,
) -> Result<(), IoError> {
    let scans_per_chunk = scans_per_chunk.max(1);
    let format = match options.format {
        Some(f) => f,
        None => LogFormat::detect(path)?,
    };
    if format == LogFormat::Carmen {
        return read_carmen_chunks(path, options.carmen, scans_per_chunk, visit);
    }
    let (mut records, mut scans, mut stopped) = (Vec::new(), 0, false);
    let read = read_log(path, options, |record| {
        scans += usize::from(matches!(record, LogRecord::Scan(_)));
        records.push(record);
        if scans == scans_per_chunk {
            let records = std::mem::take(&mut records);
            let chunk = LogChunk { content: Content::Records { records, scans } };
            scans = 0;
            if visit(chunk).is_break() {
                stopped = true;
                return ControlFlow::Break(());
            }
        }
        ControlFlow::Continue(())
    });
    if !stopped && !records.is_empty() {
        let _ = visit(LogChunk { content: Content::Records { records, scans } });
    }
    read.map(|_| ())
}

/// [`read_log_chunks`] for a CARMEN log: lines, counting the scan messages.
fn read_carmen_chunks(
    path: &Path,
    options: CarmenOptions,
    scans_per_chunk: usize,
    mut visit: impl FnMut(LogChunk) -> ControlFlow<()>,
) -> Result<(), IoError> {
    // Decided once for the whole log: each chunk's reader sees only its lines.
    let options = crate::carmen::resolve_raw_laser(path, options)?;
    let raw = options.raw_laser == RawLaserScans::Always;
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let shared_path: Arc<Path> = path.into();
    let mut input = std::io::BufReader::with_capacity(1 << 16, file);
    let mut g = Gathered { first_line: 1, lines: 0, scans: 0, text: Vec::new() };
    loop {
        let start = g.text.len();
        let read = match input.read_until(b'\n', &mut g.text) {
            Ok(read) => read,
            Err(e) => {
                // The lines before the failed read come first.
                g.text.truncate(start);
                if g.lines > 0 {
                    let _ = visit(g.take(&shared_path, options));
                }
                return Err(IoError::io(path, e));
            }
        };
        if read == 0 {
            break;
        }
        g.lines += 1;
        g.scans += usize::from(is_scan_line(&g.text[start..], raw));
        if (g.scans == scans_per_chunk || g.text.len() >= MAX_CHUNK_BYTES)
            && visit(g.take(&shared_path, options)).is_break()
        {
            return Ok(());
        }
    }
    if g.lines > 0 {
        let _ = visit(g.take(&shared_path, options));
    }
    Ok(())
}

/// The lines of a CARMEN log read since the last chunk.
struct Gathered {
    /// The first one's line number, 1-based.
    first_line: usize,
    /// How many.
    lines: usize,
    /// How many are scan messages.
    scans: usize,
    text: Vec<u8>,
}

impl Gathered {
    /// The lines as a chunk of the log at `path`; the next lines gathered
    /// follow them.
    fn take(&mut self, path: &Arc<Path>, options: CarmenOptions) -> LogChunk {
        let chunk = LogChunk {
            content: Content::CarmenLines {
                path: Arc::clone(path),
                options,
                first_line: self.first_line,
                scans: self.scans,
                text: std::mem::take(&mut self.text),
            },
        };
        self.first_line += self.lines;
        (self.lines, self.scans) = (0, 0);
        chunk
    }
}

/// Whether a CARMEN line is a scan message: its first field is `FLASER` or
/// `ROBOTLASER1`, or `RAWLASER1` when `raw` ([`RawLaserScans::Always`]),
/// the messages [`CarmenReader`] reads as scans.
fn is_scan_line(line: &[u8], raw: bool) -> bool {
    match crate::carmen::first_field(line) {
        b"FLASER" | b"ROBOTLASER1" => true,
        b"RAWLASER1" => raw,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file in the system's temporary folder, removed when dropped.
    struct TempFile(std::path::PathBuf);

    impl Drop for TempFile {
        fn drop(&mut self) {
            let _ = std::fs::remove_file(&self.0);
        }
    }

    fn temp(name: &str, bytes: &[u8]) -> TempFile {
        let path =
            std::env::temp_dir().join(format!("pcaline-chunks-{}-{name}", std::process::id()));
        std::fs::write(&path, bytes).unwrap();
        TempFile(path)
    }

    /// Every record of every chunk, in order, and the error that ended the
    /// read or a chunk's parse, as text.
    fn records_in_chunks(path: &Path, per_chunk: usize) -> (Vec<String>, Option<String>, usize) {
        let options = LogOptions::default();
        let mut chunks = Vec::new();
        let read = read_log_chunks(path, &options, per_chunk, |c| {
            chunks.push(c);
            ControlFlow::Continue(())
        });
        let n_chunks = chunks.len();
        let mut records = Vec::new();
        for chunk in chunks {
            let scans = chunk.scans();
            let before = records.len();
            let parsed = chunk.parse(|r| {
                records.push(format!("{r:?}"));
                ControlFlow::Continue(())
            });
            if let Err(e) = parsed {
                return (records, Some(e.to_string()), n_chunks);
            }
            let got = records[before..].iter().filter(|r| r.starts_with("Scan")).count();
            assert_eq!(got, scans, "a chunk's scan count");
        }
        (records, read.err().map(|e| e.to_string()), n_chunks)
    }

    /// Every record and error of [`read_log`], as text.
    fn records_in_order(path: &Path) -> (Vec<String>, Option<String>) {
        let mut records = Vec::new();
        let read = read_log(path, &LogOptions::default(), |r| {
            records.push(format!("{r:?}"));
            ControlFlow::Continue(())
        });
        (records, read.err().map(|e| e.to_string()))
    }

    fn carmen_log(scans: usize, bad_line: Option<(usize, &str)>) -> String {
        let mut text = String::from("# a comment\nPARAM robot_width 0.5\n");
        for k in 0..scans {
            let ranges = format!(" {}", 1 + k % 7).repeat(180);
            text.push_str(&format!("ODOM {k} 0 0 0 0 0 {k} host {k}\n"));
            text.push_str(&format!("FLASER 180{ranges} 0 0 0 0 0 0 {k} host {k}\n"));
        }
        if let Some((at, line)) = bad_line {
            let mut lines: Vec<&str> = text.lines().collect();
            lines[at] = line;
            text = lines.join("\n") + "\n";
        }
        text
    }

    /// The chunks hold read_log's records, in order, with the same line
    /// numbers, whatever the chunk size.
    #[test]
    fn chunks_parse_to_the_records_of_a_sequential_read() {
        let log = temp("ok.clf", carmen_log(50, None).as_bytes());
        let want = records_in_order(&log.0);
        assert_eq!(want.0.len(), 100);
        for per_chunk in [1, 7, 50, 1000] {
            let (records, error, chunks) = records_in_chunks(&log.0, per_chunk);
            assert_eq!((records, error), want.clone(), "{per_chunk} scans per chunk");
            assert_eq!(chunks, 50usize.div_ceil(per_chunk), "{per_chunk} scans per chunk");
        }
    }

    /// A bad line in a later chunk, a pose out of bounds and bytes that are
    /// not text: the error of a sequential read, after the same records.
    #[test]
    fn errors_come_at_the_line_a_sequential_read_reports() {
        let range = format!(" 1{}", " 2".repeat(179));
        let far = format!("FLASER 180{range} 1e12 0 0 0 0 0 3 host 3");
        let cases: [(&str, Vec<u8>); 3] = [
            ("bad.clf", carmen_log(30, Some((41, "FLASER 180 1 x"))).into_bytes()),
            ("far.clf", carmen_log(30, Some((23, &far))).into_bytes()),
            ("binary.clf", {
                let mut b = carmen_log(30, None).into_bytes();
                let at = b.len() / 2;
                b[at] = 0xff;
                b
            }),
        ];
        for (name, bytes) in cases {
            let log = temp(name, &bytes);
            let want = records_in_order(&log.0);
            assert!(want.1.is_some(), "{name}");
            let (records, error, _) = records_in_chunks(&log.0, 4);
            assert_eq!((records, error), want, "{name}");
        }
    }

    /// Only FLASER and ROBOTLASER1 lines count as scans, and RAWLASER1
    /// lines when the log is read with them.
    #[test]
    fn scan_lines_are_the_scan_messages() {
        for raw in [false, true] {
            assert!(is_scan_line(b"FLASER 180 1 2\n", raw));
            assert!(is_scan_line(b"  ROBOTLASER1\t0 1\n", raw));
            assert_eq!(is_scan_line(b"RAWLASER1 0 1\n", raw), raw);
            assert!(!is_scan_line(b"RAWLASER2 0 1\n", raw));
            assert!(!is_scan_line(b"FLASERX 180\n", raw));
            assert!(!is_scan_line(b"# FLASER 180\n", raw));
            assert!(!is_scan_line(b"ODOM 1 2 3\n", raw));
            assert!(!is_scan_line(b"\n", raw));
        }
    }

    /// A log of RAWLASER1 lines alone comes in chunks of its scans, as
    /// [`read_log`] reads it.
    #[test]
    fn rawlaser_logs_come_in_chunks_of_their_scans() {
        let mut line = String::from("RAWLASER1 0 -1.5708 3.14159 0.0174533 81.9 0.01 0 3");
        line.push_str(" 1.5 2.5 3.5 0 12.5 host 12.6\n");
        let text = format!("ODOM 1 2 0.1 0 0 0 3.0 host 3.0\n{}", line.repeat(9));
        let log = temp("raw.clf", text.as_bytes());
        let (chunked, error, n_chunks) = records_in_chunks(&log.0, 4);
        assert_eq!(error, None);
        assert_eq!(n_chunks, 3);
        assert_eq!(chunked.iter().filter(|r| r.starts_with("Scan")).count(), 9);
        assert_eq!((chunked, None), records_in_order(&log.0));
    }

    /// The other formats come as parsed records, in chunks of the asked size.
    #[test]
    fn other_formats_come_parsed() {
        let mut text =
            "stamp_s,angle_min,angle_increment,range_min,range_max,r0,r1,r2\n".to_string();
        for k in 0..10 {
            text.push_str(&format!("{k},-1.0,0.1,0.0,30.0,1.0,1.0,1.0\n"));
        }
        let log = temp("scans.csv", text.as_bytes());
        let want = records_in_order(&log.0);
        let (records, error, chunks) = records_in_chunks(&log.0, 3);
        assert!(want.1.is_none(), "{:?}", want.1);
        assert_eq!((records, error), want);
        assert_eq!(chunks, 4);
    }
}
