//! Which of two trajectories the scans themselves agree with, link by link.
//!
//! A real log's reference poses (a SLAM system's corrected poses) carry their
//! own errors, and a trajectory scored against them is charged for those
//! too. The scans are a witness that needs no reference: place each scan in
//! the previous one's frame with a trajectory's relative pose and count the
//! points that fall on the previous scan's surfaces
//! ([`pcaline_aiding::agreeing_points`]). Where one trajectory's relative
//! pose leaves few points on their surfaces and the other's many, the first
//! contradicts the scans on that link.

use pcaline_aiding::{BeamCloud, ScanMatchConfig, agreeing_points};
use pcaline_geometry::Pose2;

/// A relative pose leaving fewer than this share of a scan's points on the
/// previous scan's surfaces contradicts the scans (when the other
/// trajectory's reaches [`AGREEING_SHARE`]). Consecutive scans of a moving
/// platform that overlap at all agree at 0.4-0.9 when placed right.
pub const CONTRADICTED_SHARE: f64 = 0.25;

/// The share the other trajectory must reach on a link for one to be
/// called contradicted there.
pub const AGREEING_SHARE: f64 = 0.4;

/// The most scans a stretch of [`ScanAgreement::reference_outliers`] holds.
pub const MAX_OUTLIER_STRETCH: usize = 4;

/// How well the scans agree with two trajectories' relative pose on one
/// link (scan `to` placed in scan `from`'s frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkAgreement {
    /// Index of the earlier scan.
    pub from: usize,
    /// Index of the later scan (`from + 1`).
    pub to: usize,
    /// Share of the later scan's valid points on the earlier scan's
    /// surfaces with the reference's relative pose (0 without points).
    pub reference_share: f64,
    /// The same with the estimate's relative pose.
    pub estimate_share: f64,
}

impl LinkAgreement {
    /// The reference contradicts the scans here and the estimate does not.
    pub fn reference_contradicted(&self) -> bool {
        self.reference_share < CONTRADICTED_SHARE && self.estimate_share >= AGREEING_SHARE
    }

    /// The estimate contradicts the scans here and the reference does not.
    pub fn estimate_contradicted(&self) -> bool {
        self.estimate_share < CONTRADICTED_SHARE && self.reference_share >= AGREEING_SHARE
    }
}

/// The links of a sequence of scans judged by the scans
/// ([`scan_agreement`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ScanAgreement {
    /// One per pair of consecutive scans.
    pub links: Vec<LinkAgreement>,
    /// Scans whose reference pose the scans contradict from both sides: the
    /// scans from the later end of one reference-contradicted link to the
    /// earlier end of the next, at most [`MAX_OUTLIER_STRETCH`] scans. A
    /// lone contradicted link marks no scan (which side of it is off is not
    /// known).
    pub reference_outliers: Vec<usize>,
}

impl ScanAgreement {
    /// Links where the reference contradicts the scans and the estimate
    /// does not.
    pub fn reference_contradicted(&self) -> impl Iterator<Item = &LinkAgreement> {
        self.links.iter().filter(|l| l.reference_contradicted())
    }

    /// Links where the estimate contradicts the scans and the reference
    /// does not.
    pub fn estimate_contradicted(&self) -> impl Iterator<Item = &LinkAgreement> {
        self.links.iter().filter(|l| l.estimate_contradicted())
    }
}

