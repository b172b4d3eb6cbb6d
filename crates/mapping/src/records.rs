//! Plain records of a map for saving and loading with serde (feature `serde`).

use crate::{Extremes, LineId, LineMap, LineStatus, MapConfig, MapLine};
use pcaline_fitting::Moments;
use pcaline_geometry::{ConfigError, LineSegment, Matrix2, Point2, Vector2};

/// One saved map line.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MapLineRecord {
    /// Identifier.
    pub id: u64,
    /// Normal angle, radians.
    pub alpha: f64,
    /// Distance from the origin, metres.
    pub d: f64,
    /// First endpoint `[x, y]`.
    pub start: [f64; 2],
    /// Last endpoint `[x, y]`.
    pub end: [f64; 2],
    /// Points absorbed.
    pub n_points: usize,
    /// Residual standard deviation, metres.
    pub residual_std_m: f64,
    /// Covariance of (alpha, d), row-major. JSON has no infinity or NaN:
    /// those are written as the strings `"inf"`, `"-inf"` and `"nan"`, so
    /// a line whose covariance is unbounded reads back as it was written.
    #[serde(with = "non_finite_as_text")]
    pub covariance: [f64; 4],
    /// Centroid of the absorbed points.
    pub centroid: [f64; 2],
    /// Centred second moments `[sxx, sxy, syy]`.
    pub scatter: [f64; 3],
    /// Detections merged.
    pub observations: u32,
    /// Unit normal towards the side the line was seen from (absent in
    /// files written before it existed).
    #[serde(default)]
    pub facing: Option<[f64; 2]>,
    /// What the line may be used for (absent in older files: confirmed).
    #[serde(default)]
    pub status: LineStatus,
    /// Distinct scans the line was seen in (absent in older files: its
    /// observations).
    #[serde(default)]
    pub scans_seen: Option<u32>,
    /// The scan it was last seen in.
    #[serde(default)]
    pub last_scan: u64,
    /// `sum n_points * residual_std²` of its observations, m² (absent in
    /// older files: its own scatter).
    #[serde(default)]
    pub observed_scatter: Option<f64>,
}

/// Floats that may be infinite or NaN, as numbers when finite and as the
/// strings `"inf"`, `"-inf"`, `"nan"` otherwise (serde_json would write
/// `null`, which does not read back).
mod non_finite_as_text {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    #[derive(Serialize, Deserialize)]
    #[serde(untagged)]
    enum Float {
        Number(f64),
        Text(String),
    }

    pub fn serialize<S: Serializer, const N: usize>(v: &[f64; N], s: S) -> Result<S::Ok, S::Error> {
        let items: Vec<Float> = v
            .iter()
            .map(|&x| match x {
                x if x.is_finite() => Float::Number(x),
                x if x.is_nan() => Float::Text("nan".into()),
                x if x > 0.0 => Float::Text("inf".into()),
                _ => Float::Text("-inf".into()),
            })
            .collect();
        items.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>, const N: usize>(
        d: D,
    ) -> Result<[f64; N], D::Error> {
        let items = Vec::<Float>::deserialize(d)?;
        let values: Vec<f64> = items
            .into_iter()
            .map(|f| match f {
                Float::Number(x) => Ok(x),
                Float::Text(t) => match t.as_str() {
                    "inf" => Ok(f64::INFINITY),
                    "-inf" => Ok(f64::NEG_INFINITY),
                    "nan" => Ok(f64::NAN),
                    other => Err(serde::de::Error::custom(format!(
                        "expected a number, \"inf\", \"-inf\" or \"nan\", found {other:?}"
                    ))),
                },
            })
            .collect::<Result<_, _>>()?;
        let n = values.len();
        values
            .try_into()
            .map_err(|_| serde::de::Error::custom(format!("expected {N} numbers, found {n}")))
    }
}

/// A saved map.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MapRecord {
    /// The map's configuration.
    pub config: MapConfig,
    /// Its lines.
    pub lines: Vec<MapLineRecord>,
}

