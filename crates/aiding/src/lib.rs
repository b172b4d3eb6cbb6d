//! Localization aiding from line matches (paper, section 2.1, and beyond).
//!
//! A localization source (odometry, inertial, a log's poses) drifts. Each
//! scan's lines, placed in the world with the current estimate, are matched
//! against the line map; the matches correct the heading by the weighted mean
//! of their orientation offsets (eq. 11-13) and rotate the position step
//! accordingly (eq. 14). Beyond the paper, [`AidingMode::FullPose`] then
//! solves the translation from the matched lines' normal offsets (robust
//! weighted least squares, only along directions the matches constrain) and
//! iterates match and solve.
//!
//! ```
//! use pcaline_aiding::{Aiding, AidingConfig, SensorLine};
//! use pcaline_fitting::{Moments, line_from_moments};
//! use pcaline_geometry::{Point2, Pose2};
//! use pcaline_mapping::MapConfig;
//!
//! // A wall 3 m ahead, seen from the origin.
//! let pts: Vec<_> = (0..=20).map(|i| Point2::new(3.0, -1.0 + 0.1 * i as f64)).collect();
//! let moments = Moments::from_points(&pts);
//! let wall = SensorLine { line: line_from_moments(&moments, &pts[0], &pts[20]).unwrap(), moments };
//!
//! let mut aiding = Aiding::new(AidingConfig::paper(), MapConfig::paper()).unwrap();
//! aiding.step(&Pose2::identity(), &[wall]);
//! // The source claims the sensor turned by 0.05 rad; the wall says it did not.
//! let (pose, report) = aiding.step(&Pose2::new(0.0, 0.0, 0.05), &[wall]);
//! assert!(pose.heading().abs() < 1e-9);
//! assert_eq!(report.matches, 1);
//! ```

mod aiding;
mod heading;
mod line_alignment;
mod line_measurement;
mod localizer;
mod loop_closure;
mod motion_noise;
mod place_descriptor;
mod pose_graph;
mod pose_update;
mod pose_window;
mod recovery;
mod scan_registration;
mod source_calibration;
mod translation;

pub use aiding::{Aiding, Association, MatchOutcome, ObservedLine, SensorLine};

pub use heading::{MIN_D_RHO_M, heading_correction, rotate_step, weighted_offset};
pub use line_alignment::{
    Alignment, AlignmentConfig, AlignmentPrior, Facing, align_lines, laid_length,
    see_through_fraction,
};
pub use line_measurement::{LineMeasurement, MeasurementNoise, measure};
pub use localizer::Localizer;
pub use loop_closure::{
    Keyframe, LoopClosing, LoopClosureConfig, LoopOutcome, LoopRecord, LoopSearch, LoopStep,
    OptimizeSchedule,
};
pub use motion_noise::{MotionNoise, predict, predict_with};
pub use place_descriptor::{
    PlaceDescriptor, PlaceRecognitionConfig, SEPARATION_BIN_M, SEPARATION_BINS,
};
pub use pose_graph::{
    EdgeKind, NotOptimized, OptimizeReport, OptimizerConfig, PoseEdge, PoseGraph,
};
pub use pose_update::{PoseUpdate, gate_distance2, iterated_update, joint_consistent};
pub use pose_window::{MeasureAt, PoseWindow, WindowStep};
pub use recovery::{Recovered, Recovery, recover};
pub use scan_registration::{
    BeamCloud, FusedIncrement, Registration, ScanMatchConfig, ScanRegistrar, agreeing_points,
    fuse_registration, register_from_guesses, register_scans,
};
pub use source_calibration::{
    CalibrationConfig, MAX_TURN_RATE_RAD_S, STILL_STEP_M, STILL_TURN_RAD, SourceCalibration,
};
pub use translation::{NormalConstraint, TranslationFix, solve_translation};

use pcaline_geometry::{ConfigError, Matrix3, Pose2, Vector2};

