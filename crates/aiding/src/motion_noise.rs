//! The localization source's uncertainty (beyond the paper): a motion noise
//! model that says how far an increment of the source may be wrong, and the
//! prediction that composes an increment onto a pose with its covariance.
//!
//! The paper applies each scan's correction in full, as if the source knew
//! nothing. A source comes with a confidence: wheel odometry drifts by a few
//! percent of the distance and the rotation it measures, an inertial
//! heading by a fraction of a degree per metre. The estimator weighs the
//! line matches against it.

use pcaline_geometry::{ConfigError, Matrix3, Pose2};

/// Standard deviations of an increment's error, growing with the motion
/// (the classic odometry model: Thrun et al., *Probabilistic Robotics*,
/// 5.4), plus a floor per step.
///
/// For an increment of translation `t` metres and rotation `r` radians:
/// `sigma_translation = hypot(translation_per_m * t, translation_per_rad * r,
/// translation_floor_m)` (along and across the motion alike), and
/// `sigma_rotation = hypot(rotation_per_rad * r, rotation_per_m * t,
/// rotation_floor_rad)`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct MotionNoise {
    /// Translation error per metre travelled, metres per metre.
    pub translation_per_m: f64,
    /// Translation error per radian turned, metres per radian.
    pub translation_per_rad: f64,
    /// Rotation error per radian turned, radians per radian.
    pub rotation_per_rad: f64,
    /// Rotation error per metre travelled, radians per metre.
    pub rotation_per_m: f64,
    /// Translation error of every step, however small, metres.
    pub translation_floor_m: f64,
    /// Rotation error of every step, however small, radians.
    pub rotation_floor_rad: f64,
}

impl MotionNoise {
    /// Wheel odometry of an indoor robot: 5% of the distance, 2 cm per
    /// radian turned; 5% of the rotation, 1° per metre; floors 5 mm and
    /// 0.1° a step. One model for every log: it is not tuned per dataset
    /// (the estimator adapts its scale, [`crate::NoiseAdaptation`]).
    pub const fn wheel_odometry() -> Self {
        MotionNoise {
            translation_per_m: 0.05,
            translation_per_rad: 0.02,
            rotation_per_rad: 0.05,
            rotation_per_m: 0.017_45, // 1° per metre
            translation_floor_m: 0.005,
            rotation_floor_rad: 0.001_745, // 0.1°
        }
    }

    /// The prediction of a log without a motion source (LIDAR-only mode):
    /// the last estimated motion repeated. Its error is the change of
    /// velocity between scans: 50% of the predicted step and 5 cm, 50% of
    /// the predicted turn and 3°, a step.
    pub const fn constant_velocity() -> Self {
        MotionNoise {
            translation_per_m: 0.5,
            translation_per_rad: 0.05,
            rotation_per_rad: 0.5,
            rotation_per_m: 0.05,
            translation_floor_m: 0.05,
            rotation_floor_rad: 0.052_36, // 3°
        }
    }

    /// A model with floors only: every step, whatever its size, is wrong by
    /// `translation_m` and `rotation_rad` (one standard deviation).
    pub const fn floors(translation_m: f64, rotation_rad: f64) -> Self {
        MotionNoise {
            translation_per_m: 0.0,
            translation_per_rad: 0.0,
            rotation_per_rad: 0.0,
            rotation_per_m: 0.0,
            translation_floor_m: translation_m,
            rotation_floor_rad: rotation_rad,
        }
    }

    /// The model with every variance times `factor` (standard deviations
    /// times its square root).
    pub fn scaled(&self, factor: f64) -> Self {
        let k = factor.max(0.0).sqrt();
        MotionNoise {
            translation_per_m: self.translation_per_m * k,
            translation_per_rad: self.translation_per_rad * k,
            rotation_per_rad: self.rotation_per_rad * k,
            rotation_per_m: self.rotation_per_m * k,
            translation_floor_m: self.translation_floor_m * k,
            rotation_floor_rad: self.rotation_floor_rad * k,
        }
    }

    /// The covariance of the error of `increment` in the previous body
    /// frame, `(x, y, heading)`. A non-finite increment gives a non-finite
    /// covariance (the caller falls back before using it).
    pub fn covariance(&self, increment: &Pose2) -> Matrix3<f64> {
        let t = increment.x().hypot(increment.y());
        let r = increment.heading().abs();
        let var_t = (self.translation_per_m * t).powi(2)
            + (self.translation_per_rad * r).powi(2)
            + self.translation_floor_m.powi(2);
        let var_r = (self.rotation_per_rad * r).powi(2)
            + (self.rotation_per_m * t).powi(2)
            + self.rotation_floor_rad.powi(2);
        Matrix3::from_diagonal(&[var_t, var_t, var_r].into())
    }

    /// Whether a step `increment` is a standstill: it moves less than half
    /// the floors, in translation and in rotation (below what the floors say
    /// any step is off by). False for a non-finite step.
    pub fn standstill(&self, increment: &Pose2) -> bool {
        increment.x().hypot(increment.y()) < 0.5 * self.translation_floor_m
            && increment.heading().abs() < 0.5 * self.rotation_floor_rad
    }

