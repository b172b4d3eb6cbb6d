//! The relation metric of Kuemmerle et al. (2009, "On measuring the accuracy
//! of SLAM algorithms"): a trajectory is scored by how well it reproduces
//! measured relative poses, not by absolute errors, so a trajectory in its
//! own world frame can be compared with ground-truth relations directly.

use pcaline_geometry::{Pose2, Relation, wrap_angle};

/// A trajectory with a timestamp per pose, sorted by time.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StampedTrajectory {
    times_s: Vec<f64>,
    poses: Vec<Pose2>,
}

impl StampedTrajectory {
    /// The samples, sorted by time (stable; samples with a NaN time are dropped).
    pub fn new(mut samples: Vec<(f64, Pose2)>) -> Self {
        samples.retain(|(t, _)| !t.is_nan());
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (times_s, poses) = samples.into_iter().unzip();
        StampedTrajectory { times_s, poses }
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// True when there is no pose.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// The pose whose time is nearest `t_s`, if it is within `tolerance_s`
    /// (the earlier of two equally near).
    pub fn nearest(&self, t_s: f64, tolerance_s: f64) -> Option<Pose2> {
        let i = self.times_s.partition_point(|&t| t < t_s);
        let candidates = [i.checked_sub(1), Some(i)];
        candidates
            .into_iter()
            .flatten()
            .filter(|&k| k < self.times_s.len())
            .map(|k| ((self.times_s[k] - t_s).abs(), k))
            .filter(|(dt, _)| *dt <= tolerance_s)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, k)| self.poses[k])
    }
}

/// The relation errors of a trajectory: for every relation whose two times
/// both meet a pose, the error `e = relative⁻¹ ∘ (pose(t1)⁻¹ ∘ pose(t2))`,
/// its translational part `|(e.x(), e.y())|` and its rotational part `|e.heading()|`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct RelationErrors {
    /// Relations scored.
    pub relations: usize,
    /// Relations skipped because a time met no pose within the tolerance.
    pub unmatched: usize,
    /// Mean translational error, metres.
    pub translation_mean_m: f64,
    /// Standard deviation of the translational error, metres.
    pub translation_std_m: f64,
    /// Largest translational error, metres.
    pub translation_max_m: f64,
    /// Mean rotational error, radians.
    pub rotation_mean_rad: f64,
    /// Standard deviation of the rotational error, radians.
    pub rotation_std_rad: f64,
    /// Largest rotational error, radians.
    pub rotation_max_rad: f64,
}

/// Scores `trajectory` against `relations` (Kuemmerle et al. 2009, the
/// absolute errors their tables report as mean and standard deviation).
/// A relation is skipped, and counted in `unmatched`, when one of its times
/// meets no pose within `tolerance_s`. `None` when no relation is scored.
///
/// ```
/// use pcaline_eval::{StampedTrajectory, relation_errors};
/// use pcaline_geometry::{Pose2, Relation};
/// let path = StampedTrajectory::new(vec![
///     (0.0, Pose2::new(0.0, 0.0, 0.0)),
///     (1.0, Pose2::new(1.1, 0.0, 0.0)),
/// ]);
/// let truth = [Relation { t1_s: 0.0, t2_s: 1.0, relative: Pose2::new(1.0, 0.0, 0.0) }];
/// let e = relation_errors(&path, &truth, 0.05).unwrap();
/// assert!((e.translation_mean_m - 0.1).abs() < 1e-12);
/// ```
pub fn relation_errors(
    trajectory: &StampedTrajectory,
    relations: &[Relation],
    tolerance_s: f64,
) -> Option<RelationErrors> {
    let mut translation = Vec::with_capacity(relations.len());
    let mut rotation = Vec::with_capacity(relations.len());
    let mut unmatched = 0;
    for r in relations {
        let (Some(a), Some(b)) =
            (trajectory.nearest(r.t1_s, tolerance_s), trajectory.nearest(r.t2_s, tolerance_s))
        else {
            unmatched += 1;
            continue;
        };
        let e = r.relative.between(&a.between(&b));
        translation.push(if e.is_finite() { e.x().hypot(e.y()) } else { f64::INFINITY });
        rotation.push(if e.is_finite() { wrap_angle(e.heading()).abs() } else { f64::INFINITY });
    }
    if translation.is_empty() {
        return None;
    }
    let (translation_mean_m, translation_std_m, translation_max_m) = mean_std_max(&translation);
    let (rotation_mean_rad, rotation_std_rad, rotation_max_rad) = mean_std_max(&rotation);
    Some(RelationErrors {
        relations: translation.len(),
        unmatched,
        translation_mean_m,
        translation_std_m,
        translation_max_m,
        rotation_mean_rad,
        rotation_std_rad,
        rotation_max_rad,
    })
}