/// Which corrections are applied.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
#[non_exhaustive]
pub enum AidingMode {
    /// No correction: the map is built with the source's poses (for comparison).
    None,
    /// The paper: heading from eq. 11-13, position step rotated by eq. 14.
    Heading,
    /// Heading as the paper, then the translation from the matched lines,
    /// iterated; every scan's correction applied in full.
    FullPose,
    /// The estimator (the default): the pose carries a covariance grown by
    /// the source's [`MotionNoise`]; each match is a measurement with its
    /// covariance, gated by Mahalanobis distance and checked jointly; an
    /// iterated EKF update fuses them; a correction inconsistent with the
    /// source is refused. Only confirmed map lines correct the pose.
    Estimator,
}

/// Configuration of [`AidingMode::Estimator`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct EstimatorConfig {
    /// The localization source's motion noise.
    pub motion: MotionNoise,
    /// The prediction's noise when there is no source (LIDAR-only mode: the
    /// last estimated motion repeated) and the scans are not stamped, or
    /// when the source jumped.
    pub constant_velocity: MotionNoise,
    /// LIDAR-only mode with stamped scans: the last estimated velocity
    /// carried over the scan's duration, wrong by at most these
    /// accelerations.
    pub max_acceleration: Acceleration,
    /// The floors of a match's covariance.
    pub measurement: MeasurementNoise,
    /// A match is a candidate when its squared Mahalanobis distance under
    /// the predicted covariance is at most this (two degrees of freedom;
    /// 13.8 is the 99.9% quantile).
    pub gate_chi2: f64,
    /// A match supports a joint hypothesis when its squared Mahalanobis
    /// distance after that hypothesis' correction is at most this (9.21:
    /// 99%, two degrees of freedom).
    pub consensus_chi2: f64,
    /// The correction is refused when its squared Mahalanobis distance
    /// under the predicted covariance exceeds this (16.3: 99.9%, three
    /// degrees of freedom); the covariance is then inflated by the excess,
    /// so a correction that persists is accepted on a later scan.
    pub innovation_chi2: f64,
    /// The largest inflation of a refused step.
    pub max_inflation: f64,
    /// Relinearisations of the iterated update.
    pub iterations: usize,
    /// Estimates the source's heading-rate bias, speed scale error and latency
    /// ([`CalibrationConfig`]); `None`: the source is taken as calibrated.
    pub calibration: Option<CalibrationConfig>,
    /// Adapts the motion noise to the source at hand from the innovation
    /// test's statistic; `None`: the model is used as it is.
    pub adaptation: Option<NoiseAdaptation>,
    /// Adapts the matches' covariances to the lines at hand from their
    /// scatter about each solution ([`NoiseAdaptation::next_mean`]);
    /// `None` (the default): [`MeasurementNoise`] as it is. Measured: on the
    /// simulated UTM-30LX-EW scenes, whose lines are better than the real
    /// SICK logs' the floors were measured on, it takes the estimator from
    /// 2.1 cm to 4 mm position rms; on Intel it moved the log's own poses
    /// 1.3-2.3° instead of 0.8°. Not the default until the floors come from
    /// a sensor profile.
    pub measurement_adaptation: Option<NoiseAdaptation>,
    /// Tentative map lines correct the pose too, with their matches'
    /// variances times this; `None`: only confirmed lines correct it.
    pub tentative_variance_scale: Option<f64>,
    /// Huber's threshold of the update's robust weights, in standard
    /// deviations of a match's own covariance.
    pub huber_k: f64,
    /// Smooth over a sliding window of this many scans' poses
    /// ([`PoseWindow`]) instead of the iterated EKF alone; `None` (the
    /// default): the iterated EKF. Measured in `docs/accuracy.md`.
    pub window: Option<usize>,
    /// Fewest consistent matches that may correct the pose: a single line
    /// cannot be checked against anything, and one wrong match pulls as
    /// hard as a right one.
    pub min_matches: usize,
    /// The widest orientation gate of a candidate, radians, however
    /// uncertain the pose.
    pub max_gate_alpha_rad: f64,
    /// The widest offset gate of a candidate, metres.
    pub max_gate_offset_m: f64,
    /// A source increment longer than this between two scans is a jump
    /// (a teleport, a reset), metres: the step is predicted without it.
    pub max_source_step_m: f64,
    /// A source turn larger than this between two scans is a jump, radians.
    pub max_source_turn_rad: f64,
    /// When fewer than two matches agree, the scan's lines are aligned with
    /// the confirmed map lines around the prediction without its gates
    /// ([`recover`]); a clearly better placement that the predicted
    /// covariance does not allow ([`Recovery::min_change_chi2`]) becomes
    /// the prediction, its covariance widened to cover the change, and the
    /// step's correction does not teach the calibration. `None` (the
    /// default): the source's prediction is kept whatever the scan says.
    /// Measured in `docs/accuracy.md` ("Recovery from a source far off"):
    /// it pulls a drifting source back better, but moves the results on MIT
    /// CSAIL's raw odometry unpredictably.
    pub recovery: Option<Recovery>,
    /// Each scan registered to the previous one ([`ScanRegistrar`], run
    /// by [`Localizer::step_scan`]) and the registration fused with the
    /// source's increment ([`fuse_registration`]) once the registrations
    /// find the source worse than its noise model: their disagreement
    /// adapts a scale on the model of its own, and while that scale stays
    /// at or below 1 the source is kept as it is (a good source comes out
    /// as before). A registration-fused step teaches the calibration its
    /// heading correction and does not adapt the line matches' motion
    /// noise scale. `None`: the source alone. Beyond the paper; the
    /// default since 2026-12-05 (`docs/accuracy.md`, "Scan-to-scan
    /// registration"). In a configuration file, `scan_matching = false`
    /// turns it off.
    pub scan_matching: Option<ScanMatchConfig>,
}

