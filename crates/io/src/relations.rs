//! Relation files (Kuemmerle et al. 2009): `t1 t2 x y z roll pitch yaw`, the
//! pose at `t2` expressed in the frame of `t1`.

use crate::IoError;
use pcaline_geometry::Pose2;
use std::io::BufRead;
use std::path::Path;

/// One ground-truth relation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relation {
    /// Time of the first pose, seconds.
    pub t1_s: f64,
    /// Time of the second pose, seconds.
    pub t2_s: f64,
    /// The second pose in the frame of the first (x, y, yaw).
    pub relative: Pose2,
}

/// Reads a relations file (small: read whole). Blank lines and `#` comments
/// are skipped; errors name the line.
pub fn read_relations(path: &Path) -> Result<Vec<Relation>, IoError> {
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let mut out = Vec::new();
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
            .map_err(|_| IoError::parse(path, Some(i + 1), format!("not 8 numbers: {t:?}")))?;
        if v.len() != 8 {
            return Err(IoError::parse(
                path,
                Some(i + 1),
                format!("{} fields, expected 8", v.len()),
            ));
        }
        out.push(Relation { t1_s: v[0], t2_s: v[1], relative: Pose2::new(v[2], v[3], v[7]) });
    }
    Ok(out)
}
