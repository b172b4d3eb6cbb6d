//! Localization errors of an estimated trajectory against the truth.

use pcaline_geometry::{Pose2, wrap_angle};

/// Heading and position errors of a trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct TrajectoryErrors {
    /// Root mean square heading error, radians.
    pub heading_rms_rad: f64,
    /// Largest absolute heading error, radians.
    pub heading_max_rad: f64,
    /// Root mean square position error, metres.
    pub position_rms_m: f64,
    /// Position error of the last pose, metres.
    pub position_final_m: f64,
}

/// Errors of `estimate` against `truth`, pose by pose (the shorter length
/// counts). Non-finite estimates count as infinite errors. `None` when empty.
pub fn trajectory_errors(estimate: &[Pose2], truth: &[Pose2]) -> Option<TrajectoryErrors> {
    let n = estimate.len().min(truth.len());
    if n == 0 {
        return None;
    }
    let (mut h2, mut hmax, mut p2, mut last) = (0.0, 0.0f64, 0.0, 0.0);
    for (e, t) in estimate.iter().zip(truth).take(n) {
        let dh =
            if e.is_finite() { wrap_angle(e.heading() - t.heading()).abs() } else { f64::INFINITY };
        let dp = if e.is_finite() { (e.x() - t.x()).hypot(e.y() - t.y()) } else { f64::INFINITY };
        h2 += dh * dh;
        hmax = hmax.max(dh);
        p2 += dp * dp;
        last = dp;
    }
    Some(TrajectoryErrors {
        heading_rms_rad: (h2 / n as f64).sqrt(),
        heading_max_rad: hmax,
        position_rms_m: (p2 / n as f64).sqrt(),
        position_final_m: last,
    })
}

/// Errors of `estimate` against `reference` after aligning the estimate's
/// first pose onto the reference's (the two live in different world frames:
/// raw odometry and a SLAM solution).
pub fn aligned_trajectory_errors(
    estimate: &[Pose2],
    reference: &[Pose2],
) -> Option<TrajectoryErrors> {
    let (e0, r0) = (estimate.first()?, reference.first()?);
    let reference_from_estimate = r0.compose(&e0.inverse());
    let aligned: Vec<Pose2> = estimate.iter().map(|p| reference_from_estimate.compose(p)).collect();
    trajectory_errors(&aligned, reference)
}
/// The least-squares rigid alignment of `estimate`'s positions onto
/// `reference`'s (rotation and translation, no scale; Horn's closed form in
/// 2D): the `reference_from_estimate` transform that, composed onto each
/// estimated pose, brings the trajectory's shape onto the reference. Pairs
/// with a non-finite pose are left out. When every finite position
/// coincides, the mean heading difference is aligned instead. `None` when
/// no finite pair is left.
///
/// ```
/// use pcaline_eval::rigid_alignment;
/// use pcaline_geometry::Pose2;
///
/// let reference = [Pose2::new(0.0, 0.0, 0.0), Pose2::new(1.0, 0.0, 0.0)];
/// let moved = Pose2::new(3.0, -2.0, 0.5);
/// let estimate: Vec<Pose2> = reference.iter().map(|p| moved.compose(p)).collect();
/// let reference_from_estimate = rigid_alignment(&estimate, &reference).unwrap();
/// let back = reference_from_estimate.compose(&estimate[1]);
/// assert!((back.x() - 1.0).abs() < 1e-12 && back.y().abs() < 1e-12);
/// ```
pub fn rigid_alignment(estimate: &[Pose2], reference: &[Pose2]) -> Option<Pose2> {
    let pairs: Vec<(&Pose2, &Pose2)> =
        estimate.iter().zip(reference).filter(|(e, r)| e.is_finite() && r.is_finite()).collect();
    if pairs.is_empty() {
        return None;
    }
    let n = pairs.len() as f64;
    let (mut ex, mut ey, mut rx, mut ry) = (0.0, 0.0, 0.0, 0.0);
    for (e, r) in &pairs {
        ex += e.x() / n;
        ey += e.y() / n;
        rx += r.x() / n;
        ry += r.y() / n;
    }
    let (mut cross, mut dot) = (0.0, 0.0);
    for (e, r) in &pairs {
        let (px, py, qx, qy) = (e.x() - ex, e.y() - ey, r.x() - rx, r.y() - ry);
        cross += px * qy - py * qx;
        dot += px * qx + py * qy;
    }
    let theta = if cross == 0.0 && dot == 0.0 {
        // All positions coincide: align the mean heading instead.
        let (s, c) = pairs.iter().fold((0.0, 0.0), |(s, c), (e, r)| {
            let d = wrap_angle(r.heading() - e.heading());
            (s + d.sin(), c + d.cos())
        });
        s.atan2(c)
    } else {
        cross.atan2(dot)
    };
    let rotation = Pose2::new(0.0, 0.0, theta);
    let moved = rotation.transform_point(&pcaline_geometry::Point2::new(ex, ey));
    Some(Pose2::new(rx - moved.x, ry - moved.y, theta))
}

/// Errors of `estimate` against `reference` after the least-squares rigid
/// alignment of all positions ([`rigid_alignment`]): how well the
/// trajectory's shape agrees, whatever its start. Pairs with a non-finite
/// pose are left out of the alignment and count as infinite errors. `None`
/// when no finite pair is left.
pub fn rigidly_aligned_trajectory_errors(
    estimate: &[Pose2],
    reference: &[Pose2],
) -> Option<TrajectoryErrors> {
    let reference_from_estimate = rigid_alignment(estimate, reference)?;
    let aligned: Vec<Pose2> = estimate.iter().map(|p| reference_from_estimate.compose(p)).collect();
    trajectory_errors(&aligned, reference)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_alignment_removes_any_rigid_motion() {
        let reference: Vec<Pose2> =
            (0..20).map(|k| Pose2::new(k as f64, (k as f64 * 0.3).sin(), 0.1 * k as f64)).collect();
        let motion = Pose2::new(3.0, -7.0, 2.0);
        let estimate: Vec<Pose2> = reference.iter().map(|p| motion.compose(p)).collect();
        let e = rigidly_aligned_trajectory_errors(&estimate, &reference).unwrap();
        assert!(e.position_rms_m < 1e-9 && e.heading_rms_rad < 1e-9, "{e:?}");
        assert!(rigidly_aligned_trajectory_errors(&[], &reference).is_none());
    }
}