/// Judges `reference` and `estimate` (a sensor pose per cloud of `clouds`)
/// link by link by the clouds themselves, with `config`'s agreement test
/// ([`agreeing_points`]). The three slices are cut to the shortest; a
/// non-finite pose gives its links a share of 0.
///
/// ```
/// use pcaline_aiding::{BeamCloud, ScanMatchConfig};
/// use pcaline_eval::scan_agreement;
/// use pcaline_geometry::{Pose2, Scan};
///
/// // A wall 2 m ahead seen twice from the same place, 181 beams over 90°.
/// let scan = Scan::new(-0.785, 0.785 / 90.0, 0.1, 30.0,
///     (0..181).map(|i| (2.0 / (-0.785 + 0.785 / 90.0 * i as f64).cos()) as f32).collect());
/// let config = ScanMatchConfig::standard();
/// let clouds = [BeamCloud::from_scan(&scan, &config), BeamCloud::from_scan(&scan, &config)];
/// let still = [Pose2::identity(), Pose2::identity()];
/// let moved = [Pose2::identity(), Pose2::new(0.5, 0.0, 0.0)];
/// let a = scan_agreement(&clouds, &moved, &still, &config);
/// assert!(a.links[0].reference_contradicted());
/// assert!(a.reference_outliers.is_empty()); // one link cannot say which scan is off
/// ```
pub fn scan_agreement(
    clouds: &[BeamCloud],
    reference: &[Pose2],
    estimate: &[Pose2],
    config: &ScanMatchConfig,
) -> ScanAgreement {
    let n = clouds.len().min(reference.len()).min(estimate.len());
    let share = |from: usize, to: usize, poses: &[Pose2]| {
        let points = clouds[to].len();
        if points == 0 {
            return 0.0;
        }
        let relative = poses[from].between(&poses[to]);
        agreeing_points(&clouds[from], &clouds[to], &relative, config) as f64 / points as f64
    };
    let links: Vec<LinkAgreement> = (1..n)
        .map(|to| LinkAgreement {
            from: to - 1,
            to,
            reference_share: share(to - 1, to, reference),
            estimate_share: share(to - 1, to, estimate),
        })
        .collect();
    let contradicted: Vec<&LinkAgreement> =
        links.iter().filter(|l| l.reference_contradicted()).collect();
    let reference_outliers = contradicted
        .windows(2)
        .filter(|w| w[1].from + 1 - w[0].to <= MAX_OUTLIER_STRETCH)
        .flat_map(|w| w[0].to..=w[1].from)
        .collect();
    ScanAgreement { links, reference_outliers }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scans::room_scan;
    use pcaline_geometry::Scan;

    #[test]
    fn a_reference_pose_off_at_one_scan_is_caught_from_both_sides() {
        let config = ScanMatchConfig::standard();
        let truth: Vec<Pose2> =
            (0..8).map(|k| Pose2::new(0.1 * k as f64, 0.05 * k as f64, 0.1 * k as f64)).collect();
        let clouds: Vec<BeamCloud> =
            truth.iter().map(|p| BeamCloud::from_scan(&room_scan(p), &config)).collect();
        let mut reference = truth.clone();
        // Scans 3 and 4 turned by 12° in the reference: both their outer
        // links are contradicted, the link between them is not.
        for p in &mut reference[3..5] {
            *p = Pose2::new(p.x(), p.y(), p.heading() + 12f64.to_radians());
        }
        // The estimate off at scan 6 alone, and only in the estimate.
        let mut estimate = truth.clone();
        let e = estimate[6];
        estimate[6] = Pose2::new(e.x(), e.y(), e.heading() - 10f64.to_radians());
        let a = scan_agreement(&clouds, &reference, &estimate, &config);
        assert_eq!(a.links.len(), 7);
        let flagged: Vec<usize> = a.reference_contradicted().map(|l| l.to).collect();
        assert_eq!(flagged, vec![3, 5]);
        assert_eq!(a.reference_outliers, vec![3, 4]);
        let estimate_flagged: Vec<usize> = a.estimate_contradicted().map(|l| l.to).collect();
        assert_eq!(estimate_flagged, vec![6, 7]);
        assert!(a.links[0].reference_share > 0.9 && a.links[0].estimate_share > 0.9);
    }

    #[test]
    fn contradicted_links_far_apart_mark_no_scan() {
        let config = ScanMatchConfig::standard();
        let truth: Vec<Pose2> = (0..12).map(|k| Pose2::new(0.05 * k as f64, 0.0, 0.0)).collect();
        let clouds: Vec<BeamCloud> =
            truth.iter().map(|p| BeamCloud::from_scan(&room_scan(p), &config)).collect();
        let mut reference = truth.clone();
        for p in &mut reference[2..10] {
            *p = Pose2::new(p.x(), p.y(), p.heading() + 12f64.to_radians());
        }
        let a = scan_agreement(&clouds, &reference, &truth, &config);
        assert_eq!(a.reference_contradicted().count(), 2);
        assert!(a.reference_outliers.is_empty(), "{:?}", a.reference_outliers);
    }

    #[test]
    fn empty_clouds_and_bad_poses_give_zero_shares_not_nan() {
        let config = ScanMatchConfig::standard();
        let empty =
            BeamCloud::from_scan(&Scan::new(0.0, 0.01, 0.1, 30.0, vec![f32::NAN; 10]), &config);
        let full = BeamCloud::from_scan(&room_scan(&Pose2::identity()), &config);
        let poses = [Pose2::identity(), Pose2::new(f64::NAN, 0.0, 0.0)];
        let a = scan_agreement(&[full.clone(), empty], &poses, &poses, &config);
        assert_eq!(a.links[0].reference_share, 0.0);
        let a = scan_agreement(&[full.clone(), full], &poses, &poses[..1], &config);
        assert!(a.links.is_empty());
    }
}
