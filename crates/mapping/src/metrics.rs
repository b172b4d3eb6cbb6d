//! The matching metrics of the paper's section 2.1: the orientation difference
//! `d_alpha` and the distance `d_rho = d_d + d_C` (eq. 8-10), in Hessian form.

use pcaline_geometry::{LineSegment, Point2, line_angle_diff};

/// Which centroid term `d_C` enters `d_rho`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum CentroidTerm {
    /// Eq. 10: the distance between the two centroids. A long map line's
    /// centroid is far from a new observation of one of its ends, so long
    /// walls fragment into several map lines.
    Centroid,
    /// The distance from the new line's centroid to the map *segment* (zero
    /// when it projects inside the segment): the same as eq. 10 for short
    /// lines, and it lets any part of a long wall match it.
    SegmentGap,
}

/// The two metrics between a map line and a new line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineDistance {
    /// Orientation difference `map - new`, radians, wrapped to (-pi/2, pi/2].
    pub d_alpha: f64,
    /// `d_rho = d_d + d_C`, metres (eq. 8).
    pub d_rho: f64,
}

/// The metrics between `map` and `new` (both in the world frame).
///
/// `d_d` is `|n_map . C_new - d_map|`: the distance of the new centroid from
/// the map line. For parallel lines with the same normal it equals the
/// paper's `|d_L1 - d_L2|` (eq. 9), and unlike eq. 9 it is defined for
/// vertical lines and does not jump when a line near the origin flips its
/// normal.
///
/// ```
/// use pcaline_geometry::{LineSegment, Point2, Vector2};
/// use pcaline_mapping::{CentroidTerm, line_distance};
/// let wall = |x: f64, y0: f64, y1: f64| LineSegment::through(
///     Point2::new(x, (y0 + y1) / 2.0), Vector2::new(0.0, 1.0), Point2::new(x, y0), Point2::new(x, y1));
/// let m = line_distance(&wall(3.0, 0.0, 10.0), &wall(3.1, 8.0, 9.0), CentroidTerm::SegmentGap);
/// assert!((m.d_rho - 0.1).abs() < 1e-12 && m.d_alpha.abs() < 1e-12);
/// let m = line_distance(&wall(3.0, 0.0, 10.0), &wall(3.1, 8.0, 9.0), CentroidTerm::Centroid);
/// assert!((m.d_rho - (0.1 + (0.1f64.powi(2) + 3.5f64.powi(2)).sqrt())).abs() < 1e-12);
/// ```
pub fn line_distance(map: &LineSegment, new: &LineSegment, term: CentroidTerm) -> LineDistance {
    let d_alpha = line_angle_diff(map.alpha(), new.alpha());
    let d_d = normal_offset(map, new);
    LineDistance { d_alpha, d_rho: d_d + centroid_distance(map, new, term) }
}

/// `d_d` of [`line_distance`]: `|n_map . C_new - d_map|`.
pub(crate) fn normal_offset(map: &LineSegment, new: &LineSegment) -> f64 {
    (map.normal().dot(&new.centroid().coords) - map.d()).abs()
}

/// `d_c` of [`line_distance`]: the centroids' distance, or the new
/// centroid's gap to the map segment, by `term`.
pub(crate) fn centroid_distance(map: &LineSegment, new: &LineSegment, term: CentroidTerm) -> f64 {
    match term {
        CentroidTerm::Centroid => (map.centroid() - new.centroid()).norm(),
        CentroidTerm::SegmentGap => segment_gap(map, &new.centroid()),
    }
}

/// Distance along the line from `p`'s projection to the segment (0 inside it).
fn segment_gap(segment: &LineSegment, p: &Point2<f64>) -> f64 {
    let s = (p - segment.start()).dot(&segment.direction());
    let len = segment.length();
    if s < 0.0 {
        -s
    } else if s > len {
        s - len
    } else {
        0.0
    }
}
