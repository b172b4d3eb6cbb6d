//! The source's systematic errors as states of the estimator (beyond the
//! paper): a heading-rate bias (a gyro's, or wheel odometry that turns too
//! much one way) and a speed scale error (a wheel diameter off by a few
//! percent).
//!
//! Each accepted correction of a step observes what is left of them in the
//! step: a heading correction over `dt` seconds observes the bias, a
//! correction along the step observes the scale. Two scalar Kalman filters
//! beside the pose's estimate them, and the next increments are corrected
//! with the estimates. Without them, a constant bias drifts the map with the
//! pose: the lines inserted a scan ago agree with the drift, and every
//! correction sees only the newest step's share of it.

use pcaline_geometry::{Matrix3, Pose2, Vector2};

/// Which systematic errors of the source are estimated, and how uncertain
/// they are before the first scan.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct CalibrationConfig {
    /// Standard deviation of the heading-rate bias before any scan, rad/s;
    /// `None`: no bias is estimated. Needs stamped scans
    /// ([`crate::Aiding::step_at`]).
    pub heading_rate_bias_std_rad_s: Option<f64>,
    /// Random walk of the bias, rad/s per square-root second.
    pub heading_rate_bias_walk_rad_s_per_sqrt_s: f64,
    /// Standard deviation of the speed scale error before any scan (0.05:
    /// 5%); `None`: no scale is estimated.
    pub speed_scale_std: Option<f64>,
    /// Random walk of the scale error per square-root metre travelled.
    pub speed_scale_walk_per_sqrt_m: f64,
}

impl CalibrationConfig {
    /// A bias of 1°/s and a scale error of 5% before any scan, slow random
    /// walks (0.001°/s per root second, 0.01% per root metre).
    pub const fn standard() -> Self {
        CalibrationConfig {
            heading_rate_bias_std_rad_s: Some(0.017_45),
            heading_rate_bias_walk_rad_s_per_sqrt_s: 1.745e-5,
            speed_scale_std: Some(0.05),
            speed_scale_walk_per_sqrt_m: 1e-4,
        }
    }
}

/// The estimates and their variances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SourceCalibration {
    /// Heading-rate bias, rad/s (the source turns this much too fast).
    pub heading_rate_bias_rad_s: f64,
    /// Its variance.
    pub heading_rate_bias_var: f64,
    /// Speed scale error (0.03: the source's steps are 3% too long).
    pub speed_scale_error: f64,
    /// Its variance.
    pub speed_scale_var: f64,
}

/// A correction of a prior error seen as a measurement of that error: the
/// correction `c` moved an estimate of prior variance `p_prior` to posterior
/// variance `p_post`. Returns the measurement-only value and its variance,
/// or `None` when the update carried no information along it.
fn as_measurement(c: f64, p_prior: f64, p_post: f64) -> Option<(f64, f64)> {
    let gain = (p_prior - p_post) / p_prior;
    if !(gain > 1e-3 && gain.is_finite() && c.is_finite()) {
        return None;
    }
    let r = p_prior * p_post / (p_prior - p_post);
    Some((c / gain, r))
}

impl SourceCalibration {
    /// Nothing known yet.
    pub fn new(config: &CalibrationConfig) -> Self {
        SourceCalibration {
            heading_rate_bias_rad_s: 0.0,
            heading_rate_bias_var: config.heading_rate_bias_std_rad_s.map_or(0.0, |s| s * s),
            speed_scale_error: 0.0,
            speed_scale_var: config.speed_scale_std.map_or(0.0, |s| s * s),
        }
    }

    /// The increment with the estimated errors removed, and the variance
    /// their uncertainty adds to the predicted heading and along the step.
    /// `dt_s` is the step's duration when known. The random walks are
    /// added to the variances here.
    pub fn correct(
        &mut self,
        config: &CalibrationConfig,
        increment: &Pose2,
        dt_s: Option<f64>,
    ) -> (Pose2, f64, f64) {
        let mut inc = *increment;
        let (mut var_heading, mut var_along) = (0.0, 0.0);
        if let (Some(_), Some(dt)) = (config.heading_rate_bias_std_rad_s, dt_s) {
            self.heading_rate_bias_var +=
                config.heading_rate_bias_walk_rad_s_per_sqrt_s.powi(2) * dt;
            inc = Pose2::new(inc.x(), inc.y(), inc.heading() - self.heading_rate_bias_rad_s * dt);
            var_heading = self.heading_rate_bias_var * dt * dt;
        }
        let len = inc.x().hypot(inc.y());
        if config.speed_scale_std.is_some() {
            self.speed_scale_var += config.speed_scale_walk_per_sqrt_m.powi(2) * len;
            let k = 1.0 / (1.0 + self.speed_scale_error);
            inc = Pose2::new(inc.x() * k, inc.y() * k, inc.heading());
            var_along = self.speed_scale_var * len * len;
        }
        (inc, var_heading, var_along)
    }