/// The largest accelerations of a sensor carried without a motion source
/// (one standard deviation of the constant-velocity prediction's error).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct Acceleration {
    /// Linear, metres per second squared.
    pub linear_m_s2: f64,
    /// Angular, radians per second squared.
    pub angular_rad_s2: f64,
}

impl Acceleration {
    /// 5 m/s² and 10 rad/s²: a hand-carried or small wheeled sensor.
    pub const fn hand_held() -> Self {
        Acceleration { linear_m_s2: 5.0, angular_rad_s2: 10.0 }
    }
}

/// Innovation-based adaptation of the motion noise (Mehra 1970; Mohamed
/// and Schwarz 1999): one factor on the model's variances, moved after
/// every update towards what the matches say. When the prior disagrees with
/// what the matches alone say by less than its degrees of freedom lead one
/// to expect, the source is better than the model and the factor shrinks;
/// when by more, it grows. A good source is then trusted as it deserves,
/// and a drifting one is followed less and pulled back more, with one model.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct NoiseAdaptation {
    /// Exponent of one update's ratio (statistic / degrees of freedom) on
    /// the factor: the adaptation's speed, in (0, 1].
    pub rate: f64,
    /// Smallest factor.
    pub min_scale: f64,
    /// Largest factor.
    pub max_scale: f64,
}

impl NoiseAdaptation {
    /// Rate 0.1 (about ten updates to follow a change), factors 0.03-100.
    /// The floor keeps some trust in the lines however good the source
    /// looks: lines inserted a scan ago agree with the source's latest
    /// drift, so the statistic cannot see all of it.
    pub const fn standard() -> Self {
        NoiseAdaptation { rate: 0.1, min_scale: 0.03, max_scale: 100.0 }
    }

    /// The motion noise's factor after an update whose statistic was
    /// `distance2` with `dof` degrees of freedom: a step of `rate` in the
    /// logarithm, `scale * ratio^rate` with `ratio = distance2 / dof`
    /// bounded to 0.05-20. Its fixed point is where the statistic's
    /// geometric mean meets its degrees of freedom, below its arithmetic
    /// mean (the mean of `ln(chi2_1)` is -1.27): it errs towards trusting
    /// the source, which is what keeps a good source's poses unchanged on
    /// the real logs (measured: `docs/accuracy.md`).
    pub fn next(&self, scale: f64, distance2: f64, dof: usize) -> f64 {
        let ratio = (distance2 / dof.max(1) as f64).clamp(0.05, 20.0);
        let next = scale * ratio.powf(self.rate);
        if next.is_finite() { next.clamp(self.min_scale, self.max_scale) } else { scale }
    }

