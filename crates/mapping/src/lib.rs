//! The incremental line map of pcaline (paper, section 2.1): each detected
//! line, placed in the world frame with the current pose estimate, is matched
//! against the map by orientation difference `d_alpha` and distance
//! `d_rho = d_d + d_C` (eq. 8-10); a match extends the map line's endpoints
//! (and, in the refined variant, refits it from every point it absorbed), no
//! match adds a new map line. A uniform grid over segment extents keeps the
//! cost of a match independent of the map's size.
//!
//! ```
//! use pcaline_fitting::{Moments, line_from_moments};
//! use pcaline_geometry::Point2;
//! use pcaline_mapping::{LineMap, MapConfig};
//!
//! let mut map = LineMap::new(MapConfig::paper()).unwrap();
//! for (y0, y1) in [(0.0, 1.0), (0.8, 2.0)] {
//!     let pts: Vec<_> = (0..=10).map(|i| Point2::new(3.0, y0 + (y1 - y0) * i as f64 / 10.0)).collect();
//!     let m = Moments::from_points(&pts);
//!     let line = line_from_moments(&m, &pts[0], &pts[10]).unwrap();
//!     map.insert(&line, &m);
//! }
//! assert_eq!(map.len(), 1); // the second piece matched the first
//! assert!((map.lines()[0].line.length() - 2.0).abs() < 1e-9);
//! ```

mod fast_hash;
mod grid;
mod lifecycle;
mod map;
mod metrics;
#[cfg(feature = "serde")]
mod records;

pub use lifecycle::{Lifecycle, LineStatus};
pub use map::{Extremes, LineId, LineMap, MapLine, Match, MatchGate};
pub use metrics::{CentroidTerm, LineDistance, line_distance};
#[cfg(feature = "serde")]
pub use records::{MapLineRecord, MapRecord};

use pcaline_geometry::ConfigError;

/// Configuration of a [`LineMap`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct MapConfig {
    /// Largest orientation difference of a match, radians (paper: 15°).
    pub max_d_alpha_rad: f64,
    /// Largest `d_rho` of a match, metres (paper: 1 m).
    pub max_d_rho_m: f64,
    /// The centroid term of `d_rho`.
    pub centroid_term: CentroidTerm,
    /// Largest distance of the new centroid from the map line (`d_d`) of a
    /// match, metres, in addition to the `d_rho` gate; `None` in the paper.
    /// Without it, a box 0.3 m in front of a wall matches the wall.
    pub max_offset_m: Option<f64>,
    /// Refit map lines from all absorbed points (the paper keeps a map line's
    /// parameters and only extends its endpoints).
    pub refine: bool,
    /// An extension of a map line's extent needs a second observation to
    /// confirm it (the paper keeps the longest extent ever seen, so one
    /// glitch extends a wall for good).
    pub robust_extent: bool,
    /// A detected line that matches nothing starts a new map line only when
    /// its orientation is known to this standard deviation (radians, from its
    /// covariance); `None` in the paper. A piece of a few centimetres at a
    /// corner is straight but points anywhere; it may still be absorbed by a
    /// map line it matches.
    pub max_new_alpha_std_rad: Option<f64>,
    /// A map line remembers the side it was seen from, and a line seen from
    /// the other side does not match it: the two faces of a thin wall stay
    /// two map lines instead of pulling the pose across the wall. Needs the
    /// viewpoint ([`LineMap::insert_observed`]); off in the paper (and in
    /// map files written before the option existed).
    #[cfg_attr(feature = "serde", serde(default))]
    pub sided: bool,
    /// A detected line merges into the map line it matches only within this
    /// gate; otherwise it starts a new map line. The matching gates allow for
    /// the pose error before aiding; merging happens after it. `None` in the
    /// paper (and in older map files).
    #[cfg_attr(feature = "serde", serde(default))]
    pub merge_gate: Option<MergeGate>,
    /// Tentative lines, confirmation, expiry, duplicate merging and the
    /// straightness check ([`Lifecycle`]); `None` in the paper, where every
    /// line is used at once and kept for ever (and in older map files).
    #[cfg_attr(feature = "serde", serde(default))]
    pub lifecycle: Option<Lifecycle>,
    /// Cell size of the spatial index, metres.
    pub grid_cell_m: f64,
}

