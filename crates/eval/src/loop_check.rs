//! Loop closures checked against reference poses: each loop edge's relative
//! pose (what the line alignment found) against the relative pose of its two
//! keyframes in the reference, so a run can say how many of its loops are
//! wrong, not only how its trajectory ends up.
//!
//! A real log rarely has a reference pose at every scan (MIT CSAIL's
//! corrected log holds one scan in five). [`reference_by_source`] carries the
//! reference from the nearest scan that has one by the source's own relative
//! motion, which over a few scans is good to a fraction of a degree.

use pcaline_aiding::{LoopOutcome, LoopRecord};
use pcaline_geometry::{Pose2, wrap_angle};

/// A loop edge is wrong when its relative pose is off the reference's by more
/// than this, metres (the loop confirmation's own tolerance,
/// `LoopClosureConfig::confirm_distance_m`).
pub const WRONG_LOOP_M: f64 = 0.3;
/// ... or by more than this, degrees (about three times a line's orientation
/// floor in `MeasurementNoise::standard`).
pub const WRONG_LOOP_DEG: f64 = 2.0;

/// The reference pose of every scan: the reference of the nearest scan that
/// has one, within `max_gap` scans, moved by the source's relative motion
/// between the two scans.
///
/// `reference` holds `(scan index, reference pose)`, in any order;
/// `source` the source's pose of every scan. Edge cases: a scan with no
/// referenced scan within `max_gap`, a reference index beyond `source`, or
/// a non-finite result gives `None`; of two equally near referenced scans
/// the earlier is used.
///
/// ```
/// use pcaline_eval::reference_by_source;
/// use pcaline_geometry::Pose2;
/// let source = [Pose2::identity(), Pose2::new(1.0, 0.0, 0.0), Pose2::new(2.0, 0.0, 0.0)];
/// // The reference frame is turned by 90° against the source's.
/// let reference = [(0, Pose2::new(5.0, 5.0, std::f64::consts::FRAC_PI_2))];
/// let all = reference_by_source(&reference, &source, 1);
/// let p = all[1].unwrap();
/// assert!((p.x() - 5.0).abs() < 1e-12 && (p.y() - 6.0).abs() < 1e-12);
/// assert!(all[2].is_none());
/// ```
pub fn reference_by_source(
    reference: &[(usize, Pose2)],
    source: &[Pose2],
    max_gap: usize,
) -> Vec<Option<Pose2>> {
    let mut sorted: Vec<(usize, Pose2)> =
        reference.iter().copied().filter(|(i, p)| *i < source.len() && p.is_finite()).collect();
    sorted.sort_by_key(|(i, _)| *i);
    (0..source.len())
        .map(|scan| {
            let at = sorted.partition_point(|(i, _)| *i < scan);
            let nearest = [at.checked_sub(1), Some(at)]
                .into_iter()
                .flatten()
                .filter_map(|k| sorted.get(k))
                .min_by_key(|(i, _)| i.abs_diff(scan))?;
            let (i, pose) = *nearest;
            if i.abs_diff(scan) > max_gap {
                return None;
            }
            let moved = pose.compose(&source[i].between(&source[scan]));
            moved.is_finite().then_some(moved)
        })
        .collect()
}

/// The loops of one run, checked against the reference.
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct LoopCheck {
    /// Loop edges standing at the end (outcome accepted).
    pub standing: usize,
    /// Loop edges the optimizer switched off.
    pub switched_off: usize,
    /// Standing loops off the reference by more than [`WRONG_LOOP_M`] or
    /// [`WRONG_LOOP_DEG`].
    pub standing_wrong: usize,
    /// Switched-off loops that were wrong (rightly switched off).
    pub switched_off_wrong: usize,
    /// Loops with an edge whose keyframes have no reference pose (not
    /// counted above).
    pub unchecked: usize,
    /// Each standing loop's error: translation, metres, and rotation,
    /// degrees (absolute), in loop order.
    pub standing_errors: Vec<(f64, f64)>,
}

