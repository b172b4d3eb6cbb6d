//! Map quality against the true walls: how far each map line lies from the
//! wall it represents, and how much of the wall length the sensor saw is
//! covered by the map.

use pcaline_geometry::{LineSegment, Point2, Vector2};
use pcaline_mapping::MapLine;
use pcaline_sim::{Fault, SimFrame, Wall};

/// The parts of each wall that the sensor saw, in bins along the wall.
#[derive(Debug, Clone)]
pub struct VisibleWalls {
    walls: Vec<Wall>,
    bin_m: f64,
    seen: Vec<Vec<bool>>,
}

impl VisibleWalls {
    /// No wall seen yet; walls are cut into bins of `bin_m` metres.
    pub fn new(walls: &[Wall], bin_m: f64) -> Self {
        let seen = walls.iter().map(|w| vec![false; bins(w, bin_m)]).collect();
        VisibleWalls { walls: walls.to_vec(), bin_m, seen }
    }

    /// Marks the bins hit by the frame's valid, fault-free returns.
    pub fn observe(&mut self, frame: &SimFrame) {
        for (i, b) in frame.beams.iter().enumerate() {
            let (Some(w), Some(p)) = (b.wall, b.point) else { continue };
            if b.fault != Fault::None || !frame.scan.is_valid_range(frame.scan.ranges[i]) {
                continue;
            }
            let wall = &self.walls[w as usize];
            let s = (p - wall.a).dot(&(wall.b - wall.a).normalize());
            let k =
                ((s / self.bin_m).floor().max(0.0) as usize).min(self.seen[w as usize].len() - 1);
            self.seen[w as usize][k] = true;
        }
    }

    /// Total length seen, metres.
    pub fn seen_length_m(&self) -> f64 {
        self.seen.iter().flatten().filter(|s| **s).count() as f64 * self.bin_m
    }
}

fn bins(w: &Wall, bin_m: f64) -> usize {
    (((w.b - w.a).norm() / bin_m).ceil() as usize).max(1)
}

/// How a map compares with the true walls.
#[derive(Debug, Clone, PartialEq)]
pub struct MapQuality {
    /// Number of map lines.
    pub lines: usize,
    /// Per map line: the rms distance of its two endpoints from the nearest
    /// true wall (metres), in map order.
    pub line_errors_m: Vec<f64>,
    /// Map lines farther than `tolerance_m` (rms) from every wall, or more
    /// than `max_angle_rad` off it.
    pub spurious: usize,
    /// Fraction of the seen wall length covered by map lines that lie within
    /// the tolerances of that wall.
    pub covered_fraction: f64,
}

/// Compares `map` with the walls seen in `visible`. A map line belongs to the
/// wall minimising the rms distance of its endpoints from the wall's segment;
/// it covers the bins of that wall its extent projects onto, when its rms
/// distance is within `tolerance_m` and its direction within `max_angle_rad`.
pub fn map_quality(
    map: &[MapLine],
    visible: &VisibleWalls,
    tolerance_m: f64,
    max_angle_rad: f64,
) -> MapQuality {
    let mut covered: Vec<Vec<bool>> = visible.seen.iter().map(|v| vec![false; v.len()]).collect();
    let mut line_errors_m = Vec::with_capacity(map.len());
    let mut spurious = 0;
    for m in map {
        let l = &m.line;
        let best = visible
            .walls
            .iter()
            .enumerate()
            .map(|(i, w)| (i, rms_to_segment(l, w)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        let Some((wi, err)) = best else {
            spurious += 1;
            line_errors_m.push(f64::INFINITY);
            continue;
        };
        line_errors_m.push(err);
        let w = &visible.walls[wi];
        let dir = (w.b - w.a).normalize();
        let angle = l.direction.dot(&dir).abs().min(1.0).acos();
        if err > tolerance_m || angle > max_angle_rad {
            spurious += 1;
            continue;
        }
        let (s0, s1) = ((l.start - w.a).dot(&dir), (l.end - w.a).dot(&dir));
        let (lo, hi) = (s0.min(s1), s0.max(s1));
        for (k, c) in covered[wi].iter_mut().enumerate() {
            let mid = (k as f64 + 0.5) * visible.bin_m;
            if mid >= lo && mid <= hi {
                *c = true;
            }
        }
    }
    let (mut seen, mut both) = (0usize, 0usize);
    for (s, c) in visible.seen.iter().zip(&covered) {
        for (a, b) in s.iter().zip(c) {
            seen += *a as usize;
            both += (*a && *b) as usize;
        }
    }
    MapQuality {
        lines: map.len(),
        line_errors_m,
        spurious,
        covered_fraction: if seen > 0 { both as f64 / seen as f64 } else { 1.0 },
    }
}

/// Rms distance of the segment's two endpoints from the wall segment.
fn rms_to_segment(l: &LineSegment, w: &Wall) -> f64 {
    let d = |p: &Point2<f64>| point_segment_distance(p, &w.a, &w.b);
    ((d(&l.start).powi(2) + d(&l.end).powi(2)) / 2.0).sqrt()
}

fn point_segment_distance(p: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let ab: Vector2<f64> = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 { ((p - a).dot(&ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p - (a + ab * t)).norm()
}