    /// The measurement noise's factor: `scale * (1 + rate * (ratio - 1))`
    /// with the ratio bounded to 0-5, a stochastic approximation whose
    /// fixed point is the scale at which the statistic averages its degrees
    /// of freedom (unbiased, unlike [`NoiseAdaptation::next`]).
    pub fn next_mean(&self, scale: f64, distance2: f64, dof: usize) -> f64 {
        let ratio = (distance2 / dof.max(1) as f64).clamp(0.0, 5.0);
        let next = scale * (1.0 + self.rate * (ratio - 1.0));
        if next.is_finite() { next.clamp(self.min_scale, self.max_scale) } else { scale }
    }
}

impl EstimatorConfig {
    /// Wheel odometry adapted to the source, its heading-rate bias and
    /// speed scale estimated; the measured floors of
    /// [`MeasurementNoise::standard`]; 99.9% gates, a 99% joint test, a
    /// 99.9% innovation test; tentative lines used at 4 times the variance;
    /// 3 relinearisations with Huber weights at 2 sigma; gates of at most 15°
    /// and 1 m; jumps beyond 5 m or 90° between scans.
    pub const fn standard() -> Self {
        EstimatorConfig {
            motion: MotionNoise::wheel_odometry(),
            constant_velocity: MotionNoise::constant_velocity(),
            max_acceleration: Acceleration::hand_held(),
            measurement: MeasurementNoise::standard(),
            gate_chi2: 13.8,
            consensus_chi2: 9.21,
            innovation_chi2: 16.3,
            max_inflation: 100.0,
            iterations: 3,
            window: None,
            min_matches: 1,
            huber_k: 2.0,
            tentative_variance_scale: Some(4.0),
            adaptation: Some(NoiseAdaptation::standard()),
            measurement_adaptation: None,
            calibration: Some(CalibrationConfig::standard()),
            max_gate_alpha_rad: 0.261_8, // 15°
            max_gate_offset_m: 1.0,
            max_source_step_m: 5.0,
            max_source_turn_rad: std::f64::consts::FRAC_PI_2,
            recovery: None,
            scan_matching: Some(ScanMatchConfig::standard()),
        }
    }

    /// Checks every value; errors name the field as a configuration file
    /// writes it (`aiding.estimator.*`).
    pub fn validate(&self) -> Result<(), ConfigError> {
        const P: &str = "aiding.estimator";
        self.motion.validate("aiding.estimator.motion")?;
        self.constant_velocity.validate("aiding.estimator.constant_velocity")?;
        if let Some(s) = &self.scan_matching {
            s.validate()?;
        }
        ConfigError::positive_fields(
            P,
            &[
                ("measurement.alpha_floor_rad", self.measurement.alpha_floor_rad),
                ("measurement.offset_floor_m", self.measurement.offset_floor_m),
                ("measurement.line_variance_scale", self.measurement.line_variance_scale),
                ("huber_k", self.huber_k),
                ("gate_chi2", self.gate_chi2),
                ("consensus_chi2", self.consensus_chi2),
                ("innovation_chi2", self.innovation_chi2),
                ("max_gate_alpha_rad", self.max_gate_alpha_rad),
                ("max_gate_offset_m", self.max_gate_offset_m),
                ("max_source_step_m", self.max_source_step_m),
                ("max_acceleration.linear_m_s2", self.max_acceleration.linear_m_s2),
                ("max_acceleration.angular_rad_s2", self.max_acceleration.angular_rad_s2),
                ("max_source_turn_rad", self.max_source_turn_rad),
            ],
        )?;
        if let Some(a) = self.adaptation {
            ConfigError::check_field(
                a.rate > 0.0 && a.rate <= 1.0,
                P,
                "adaptation.rate",
                a.rate,
                "must be in (0, 1]",
            )?;
            ConfigError::check_field(
                a.min_scale > 0.0 && a.min_scale <= 1.0 && a.min_scale.is_finite(),
                P,
                "adaptation.min_scale",
                a.min_scale,
                "must be in (0, 1]",
            )?;
            ConfigError::check_field(
                a.max_scale >= 1.0 && a.max_scale.is_finite(),
                P,
                "adaptation.max_scale",
                a.max_scale,
                "must be finite and >= 1",
            )?;
        }
        if let Some(r) = self.recovery {
            r.validate("aiding.estimator.recovery")?;
        }
        if let Some(c) = self.calibration {
            for (field, v) in [
                (
                    "calibration.heading_rate_bias_std_rad_s",
                    c.heading_rate_bias_std_rad_s.unwrap_or(0.0),
                ),
                (
                    "calibration.heading_rate_bias_walk_rad_s_per_sqrt_s",
                    c.heading_rate_bias_walk_rad_s_per_sqrt_s,
                ),
                ("calibration.speed_scale_std", c.speed_scale_std.unwrap_or(0.0)),
                ("calibration.speed_scale_walk_per_sqrt_m", c.speed_scale_walk_per_sqrt_m),
                ("calibration.latency_std_s", c.latency_std_s.unwrap_or(0.0)),
                ("calibration.latency_walk_s_per_sqrt_s", c.latency_walk_s_per_sqrt_s),
            ] {
                ConfigError::check_field(
                    v >= 0.0 && v.is_finite(),
                    P,
                    field,
                    v,
                    "must be finite and >= 0",
                )?;
            }
        }
        if let Some(t) = self.tentative_variance_scale {
            ConfigError::check_field(
                t >= 1.0 && t.is_finite(),
                P,
                "tentative_variance_scale",
                t,
                "must be finite and >= 1",
            )?;
        }
        ConfigError::check_field(
            self.max_inflation >= 1.0 && self.max_inflation.is_finite(),
            P,
            "max_inflation",
            self.max_inflation,
            "must be finite and >= 1",
        )?;
        ConfigError::check_field(
            (1..=20).contains(&self.iterations),
            P,
            "iterations",
            self.iterations as f64,
            "must be in 1..=20",
        )
    }
}

