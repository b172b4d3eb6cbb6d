//! Map quality against the true walls: how far each map line lies from the
//! wall it represents, and how much of the wall length the sensor saw is
//! covered by the map.

use pcaline_geometry::{LineSegment, Point2, point_segment_distance};
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

    /// Surfaces of which the sensor saw at least `min_m` metres. A surface
    /// is a run of consecutive segments of one scene shape that turn by
    /// less than 15° from one to the next: a straight wall drawn in pieces,
    /// or a curved wall drawn as chords, is one surface; a corner starts
    /// another.
    pub fn surfaces_seen(&self, min_m: f64) -> usize {
        let mut count = 0;
        let mut seen_m = 0.0;
        for (k, (w, bins)) in self.walls.iter().zip(&self.seen).enumerate() {
            let continues = k > 0 && {
                let p = &self.walls[k - 1];
                let (d0, d1) = ((p.b - p.a).normalize(), (w.b - w.a).normalize());
                p.shape == w.shape
                    && (p.b - w.a).norm() < 1e-9
                    && d0.dot(&d1) > 15f64.to_radians().cos()
            };
            if !continues {
                count += usize::from(seen_m >= min_m);
                seen_m = 0.0;
            }
            seen_m += bins.iter().filter(|s| **s).count() as f64 * self.bin_m;
        }
        count + usize::from(seen_m >= min_m)
    }
}

fn bins(w: &Wall, bin_m: f64) -> usize {
    (((w.b - w.a).norm() / bin_m).ceil() as usize).max(1)
}

/// How a map compares with the true walls.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct MapQuality {
    /// Number of map lines.
    pub lines: usize,
    /// Per map line: the rms orthogonal distance of its two endpoints from
    /// the line of its nearest true wall (metres), in map order.
    pub line_errors_m: Vec<f64>,
    /// Map lines farther than `tolerance_m` (rms) from every wall, or more
    /// than `max_angle_rad` off it.
    pub spurious: usize,
    /// Fraction of the seen wall length covered by map lines that lie within
    /// the tolerances of that wall.
    pub covered_fraction: f64,
}

