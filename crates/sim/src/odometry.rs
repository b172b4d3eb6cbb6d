//! [`OdometryModel`]: the "localization algorithm" of the paper, simulated: the
//! true motion corrupted by a heading-rate bias, random walks and a speed
//! scale error, seeded.

use crate::rng::{Stream, stream_rng};
use pcaline_geometry::{ConfigError, Pose2};
use rand_distr::{Distribution, StandardNormal};

/// Errors of a dead-reckoning source, applied to each increment of the true motion.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OdometryModel {
    /// Constant heading-rate bias, rad/s (a gyro bias).
    pub heading_rate_bias_rad_s: f64,
    /// Heading random walk, rad/sqrt(s).
    pub heading_random_walk_rad_sqrt_s: f64,
    /// Relative speed error (0.02 = distances 2% too long).
    pub speed_scale_error: f64,
    /// Position random walk per axis, m/sqrt(s).
    pub position_random_walk_m_sqrt_s: f64,
}

impl OdometryModel {
    /// Odometry poses for the true poses `truth` sampled every `dt_s`: the
    /// first pose is exact, each later one composes a corrupted increment.
    /// Noise of step `k` comes from its own seeded stream.
    pub fn corrupt(&self, truth: &[Pose2], dt_s: f64, seed: u64) -> Vec<Pose2> {
        self.corrupt_with(truth, |_| dt_s, seed)
    }

    /// As [`OdometryModel::corrupt`], for poses sampled at the times `times_s`
    /// (seconds, one per pose, non-decreasing; a log's timestamps): step `k`
    /// lasts `times_s[k] - times_s[k - 1]` (a negative or NaN step counts as 0).
    /// Extra poses or times beyond the shorter slice are ignored.
    pub fn corrupt_stamped(&self, truth: &[Pose2], times_s: &[f64], seed: u64) -> Vec<Pose2> {
        let n = truth.len().min(times_s.len());
        self.corrupt_with(&truth[..n], |k| times_s[k] - times_s[k - 1], seed)
    }

    fn corrupt_with(&self, truth: &[Pose2], dt_of: impl Fn(usize) -> f64, seed: u64) -> Vec<Pose2> {
        let mut out = Vec::with_capacity(truth.len());
        let Some(first) = truth.first() else {
            return out;
        };
        out.push(*first);
        for k in 1..truth.len() {
            let dt_s = dt_of(k).max(0.0);
            let sqrt_dt = dt_s.sqrt();
            let inc = truth[k - 1].between(&truth[k]);
            let mut rng = stream_rng(seed, Stream::Odometry, k as u64);
            let mut normal = || -> f64 { StandardNormal.sample(&mut rng) };
            let dh = inc.heading()
                + self.heading_rate_bias_rad_s * dt_s
                + self.heading_random_walk_rad_sqrt_s * sqrt_dt * normal();
            let scale = 1.0 + self.speed_scale_error;
            let dx = inc.x() * scale + self.position_random_walk_m_sqrt_s * sqrt_dt * normal();
            let dy = inc.y() * scale + self.position_random_walk_m_sqrt_s * sqrt_dt * normal();
            let prev = out[k - 1];
            out.push(prev.compose(&Pose2::new(dx, dy, dh)));
        }
        out
    }

    /// Checks every value.
    pub fn validate(&self) -> Result<(), ConfigError> {
        for (field, v) in [
            ("odometry.heading_rate_bias", self.heading_rate_bias_rad_s),
            ("odometry.heading_random_walk", self.heading_random_walk_rad_sqrt_s),
            ("odometry.speed_scale_error", self.speed_scale_error),
            ("odometry.position_random_walk", self.position_random_walk_m_sqrt_s),
        ] {
            ConfigError::check(v.is_finite(), field, v, "must be finite")?;
        }
        ConfigError::check(
            self.heading_random_walk_rad_sqrt_s >= 0.0
                && self.heading_random_walk_rad_sqrt_s.is_finite(),
            "odometry.heading_random_walk",
            self.heading_random_walk_rad_sqrt_s,
            "must be finite and >= 0",
        )?;
        ConfigError::check(
            self.position_random_walk_m_sqrt_s >= 0.0
                && self.position_random_walk_m_sqrt_s.is_finite(),
            "odometry.position_random_walk",
            self.position_random_walk_m_sqrt_s,
            "must be finite and >= 0",
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pure_heading_bias_drifts_linearly() {
        let truth: Vec<_> = (0..101).map(|k| Pose2::new(0.1 * k as f64, 0.0, 0.0)).collect();
        let m = OdometryModel { heading_rate_bias_rad_s: 0.01, ..Default::default() };
        let odo = m.corrupt(&truth, 0.1, 1);
        assert!((odo[100].heading() - 0.1).abs() < 1e-12);
        let exact = OdometryModel::default().corrupt(&truth, 0.1, 1);
        assert!((exact[100].x() - 10.0).abs() < 1e-9 && exact[100].y().abs() < 1e-9);
    }

    #[test]
    fn same_seed_same_drift() {
        let truth: Vec<_> =
            (0..50).map(|k| Pose2::new(0.1 * k as f64, 0.0, 0.01 * k as f64)).collect();
        let m = OdometryModel {
            heading_random_walk_rad_sqrt_s: 0.01,
            position_random_walk_m_sqrt_s: 0.01,
            ..Default::default()
        };
        assert_eq!(m.corrupt(&truth, 0.025, 3), m.corrupt(&truth, 0.025, 3));
        assert_ne!(m.corrupt(&truth, 0.025, 3), m.corrupt(&truth, 0.025, 4));
    }

    #[test]
    fn stamped_steps_follow_the_timestamps() {
        let truth: Vec<_> = (0..4).map(|k| Pose2::new(k as f64, 0.0, 0.0)).collect();
        let m = OdometryModel { heading_rate_bias_rad_s: 0.1, ..Default::default() };
        // Steps of 1 s, 3 s, then a backwards stamp (counted as 0 s).
        let odo = m.corrupt_stamped(&truth, &[0.0, 1.0, 4.0, 3.0], 1);
        assert!((odo[3].heading() - 0.4).abs() < 1e-12, "{:?}", odo[3]);
        let uniform = m.corrupt(&truth, 0.5, 9);
        assert_eq!(m.corrupt_stamped(&truth, &[0.0, 0.5, 1.0, 1.5], 9), uniform);
        assert_eq!(m.corrupt_stamped(&truth, &[0.0, 0.5], 9).len(), 2);
    }
}
