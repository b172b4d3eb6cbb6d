//! Loop closures checked against reference poses: each loop edge's relative
//! pose (what the line alignment found) against the relative pose of its two
//! keyframes in the reference, so a run can say how many of its loops are
//! wrong, not only how its trajectory ends up.
//!
//! A real log rarely has a reference pose at every scan (MIT CSAIL's
//! corrected log holds one scan in five). [`reference_by_source`] carries the
//! reference from the nearest scan that has one by the source's own relative
//! motion, which over a few scans of a straight run is good to a fraction of
//! a degree, and in a turn carries the source's lag (MIT CSAIL's odometry
//! is about 0.1 s late: several degrees over two scans of a fast turn).
//! [`reference_by_registration`] carries it by registering the two scans
//! instead, and leaves a scan without a reference where the registration
//! cannot be trusted.

use pcaline_aiding::{BeamCloud, LoopOutcome, LoopRecord, ScanMatchConfig, register_from_guesses};
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
    carried(reference, source.len(), max_gap, |i, pose, scan| {
        Some(pose.compose(&source[i].between(&source[scan])))
    })
}

/// The pose of each of `scans` scans carried by `carry` (from scan `i`,
/// its pose, to scan `scan`) from the nearest of `reference`'s scans
/// within `max_gap` (of two equally near, the earlier); `None` where there
/// is none, where `carry` gives `None` and where its result is not finite.
fn carried(
    reference: &[(usize, Pose2)],
    scans: usize,
    max_gap: usize,
    carry: impl Fn(usize, Pose2, usize) -> Option<Pose2>,
) -> Vec<Option<Pose2>> {
    let mut sorted: Vec<(usize, Pose2)> =
        reference.iter().copied().filter(|(i, p)| *i < scans && p.is_finite()).collect();
    sorted.sort_by_key(|(i, _)| *i);
    (0..scans)
        .map(|scan| {
            let at = sorted.partition_point(|(i, _)| *i < scan);
            let &(i, pose) = [at.checked_sub(1), Some(at)]
                .into_iter()
                .flatten()
                .filter_map(|k| sorted.get(k))
                .min_by_key(|(i, _)| i.abs_diff(scan))?;
            if i.abs_diff(scan) > max_gap {
                return None;
            }
            carry(i, pose, scan).filter(Pose2::is_finite)
        })
        .collect()
}

/// The reference pose of every scan, carried from the nearest scan that has
/// one, within `max_gap` scans, by the registration of the scan's `clouds`
/// entry to that scan's ([`register_from_guesses`] from the source's
/// relative motion, under `config`), where the registration is trusted
/// ([`pcaline_aiding::Registration::is_trusted`]). The poses are the
/// sensor's (the registration relates the sensors).
///
/// As [`reference_by_source`] otherwise: `reference` holds `(scan index,
/// reference pose)` in any order, `source` and `clouds` one entry per scan.
/// Edge cases: a referenced scan keeps its reference; a scan with no
/// referenced scan within `max_gap`, without a cloud (`None`) or whose
/// referenced scan has none, whose registration fails or is not trusted,
/// or with a non-finite result gives `None`.
///
/// ```
/// use pcaline_aiding::{BeamCloud, ScanMatchConfig};
/// use pcaline_eval::reference_by_registration;
/// use pcaline_geometry::{Pose2, Scan};
///
/// // A corner 2 m ahead and 1.5 m to the left, seen from two places 0.2 m
/// // apart; the source says the sensor did not move.
/// let corner = |pose: &Pose2| {
///     let ranges = (0..361).map(|i| {
///         let a = pose.heading() - 1.5 + 3.0 * i as f64 / 360.0;
///         let (c, s) = (a.cos(), a.sin());
///         let to_front = if c > 1e-9 { (2.0 - pose.x()) / c } else { f64::INFINITY };
///         let to_left = if s > 1e-9 { (1.5 - pose.y()) / s } else { f64::INFINITY };
///         to_front.min(to_left) as f32
///     });
///     Scan::new(-1.5, 3.0 / 360.0, 0.05, 30.0, ranges.collect())
/// };
/// let config = ScanMatchConfig::standard();
/// let truth = [Pose2::identity(), Pose2::new(0.2, 0.0, 0.0)];
/// let clouds: Vec<Option<BeamCloud>> =
///     truth.iter().map(|p| Some(BeamCloud::from_scan(&corner(p), &config))).collect();
/// let source = [Pose2::identity(), Pose2::identity()];
/// let all = reference_by_registration(&[(0, truth[0])], &source, &clouds, 1, &config);
/// let carried = all[1].unwrap();
/// assert!((carried.x() - 0.2).abs() < 0.01 && carried.y().abs() < 0.01);
/// ```
pub fn reference_by_registration(
    reference: &[(usize, Pose2)],
    source: &[Pose2],
    clouds: &[Option<BeamCloud>],
    max_gap: usize,
    config: &ScanMatchConfig,
) -> Vec<Option<Pose2>> {
    carried(reference, source.len(), max_gap, |i, pose, scan| {
        if i == scan {
            return Some(pose);
        }
        let (from, to) = (clouds.get(i)?.as_ref()?, clouds.get(scan)?.as_ref()?);
        let guess = source[i].between(&source[scan]);
        let r = register_from_guesses(from, to, &guess, None, config)
            .filter(|r| r.is_trusted(config))?;
        Some(pose.compose(&r.reference_from_current))
    })
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
    use crate::test_scans::room_scan;
    use pcaline_geometry::Matrix3;

    #[test]
    fn a_reference_is_carried_by_registration_past_a_lagging_source() {
        let config = ScanMatchConfig::standard();
        // A turn of 15° a scan; the source lags by one scan's turn.
        let truth: Vec<Pose2> =
            (0..4).map(|k| Pose2::new(0.05 * k as f64, 0.0, 0.26 * k as f64)).collect();
        let source: Vec<Pose2> = (0..4)
            .map(|k| Pose2::new(0.05 * k as f64, 0.0, 0.26 * (k as f64 - 1.0).max(0.0)))
            .collect();
        let mut clouds: Vec<Option<BeamCloud>> =
            truth.iter().map(|p| Some(BeamCloud::from_scan(&room_scan(p), &config))).collect();
        clouds[3] = None;
        // The reference frame is shifted and turned against the truth's.
        let frame = Pose2::new(10.0, -4.0, 1.0);
        let reference = [(0, frame.compose(&truth[0]))];
        let carried = reference_by_registration(&reference, &source, &clouds, 3, &config);
        let by_source = reference_by_source(&reference, &source, 3);
        for k in 1..3 {
            let e = frame.compose(&truth[k]).between(&carried[k].unwrap());
            assert!(e.heading().abs() < 1e-3 && e.x().hypot(e.y()) < 1e-3, "{k}: {e:?}");
            let lagging = frame.compose(&truth[k]).between(&by_source[k].unwrap());
            assert!((lagging.heading().abs() - 0.26).abs() < 1e-9, "{k}: {lagging:?}");
        }
        // Scan 0 keeps its own; scan 3 has no cloud.
        assert_eq!(carried[0], Some(reference[0].1));
        assert_eq!(carried[3], None);
        assert!(by_source[3].is_some());
    }

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
