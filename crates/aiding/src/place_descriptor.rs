//! [`PlaceDescriptor`]: a summary of a local line set that does not change
//! when the set is moved or turned, so that loop closure can compare a
//! keyframe with older ones wherever the drifted graph has put them
//! ([`PlaceRecognitionConfig`]).
//!
//! The descriptor holds two histograms over the pairs of lines at least
//! [`PlaceRecognitionConfig::min_line_m`] long:
//!
//! - **parallel pairs** (directions within 10°): their separation across the
//!   lines (a corridor's width, a wall and the cabinet in front of it), in
//!   [`SEPARATION_BINS`] bins of [`SEPARATION_BIN_M`];
//! - **crossing pairs**: the angle between them, in bins of 10° from 10° to
//!   90°, by how far their intersection lies from the farther of the two
//!   segments (0 at a corner both lines reach), in bins of 1 m up to 3 m.
//!
//! A pair adds the shorter line's length, split linearly between its two
//! nearest bins so that a small change of a line moves weight smoothly
//! instead of from one bin to another. The descriptor is scaled to unit
//! norm; the similarity of two is their dot product, in `[0, 1]`.
//!
//! This is no verification: corridors of one width look alike everywhere.
//! It only chooses which far keyframes [`crate::align_lines`] examines.

use pcaline_geometry::{ConfigError, LineSegment, Point2, Vector2, point_segment_distance};

/// Bins of the parallel pairs' separation ...
pub const SEPARATION_BINS: usize = 32;
/// ... each this wide, metres (32 x 0.25 m: separations up to 8 m).
pub const SEPARATION_BIN_M: f64 = 0.25;
/// Two directions within this are parallel, radians (10°).
const PARALLEL_RAD: f64 = 0.174_532_925_199_432_95;
/// Bins of the crossing angle: 10° each, from 10° to 90°.
const ANGLE_BINS: usize = 8;
/// Bins of the intersection's distance from the segments: 1 m each.
const CORNER_BINS: usize = 4;
const BINS: usize = SEPARATION_BINS + ANGLE_BINS * CORNER_BINS;

/// Place recognition for loop closure ([`crate::LoopClosureConfig::place_recognition`]):
/// when the uncertainty of the current pose relative to an older keyframe
/// is larger than the local search covers
/// ([`crate::LoopClosureConfig::max_search_radius_m`]), older keyframes
/// beyond that radius but within the uncertainty are examined too, the
/// most similar first. Errors name fields under
/// `loop_closure.place_recognition.`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct PlaceRecognitionConfig {
    /// Lines shorter than this are left out of a descriptor, metres.
    pub min_line_m: f64,
    /// A far keyframe is examined when its descriptor's similarity with the
    /// current keyframe's is at least this, in `(0, 1]`.
    pub min_similarity: f64,
    /// Far keyframes examined per keyframe, the most similar first, one per
    /// stretch of [`crate::LoopClosureConfig::submap_keyframes`].
    pub max_candidates: usize,
}

impl PlaceRecognitionConfig {
    /// Lines of 0.5 m and more, similarity at least 0.8, three far
    /// keyframes examined per keyframe.
    pub const fn standard() -> Self {
        PlaceRecognitionConfig { min_line_m: 0.5, min_similarity: 0.8, max_candidates: 3 }
    }

    /// Checks every value; errors name `prefix.<field>`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        ConfigError::positive_fields(prefix, &[("min_line_m", self.min_line_m)])?;
        ConfigError::check_field(
            self.min_similarity > 0.0 && self.min_similarity <= 1.0,
            prefix,
            "min_similarity",
            self.min_similarity,
            "must be in (0, 1]",
        )?;
        ConfigError::check_field(
            (1..=100).contains(&self.max_candidates),
            prefix,
            "max_candidates",
            self.max_candidates as f64,
            "must be in 1..=100",
        )
    }
}

impl Default for PlaceRecognitionConfig {
    fn default() -> Self {
        Self::standard()
    }
}

/// A local line set's histogram of line pairs; see the module
/// documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaceDescriptor {
    bins: [f64; BINS],
}

