//! Detection against ground truth (design, section 5): per scan, the true
//! visible walls and the detected lines are matched, and recall, false
//! positives, fragmentation and parameter errors are counted.
//!
//! A true visible wall is a maximal run of consecutive valid beams hitting
//! the same wall, at least `min_beams` beams and `min_extent_m` long. A
//! detected line matches it when their orientations differ by at most
//! `max_angle_rad`, both detected endpoints lie within `max_endpoint_m` of
//! the true wall's line, and the two overlap along it by at least
//! `min_overlap` of the shorter.

use pcaline_geometry::{LineSegment, Point2, line_angle_diff};
use pcaline_sim::{SimFrame, World};

/// The matching rule.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct DetectionCriteria {
    /// Fewest beams of a true visible wall (10).
    pub min_beams: usize,
    /// Shortest true visible wall, metres (0.3).
    pub min_extent_m: f64,
    /// Largest orientation difference, radians (2°).
    pub max_angle_rad: f64,
    /// Largest distance of a detected endpoint from the true line, metres (0.10).
    pub max_endpoint_m: f64,
    /// Smallest overlap, as a fraction of the shorter of the two (0.5).
    pub min_overlap: f64,
}

impl Default for DetectionCriteria {
    fn default() -> Self {
        DetectionCriteria {
            min_beams: 10,
            min_extent_m: 0.3,
            max_angle_rad: 2f64.to_radians(),
            max_endpoint_m: 0.10,
            min_overlap: 0.5,
        }
    }
}

/// A true visible wall, in the sensor frame: the wall's line, clipped to the
/// extent the sensor saw.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrueWall {
    /// Index of the wall in the world.
    pub wall: u32,
    /// The visible part, sensor frame.
    pub line: LineSegment,
}

/// The true visible walls of a frame, in its sensor frame.
pub fn true_walls(frame: &SimFrame, world: &World, criteria: &DetectionCriteria) -> Vec<TrueWall> {
    let sensor_from_world = frame.true_pose.inverse();
    frame
        .surface_runs(criteria.min_beams, world.surfaces())
        .into_iter()
        .filter_map(|run| {
            let w = &world.walls()[run.wall as usize];
            let (p0, p1) = (frame.beams[run.first_beam].point?, frame.beams[run.last_beam].point?);
            let (a, b) =
                (sensor_from_world.transform_point(&p0), sensor_from_world.transform_point(&p1));
            if (b - a).norm() < criteria.min_extent_m {
                return None;
            }
            let dir = sensor_from_world.rotate(&(w.b - w.a));
            let mid = Point2::from((a.coords + b.coords) / 2.0);
            Some(TrueWall { wall: run.wall, line: LineSegment::through(mid, dir, a, b) })
        })
        .collect()
}

/// Whether `detected` matches `truth` under `criteria`, and the overlap.
pub fn matches(truth: &LineSegment, detected: &LineSegment, criteria: &DetectionCriteria) -> bool {
    if line_angle_diff(truth.alpha(), detected.alpha()).abs() > criteria.max_angle_rad {
        return false;
    }
    if truth.signed_distance(&detected.start()).abs() > criteria.max_endpoint_m
        || truth.signed_distance(&detected.end()).abs() > criteria.max_endpoint_m
    {
        return false;
    }
    let s = |p: &Point2<f64>| (p - truth.start()).dot(&truth.direction());
    let (t0, t1) = (0.0f64, truth.length());
    let (d0, d1) = {
        let (a, b) = (s(&detected.start()), s(&detected.end()));
        (a.min(b), a.max(b))
    };
    let overlap = (t1.min(d1) - t0.max(d0)).max(0.0);
    let shorter = (t1 - t0).min(d1 - d0);
    shorter > 0.0 && overlap >= criteria.min_overlap * shorter
}