impl MapRecord {
    /// The record of a map.
    pub fn from_map(map: &LineMap) -> Self {
        let lines = map
            .lines()
            .iter()
            .map(|m| {
                let l = &m.line;
                MapLineRecord {
                    id: m.id.0,
                    alpha: l.alpha(),
                    d: l.d(),
                    start: [l.start().x, l.start().y],
                    end: [l.end().x, l.end().y],
                    n_points: l.n_points(),
                    residual_std_m: l.residual_std(),
                    covariance: [
                        l.covariance()[(0, 0)],
                        l.covariance()[(0, 1)],
                        l.covariance()[(1, 0)],
                        l.covariance()[(1, 1)],
                    ],
                    centroid: [m.moments.mean.x, m.moments.mean.y],
                    scatter: [m.moments.sxx, m.moments.sxy, m.moments.syy],
                    observations: m.observations,
                    facing: m.facing.map(|f| [f.x, f.y]),
                    status: m.status,
                    scans_seen: Some(m.scans_seen),
                    last_scan: m.last_scan,
                    observed_scatter: Some(m.observed_scatter),
                }
            })
            .collect();
        MapRecord { config: *map.config(), lines }
    }

    /// The map of a record (its configuration is validated).
    pub fn to_map(&self) -> Result<LineMap, ConfigError> {
        let lines = self
            .lines
            .iter()
            .map(|r| {
                let start = Point2::new(r.start[0], r.start[1]);
                let end = Point2::new(r.end[0], r.end[1]);
                let line = LineSegment::from_hessian(
                    r.alpha,
                    r.d,
                    Point2::new(r.centroid[0], r.centroid[1]),
                    start,
                    end,
                )
                .with_statistics(
                    r.n_points,
                    r.residual_std_m,
                    Matrix2::new(
                        r.covariance[0],
                        r.covariance[1],
                        r.covariance[2],
                        r.covariance[3],
                    ),
                );
                let moments = Moments {
                    n: r.n_points,
                    mean: Point2::new(r.centroid[0], r.centroid[1]),
                    sxx: r.scatter[0],
                    sxy: r.scatter[1],
                    syy: r.scatter[2],
                };
                let extremes = Extremes {
                    low: start,
                    high: end,
                    pending_low: [None; 2],
                    pending_high: [None; 2],
                };
                let mut m = MapLine::new(LineId(r.id), line, moments, r.last_scan);
                m.observations = r.observations;
                m.extremes = extremes;
                m.facing = r.facing.map(|f| Vector2::new(f[0], f[1]));
                m.status = r.status;
                m.scans_seen = r.scans_seen.unwrap_or(r.observations);
                m.observed_scatter =
                    r.observed_scatter.unwrap_or(moments.orthogonal_scatter(&line.direction()));
                m
            })
            .collect();
        LineMap::from_lines(self.config, lines)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_fitting::line_from_moments;

    #[test]
    fn round_trip_through_json() {
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        for x in [1.0, 4.0] {
            let pts: Vec<_> = (0..10).map(|i| Point2::new(x, i as f64 * 0.1)).collect();
            let m = Moments::from_points(&pts);
            map.insert(&line_from_moments(&m, &pts[0], &pts[9]).unwrap(), &m);
        }
        let json = serde_json::to_string(&MapRecord::from_map(&map)).unwrap();
        let back: MapRecord = serde_json::from_str(&json).unwrap();
        let map2 = back.to_map().unwrap();
        assert_eq!(map2.lines(), map.lines());
        let pts: Vec<_> = (0..10).map(|i| Point2::new(4.01, 0.5 + i as f64 * 0.1)).collect();
        let m = Moments::from_points(&pts);
        let q = line_from_moments(&m, &pts[0], &pts[9]).unwrap();
        assert_eq!(map2.find_match(&q).map(|m| m.id), Some(LineId(1)));
    }

    /// A covariance that is not finite (unbounded, or NaN) reads back as
    /// written instead of failing on a `null`.
    #[test]
    fn non_finite_covariances_read_back() {
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        let pts: Vec<_> = (0..10).map(|i| Point2::new(1.0, i as f64 * 0.1)).collect();
        let m = Moments::from_points(&pts);
        map.insert(&line_from_moments(&m, &pts[0], &pts[9]).unwrap(), &m);
        let mut record = MapRecord::from_map(&map);
        record.lines[0].covariance = [f64::INFINITY, 0.0, f64::NEG_INFINITY, f64::NAN];
        let json = serde_json::to_string(&record).unwrap();
        assert!(json.contains(r#""covariance":["inf",0.0,"-inf","nan"]"#), "{json}");
        let back: MapRecord = serde_json::from_str(&json).unwrap();
        let c = back.lines[0].covariance;
        assert!(c[0] == f64::INFINITY && c[1] == 0.0 && c[2] == f64::NEG_INFINITY && c[3].is_nan());
        let bad = json.replace(r#""inf",0.0"#, r#""big",0.0"#);
        let e = serde_json::from_str::<MapRecord>(&bad).unwrap_err().to_string();
        assert!(e.contains("\"big\""), "{e}");
    }
}