/// How the orientation offsets of the matches are weighted.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
#[non_exhaustive]
pub enum HeadingWeights {
    /// Eq. 13: `1 / d_rho²`.
    InverseDRhoSquared,
    /// `1 / (var(alpha_new) + var(alpha_map) + floor²)` from the lines'
    /// covariances: long, well-fitted lines count most.
    InverseVariance {
        /// Floor of the orientation standard deviation, radians (model and
        /// pose errors the covariances do not hold).
        floor_rad: f64,
    },
}

/// Configuration of [`Aiding`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct AidingConfig {
    /// Which corrections are applied.
    pub mode: AidingMode,
    /// Weights of the heading correction.
    pub heading_weights: HeadingWeights,
    /// Match/solve rounds in [`AidingMode::FullPose`].
    pub iterations: usize,
    /// Residual scale of the Cauchy robust weights, metres.
    pub robust_scale_m: f64,
    /// Smallest information along a direction, relative to the best
    /// direction, for the translation to be corrected along it.
    pub min_information_ratio: f64,
    /// Floor of a constraint's standard deviation, metres (map and model errors).
    pub offset_floor_m: f64,
    /// Largest heading correction of one step, radians (the matching
    /// threshold already bounds it).
    pub max_heading_step_rad: f64,
    /// Largest translation correction of one round, metres.
    pub max_translation_step_m: f64,
    /// The estimator ([`AidingMode::Estimator`]).
    pub estimator: EstimatorConfig,
}

impl AidingConfig {
    /// The paper's heading aiding: eq. 11-14 with eq. 13's weights.
    pub fn paper() -> Self {
        AidingConfig {
            mode: AidingMode::Heading,
            heading_weights: HeadingWeights::InverseDRhoSquared,
            ..Self::full_pose()
        }
    }

    /// Heading aiding as the paper (eq. 11, 12, 14) with inverse-variance
    /// weights instead of eq. 13.
    pub fn heading() -> Self {
        AidingConfig { mode: AidingMode::Heading, ..Self::full_pose() }
    }

    /// Full-pose aiding: heading with inverse-variance weights, then
    /// translation, 3 rounds.
    pub fn full_pose() -> Self {
        AidingConfig {
            mode: AidingMode::FullPose,
            heading_weights: HeadingWeights::InverseVariance { floor_rad: 0.1f64.to_radians() },
            iterations: 3,
            robust_scale_m: 0.05,
            min_information_ratio: 0.05,
            offset_floor_m: 0.01,
            max_heading_step_rad: 15f64.to_radians(),
            max_translation_step_m: 0.5,
            estimator: EstimatorConfig::standard(),
        }
    }