/// Counts over any number of scans.
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct DetectionScore {
    /// Scans scored.
    pub scans: usize,
    /// True visible walls.
    pub true_walls: usize,
    /// True walls matched by at least one detection.
    pub matched_walls: usize,
    /// Detected lines.
    pub detections: usize,
    /// Detections matching no true wall.
    pub false_positives: usize,
    /// Detections matching a true wall.
    pub matching_detections: usize,
    /// Orientation errors of matching detections, radians.
    pub alpha_errors: Vec<f64>,
    /// Offsets of matching detections' centroids from the true line, metres.
    pub d_errors: Vec<f64>,
    /// Distances of matching detections' endpoints from the true visible
    /// wall's endpoints (paired in the order with the smaller sum), metres:
    /// two per matching detection. A wall found in pieces has large
    /// endpoint errors at the cuts.
    pub endpoint_errors: Vec<f64>,
    /// True walls and matched true walls by length, in the bins of
    /// [`LENGTH_BINS_M`].
    pub by_length: [(usize, usize); 4],
}

/// Upper ends of the wall-length bins of [`DetectionScore::by_length`],
/// metres: under 0.5, 0.5-1, 1-2, 2 and more.
pub const LENGTH_BINS_M: [f64; 4] = [0.5, 1.0, 2.0, f64::INFINITY];

impl DetectionScore {
    /// Scores one scan's detections against its true walls.
    pub fn add_scan(
        &mut self,
        truth: &[TrueWall],
        detected: &[LineSegment],
        criteria: &DetectionCriteria,
    ) {
        self.scans += 1;
        self.true_walls += truth.len();
        self.detections += detected.len();
        let mut matched = vec![false; truth.len()];
        for d in detected {
            let best =
                truth.iter().enumerate().filter(|(_, t)| matches(&t.line, d, criteria)).min_by(
                    |a, b| {
                        let e = |t: &TrueWall| t.line.signed_distance(&d.centroid()).abs();
                        e(a.1).total_cmp(&e(b.1))
                    },
                );
            match best {
                Some((k, t)) => {
                    matched[k] = true;
                    self.matching_detections += 1;
                    self.alpha_errors.push(line_angle_diff(d.alpha(), t.line.alpha()));
                    self.d_errors.push(t.line.signed_distance(&d.centroid()));
                    let (a, b) = (t.line.start(), t.line.end());
                    let straight = (d.start() - a).norm() + (d.end() - b).norm();
                    let crossed = (d.start() - b).norm() + (d.end() - a).norm();
                    let (e0, e1) = if straight <= crossed {
                        ((d.start() - a).norm(), (d.end() - b).norm())
                    } else {
                        ((d.start() - b).norm(), (d.end() - a).norm())
                    };
                    self.endpoint_errors.extend([e0, e1]);
                }
                None => self.false_positives += 1,
            }
        }
        self.matched_walls += matched.iter().filter(|m| **m).count();
        for (t, m) in truth.iter().zip(&matched) {
            let bin = LENGTH_BINS_M.iter().position(|&hi| t.line.length() < hi).unwrap_or(3);
            self.by_length[bin].0 += 1;
            self.by_length[bin].1 += usize::from(*m);
        }
    }

    /// Recall in each wall-length bin of [`LENGTH_BINS_M`] (NaN for an empty bin).
    pub fn recall_by_length(&self) -> [f64; 4] {
        self.by_length.map(|(walls, matched)| matched as f64 / walls as f64)
    }

    /// Matched true walls / true walls (1 when there are none).
    pub fn recall(&self) -> f64 {
        if self.true_walls == 0 { 1.0 } else { self.matched_walls as f64 / self.true_walls as f64 }
    }

    /// Unmatched detections / detections (0 when there are none).
    pub fn false_positive_fraction(&self) -> f64 {
        if self.detections == 0 {
            0.0
        } else {
            self.false_positives as f64 / self.detections as f64
        }
    }

    /// Matching detections per matched wall (1 is no fragmentation).
    pub fn fragmentation(&self) -> f64 {
        if self.matched_walls == 0 {
            0.0
        } else {
            self.matching_detections as f64 / self.matched_walls as f64
        }
    }