/// Compares `map` with the walls seen in `visible`. A map line belongs to the
/// nearest (orthogonal distance) of the walls its extent overlaps, or to the
/// wall segment nearest its endpoints when it overlaps none; its error
/// is the rms orthogonal distance of its endpoints from that wall's line
/// (design, section 5). It is spurious when that error exceeds `tolerance_m`
/// or its direction is more than `max_angle_rad` off. It covers the bins its
/// extent projects onto of every wall whose line it lies on within both
/// tolerances: a map line along a corridor whose doorways the sensor never
/// saw edge-on covers every wall piece between them.
pub fn map_quality(
    map: &[MapLine],
    visible: &VisibleWalls,
    tolerance_m: f64,
    max_angle_rad: f64,
) -> MapQuality {
    let mut covered: Vec<Vec<bool>> = visible.seen.iter().map(|v| vec![false; v.len()]).collect();
    let mut line_errors_m = Vec::with_capacity(map.len());
    let mut spurious = 0;
    let on_wall = |l: &LineSegment, w: &Wall| {
        let dir = (w.b - w.a).normalize();
        let angle = l.direction().dot(&dir).abs().min(1.0).acos();
        (rms_to_line(l, w), angle)
    };
    for m in map {
        let l = &m.line;
        // The nearest wall among those the line overlaps (orthogonal
        // distance), else the nearest segment.
        let overlapping = visible
            .walls
            .iter()
            .enumerate()
            .filter(|(_, w)| overlap_m(l, w) > 0.0)
            .map(|(i, w)| (i, on_wall(l, w).0))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        let best = overlapping.or_else(|| {
            visible
                .walls
                .iter()
                .enumerate()
                .map(|(i, w)| (i, rms_to_segment(l, w)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
        });
        let Some((wi, _)) = best else {
            spurious += 1;
            line_errors_m.push(f64::INFINITY);
            continue;
        };
        let (err, angle) = on_wall(l, &visible.walls[wi]);
        line_errors_m.push(err);
        if err > tolerance_m || angle > max_angle_rad {
            spurious += 1;
            continue;
        }
        for (w, cov) in visible.walls.iter().zip(covered.iter_mut()) {
            let (e, a) = on_wall(l, w);
            if e > tolerance_m || a > max_angle_rad {
                continue;
            }
            let dir = (w.b - w.a).normalize();
            let (s0, s1) = ((l.start() - w.a).dot(&dir), (l.end() - w.a).dot(&dir));
            let (lo, hi) = (s0.min(s1), s0.max(s1));
            for (k, c) in cov.iter_mut().enumerate() {
                let mid = (k as f64 + 0.5) * visible.bin_m;
                if mid >= lo && mid <= hi {
                    *c = true;
                }
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

/// Length of the overlap of the segment's projection onto the wall with the wall.
fn overlap_m(l: &LineSegment, w: &Wall) -> f64 {
    let ab = w.b - w.a;
    let len = ab.norm();
    let dir = ab / len;
    let (s0, s1) = ((l.start() - w.a).dot(&dir), (l.end() - w.a).dot(&dir));
    (s0.max(s1).min(len) - s0.min(s1).max(0.0)).max(0.0)
}

/// Rms orthogonal distance of the segment's two endpoints from the wall's line.
fn rms_to_line(l: &LineSegment, w: &Wall) -> f64 {
    let dir = (w.b - w.a).normalize();
    let d = |p: &Point2<f64>| {
        let v = p - w.a;
        (v.x * dir.y - v.y * dir.x).abs()
    };
    ((d(&l.start()).powi(2) + d(&l.end()).powi(2)) / 2.0).sqrt()
}

/// Rms distance of the segment's two endpoints from the wall segment.
fn rms_to_segment(l: &LineSegment, w: &Wall) -> f64 {
    let d = |p: &Point2<f64>| point_segment_distance(p, &w.a, &w.b);
    ((d(&l.start()).powi(2) + d(&l.end()).powi(2)) / 2.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_fitting::{Moments, fit_pca};
    use pcaline_mapping::{LineId, LineMap, MapConfig};

    fn map_line(a: (f64, f64), b: (f64, f64)) -> MapLine {
        let pts: Vec<_> = (0..=10)
            .map(|i| {
                let t = i as f64 / 10.0;
                Point2::new(a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t)
            })
            .collect();
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        map.insert(&fit_pca(&pts).unwrap(), &Moments::from_points(&pts));
        let mut l = map.lines()[0].clone();
        l.id = LineId(0);
        l
    }

    #[test]
    fn a_line_across_an_unseen_doorway_covers_both_walls_and_an_offset_line_is_spurious() {
        let wall =
            |x0: f64, x1: f64| Wall { a: Point2::new(x0, 0.0), b: Point2::new(x1, 0.0), shape: 0 };
        let mut visible = VisibleWalls::new(&[wall(0.0, 2.0), wall(3.0, 5.0)], 0.05);
        for row in &mut visible.seen {
            row.iter_mut().for_each(|b| *b = true);
        }
        let across = map_line((0.0, 0.0), (5.0, 0.0));
        let q = map_quality(std::slice::from_ref(&across), &visible, 0.05, 2f64.to_radians());
        assert_eq!(q.spurious, 0);
        assert!(q.line_errors_m[0] < 1e-9 && (q.covered_fraction - 1.0).abs() < 1e-9, "{q:?}");
        let off = map_line((0.5, 0.1), (1.5, 0.1));
        let q = map_quality(&[off], &visible, 0.05, 2f64.to_radians());
        assert_eq!(q.spurious, 1);
        assert!((q.line_errors_m[0] - 0.1).abs() < 1e-9 && q.covered_fraction == 0.0, "{q:?}");
    }
}