/// Mean, population standard deviation and maximum of a non-empty slice.
fn mean_std_max(v: &[f64]) -> (f64, f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
    (mean, var.sqrt(), v.iter().copied().fold(f64::NEG_INFINITY, f64::max))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn relation(t1_s: f64, t2_s: f64, relative: Pose2) -> Relation {
        Relation { t1_s, t2_s, relative }
    }

    #[test]
    fn a_trajectory_agreeing_with_every_relation_scores_zero() {
        let poses: Vec<(f64, Pose2)> = (0..20)
            .map(|k| (k as f64 * 0.5, Pose2::new(k as f64, 0.3 * k as f64, 0.1 * k as f64)))
            .collect();
        let relations: Vec<Relation> = (0..19)
            .map(|k| relation(poses[k].0, poses[k + 1].0, poses[k].1.between(&poses[k + 1].1)))
            .collect();
        // The same trajectory moved to another world frame scores the same.
        let moved = Pose2::new(-4.0, 7.0, 2.0);
        let path =
            StampedTrajectory::new(poses.iter().map(|(t, p)| (*t, moved.compose(p))).collect());
        let e = relation_errors(&path, &relations, 0.01).unwrap();
        assert_eq!((e.relations, e.unmatched), (19, 0));
        assert!(e.translation_max_m < 1e-12 && e.rotation_max_rad < 1e-12, "{e:?}");
    }

    #[test]
    fn a_rotation_error_wraps_and_a_relation_off_the_trajectory_is_unmatched() {
        let path = StampedTrajectory::new(vec![
            (1.0, Pose2::new(0.0, 0.0, 3.1)),
            (0.0, Pose2::new(0.0, 0.0, 0.0)), // out of order: sorted
        ]);
        let relations = [
            relation(0.0, 1.0, Pose2::new(0.0, 0.0, -3.1)),
            relation(0.0, 1.5, Pose2::new(0.0, 0.0, 0.0)),
        ];
        let e = relation_errors(&path, &relations, 0.05).unwrap();
        assert_eq!((e.relations, e.unmatched), (1, 1));
        let expected = 2.0 * std::f64::consts::PI - 6.2;
        assert!((e.rotation_mean_rad - expected).abs() < 1e-9, "{e:?}");
        assert!(relation_errors(&path, &relations[1..], 0.05).is_none());
    }

    #[test]
    fn nearest_picks_the_closer_pose_within_the_tolerance() {
        let path = StampedTrajectory::new(vec![
            (0.0, Pose2::new(0.0, 0.0, 0.0)),
            (1.0, Pose2::new(1.0, 0.0, 0.0)),
            (f64::NAN, Pose2::new(9.0, 0.0, 0.0)),
        ]);
        assert_eq!(path.len(), 2);
        assert_eq!(path.nearest(0.6, 0.5).unwrap().x(), 1.0);
        assert_eq!(path.nearest(0.4, 0.5).unwrap().x(), 0.0);
        assert!(path.nearest(0.5, 0.4).is_none());
        assert!(path.nearest(-1.0, 0.5).is_none());
        assert!(StampedTrajectory::default().nearest(0.0, 1.0).is_none());
    }

    #[test]
    fn translational_error_is_measured_in_the_first_pose_frame() {
        // The truth says 1 m ahead; the estimate turned 90° and went 1 m to its left.
        let path = StampedTrajectory::new(vec![
            (0.0, Pose2::new(5.0, 5.0, std::f64::consts::FRAC_PI_2)),
            (1.0, Pose2::new(5.0, 6.0, std::f64::consts::FRAC_PI_2)),
        ]);
        let e =
            relation_errors(&path, &[relation(0.0, 1.0, Pose2::new(1.0, 0.0, 0.0))], 0.0).unwrap();
        assert!(e.translation_mean_m < 1e-12 && e.rotation_mean_rad < 1e-12, "{e:?}");
    }
}