    /// Median and rms of the absolute orientation errors, radians.
    pub fn alpha_error(&self) -> (f64, f64) {
        median_rms(&self.alpha_errors)
    }

    /// Median and rms of the absolute offsets, metres.
    pub fn d_error(&self) -> (f64, f64) {
        median_rms(&self.d_errors)
    }

    /// Median and rms of the endpoint errors, metres.
    pub fn endpoint_error(&self) -> (f64, f64) {
        median_rms(&self.endpoint_errors)
    }
}

fn median_rms(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mut a: Vec<f64> = v.iter().map(|x| x.abs()).collect();
    a.sort_by(f64::total_cmp);
    let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    (a[a.len() / 2], rms)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::Vector2;

    fn seg(a: (f64, f64), b: (f64, f64)) -> LineSegment {
        LineSegment::between(Point2::new(a.0, a.1), Point2::new(b.0, b.1))
    }

    fn truth() -> Vec<TrueWall> {
        vec![
            TrueWall { wall: 0, line: seg((3.0, -2.0), (3.0, 2.0)) },
            TrueWall { wall: 1, line: seg((-1.0, 2.5), (3.0, 2.5)) },
        ]
    }

    #[test]
    fn perfect_detection_scores_full_recall_and_no_false_positive() {
        let mut s = DetectionScore::default();
        let det: Vec<_> = truth().iter().map(|t| t.line).collect();
        s.add_scan(&truth(), &det, &DetectionCriteria::default());
        assert_eq!((s.recall(), s.false_positive_fraction(), s.fragmentation()), (1.0, 0.0, 1.0));
        assert!(s.alpha_error().1 < 1e-12 && s.d_error().1 < 1e-12);
        assert!(s.endpoint_error().1 < 1e-12 && s.endpoint_errors.len() == 4);
    }

    #[test]
    fn a_split_wall_is_fragmentation_not_a_miss() {
        let mut s = DetectionScore::default();
        let det = vec![seg((3.0, -2.0), (3.0, 0.0)), seg((3.0, 0.05), (3.0, 2.0)), truth()[1].line];
        s.add_scan(&truth(), &det, &DetectionCriteria::default());
        assert_eq!(s.recall(), 1.0);
        assert_eq!(s.false_positive_fraction(), 0.0);
        assert_eq!(s.fragmentation(), 1.5);
        // The cut shows in the endpoint errors: the inner endpoints lie 2 m and
        // 2.05 m from the true ends they pair with; the outer ones are exact.
        let mut e = s.endpoint_errors.clone();
        e.sort_by(f64::total_cmp);
        assert!(e[..4].iter().all(|v| *v < 1e-12), "{e:?}");
        assert!((e[4] - 2.0).abs() < 1e-9 && (e[5] - 2.05).abs() < 1e-9, "{e:?}");
    }

    #[test]
    fn a_spurious_line_is_a_false_positive_and_a_missing_wall_a_miss() {
        let mut s = DetectionScore::default();
        let det = vec![truth()[0].line, seg((0.0, -1.0), (1.0, -1.5))];
        s.add_scan(&truth(), &det, &DetectionCriteria::default());
        assert_eq!(s.recall(), 0.5);
        assert_eq!(s.false_positive_fraction(), 0.5);
    }

    #[test]
    fn tolerances_are_enforced() {
        let c = DetectionCriteria::default();
        let t = truth()[0].line;
        assert!(!matches(&t, &seg((3.2, -2.0), (3.2, 2.0)), &c), "20 cm off");
        let tilted = LineSegment::through(
            Point2::new(3.0, 0.0),
            Vector2::new(0.06, 1.0),
            Point2::new(3.0, -1.0),
            Point2::new(3.0, 1.0),
        );
        assert!(!matches(&t, &tilted, &c), "3.4° off");
        assert!(!matches(&t, &seg((3.0, 1.8), (3.0, 6.0)), &c), "too little overlap");
        assert!(matches(&t, &seg((3.05, -1.0), (3.05, 1.0)), &c));
    }
}
