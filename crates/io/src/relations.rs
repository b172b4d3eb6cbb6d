//! Relation files (Kuemmerle et al. 2009): `t1 t2 x y z roll pitch yaw`, the
//! pose at `t2` expressed in the frame of `t1`.

use crate::IoError;
use pcaline_geometry::{Pose2, Relation};
use std::io::BufRead;
use std::path::Path;

/// Calls `each` with the 1-based line number and the numbers of every line
/// of `path` that is not blank or a `#` comment, checking there are `fields`
/// of them.
fn numeric_lines(
    path: &Path,
    fields: usize,
    mut each: impl FnMut(usize, &[f64]) -> Result<(), IoError>,
) -> Result<(), IoError> {
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    for (i, line) in std::io::BufReader::new(file).lines().enumerate() {
        let line = line.map_err(|e| IoError::parse(path, Some(i + 1), format!("not text: {e}")))?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let v: Vec<f64> = t
            .split_ascii_whitespace()
            .map(|s| s.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                IoError::parse(path, Some(i + 1), format!("not {fields} numbers: {t:?}"))
            })?;
        if v.len() != fields {
            return Err(IoError::parse(
                path,
                Some(i + 1),
                format!("{} fields, expected {fields}", v.len()),
            ));
        }
        each(i + 1, &v)?;
    }
    Ok(())
}

/// Reads a relations file (small: read whole). Blank lines and `#` comments
/// are skipped; errors name the line.
pub fn read_relations(path: &Path) -> Result<Vec<Relation>, IoError> {
    let mut out = Vec::new();
    numeric_lines(path, 8, |_, v| {
        out.push(Relation { t1_s: v[0], t2_s: v[1], relative: Pose2::new(v[2], v[3], v[7]) });
        Ok(())
    })?;
    Ok(out)
}

/// One line of a pairing file (`csail_corrected_to_raw_pairs.txt`): a scan of
/// a corrected log and the raw log's scan with identical ranges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanPair {
    /// Index of the scan in the corrected log, from 0.
    pub corrected_index: usize,
    /// Index of the scan in the raw log, from 0.
    pub raw_index: usize,
    /// The raw log's odometry pose of the scan.
    pub raw_pose: Pose2,
    /// The corrected pose of the scan.
    pub corrected_pose: Pose2,
}

/// Reads a pairing file: `corrected_idx raw_idx raw_ipc_timestamp raw_x raw_y
/// raw_theta corrected_x corrected_y corrected_theta` per line, `#` comments.
pub fn read_scan_pairs(path: &Path) -> Result<Vec<ScanPair>, IoError> {
    let mut out = Vec::new();
    numeric_lines(path, 9, |line, v| {
        if v[0] < 0.0 || v[1] < 0.0 || v[0].fract() != 0.0 || v[1].fract() != 0.0 {
            return Err(IoError::parse(path, Some(line), "scan indices must be whole and >= 0"));
        }
        out.push(ScanPair {
            corrected_index: v[0] as usize,
            raw_index: v[1] as usize,
            raw_pose: Pose2::new(v[3], v[4], v[5]),
            corrected_pose: Pose2::new(v[6], v[7], v[8]),
        });
        Ok(())
    })?;
    Ok(out)
}