/// When a matched line may merge into a map line (both endpoints of the
/// new line are tested).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct MergeGate {
    /// Largest distance of an endpoint from the map line, metres: a wall's
    /// 10 cm end face beside a box face must not bend the box's line.
    pub max_offset_m: f64,
    /// Largest gap along the line between the new line and the map line's
    /// extent, metres: collinear walls either side of a doorway stay two
    /// map lines instead of one line across the door.
    pub max_gap_m: f64,
}

impl MapConfig {
    /// The paper: 15° and 1 m, centroid distance (eq. 10), endpoints extended only.
    pub fn paper() -> Self {
        MapConfig {
            max_d_alpha_rad: 15f64.to_radians(),
            max_d_rho_m: 1.0,
            centroid_term: CentroidTerm::Centroid,
            max_offset_m: None,
            refine: false,
            robust_extent: false,
            max_new_alpha_std_rad: None,
            sided: false,
            merge_gate: None,
            lifecycle: None,
            grid_cell_m: 2.0,
        }
    }

    /// Checks every value.
    pub fn validate(&self) -> Result<(), ConfigError> {
        ConfigError::check(
            self.max_d_alpha_rad > 0.0 && self.max_d_alpha_rad < std::f64::consts::FRAC_PI_2,
            "map.max_d_alpha_rad",
            self.max_d_alpha_rad,
            "must be in (0, pi/2)",
        )?;
        ConfigError::positive("map.max_d_rho_m", self.max_d_rho_m)?;
        if let Some(a) = self.max_new_alpha_std_rad {
            ConfigError::check(a > 0.0, "map.max_new_alpha_std_rad", a, "must be > 0")?;
        }
        if let Some(g) = self.merge_gate {
            for (field, v) in [
                ("map.merge_gate.max_offset_m", g.max_offset_m),
                ("map.merge_gate.max_gap_m", g.max_gap_m),
            ] {
                ConfigError::non_negative(field, v)?;
            }
        }
        if let Some(o) = self.max_offset_m {
            ConfigError::positive("map.max_offset_m", o)?;
        }
        if let Some(l) = &self.lifecycle {
            l.validate()?;
        }
        ConfigError::check(
            self.grid_cell_m >= 1e-3 && self.grid_cell_m.is_finite(),
            "map.grid_cell_m",
            self.grid_cell_m,
            "must be finite and >= 0.001",
        )
    }
}

impl Default for MapConfig {
    /// Gates for an aided pose (5°, 0.15 m off the line, `d_rho` 1 m), the
    /// segment-gap centroid term (long walls stay one map line), refinement
    /// from all absorbed points, a robust extent, new map lines only from
    /// lines whose orientation is known to 1°, sided lines, and merges only of
    /// lines within 5 cm of a map line and 0.3 m of its ends, and the
    /// standard [`Lifecycle`] (confirmed from 3 scans, expired after 10).
    fn default() -> Self {
        MapConfig {
            max_d_alpha_rad: 5f64.to_radians(),
            max_d_rho_m: 1.0,
            centroid_term: CentroidTerm::SegmentGap,
            max_offset_m: Some(0.15),
            refine: true,
            robust_extent: true,
            max_new_alpha_std_rad: Some(1f64.to_radians()),
            sided: true,
            merge_gate: Some(MergeGate { max_offset_m: 0.05, max_gap_m: 0.3 }),
            lifecycle: Some(Lifecycle::standard()),
            grid_cell_m: 2.0,
        }
    }
}