impl LoopCheck {
    /// Checks every loop that became an edge (accepted or switched off):
    /// `keyframe_scans[k]` is keyframe `k`'s scan index into `reference`.
    /// Loops refused before becoming an edge are not checked. Edge cases: a
    /// keyframe index beyond `keyframe_scans`, or a scan without a
    /// reference, counts as unchecked.
    pub fn of(
        loops: &[LoopRecord],
        keyframe_scans: &[usize],
        reference: &[Option<Pose2>],
    ) -> LoopCheck {
        let mut check = LoopCheck::default();
        let pose_of = |k: usize| keyframe_scans.get(k).and_then(|&s| reference.get(s).copied()?);
        for l in loops.iter().filter(|l| l.edge.is_some()) {
            let (Some(current), Some(candidate)) = (pose_of(l.keyframe), pose_of(l.candidate))
            else {
                check.unchecked += 1;
                continue;
            };
            let error = candidate.between(&current).between(&l.candidate_from_current);
            let (m, deg) =
                (error.x().hypot(error.y()), wrap_angle(error.heading()).to_degrees().abs());
            let wrong = m > WRONG_LOOP_M || deg > WRONG_LOOP_DEG;
            match l.outcome {
                LoopOutcome::SwitchedOff => {
                    check.switched_off += 1;
                    check.switched_off_wrong += usize::from(wrong);
                }
                _ => {
                    check.standing += 1;
                    check.standing_wrong += usize::from(wrong);
                    check.standing_errors.push((m, deg));
                }
            }
        }
        check
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::Matrix3;

    fn record(keyframe: usize, candidate: usize, found: Pose2, outcome: LoopOutcome) -> LoopRecord {
        LoopRecord {
            keyframe,
            candidate,
            edge: Some(0),
            candidate_from_current: found,
            matched_length_m: 10.0,
            weakest_direction_m: 3.0,
            runner_up_length_m: 0.0,
            rms_m: 0.02,
            see_through: 0.0,
            other_place_length_m: 0.0,
            information: Matrix3::identity(),
            search: pcaline_aiding::LoopSearch::Local,
            weak_prior: false,
            confirmed_with: None,
            outcome,
        }
    }

    #[test]
    fn the_reference_is_carried_by_the_source_from_the_nearest_scan() {
        let source: Vec<Pose2> =
            (0..6).map(|i| Pose2::new(i as f64, 0.0, 0.1 * i as f64)).collect();
        // The reference is the source shifted and turned, known at scans 1 and 4.
        let frame = Pose2::new(2.0, -1.0, 0.5);
        let truth: Vec<Pose2> = source.iter().map(|p| frame.compose(p)).collect();
        let all = reference_by_source(&[(4, truth[4]), (1, truth[1])], &source, 1);
        for (scan, r) in all.iter().enumerate() {
            let r = r.expect("every scan is within one of a reference");
            let d = r.between(&truth[scan]);
            assert!(d.x().hypot(d.y()) < 1e-9 && d.heading().abs() < 1e-9, "scan {scan}");
        }
        let sparse = reference_by_source(&[(0, truth[0])], &source, 2);
        assert!(sparse[2].is_some() && sparse[3].is_none());
        assert!(reference_by_source(&[(9, truth[0])], &source, 9).iter().all(Option::is_none));
    }

    #[test]
    fn loops_are_scored_against_the_reference() {
        let reference: Vec<Option<Pose2>> =
            vec![Some(Pose2::new(0.0, 0.0, 0.0)), Some(Pose2::new(1.0, 0.0, 0.3)), None];
        let truth = reference[0].unwrap().between(&reference[1].unwrap());
        let off =
            |dx: f64, dtheta: f64| Pose2::new(truth.x() + dx, truth.y(), truth.heading() + dtheta);
        let loops = [
            record(1, 0, off(0.05, 0.01), LoopOutcome::Accepted),
            record(1, 0, off(0.5, 0.0), LoopOutcome::Accepted),
            record(1, 0, off(0.0, 3f64.to_radians()), LoopOutcome::SwitchedOff),
            record(2, 0, truth, LoopOutcome::Accepted),
        ];
        let c = LoopCheck::of(&loops, &[0, 1, 2], &reference);
        assert_eq!((c.standing, c.standing_wrong), (2, 1));
        assert_eq!((c.switched_off, c.switched_off_wrong), (1, 1));
        assert_eq!(c.unchecked, 1);
        assert!((c.standing_errors[0].0 - 0.05).abs() < 1e-9);
        assert!((c.standing_errors[0].1 - 0.01f64.to_degrees()).abs() < 1e-9);
        // A loop that never became an edge is not checked.
        let mut refused = loops[0];
        refused.edge = None;
        assert_eq!(LoopCheck::of(&[refused], &[0, 1], &reference), LoopCheck::default());
    }
}