    /// Checks every value; errors name the field as a configuration file
    /// writes it, under `prefix` (such as `aiding.estimator.motion`).
    pub fn validate(&self, prefix: &'static str) -> Result<(), ConfigError> {
        for (field, v) in [
            ("translation_per_m", self.translation_per_m),
            ("translation_per_rad", self.translation_per_rad),
            ("rotation_per_rad", self.rotation_per_rad),
            ("rotation_per_m", self.rotation_per_m),
            ("translation_floor_m", self.translation_floor_m),
            ("rotation_floor_rad", self.rotation_floor_rad),
        ] {
            ConfigError::check_field(
                v >= 0.0 && v.is_finite(),
                prefix,
                field,
                v,
                "must be finite and >= 0",
            )?;
        }
        ConfigError::check_field(
            self.translation_floor_m > 0.0
                && self.rotation_floor_rad > 0.0
                && self.translation_floor_m.is_finite()
                && self.rotation_floor_rad.is_finite(),
            prefix,
            "translation_floor_m",
            self.translation_floor_m.min(self.rotation_floor_rad),
            "the floors must be finite and > 0 (a step is never known exactly)",
        )
    }
}

/// Composes `increment` (in the body frame of `pose`) onto `pose` and
/// propagates the covariance: `P' = F P F^T + G Q G^T`, with `F` the
/// Jacobian of the composition in the pose and `G` in the increment.
///
/// ```
/// use pcaline_aiding::{MotionNoise, predict};
/// use pcaline_geometry::{Matrix3, Pose2};
/// let (pose, cov) = predict(&Pose2::identity(), &Matrix3::zeros(), &Pose2::new(1.0, 0.0, 0.0),
///                           &MotionNoise::wheel_odometry());
/// assert_eq!(pose, Pose2::new(1.0, 0.0, 0.0));
/// assert!(cov[(0, 0)] > 0.0 && cov[(2, 2)] > 0.0);
/// ```
pub fn predict(
    pose: &Pose2,
    covariance: &Matrix3<f64>,
    increment: &Pose2,
    noise: &MotionNoise,
) -> (Pose2, Matrix3<f64>) {
    predict_with(pose, covariance, increment, &noise.covariance(increment))
}

/// [`predict`] with the increment's own covariance `increment_covariance`
/// (previous body frame, `(x, y, heading)`) instead of a noise model's: an
/// increment fused with a scan registration
/// ([`crate::fuse_registration`]) carries the fused covariance.
pub fn predict_with(
    pose: &Pose2,
    covariance: &Matrix3<f64>,
    increment: &Pose2,
    increment_covariance: &Matrix3<f64>,
) -> (Pose2, Matrix3<f64>) {
    let predicted = pose.compose(increment);
    let (s, c) = pose.heading().sin_cos();
    let (ux, uy) = (increment.x(), increment.y());
    #[rustfmt::skip]
    let f = Matrix3::new(
        1.0, 0.0, -s * ux - c * uy,
        0.0, 1.0, c * ux - s * uy,
        0.0, 0.0, 1.0,
    );
    #[rustfmt::skip]
    let g = Matrix3::new(
        c, -s, 0.0,
        s, c, 0.0,
        0.0, 0.0, 1.0,
    );
    let p = f * covariance * f.transpose() + g * increment_covariance * g.transpose();
    (predicted, (p + p.transpose()) * 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_standstill_moves_less_than_half_the_floors() {
        let m = MotionNoise::wheel_odometry();
        assert!(m.standstill(&Pose2::identity()));
        assert!(m.standstill(&Pose2::new(0.002, 0.0, 0.0005)));
        // 2.5 cm a scan: 1 m/s at 40 Hz.
        assert!(!m.standstill(&Pose2::new(0.025, 0.0, 0.0)));
        assert!(!m.standstill(&Pose2::new(0.0, 0.0, 0.1f64.to_radians())));
        assert!(!m.standstill(&Pose2::new(f64::NAN, 0.0, 0.0)));
    }

    #[test]
    fn uncertainty_grows_with_motion_and_heading_error_spreads_position() {
        let noise = MotionNoise::wheel_odometry();
        let still = noise.covariance(&Pose2::identity());
        let moving = noise.covariance(&Pose2::new(1.0, 0.0, 0.5));
        assert!(moving[(0, 0)] > still[(0, 0)] && moving[(2, 2)] > still[(2, 2)]);
        // A heading uncertainty turns into a position uncertainty across a step.
        let p0 = Matrix3::from_diagonal(&[0.0, 0.0, 0.01].into());
        let (_, p) = predict(&Pose2::identity(), &p0, &Pose2::new(2.0, 0.0, 0.0), &noise);
        assert!(p[(1, 1)] > 0.03, "{p}");
        assert!(p[(0, 0)] < 0.02, "{p}");
    }

    #[test]
    fn invalid_values_name_their_field() {
        let bad = MotionNoise { rotation_per_m: -1.0, ..MotionNoise::wheel_odometry() };
        let e = bad.validate("aiding.estimator.motion").unwrap_err().to_string();
        assert!(e.contains("aiding.estimator.motion.rotation_per_m"), "{e}");
    }
}
