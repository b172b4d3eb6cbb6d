//! Localization errors of an estimated trajectory against the truth.

use pcaline_geometry::{Pose2, wrap_angle};

/// Heading and position errors of a trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
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
            if e.is_finite() { wrap_angle(e.heading - t.heading).abs() } else { f64::INFINITY };
        let dp = if e.is_finite() { (e.x - t.x).hypot(e.y - t.y) } else { f64::INFINITY };
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