impl PlaceDescriptor {
    /// The descriptor of `lines` (any frame: the result is the same in
    /// every frame). `None` when fewer than two lines are at least
    /// `min_line_m` long, or when their pairs add no weight (non-finite
    /// lines are left out).
    ///
    /// ```
    /// use pcaline_aiding::PlaceDescriptor;
    /// use pcaline_geometry::{LineSegment, Point2, Pose2};
    /// // Three walls of a room, and the same walls seen from elsewhere.
    /// let walls = [((0.0, 0.0), (4.0, 0.0)), ((4.0, 0.0), (4.0, 3.0)), ((0.0, 3.0), (4.0, 3.0))]
    ///     .map(|(a, b)| LineSegment::between(Point2::new(a.0, a.1), Point2::new(b.0, b.1)));
    /// let moved = walls.map(|l| l.transformed(&Pose2::new(7.0, -2.0, 1.2)));
    /// let a = PlaceDescriptor::of(&walls, 0.5).unwrap();
    /// let b = PlaceDescriptor::of(&moved, 0.5).unwrap();
    /// assert!(a.similarity(&b) > 0.999);
    /// assert!(PlaceDescriptor::of(&walls[..1], 0.5).is_none());
    /// ```
    pub fn of(lines: &[LineSegment], min_line_m: f64) -> Option<Self> {
        let kept: Vec<&LineSegment> = lines
            .iter()
            .filter(|l| {
                let finite = |p: Point2<f64>| p.coords.iter().all(|v| v.is_finite());
                l.length() >= min_line_m && finite(l.start()) && finite(l.end())
            })
            .collect();
        let mut bins = [0.0; BINS];
        for (i, a) in kept.iter().enumerate() {
            for b in &kept[i + 1..] {
                add_pair(&mut bins, a, b);
            }
        }
        let norm = bins.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return None;
        }
        bins.iter_mut().for_each(|v| *v /= norm);
        Some(PlaceDescriptor { bins })
    }

    /// The similarity of two descriptors: the dot product of their unit
    /// histograms, 1 for the same line set seen from anywhere, 0 when they
    /// share no bin.
    pub fn similarity(&self, other: &PlaceDescriptor) -> f64 {
        self.bins.iter().zip(&other.bins).map(|(a, b)| a * b).sum::<f64>().clamp(0.0, 1.0)
    }
}

/// Adds the pair `(a, b)` to `bins`.
fn add_pair(bins: &mut [f64; BINS], a: &LineSegment, b: &LineSegment) {
    let (da, db) = (a.end() - a.start(), b.end() - b.start());
    let (la, lb) = (da.norm(), db.norm());
    let weight = la.min(lb);
    let cross = (da.x * db.y - da.y * db.x) / (la * lb);
    let angle = cross.abs().clamp(0.0, 1.0).asin();
    if angle < PARALLEL_RAD {
        // The separation: b's midpoint from a's infinite line.
        let normal = Vector2::new(-da.y, da.x) / la;
        let mid = Point2::from((b.start().coords + b.end().coords) * 0.5);
        let separation = (mid - a.start()).dot(&normal).abs();
        spread(&mut bins[..SEPARATION_BINS], separation / SEPARATION_BIN_M, weight);
        return;
    }
    // The intersection of the two infinite lines, and how far it lies
    // from the farther segment.
    let denominator = da.x * db.y - da.y * db.x;
    let w = b.start() - a.start();
    let t = (w.x * db.y - w.y * db.x) / denominator;
    let corner = a.start() + da * t;
    let away = point_segment_distance(&corner, &a.start(), &a.end()).max(point_segment_distance(
        &corner,
        &b.start(),
        &b.end(),
    ));
    let angle_bin = (angle.to_degrees() - 10.0) / 10.0 - 0.5;
    let corner_bin = away.min(CORNER_BINS as f64 - 1.0);
    // Bilinear: the angle's two nearest bins by the corner's two.
    let (a0, a1, fa) = neighbours(angle_bin, ANGLE_BINS);
    let (c0, c1, fc) = neighbours(corner_bin, CORNER_BINS);
    let crossing = &mut bins[SEPARATION_BINS..];
    for (ai, wa) in [(a0, 1.0 - fa), (a1, fa)] {
        for (ci, wc) in [(c0, 1.0 - fc), (c1, fc)] {
            crossing[ai * CORNER_BINS + ci] += weight * wa * wc;
        }
    }
}

/// Adds `weight` at fractional bin `x` of `bins`, split between its two
/// nearest bins (clamped at the ends); nothing when `x` is not finite.
fn spread(bins: &mut [f64], x: f64, weight: f64) {
    if !x.is_finite() || !weight.is_finite() {
        return;
    }
    let (i0, i1, f) = neighbours(x, bins.len());
    bins[i0] += weight * (1.0 - f);
    bins[i1] += weight * f;
}

