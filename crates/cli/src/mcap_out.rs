//! `--mcap OUT.mcap` on `detect`, `map` and `run`: the Foxglove MCAP file of
//! a whole log (pcaline_io::FoxgloveMcapWriter), with the log's clock, and
//! the line map republished at most once a second of log time.

use anyhow::Result;
use pcaline::LineSegment;
use pcaline::mapping::LineMap;
use pcaline_io::{FoxgloveMcapWriter, PoseKind, Stamp};
use std::path::{Path, PathBuf};

/// Spacing of scans that have no usable stamp: the UTM-30LX-EW's 40 Hz.
const FALLBACK_PERIOD_NS: u64 = 25_000_000;
/// The map is written at most this often, in log time (and once at the end).
const MAP_PERIOD_NS: u64 = 1_000_000_000;

/// An MCAP file being written, scan by scan.
pub struct McapOut {
    path: PathBuf,
    writer: FoxgloveMcapWriter,
    last: Option<Stamp>,
    last_map: Option<Stamp>,
    unstamped: usize,
}

impl McapOut {
    /// Starts `path` (`--mcap`); `None` when the option is absent. The error
    /// names the path, and nothing is left behind.
    pub fn create(path: Option<&Path>) -> Result<Option<Self>> {
        let Some(path) = path else { return Ok(None) };
        Ok(Some(McapOut {
            path: path.to_path_buf(),
            writer: FoxgloveMcapWriter::create(path)?,
            last: None,
            last_map: None,
            unstamped: 0,
        }))
    }

    /// The time of a scan: its stamp when it has a usable one (finite, not
    /// negative), else 25 ms after the last scan's.
    pub fn stamp(&mut self, stamp_s: Option<f64>) -> Stamp {
        let stamp = match stamp_s.and_then(Stamp::from_seconds) {
            Some(s) => s,
            None => {
                self.unstamped += 1;
                Stamp(self.last.map_or(0, |s| s.0.saturating_add(FALLBACK_PERIOD_NS)))
            }
        };
        self.last = Some(stamp);
        stamp
    }

    /// One scan: the scan, its lines (sensor frame) and the poses given.
    pub fn scan<'a>(
        &mut self,
        stamp: Stamp,
        scan: &pcaline::Scan,
        lines: impl IntoIterator<Item = &'a LineSegment>,
        poses: &[(PoseKind, Option<pcaline::Pose2>)],
    ) -> Result<()> {
        for (kind, pose) in poses {
            if let Some(p) = pose {
                self.writer.write_pose(stamp, *kind, p)?;
            }
        }
        self.writer.write_scan(stamp, scan)?;
        self.writer.write_lines(stamp, lines)?;
        Ok(())
    }

    /// The map, if a second of log time has passed since it was last
    /// written (or it never was).
    pub fn map_if_due(&mut self, stamp: Stamp, map: &LineMap) -> Result<()> {
        let due = self.last_map.is_none_or(|t| stamp.0 >= t.0.saturating_add(MAP_PERIOD_NS));
        if due {
            self.writer.write_map(stamp, map)?;
            self.last_map = Some(stamp);
        }
        Ok(())
    }

    /// The map as it ends, at the last scan's time.
    pub fn final_map(&mut self, map: &LineMap) -> Result<()> {
        self.writer.write_map(self.last.unwrap_or_default(), map)?;
        Ok(())
    }

    /// The true walls of a simulated scene, at time 0.
    pub fn walls(&mut self, walls: &[[[f64; 2]; 2]]) -> Result<()> {
        self.writer.write_walls(Stamp(0), walls)?;
        Ok(())
    }

    /// Ends the file and renames it into place; says on stderr what it holds
    /// unless `quiet`.
    pub fn finish(self, quiet: bool) -> Result<PathBuf> {
        let counts = self.writer.finish()?;
        if !quiet {
            let topics: Vec<String> = counts.iter().map(|(t, n)| format!("{t} {n}")).collect();
            eprintln!("{}: {}", self.path.display(), topics.join(", "));
            if self.unstamped > 0 {
                eprintln!(
                    "{}: {} scans without a usable stamp were placed 25 ms after the scan before",
                    self.path.display(),
                    self.unstamped
                );
            }
        }
        Ok(self.path)
    }
}