    /// The estimator ([`AidingMode::Estimator`]) with
    /// [`EstimatorConfig::standard`]: the default.
    pub fn estimator() -> Self {
        AidingConfig { mode: AidingMode::Estimator, ..Self::full_pose() }
    }

    /// No aiding (the map is still built).
    pub fn none() -> Self {
        AidingConfig { mode: AidingMode::None, ..Self::full_pose() }
    }

    /// Checks every value.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.estimator.validate()?;
        for (field, v) in [
            ("aiding.robust_scale_m", self.robust_scale_m),
            ("aiding.offset_floor_m", self.offset_floor_m),
            ("aiding.max_heading_step_rad", self.max_heading_step_rad),
            ("aiding.max_translation_step_m", self.max_translation_step_m),
        ] {
            ConfigError::positive(field, v)?;
        }
        if let HeadingWeights::InverseVariance { floor_rad } = self.heading_weights {
            ConfigError::positive("aiding.heading_weights.inverse-variance.floor_rad", floor_rad)?;
        }
        ConfigError::unit_interval("aiding.min_information_ratio", self.min_information_ratio)
    }
}

impl Default for AidingConfig {
    /// The estimator.
    fn default() -> Self {
        Self::estimator()
    }
}

/// Why a step kept the uncorrected estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Fallback {
    /// No new line matched the map (or the map was empty).
    NoMatches,
    /// The matches agreed on a correction that the source's uncertainty
    /// makes implausible; the prediction was kept and its covariance
    /// inflated ([`EstimatorConfig::innovation_chi2`]).
    InconsistentWithSource,
    /// The source moved farther between two scans than
    /// [`EstimatorConfig::max_source_step_m`] or turned more than
    /// [`EstimatorConfig::max_source_turn_rad`]; the step was predicted
    /// by constant velocity instead.
    SourceJump,
    /// The scan's time stamp was earlier than the previous one; the scan
    /// was skipped.
    StampBackwards,
    /// The source pose or increment was not finite; the last corrected pose was kept.
    NonFiniteSource,
    /// The correction was not finite; the prediction was kept.
    NonFiniteCorrection,
}

/// How a step's pose was predicted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Prediction {
    /// From the localization source's motion.
    #[default]
    Source,
    /// From the last estimated motion (LIDAR-only mode, or a source jump).
    ConstantVelocity,
}

/// What one step did.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct StepReport {
    /// Matches used (in the last round).
    pub matches: usize,
    /// Lines whose best candidate lay outside the Mahalanobis gate.
    pub rejected_gate: usize,
    /// Lines with two candidates in the gate that would correct the pose
    /// differently (not used).
    pub ambiguous: usize,
    /// Gated matches left out by the joint consistency check.
    pub rejected_joint: usize,
    /// Lines that matched only tentative (or not straight) map lines.
    pub unconfirmed: usize,
    /// How the pose was predicted.
    pub prediction: Prediction,
    /// The estimator's pose covariance after the step, `(x, y, heading)`
    /// (zero for the other modes).
    pub covariance: Matrix3<f64>,
    /// Squared Mahalanobis distance of the correction under the predicted
    /// covariance (the innovation test's statistic; 0 without a correction).
    pub correction_distance2: f64,
    /// The factor on the motion noise's variances after the step
    /// ([`NoiseAdaptation`]; 1 without adaptation).
    pub motion_noise_scale: f64,
    /// The factor on the matches' covariances after the step
    /// ([`EstimatorConfig::measurement_adaptation`]; 1 without it).
    pub measurement_noise_scale: f64,
    /// Total heading correction applied, radians.
    pub heading_correction_rad: f64,
    /// Total translation correction applied, metres.
    pub translation_correction_m: Vector2<f64>,
    /// Directions the translation was corrected along (0, 1 or 2).
    pub constrained_directions: usize,
    /// Why the correction fell back, if it did.
    pub fallback: Option<Fallback>,
    /// When the source's prediction was replaced by
    /// [`EstimatorConfig::recovery`]: the change, `predicted_from_recovered`
    /// (the corrections above are then from the recovered prediction).
    pub recovery: Option<Pose2>,
}
