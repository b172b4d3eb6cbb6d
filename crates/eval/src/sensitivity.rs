//! Sensitivity runs: a source perturbed far below its own error, to see how
//! far a whole-log figure moves when nothing that matters changes.
//!
//! On a real log the estimator and loop closure take discrete decisions
//! (gates, ambiguous lines, which loops stand), and a difference in the last
//! bits can change one of them and move the whole trajectory by degrees (MIT
//! CSAIL's raw odometry: `docs/accuracy.md`, "How far one run can be
//! trusted"). A figure measured once is one draw; its spread over
//! [`SENSITIVITY_SEEDS`] runs of [`perturbed`] sources is what a change is
//! judged against.

use pcaline_geometry::Pose2;
use pcaline_sim::OdometryModel;

/// The perturbation: a random walk of 0.1 mm/sqrt(s) per axis and
/// 0.0006°/sqrt(s) (1e-5 rad/sqrt(s)) added to the source's increments, far
/// below any odometry's error. Over 7 minutes and 200 m it moves a path by
/// about 0.01° and, with the heading's lever arm, 1-2 cm.
pub const SENSITIVITY_PERTURBATION: OdometryModel = OdometryModel {
    heading_rate_bias_rad_s: 0.0,
    heading_random_walk_rad_sqrt_s: 1e-5,
    speed_scale_error: 0.0,
    position_random_walk_m_sqrt_s: 1e-4,
};

/// The seeds of the sensitivity runs.
pub const SENSITIVITY_SEEDS: [u64; 8] = [1, 2, 3, 4, 5, 6, 7, 8];

/// The source poses `source`, stamped `times_s` (seconds, one per pose),
/// with [`SENSITIVITY_PERTURBATION`] of seed `seed` added increment by
/// increment; the first pose is kept. Extra poses or times beyond the
/// shorter slice are dropped; a step whose time goes backwards (or is NaN)
/// gets no perturbation.
///
/// ```
/// use pcaline_eval::{SENSITIVITY_SEEDS, perturbed};
/// use pcaline_geometry::Pose2;
/// let path: Vec<Pose2> = (0..100).map(|k| Pose2::new(0.1 * k as f64, 0.0, 0.0)).collect();
/// let times: Vec<f64> = (0..100).map(|k| 0.2 * k as f64).collect();
/// let moved = perturbed(&path, &times, SENSITIVITY_SEEDS[0]);
/// assert_eq!(moved[0], path[0]);
/// assert!((moved[99].x() - path[99].x()).abs() < 0.01);
/// ```
pub fn perturbed(source: &[Pose2], times_s: &[f64], seed: u64) -> Vec<Pose2> {
    SENSITIVITY_PERTURBATION.corrupt_stamped(source, times_s, seed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trajectory_errors;

    /// Far below any odometry's error: over 7 minutes and 210 m at 5 scans
    /// a second it moves the path by 1-2 cm and hundredths of a degree,
    /// whatever the seed.
    #[test]
    fn the_perturbation_is_tiny() {
        let times: Vec<f64> = (0..2100).map(|k| k as f64 * 0.2).collect();
        let path: Vec<Pose2> =
            times.iter().map(|t| Pose2::new(0.5 * t, (0.1 * t).sin(), 0.05 * t)).collect();
        for seed in SENSITIVITY_SEEDS {
            let moved = perturbed(&path, &times, seed);
            let e = trajectory_errors(&moved, &path).unwrap();
            assert!(e.position_rms_m < 0.03 && e.heading_max_rad.to_degrees() < 0.05, "{e:?}");
            assert!(e.position_rms_m > 0.0, "the seeds perturb");
        }
    }
}