    /// Learns from an accepted update: the heading correction over `dt_s`
    /// seconds and the translation correction along the predicted step's
    /// world direction `step_world` (metres, its length the step's), with the
    /// prior and posterior pose covariances.
    pub fn observe(
        &mut self,
        config: &CalibrationConfig,
        dt_s: Option<f64>,
        step_world: &Vector2<f64>,
        correction: (&Vector2<f64>, f64),
        prior: &Matrix3<f64>,
        posterior: &Matrix3<f64>,
    ) {
        let (translation, heading) = correction;
        if let (Some(_), Some(dt)) = (config.heading_rate_bias_std_rad_s, dt_s)
            && let Some((z, r)) = as_measurement(heading, prior[(2, 2)], posterior[(2, 2)])
            && dt > 0.0
        {
            // The heading error of the prediction is (bias left) * dt plus
            // the step's own noise.
            let (y, var_y) = (-z / dt, (r + prior[(2, 2)]) / (dt * dt));
            let k = self.heading_rate_bias_var / (self.heading_rate_bias_var + var_y);
            self.heading_rate_bias_rad_s += k * y;
            self.heading_rate_bias_var *= 1.0 - k;
        }
        let len = step_world.norm();
        if config.speed_scale_std.is_some() && len > 0.05 {
            let u = step_world / len;
            let along = |p: &Matrix3<f64>| {
                let t = p.fixed_view::<2, 2>(0, 0);
                (u.transpose() * t * u)[(0, 0)]
            };
            if let Some((z, r)) =
                as_measurement(translation.dot(&u), along(prior), along(posterior))
            {
                // The step was too long by (scale left) * len.
                let (y, var_y) = (-z / len, (r + along(prior)) / (len * len));
                let k = self.speed_scale_var / (self.speed_scale_var + var_y);
                self.speed_scale_error += k * y;
                self.speed_scale_var *= 1.0 - k;
            }
        }
        if !(self.heading_rate_bias_rad_s.is_finite() && self.speed_scale_error.is_finite()) {
            *self = SourceCalibration::new(config);
        }
        // A scale error beyond 50% is not a calibration error.
        self.speed_scale_error = self.speed_scale_error.clamp(-0.5, 0.5);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_bias_is_learnt_from_its_corrections() {
        let config = CalibrationConfig::standard();
        let mut cal = SourceCalibration::new(&config);
        let bias = 0.005; // rad/s
        for _ in 0..200 {
            let (inc, _, _) = cal.correct(&config, &Pose2::new(0.0, 0.0, bias), Some(1.0));
            // The prediction's heading error is what is left of the bias;
            // an exact measurement corrects it entirely.
            let prior = Matrix3::from_diagonal(&[1e-4, 1e-4, 1e-4].into());
            let post = Matrix3::from_diagonal(&[1e-4, 1e-4, 1e-6].into());
            let correction = -(inc.heading() - 0.0);
            let step = Vector2::zeros();
            cal.observe(&config, Some(1.0), &step, (&Vector2::zeros(), correction), &prior, &post);
        }
        assert!((cal.heading_rate_bias_rad_s - bias).abs() < 2e-4, "{cal:?}");
    }

    #[test]
    fn a_correction_without_information_teaches_nothing() {
        assert!(as_measurement(0.1, 1.0, 1.0).is_none());
        assert!(as_measurement(f64::NAN, 1.0, 0.5).is_none());
        let (z, r) = as_measurement(0.05, 1.0, 0.5).unwrap();
        assert!((z - 0.1).abs() < 1e-12 && (r - 1.0).abs() < 1e-12);
    }
}