/// The two bins around fractional bin `x` (centres at integers) of `n`,
/// and the second's share; clamped to the ends, 0 when `x` is not finite.
fn neighbours(x: f64, n: usize) -> (usize, usize, f64) {
    let x = if x.is_finite() { x.clamp(0.0, (n - 1) as f64) } else { 0.0 };
    let i0 = x.floor() as usize;
    let i1 = (i0 + 1).min(n - 1);
    (i0, i1, x - i0 as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::Pose2;

    fn segment(a: (f64, f64), b: (f64, f64)) -> LineSegment {
        LineSegment::between(Point2::new(a.0, a.1), Point2::new(b.0, b.1))
    }

    /// An L-shaped room corner with a pillar, and a straight corridor.
    fn corner_room() -> Vec<LineSegment> {
        vec![
            segment((0.0, 0.0), (5.0, 0.0)),
            segment((0.0, 0.0), (0.0, 4.0)),
            segment((2.0, 2.0), (2.6, 2.0)),
            segment((2.6, 2.0), (2.6, 2.55)),
        ]
    }

    fn corridor(width: f64) -> Vec<LineSegment> {
        vec![segment((0.0, 0.0), (8.0, 0.0)), segment((0.0, width), (8.0, width))]
    }

    #[test]
    fn a_moved_set_has_the_same_descriptor() {
        let room = corner_room();
        let a = PlaceDescriptor::of(&room, 0.5).unwrap();
        for pose in [Pose2::new(3.0, -1.0, 2.5), Pose2::new(-40.0, 12.0, -0.3)] {
            let moved: Vec<LineSegment> = room.iter().map(|l| l.transformed(&pose)).collect();
            let b = PlaceDescriptor::of(&moved, 0.5).unwrap();
            assert!(a.similarity(&b) > 0.999_999, "{}", a.similarity(&b));
        }
    }

    #[test]
    fn different_places_are_dissimilar_and_short_lines_are_left_out() {
        let room = PlaceDescriptor::of(&corner_room(), 0.5).unwrap();
        let narrow = PlaceDescriptor::of(&corridor(2.0), 0.5).unwrap();
        let wide = PlaceDescriptor::of(&corridor(4.0), 0.5).unwrap();
        // The room's parallel pairs are 2.0 m (a pillar face and a wall)
        // and 2.6 m apart: like the 2 m corridor in part, not the 4 m one.
        assert!(room.similarity(&wide) < 0.01, "{}", room.similarity(&wide));
        assert!(room.similarity(&narrow) < 0.2, "{}", room.similarity(&narrow));
        assert!(narrow.similarity(&wide) < 0.1, "{}", narrow.similarity(&wide));
        // A corridor 5 cm wider is almost the same place.
        let slightly = PlaceDescriptor::of(&corridor(2.05), 0.5).unwrap();
        assert!(narrow.similarity(&slightly) > 0.9, "{}", narrow.similarity(&slightly));
        // The pillar's faces (0.6 and 0.55 m) are left out at 0.7 m: only
        // the corner's pair is left, one bin.
        let without = PlaceDescriptor::of(&corner_room(), 0.7).unwrap();
        assert_eq!(without.bins.iter().filter(|v| **v > 0.0).count(), 1);
    }

    #[test]
    fn degenerate_sets_have_no_descriptor() {
        assert!(PlaceDescriptor::of(&[], 0.5).is_none());
        assert!(PlaceDescriptor::of(&corridor(2.0)[..1], 0.5).is_none());
        let nan = segment((f64::NAN, 0.0), (1.0, 0.0));
        assert!(PlaceDescriptor::of(&[nan, segment((0.0, 0.0), (0.0, 2.0))], 0.5).is_none());
        // Two copies of one wall: separation 0, a valid descriptor.
        let wall = segment((0.0, 0.0), (3.0, 0.0));
        assert!(PlaceDescriptor::of(&[wall, wall], 0.5).is_some());
    }

    #[test]
    fn config_errors_name_the_field() {
        let mut c = PlaceRecognitionConfig::standard();
        c.min_similarity = 1.5;
        let e = c.validate("loop_closure.place_recognition").unwrap_err().to_string();
        assert!(e.contains("loop_closure.place_recognition.min_similarity"), "{e}");
        c = PlaceRecognitionConfig::standard();
        c.max_candidates = 0;
        assert!(c.validate("p").is_err());
    }
}
