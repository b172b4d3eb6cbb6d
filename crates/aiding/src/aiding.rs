//! [`Aiding`]: the mapping and localization-aiding loop of the paper's
//! section 2.1, one scan's lines at a time, with the paper's corrections
//! applied in full or (the default) the estimator that weighs them against
//! the source's uncertainty.

use crate::{
    AidingConfig, AidingMode, CalibrationConfig, Fallback, HeadingWeights, LineMeasurement,
    MAX_TURN_RATE_RAD_S, NormalConstraint, Prediction, SourceCalibration, StepReport,
};
use crate::{
    MotionNoise, Registration, fuse_registration, gate_distance2, heading_correction,
    iterated_update, joint_consistent, measure, predict_with, rotate_step, solve_translation,
    weighted_offset,
};
use crate::{PoseWindow, WindowStep};
use pcaline_fitting::Moments;
use pcaline_geometry::{
    ConfigError, LineSegment, Matrix3, Point2, Pose2, Twist2, Vector2, Vector3, wrap_angle,
};
use pcaline_mapping::{LineId, LineMap, LineStatus, MapConfig, MapLine, MatchGate};

/// A detected line in the sensor frame with the moments of its points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorLine {
    /// The line, sensor frame.
    pub line: LineSegment,
    /// Moments of its points, sensor frame.
    pub moments: Moments,
}

/// A line seen by the sensor with the moments of its points, both in the
/// sensor frame: what the aiding takes. [`SensorLine`] is the plain pair; a
/// detector's [`DetectedLine`](pcaline_fitting::DetectedLine) is one as it
/// comes, so detections go in without a conversion.
pub trait ObservedLine {
    /// The line, sensor frame.
    fn line(&self) -> &LineSegment;
    /// Moments of its points, sensor frame.
    fn moments(&self) -> &Moments;
}

impl ObservedLine for SensorLine {
    fn line(&self) -> &LineSegment {
        &self.line
    }
    fn moments(&self) -> &Moments {
        &self.moments
    }
}

impl ObservedLine for pcaline_fitting::DetectedLine {
    fn line(&self) -> &LineSegment {
        &self.line
    }
    fn moments(&self) -> &Moments {
        &self.moments
    }
}

impl From<&pcaline_fitting::DetectedLine> for SensorLine {
    /// The line and its moments, as the aiding takes them.
    fn from(l: &pcaline_fitting::DetectedLine) -> Self {
        SensorLine { line: l.line, moments: l.moments }
    }
}

/// What became of one line of a scan in the estimator's step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum MatchOutcome {
    /// Its match corrected the pose.
    Used,
    /// No map line within the gates.
    NoCandidate,
    /// It matched only tentative or not-straight map lines.
    Unconfirmed,
    /// Its best candidate lay outside the Mahalanobis gate.
    OutsideGate,
    /// Two map lines in its gate would correct the pose differently.
    Ambiguous,
    /// Its match disagreed with the scan's consistent set.
    Inconsistent,
    /// Its match was consistent, but the correction was refused
    /// ([`Fallback::InconsistentWithSource`]).
    Refused,
}

/// One line of a scan and what the estimator did with it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Association {
    /// Index of the line in the scan's lines.
    pub line: usize,
    /// The map line it was matched with, if any.
    pub map_line: Option<LineId>,
    /// What became of it.
    pub outcome: MatchOutcome,
}

/// The loop: a localization source's motion is composed onto the corrected
/// pose, the scan's lines are placed in the world with it and matched against
/// the map, the matches correct the pose, and the lines, placed with the
/// corrected pose, update the map.
#[derive(Debug, Clone)]
pub struct Aiding {
    config: AidingConfig,
    map: LineMap,
    corrected: Option<Pose2>,
    covariance: Matrix3<f64>,
    last_source: Option<Pose2>,
    last_stamp_s: Option<f64>,
    /// The last estimated motion (for constant-velocity prediction).
    last_motion: Option<Pose2>,
    /// The factor on the motion noise's variances ([`crate::NoiseAdaptation`]).
    motion_noise_scale: f64,
    /// The factor on the matches' covariances.
    measurement_noise_scale: f64,
    /// The time since the previous scan, when both were stamped.
    last_dt_s: Option<f64>,
    /// The estimated velocity over the last step, smoothed (for deskew).
    velocity: Option<Twist2>,
    /// The same over the last step alone (for the constant-velocity prediction).
    last_velocity: Option<Twist2>,
    /// The source's systematic errors.
    calibration: SourceCalibration,
    /// The heading variance the calibration's own uncertainty added to this
    /// step's prediction, rad² (recovery's threshold leaves it out).
    calibration_var_heading: f64,
    associations: Vec<Association>,
    /// The sliding window ([`crate::EstimatorConfig::window`]).
    window: Option<PoseWindow>,
    /// The step being processed: its increment and the increment's
    /// covariance (for the window).
    pending_step: Option<(Pose2, Matrix3<f64>)>,
    /// The next step's scan registered to the previous scan
    /// ([`Aiding::set_registration`]).
    registration: Option<Registration>,
    /// Factor on the source's noise model judged by the scan registrations
    /// ([`fuse_registration`]; 1 until the first).
    registration_scale: f64,
    /// This step's prediction used a registration.
    step_registered: bool,
    /// The last step's consistent matches (for the window).
    last_consistent: Vec<(LineSegment, MapLine)>,
    /// Where the estimate stood at the source's last pose, while scans
    /// come without the source.
    gap: Option<SourceGap>,
}

/// The estimate at the source's last pose before scans without it: a
/// source that resumes in the same frame is composed from here, by its
/// motion across the gap ([`Aiding::step_without_source`]).
#[derive(Debug, Clone, Copy)]
struct SourceGap {
    /// The source's last pose.
    source: Pose2,
    /// The corrected pose and its covariance then.
    pose: Pose2,
    covariance: Matrix3<f64>,
    /// The source's calibration then.
    calibration: SourceCalibration,
    /// That scan's stamp, if it had one.
    stamp_s: Option<f64>,
    /// Scans since then without the source.
    scans: u32,
}

impl Aiding {
    /// A loop with an empty map.
    pub fn new(config: AidingConfig, map: MapConfig) -> Result<Self, ConfigError> {
        Self::with_map(config, LineMap::new(map)?)
    }

    /// A loop that continues from an existing map (for example one loaded
    /// from a file); the first pose is taken from the source as it is.
    pub fn with_map(config: AidingConfig, map: LineMap) -> Result<Self, ConfigError> {
        config.validate()?;
        Ok(Aiding {
            config,
            map,
            corrected: None,
            covariance: Matrix3::zeros(),
            last_source: None,
            last_stamp_s: None,
            last_motion: None,
            motion_noise_scale: 1.0,
            measurement_noise_scale: 1.0,
            last_dt_s: None,
            velocity: None,
            last_velocity: None,
            calibration: SourceCalibration::new(
                &config.estimator.calibration.unwrap_or(CalibrationConfig::standard()),
            ),
            calibration_var_heading: 0.0,
            associations: Vec::new(),
            window: None,
            pending_step: None,
            registration: None,
            registration_scale: 1.0,
            step_registered: false,
            last_consistent: Vec::new(),
            gap: None,
        })
    }

    /// Moves the loop into a corrected world frame, as after a pose-graph
    /// optimization: the map is replaced by `map` (built in the new frame),
    /// and the corrected pose and its covariance are carried over by
    /// `new_world_from_old`. The source's next increment then continues from
    /// the moved pose. The sliding window, if any, starts again.
    ///
    /// Edge cases: before the first scan only the map is replaced; a
    /// non-finite `new_world_from_old` replaces the map and leaves the pose.
    pub fn reanchor(&mut self, map: LineMap, new_world_from_old: &Pose2) {
        self.map = map;
        self.associations.clear();
        self.last_consistent.clear();
        if !new_world_from_old.is_finite() {
            return;
        }
        if let Some(p) = self.corrected {
            self.corrected = Some(new_world_from_old.compose(&p));
        }
        let (s, c) = new_world_from_old.heading().sin_cos();
        let rotation = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        self.covariance = rotation * self.covariance * rotation.transpose();
        self.calibration.pose_scale_cov = rotation * self.calibration.pose_scale_cov;
        if let Some(g) = &mut self.gap {
            g.pose = new_world_from_old.compose(&g.pose);
            g.covariance = rotation * g.covariance * rotation.transpose();
            g.calibration.pose_scale_cov = rotation * g.calibration.pose_scale_cov;
        }
        self.window = None;
    }

    /// The configuration.
    pub fn config(&self) -> &AidingConfig {
        &self.config
    }

    /// The map built so far.
    pub fn map(&self) -> &LineMap {
        &self.map
    }

    /// The latest corrected pose, if any scan was processed.
    pub fn pose(&self) -> Option<Pose2> {
        self.corrected
    }

    /// The covariance of the latest pose, `(x, y, heading)`, in the world
    /// frame (the estimator's; zero in the other modes).
    pub fn covariance(&self) -> Matrix3<f64> {
        self.covariance
    }

    /// The source's estimated systematic errors ([`CalibrationConfig`];
    /// zeros without it).
    pub fn calibration(&self) -> &SourceCalibration {
        &self.calibration
    }

    /// The velocity estimated over the last step (metres and radians per
    /// second, in the frame of the pose before it), when both scans were
    /// stamped: what motion deskew of the next scan uses.
    pub fn velocity(&self) -> Option<Twist2> {
        self.velocity
    }

    /// What the last step of the estimator did with each line.
    pub fn associations(&self) -> &[Association] {
        &self.associations
    }

    /// Processes one scan given the source's absolute pose estimate
    /// (`world_from_sensor` as the localization source sees it). The source's
    /// motion since its previous pose is composed onto the corrected pose;
    /// the first pose is taken as it is.
    pub fn step(
        &mut self,
        source_pose: &Pose2,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        self.last_dt_s = None;
        self.step_source(source_pose, lines)
    }

    /// [`Aiding::step`] with the step's duration already recorded.
    fn step_source(
        &mut self,
        source_pose: &Pose2,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        if !source_pose.is_finite() {
            return self.fall_back(Fallback::NonFiniteSource);
        }
        let increment = self.last_source.map(|s| s.between(source_pose));
        self.last_source = Some(*source_pose);
        let gap = self.gap.take();
        match (self.corrected, increment) {
            (Some(_), Some(inc)) => self.step_increment(&inc, lines),
            // The source resumes after scans without it.
            (Some(previous), None) => match gap {
                // It was there before them: its motion across the gap is
                // composed from the estimate of its last scan, which
                // replaces what the LIDAR-only scans estimated of it.
                Some(g) if self.plausible_source_step(&g.source.between(source_pose)) => {
                    self.corrected = Some(g.pose);
                    self.covariance = g.covariance;
                    self.calibration = g.calibration;
                    self.window = None;
                    if self.last_dt_s.is_some() {
                        self.last_dt_s = g.stamp_s.zip(self.last_stamp_s).map(|(a, b)| b - a);
                    }
                    let out = self.step_increment(&g.source.between(source_pose), lines);
                    // The motion a constant-velocity prediction repeats is
                    // one scan's share of the gap's, not the whole of it.
                    let share = 1.0 / f64::from(g.scans + 1);
                    self.last_motion = self.last_motion.map(|m| Pose2::identity().lerp(&m, share));
                    out
                }
                // It starts after the first scans, or jumped across the gap
                // (a frame of its own, a reset): its frame is not the
                // estimate's. This scan is predicted as the LIDAR-only ones
                // were; the next takes the source's increment.
                _ => self.step_constant_velocity(previous, lines),
            },
            (None, _) => {
                self.process(*source_pose, Matrix3::zeros(), Prediction::Source, None, lines)
            }
        }
    }

    /// As [`Aiding::step`], for a scan stamped `stamp_s` seconds: a stamp
    /// earlier than the previous scan's skips the scan
    /// ([`Fallback::StampBackwards`]); a non-finite stamp is ignored.
    pub fn step_at(
        &mut self,
        stamp_s: f64,
        source_pose: &Pose2,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        if self.stamp_went_backwards(stamp_s) {
            // The source's pose is reported with the last correction, and
            // nothing is learnt from the scan.
            let mut out = self.fall_back(Fallback::StampBackwards);
            if let (Some(last), true) = (self.last_source, source_pose.is_finite()) {
                out.0 = out.0.compose(&last.between(source_pose));
            }
            return out;
        }
        self.step_source(source_pose, lines)
    }

    /// Processes one scan without a localization source (LIDAR-only mode):
    /// the last estimated motion is repeated as the prediction, with
    /// [`crate::EstimatorConfig::constant_velocity`] noise, and the line
    /// matches estimate the motion. `stamp_s`, when given, is checked as in
    /// [`Aiding::step_at`]. A source given again later that was given
    /// before these scans is composed by its motion across them from the
    /// estimate at its last pose, and the motion the scans without it
    /// estimated is replaced, not counted twice; when that motion is a jump
    /// ([`crate::EstimatorConfig::max_source_step_m`], a source reset or in
    /// another frame), or the source is new, its first scan is predicted as
    /// here and the next ones by its increments (its frame need not be the
    /// estimate's).
    pub fn step_without_source(
        &mut self,
        stamp_s: Option<f64>,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        let last_stamp_s = self.last_stamp_s;
        if stamp_s.is_some_and(|t| self.stamp_went_backwards(t)) {
            return self.fall_back(Fallback::StampBackwards);
        }
        if let (Some(source), Some(pose)) = (self.last_source.take(), self.corrected) {
            self.gap = Some(SourceGap {
                source,
                pose,
                covariance: self.covariance,
                calibration: self.calibration,
                stamp_s: last_stamp_s,
                scans: 1,
            });
        } else if let Some(g) = &mut self.gap {
            g.scans += 1;
        }
        let Some(previous) = self.corrected else {
            return self.process(
                Pose2::identity(),
                Matrix3::zeros(),
                Prediction::ConstantVelocity,
                None,
                lines,
            );
        };
        self.step_constant_velocity(previous, lines)
    }

    /// A scan predicted from `previous` by the last estimated motion
    /// ([`Aiding::step_without_source`]).
    fn step_constant_velocity(
        &mut self,
        previous: Pose2,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        let e = &self.config.estimator;
        let (motion, noise) = match (self.last_velocity, self.last_dt_s) {
            // Stamped: the velocity over the scan's own duration, wrong by at
            // most the largest acceleration over it. The velocity's own error
            // (two estimated poses differenced) is the last step's relative
            // error, which the matches keep small where they constrain the
            // pose. Modelled as twice the pose's whole covariance, it tripled
            // the variance every scan in a direction no line constrains (a
            // 40 Hz bag: 0.05 -> 0.8 m in six scans), and the gates opened
            // to a wall 1 m away (docs/accuracy.md, "LIDAR-only mode").
            (Some(v), Some(dt)) if dt > 0.0 => {
                let motion = Pose2::new(v.vx_mps * dt, v.vy_mps * dt, v.yaw_rate_radps * dt);
                let a = e.max_acceleration;
                let noise = MotionNoise::floors(
                    (a.linear_m_s2 * dt * dt).max(1e-3),
                    (a.angular_rad_s2 * dt * dt).max(1e-3),
                );
                (motion, noise)
            }
            _ => (self.last_motion.unwrap_or_default(), e.constant_velocity),
        };
        let (mut motion, mut motion_cov) = (motion, noise.covariance(&motion));
        if let (Some(r), Some(c)) = (self.registration.take(), e.scan_matching) {
            // Without a source the registration measures the step; the
            // constant-velocity motion is only its prior, doubted by
            // construction (a conflict goes to the registration).
            let f = fuse_registration(&motion, &motion_cov, &r, &c, true);
            (motion, motion_cov) = (f.increment, f.covariance);
        }
        let (predicted, mut cov) = predict_with(&previous, &self.covariance, &motion, &motion_cov);
        self.pending_step = Some((motion, motion_cov));
        if let Some(c) = e.calibration {
            // No source step to scale: the pose-scale covariance only turns
            // with the pose.
            let step_world = predicted.translation() - previous.translation();
            self.calibration.propagate_pose_scale(&c, &step_world, false, &mut cov);
        }
        self.process(predicted, cov, Prediction::ConstantVelocity, None, lines)
    }

    /// The next scan registered to the previous one
    /// ([`crate::ScanRegistrar::next`]): the next step that takes the
    /// source's increment fuses it with the registration when
    /// [`crate::EstimatorConfig::scan_matching`] is set
    /// ([`fuse_registration`]). Every step clears it, used or not.
    pub fn set_registration(&mut self, registration: Option<Registration>) {
        self.registration = registration;
    }

    /// Processes one scan given the source's motion since the previous scan
    /// (an odometry or inertial increment, in the previous body frame).
    pub fn step_increment(
        &mut self,
        increment: &Pose2,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        if !increment.is_finite() {
            return self.fall_back(Fallback::NonFiniteSource);
        }
        let previous = self.corrected.unwrap_or_default();
        self.step_registered = false;
        let e = &self.config.estimator;
        let jumped = !self.plausible_source_step(increment);
        let dt = self.step_dt();
        let (increment, noise, prediction, fallback) = if jumped {
            let motion = self.last_motion.unwrap_or_default();
            (motion, e.constant_velocity, Prediction::ConstantVelocity, Some(Fallback::SourceJump))
        } else {
            (*increment, e.motion.scaled(self.motion_noise_scale), Prediction::Source, None)
        };
        let (increment, var_heading, var_along) = match (e.calibration, jumped) {
            (Some(c), false) => self.calibration.correct(&c, &increment, dt),
            _ => (increment, 0.0, 0.0),
        };
        // The step's noise in the previous body frame, the calibration's own
        // uncertainty over the step included.
        let mut calibration_cov = Matrix3::zeros();
        calibration_cov[(2, 2)] = var_heading;
        let len = increment.x().hypot(increment.y());
        if len > 0.0 {
            let u = increment.translation() / len;
            let mut t = calibration_cov.fixed_view_mut::<2, 2>(0, 0);
            t += u * u.transpose() * var_along;
        }
        let step_cov = noise.covariance(&increment) + calibration_cov;
        self.calibration_var_heading = var_heading;
        let registration = std::mem::take(&mut self.registration);
        let (increment, step_cov) = match (registration, e.scan_matching, jumped) {
            (Some(r), Some(c), false) => {
                // The source's covariance as the registrations judge it: the
                // model's (the calibration's share included) times a scale
                // adapted from their disagreement, apart from the line
                // matches' own adaptation. At a scale of 1 or less the
                // source is no worse than its model: kept as it is, the
                // registration only judging it.
                let doubtful = self.registration_scale > 1.0;
                let source_cov = e.motion.scaled(self.registration_scale).covariance(&increment)
                    + calibration_cov;
                let f = fuse_registration(&increment, &source_cov, &r, &c, true);
                if f.distance2.is_finite()
                    && let Some(a) = e.adaptation
                {
                    let next = a.next(self.registration_scale, f.distance2, 3);
                    // At a standstill a step tests only the model's floors,
                    // not the per-metre and per-radian terms a moving source
                    // is judged by: agreement there does not lower the scale
                    // (after a minute at rest, a dozen bad steps of a turn
                    // went by before the source was doubted).
                    let stop = e.motion.standstill(&r.reference_from_current);
                    self.registration_scale =
                        if stop { next.max(self.registration_scale) } else { next };
                }
                if doubtful {
                    self.step_registered = true;
                    // The registration measures the step: what it corrects
                    // of the calibrated increment's heading is the
                    // calibration's to learn (the line matches then find
                    // little left).
                    if let Some(cal) = e.calibration {
                        let heading = wrap_angle(f.increment.heading() - increment.heading());
                        self.calibration.observe(&cal, dt, heading, &source_cov, &f.covariance);
                    }
                    (f.increment, f.covariance)
                } else {
                    (increment, step_cov)
                }
            }
            _ => (increment, step_cov),
        };
        let (predicted, mut cov) = predict_with(&previous, &self.covariance, &increment, &step_cov);
        self.pending_step = Some((increment, step_cov));
        let step_world = predicted.translation() - previous.translation();
        if !predicted.is_finite() {
            return self.fall_back(Fallback::NonFiniteSource);
        }
        if let Some(c) = e.calibration {
            self.calibration.propagate_pose_scale(&c, &step_world, !jumped, &mut cov);
        }
        self.process(predicted, cov, prediction, fallback, lines)
    }

    /// Whether a source's step is motion, not a jump: within
    /// [`crate::EstimatorConfig::max_source_step_m`] and
    /// [`crate::EstimatorConfig::max_source_turn_rad`].
    fn plausible_source_step(&self, increment: &Pose2) -> bool {
        let e = &self.config.estimator;
        increment.x().hypot(increment.y()) <= e.max_source_step_m
            && increment.heading().abs() <= e.max_source_turn_rad
    }

    /// The step's duration when both scans were stamped and it is usable.
    fn step_dt(&self) -> Option<f64> {
        self.last_dt_s.filter(|dt| *dt > 0.0 && dt.is_finite())
    }

    fn stamp_went_backwards(&mut self, stamp_s: f64) -> bool {
        if !stamp_s.is_finite() {
            return false;
        }
        if self.last_stamp_s.is_some_and(|last| stamp_s < last) {
            return true;
        }
        self.last_dt_s = self.last_stamp_s.map(|last| stamp_s - last);
        self.last_stamp_s = Some(stamp_s);
        false
    }

    /// Keeps the last corrected pose (or the identity) and reports why.
    fn fall_back(&mut self, why: Fallback) -> (Pose2, StepReport) {
        self.registration = None;
        let pose = self.corrected.unwrap_or_default();
        self.associations.clear();
        (
            pose,
            StepReport {
                fallback: Some(why),
                covariance: self.covariance,
                ..StepReport::default()
            },
        )
    }

    fn world_lines(
        &self,
        pose: &Pose2,
        lines: &[impl ObservedLine],
    ) -> Vec<(LineSegment, Moments)> {
        lines.iter().map(|l| (l.line().transformed(pose), l.moments().transformed(pose))).collect()
    }

    /// Corrects the prediction with the mode's rule, then updates the map.
    fn process(
        &mut self,
        predicted: Pose2,
        predicted_cov: Matrix3<f64>,
        prediction: Prediction,
        fallback: Option<Fallback>,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        // A registration not taken by this step is not the next step's.
        self.registration = None;
        self.map.begin_scan();
        self.associations.clear();
        self.last_consistent.clear();
        let previous = self.corrected;
        let previous_cov = self.covariance;
        let (mut pose, mut report, insert) = if self.config.mode == AidingMode::Estimator {
            self.estimate(predicted, predicted_cov, lines)
        } else {
            let (pose, report) = self.correct_in_full(predicted, lines);
            (pose, report, true)
        };
        self.calibration_var_heading = 0.0;
        report.prediction = prediction;
        if fallback.is_some() {
            report.fallback = fallback;
        }
        if let (Some(size), AidingMode::Estimator) =
            (self.config.estimator.window, self.config.mode)
        {
            pose = self.smooth(size, previous, previous_cov, pose);
        }
        if !pose.is_finite() {
            pose = predicted;
            report.fallback = Some(Fallback::NonFiniteCorrection);
        }
        if insert {
            for l in lines {
                self.map.insert_observed(&pose, l.line(), l.moments());
            }
        }
        self.last_motion = previous.map(|p| p.between(&pose));
        // Smoothed over about four steps: a velocity differenced from two
        // estimated poses carries both poses' errors divided by the step.
        let raw = match (previous, self.last_dt_s) {
            (Some(p), Some(dt)) => p.velocity_to(&pose, dt),
            _ => None,
        };
        // A step turning faster than any platform did not take the time its
        // stamps say (Intel's log has 30° in 10 ms): the last velocity stays.
        let plausible = raw.filter(|v| v.yaw_rate_radps.abs() <= MAX_TURN_RATE_RAD_S);
        self.last_velocity = plausible;
        self.velocity = match (self.velocity, raw, plausible) {
            (Some(v), _, Some(r)) => Some(v.lerp(&r, 0.25)),
            (v, Some(_), None) => v,
            (_, _, r) => r,
        };
        self.corrected = Some(pose);
        report.covariance = self.covariance;
        report.motion_noise_scale = self.motion_noise_scale;
        report.measurement_noise_scale = self.measurement_noise_scale;
        (pose, report)
    }

    /// The estimator's step: gate, joint check (and, with
    /// [`crate::EstimatorConfig::recovery`], a new prediction when fewer
    /// than two matches agree), iterated update, innovation test. Returns
    /// the pose, the report and whether the scan's lines may update the map
    /// (not after a refused correction).
    fn estimate(
        &mut self,
        predicted: Pose2,
        predicted_cov: Matrix3<f64>,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport, bool) {
        let mut report = StepReport::default();
        self.covariance = predicted_cov;
        if self.map.is_empty() {
            report.fallback = Some(Fallback::NoMatches);
            return (predicted, report, true);
        }
        let (mut predicted, mut predicted_cov) = (predicted, predicted_cov);
        let mut consistent = self.associate(&predicted, &predicted_cov, lines, &mut report);
        if consistent.len() < 2
            && let Some((pose, cov)) = self.recover(&predicted, &predicted_cov, lines)
        {
            report = StepReport { recovery: Some(predicted.between(&pose)), ..Default::default() };
            self.associations.clear();
            (predicted, predicted_cov) = (pose, cov);
            self.covariance = cov;
            consistent = self.associate(&predicted, &predicted_cov, lines, &mut report);
        }
        if consistent.len() < self.config.estimator.min_matches.max(1) {
            report.fallback = Some(Fallback::NoMatches);
            return (predicted, report, true);
        }
        let e = &self.config.estimator;
        let (map, r_scale) = (&self.map, self.measurement_noise_scale);
        let update = iterated_update(&predicted, &predicted_cov, e.iterations, e.huber_k, |pose| {
            consistent
                .iter()
                .map(|&(i, j)| {
                    match_measurement(lines[i].line(), &map.lines()[j], pose, e, r_scale)
                })
                .collect()
        });
        let Some(update) = update else {
            report.fallback = Some(Fallback::NonFiniteCorrection);
            return (predicted, report, true);
        };
        self.accept(update, &predicted, &predicted_cov, &consistent, lines, report)
    }

    /// Steps 1 and 2 of [`Aiding::estimate`]: the gated matches that agree
    /// with one another.
    fn associate(
        &mut self,
        predicted: &Pose2,
        predicted_cov: &Matrix3<f64>,
        lines: &[impl ObservedLine],
        report: &mut StepReport,
    ) -> Vec<(usize, usize)> {
        let gated = self.gate(predicted, predicted_cov, lines, report);
        if gated.is_empty() {
            return Vec::new();
        }
        self.check_jointly(gated, predicted_cov, lines, report)
    }

    /// The recovery of [`EstimatorConfig::recovery`] ([`crate::recover`])
    /// against the confirmed map lines around the prediction: the new
    /// prediction and its widened covariance.
    fn recover(
        &self,
        predicted: &Pose2,
        predicted_cov: &Matrix3<f64>,
        lines: &[impl ObservedLine],
    ) -> Option<(Pose2, Matrix3<f64>)> {
        let r = self.config.estimator.recovery?;
        if lines.len() < 2 {
            return None;
        }
        let here = Point2::new(predicted.x(), predicted.y());
        let map: Vec<LineSegment> = self
            .map
            .lines_near(&here, r.map_radius_m)
            .into_iter()
            .map(|i| &self.map.lines()[i])
            .filter(|m| m.is_confirmed())
            .map(|m| m.line)
            .collect();
        let seen: Vec<LineSegment> = lines.iter().map(|l| *l.line()).collect();
        // The change is judged against the source's own noise: the
        // calibration's uncertainty (a latency times a sudden change of turn
        // rate) would explain a failed source's jump as well as a real one.
        let mut source_cov = *predicted_cov;
        source_cov[(2, 2)] -= self.calibration_var_heading.min(source_cov[(2, 2)]);
        let found = crate::recover(predicted, &source_cov, &seen, &map, &r)?;
        Some((found.world_from_sensor, found.covariance))
    }

    /// Step 1 of [`Aiding::estimate`]: each line's best map line within
    /// gates from the predicted covariance (Mahalanobis), leaving out lines
    /// whose gate holds two map lines that would correct the pose
    /// differently. Returns `(line index, map index, measurement at the
    /// prediction)`; records every line's outcome.
    fn gate(
        &mut self,
        predicted: &Pose2,
        predicted_cov: &Matrix3<f64>,
        lines: &[impl ObservedLine],
        report: &mut StepReport,
    ) -> Vec<(usize, usize, LineMeasurement)> {
        let e = self.config.estimator;
        let r_scale = self.measurement_noise_scale;
        let viewpoint = Point2::new(predicted.x(), predicted.y());
        let sigma_heading = predicted_cov[(2, 2)].max(0.0).sqrt();
        let sigma_position = (predicted_cov[(0, 0)] + predicted_cov[(1, 1)]).max(0.0).sqrt();
        let map_gate = MatchGate::of(self.map.config());
        let mut gated: Vec<(usize, usize, LineMeasurement)> = Vec::new();
        for (i, (sensor, (world, _))) in
            lines.iter().zip(self.world_lines(predicted, lines)).enumerate()
        {
            let lever = (world.centroid() - viewpoint).norm();
            let offset_gate = (3.5 * (sigma_position + lever * sigma_heading))
                .max(map_gate.max_offset_m.unwrap_or(0.0))
                .min(e.max_gate_offset_m);
            let gate = MatchGate::new(
                (3.5 * sigma_heading).max(map_gate.max_d_alpha_rad).min(e.max_gate_alpha_rad),
                map_gate.max_d_rho_m.max(2.0 * offset_gate),
                Some(offset_gate),
            );
            let mut best: Option<(f64, usize, LineId, LineMeasurement)> = None;
            let mut in_gate: Vec<LineMeasurement> = Vec::new();
            let mut unconfirmed = false;
            self.map.for_each_candidate(&world, Some(&viewpoint), &gate, |m, map_line| {
                let tentative = map_line.status == LineStatus::Tentative;
                if !(map_line.is_confirmed() || tentative && e.tentative_variance_scale.is_some()) {
                    unconfirmed = true;
                    return;
                }
                let meas = match_measurement(sensor.line(), map_line, predicted, &e, r_scale);
                let d2 = gate_distance2(&meas, predicted_cov);
                if d2 <= e.gate_chi2 {
                    in_gate.push(meas);
                }
                if best.is_none_or(|b| d2 < b.0) {
                    best = Some((d2, m.index, m.id, meas));
                }
            });
            // Two map lines in the gate that would correct the pose
            // differently: the line is ambiguous and is not used.
            let ambiguous = best.is_some_and(|(_, _, _, b)| {
                in_gate.iter().any(|m| !same_correction(m, &b, &e.measurement))
            });
            let (map_line, outcome) = match best {
                Some((_, _, id, _)) if ambiguous => {
                    report.ambiguous += 1;
                    (Some(id), MatchOutcome::Ambiguous)
                }
                Some((d2, index, id, meas)) if d2 <= e.gate_chi2 => {
                    gated.push((i, index, meas));
                    (Some(id), MatchOutcome::Used)
                }
                Some((_, _, id, _)) => {
                    report.rejected_gate += 1;
                    (Some(id), MatchOutcome::OutsideGate)
                }
                None if unconfirmed => {
                    report.unconfirmed += 1;
                    (None, MatchOutcome::Unconfirmed)
                }
                None => (None, MatchOutcome::NoCandidate),
            };
            self.associations.push(Association { line: i, map_line, outcome });
        }
        gated
    }

    /// Step 2 of [`Aiding::estimate`]: the gated matches that agree with
    /// one another (hypotheses from the matches with the most points
    /// first). Returns `(line index, map index)`; marks the others
    /// [`MatchOutcome::Inconsistent`].
    fn check_jointly(
        &mut self,
        mut gated: Vec<(usize, usize, LineMeasurement)>,
        predicted_cov: &Matrix3<f64>,
        lines: &[impl ObservedLine],
        report: &mut StepReport,
    ) -> Vec<(usize, usize)> {
        gated.sort_by_key(|(i, _, _)| std::cmp::Reverse(lines[*i].line().n_points()));
        let measurements: Vec<LineMeasurement> = gated.iter().map(|g| g.2).collect();
        let flags = joint_consistent(
            &measurements,
            predicted_cov,
            self.config.estimator.consensus_chi2,
            12,
        );
        for ((i, _, _), ok) in gated.iter().zip(&flags) {
            if !ok {
                report.rejected_joint += 1;
                self.associations[*i].outcome = MatchOutcome::Inconsistent;
            }
        }
        gated.iter().zip(&flags).filter(|(_, f)| **f).map(|(g, _)| (g.0, g.1)).collect()
    }

    /// Step 3 of [`Aiding::estimate`]: the noise adaptation learns from the
    /// update; the innovation test refuses a correction inconsistent with
    /// the source (the prediction kept, its covariance inflated, the lines
    /// kept out of the map); an accepted one teaches the calibration.
    fn accept(
        &mut self,
        update: crate::PoseUpdate,
        predicted: &Pose2,
        predicted_cov: &Matrix3<f64>,
        consistent: &[(usize, usize)],
        lines: &[impl ObservedLine],
        mut report: StepReport,
    ) -> (Pose2, StepReport, bool) {
        let e = self.config.estimator;
        report.correction_distance2 = update.correction_distance2;
        // The scale is the source's: a step predicted with a scan
        // registration says nothing of it.
        if let (Some(a), false) = (e.adaptation, std::mem::take(&mut self.step_registered)) {
            self.motion_noise_scale =
                a.next(self.motion_noise_scale, update.correction_distance2, update.correction_dof);
        }
        if let Some(a) = e.measurement_adaptation {
            self.measurement_noise_scale =
                a.next_mean(self.measurement_noise_scale, update.residual2, update.residual_dof);
        }
        if update.correction_distance2 > e.innovation_chi2 {
            // Refused: keep the prediction, widen its uncertainty by the excess.
            let inflation = (update.correction_distance2 / e.innovation_chi2).min(e.max_inflation);
            self.covariance = predicted_cov * inflation;
            report.fallback = Some(Fallback::InconsistentWithSource);
            for &(i, _) in consistent {
                self.associations[i].outcome = MatchOutcome::Refused;
            }
            return (*predicted, report, false);
        }
        report.matches = consistent.len();
        self.last_consistent = consistent
            .iter()
            .map(|&(i, j)| (*lines[i].line(), self.map.lines()[j].clone()))
            .collect();
        report.heading_correction_rad =
            pcaline_geometry::wrap_angle(update.pose.heading() - predicted.heading());
        // A recovered step's correction is the source's failure, not its
        // calibration error: the calibration does not learn from it.
        report.translation_correction_m =
            Vector2::new(update.pose.x() - predicted.x(), update.pose.y() - predicted.y());
        if let Some(c) = e.calibration.filter(|_| report.recovery.is_none()) {
            self.calibration.observe(
                &c,
                self.step_dt(),
                report.heading_correction_rad,
                predicted_cov,
                &update.covariance,
            );
            let t = report.translation_correction_m;
            self.calibration.observe_pose(
                &c,
                &Vector3::new(t.x, t.y, report.heading_correction_rad),
                predicted_cov,
                &update.covariance,
            );
        }
        report.constrained_directions = constrained_directions(&update.covariance, predicted_cov);
        self.covariance = update.covariance;
        (update.pose, report, true)
    }

    /// The sliding window's step: the source's increment and the scan's
    /// consistent matches join the window, which is solved; the newest pose
    /// replaces the filter's. Without an increment (the first scan, a
    /// fallback) the window restarts at the filter's pose.
    fn smooth(
        &mut self,
        size: usize,
        previous: Option<Pose2>,
        previous_cov: Matrix3<f64>,
        filtered: Pose2,
    ) -> Pose2 {
        let (Some(prev), Some((increment, noise))) = (previous, self.pending_step.take()) else {
            self.window = Some(PoseWindow::new(filtered, self.covariance, size));
            return filtered;
        };
        let window = self.window.get_or_insert_with(|| PoseWindow::new(prev, previous_cov, size));
        let e = self.config.estimator;
        let r_scale = self.measurement_noise_scale;
        let matches = std::mem::take(&mut self.last_consistent);
        let measure = move |pose: &Pose2| -> Vec<LineMeasurement> {
            matches
                .iter()
                .map(|(sensor, map_line)| match_measurement(sensor, map_line, pose, &e, r_scale))
                .collect()
        };
        let oldest = window.oldest_covariance;
        window.push(
            WindowStep { increment, noise, measure: std::sync::Arc::new(measure), pose: filtered },
            oldest,
        );
        match window.solve(e.iterations, e.huber_k) {
            Some((head, next_oldest)) => {
                window.oldest_covariance = Some(next_oldest);
                self.covariance = head;
                window.head()
            }
            None => filtered,
        }
    }

    /// The paper's heading aiding and the full-pose variant: each scan's
    /// correction applied in full.
    fn correct_in_full(
        &mut self,
        predicted: Pose2,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        let mut report = StepReport::default();
        let mut pose = predicted;
        let previous = self.corrected;
        if self.config.mode != AidingMode::None {
            if self.map.is_empty() {
                report.fallback = Some(Fallback::NoMatches);
                return (pose, report);
            }
            let rounds = match self.config.mode {
                AidingMode::FullPose => self.config.iterations.max(1),
                _ => 1,
            };
            for round in 0..rounds {
                let viewpoint = Point2::new(pose.x(), pose.y());
                let world = self.world_lines(&pose, lines);
                let matches: Vec<_> = world
                    .iter()
                    .filter_map(|(l, _)| {
                        self.map.find_match_seen_from(l, Some(&viewpoint)).map(|m| (l, m))
                    })
                    .collect();
                report.matches = matches.len();
                if matches.is_empty() {
                    report.fallback = Some(Fallback::NoMatches);
                    break;
                }
                // Heading (eq. 11-14).
                let dgamma = match self.config.heading_weights {
                    HeadingWeights::InverseDRhoSquared => heading_correction(
                        matches.iter().map(|(_, m)| (m.distance.d_alpha, m.distance.d_rho)),
                    ),
                    HeadingWeights::InverseVariance { floor_rad } => {
                        weighted_offset(matches.iter().map(|(l, m)| {
                            let map_line = &self.map.lines()[m.index].line;
                            let var = l.covariance()[(0, 0)]
                                + map_line.covariance()[(0, 0)]
                                + floor_rad * floor_rad;
                            (m.distance.d_alpha, 1.0 / var)
                        }))
                    }
                };
                let Some(dgamma) = dgamma else {
                    report.fallback = Some(Fallback::NoMatches);
                    break;
                };
                let dgamma = dgamma
                    .clamp(-self.config.max_heading_step_rad, self.config.max_heading_step_rad);
                let position = match previous {
                    Some(prev) if round == 0 => rotate_step(
                        &Point2::new(prev.x(), prev.y()),
                        &Point2::new(pose.x(), pose.y()),
                        dgamma,
                    ),
                    // Later rounds rotate about the sensor (the step is already placed).
                    _ => Point2::new(pose.x(), pose.y()),
                };
                pose = Pose2::new(position.x, position.y, pose.heading() + dgamma);
                report.heading_correction_rad += dgamma;
                if self.config.mode != AidingMode::FullPose {
                    continue;
                }
                // Translation from the matched lines' normal offsets.
                let viewpoint = Point2::new(pose.x(), pose.y());
                let world = self.world_lines(&pose, lines);
                let constraints: Vec<NormalConstraint> = world
                    .iter()
                    .filter_map(|(l, _)| {
                        let m = self.map.find_match_seen_from(l, Some(&viewpoint))?;
                        let map_line = &self.map.lines()[m.index].line;
                        let n = map_line.normal();
                        let var = l.residual_std().powi(2) / l.n_points().max(1) as f64
                            + self.config.offset_floor_m.powi(2);
                        Some(NormalConstraint {
                            normal: n,
                            offset_m: map_line.d() - n.dot(&l.centroid().coords),
                            weight: 1.0 / var,
                        })
                    })
                    .collect();
                let fix = solve_translation(
                    &constraints,
                    self.config.robust_scale_m,
                    self.config.min_information_ratio,
                    6,
                );
                let t = fix.translation;
                let t = if t.norm() > self.config.max_translation_step_m {
                    t * (self.config.max_translation_step_m / t.norm())
                } else {
                    t
                };
                pose = Pose2::new(pose.x() + t.x, pose.y() + t.y, pose.heading());
                report.translation_correction_m += t;
                report.constrained_directions = fix.constrained_directions;
            }
        }
        (pose, report)
    }
}

/// One match's measurement as the estimator weighs it: [`measure`], times
/// the measurement noise's factor, times
/// [`crate::EstimatorConfig::tentative_variance_scale`] for a tentative map
/// line.
fn match_measurement(
    sensor: &LineSegment,
    map_line: &MapLine,
    pose: &Pose2,
    e: &crate::EstimatorConfig,
    noise_scale: f64,
) -> LineMeasurement {
    let mut meas = measure(sensor, map_line, pose, &e.measurement);
    meas.covariance *= noise_scale;
    if map_line.status == LineStatus::Tentative {
        meas.covariance *= e.tentative_variance_scale.unwrap_or(1.0);
    }
    meas
}

/// Whether two candidate matches of one line would correct the pose alike:
/// their residuals differ by less than the measurement floors (the pieces
/// of one wall either side of a doorway, say).
fn same_correction(
    a: &LineMeasurement,
    b: &LineMeasurement,
    floors: &crate::MeasurementNoise,
) -> bool {
    (a.residual[0] - b.residual[0]).abs() <= 2.0 * floors.alpha_floor_rad
        && (a.residual[1] - b.residual[1]).abs() <= 2.0 * floors.offset_floor_m
}

/// How many directions of the position the update constrained: those whose
/// variance it reduced to under half the prediction's.
fn constrained_directions(posterior: &Matrix3<f64>, prior: &Matrix3<f64>) -> usize {
    let post = posterior.fixed_view::<2, 2>(0, 0).symmetric_eigen();
    let prior_max = prior.fixed_view::<2, 2>(0, 0).symmetric_eigen().eigenvalues.max();
    post.eigenvalues.iter().filter(|v| **v < 0.5 * prior_max).count()
}

impl Default for StepReport {
    fn default() -> Self {
        StepReport {
            matches: 0,
            rejected_gate: 0,
            ambiguous: 0,
            rejected_joint: 0,
            unconfirmed: 0,
            prediction: Prediction::Source,
            covariance: Matrix3::zeros(),
            correction_distance2: 0.0,
            motion_noise_scale: 1.0,
            measurement_noise_scale: 1.0,
            heading_correction_rad: 0.0,
            translation_correction_m: Vector2::zeros(),
            constrained_directions: 0,
            fallback: None,
            recovery: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_fitting::line_from_moments;

    fn wall(a: (f64, f64), b: (f64, f64)) -> SensorLine {
        let pts: Vec<_> = (0..=40)
            .map(|i| {
                let t = i as f64 / 40.0;
                Point2::new(a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t)
            })
            .collect();
        let moments = Moments::from_points(&pts);
        SensorLine { line: line_from_moments(&moments, &pts[0], &pts[40]).unwrap(), moments }
    }

    fn corridor() -> Vec<SensorLine> {
        vec![wall((-3.0, 1.0), (3.0, 1.0)), wall((-3.0, -1.0), (3.0, -1.0))]
    }

    fn room() -> Vec<SensorLine> {
        vec![
            wall((2.0, -2.0), (2.0, 2.0)),
            wall((-2.0, 1.5), (2.0, 1.5)),
            wall((-2.0, -1.5), (2.0, -1.5)),
        ]
    }

    fn aiding(config: AidingConfig) -> Aiding {
        Aiding::new(config, MapConfig::default()).unwrap()
    }

    /// A source that stops and comes back (a ROS log's odometry with a
    /// dropout, or starting after the first scans): the scan it returns on
    /// is predicted from the estimate's motion, and its motion across the
    /// gap, which the LIDAR-only scans already estimated, is not added
    /// again (before, the pose ran 2 m ahead here).
    #[test]
    fn a_source_that_resumes_does_not_count_the_gap_twice() {
        let none: &[SensorLine] = &[];
        let mut a = aiding(AidingConfig::estimator());
        for k in 0..3 {
            a.step_at(k as f64, &Pose2::new(k as f64, 0.0, 0.0), none);
        }
        for k in 3..5 {
            let (pose, _) = a.step_without_source(Some(k as f64), none);
            assert!((pose.x() - k as f64).abs() < 1e-9, "scan {k}: {pose:?}");
        }
        // The source comes back in a frame 10 m away (a jump across the
        // gap): only its increments count.
        for k in 5..8 {
            let (pose, _) = a.step_at(k as f64, &Pose2::new(10.0 + k as f64, 0.0, 0.0), none);
            assert!((pose.x() - k as f64).abs() < 1e-9, "scan {k}: {pose:?}");
        }
        // A source from the first scan on the LIDAR-only scans' frame: the
        // same.
        let mut b = aiding(AidingConfig::estimator());
        b.step_without_source(Some(0.0), none);
        let (pose, _) = b.step_at(1.0, &Pose2::new(-4.0, 7.0, 0.5), none);
        assert_eq!(pose, Pose2::identity());
        // One metre ahead in the source's body frame is one metre ahead here.
        let (pose, _) =
            b.step_at(2.0, &Pose2::new(-4.0 + 0.5f64.cos(), 7.0 + 0.5f64.sin(), 0.5), none);
        assert!((pose.x() - 1.0).abs() < 1e-9 && pose.y().abs() < 1e-9, "{pose:?}");
    }

    /// A source missing on every other scan (odometry messages that do
    /// not bracket each scan): each scan that has it is placed by its
    /// motion since its last pose, from the estimate there. Before, each
    /// was predicted at constant velocity as the scans without it were, so
    /// the source was never used: here, accelerating along x, the pose fell
    /// behind it by metres.
    #[test]
    fn a_source_on_every_other_scan_is_bridged_across_the_gaps() {
        let none: &[SensorLine] = &[];
        let mut a = aiding(AidingConfig::estimator());
        let x = |k: usize| 0.05 * (k * k) as f64;
        for k in 0..20 {
            let t = k as f64;
            let (pose, report) = if k % 2 == 0 {
                a.step_at(t, &Pose2::new(x(k), 0.1 * t, 0.02 * t), none)
            } else {
                a.step_without_source(Some(t), none)
            };
            if k % 2 == 0 {
                assert_eq!(report.prediction, Prediction::Source, "scan {k}");
                let d = pose.between(&Pose2::new(x(k), 0.1 * t, 0.02 * t));
                assert!(d.x().hypot(d.y()) < 1e-9 && d.heading().abs() < 1e-9, "{k}: {pose:?}");
            }
        }
        // A reanchoring in the gap (a pose-graph optimization) moves where
        // the source resumes from with the estimate.
        let mut b = aiding(AidingConfig::estimator());
        b.step_at(0.0, &Pose2::identity(), none);
        b.step_without_source(Some(1.0), none);
        let moved = Pose2::new(0.5, -0.2, 0.1);
        b.reanchor(LineMap::new(MapConfig::default()).unwrap(), &moved);
        let (pose, _) = b.step_at(2.0, &Pose2::new(1.0, 0.0, 0.0), none);
        let d = pose.between(&moved.compose(&Pose2::new(1.0, 0.0, 0.0)));
        assert!(d.x().hypot(d.y()) < 1e-9 && d.heading().abs() < 1e-9, "{pose:?}");
        // Unstamped, a scan without the source after a bridged gap of two
        // scans repeats one scan's motion (0.1 m), not the gap's (0.3 m).
        let mut c = aiding(AidingConfig::estimator());
        c.step(&Pose2::identity(), none);
        c.step_without_source(None, none);
        c.step_without_source(None, none);
        c.step(&Pose2::new(0.3, 0.0, 0.03), none);
        let (pose, report) = c.step_without_source(None, none);
        assert_eq!(report.prediction, Prediction::ConstantVelocity);
        let d = pose.between(&Pose2::new(0.3, 0.0, 0.03).compose(&Pose2::new(0.1, 0.0, 0.01)));
        assert!(d.x().hypot(d.y()) < 1e-9 && d.heading().abs() < 1e-9, "{pose:?}");
    }

    #[test]
    fn no_matches_keeps_the_prediction_and_says_so() {
        // The first scan meets an empty map: that too is reported.
        for config in [AidingConfig::full_pose(), AidingConfig::estimator(), AidingConfig::paper()]
        {
            let (pose, first) = aiding(config).step(&Pose2::new(1.0, 2.0, 0.3), &room());
            assert_eq!(first.fallback, Some(Fallback::NoMatches), "{:?}", config.mode);
            assert_eq!(pose, Pose2::new(1.0, 2.0, 0.3));
        }
        let mut a = aiding(AidingConfig::full_pose());
        a.step(&Pose2::identity(), &room());
        let far = vec![wall((40.0, -2.0), (40.0, 2.0))];
        let (pose, report) = a.step(&Pose2::new(0.1, 0.0, 0.0), &far);
        assert_eq!(report.fallback, Some(Fallback::NoMatches));
        assert_eq!(pose, Pose2::new(0.1, 0.0, 0.0));
        let (pose, report) = a.step(&Pose2::new(0.2, 0.0, 0.0), &[] as &[SensorLine]);
        assert_eq!(report.fallback, Some(Fallback::NoMatches));
        assert!(pose.is_finite());
    }

    #[test]
    fn one_match_and_parallel_matches_constrain_one_direction() {
        for lines in [vec![wall((-3.0, 1.0), (3.0, 1.0))], corridor()] {
            let mut a = aiding(AidingConfig::full_pose());
            a.step(&Pose2::identity(), &lines);
            // The source claims a step of 0.1 m along and across the corridor.
            let (pose, report) = a.step(&Pose2::new(0.1, 0.05, 0.0), &lines);
            assert_eq!(report.constrained_directions, 1, "{report:?}");
            assert!(pose.y().abs() < 1e-6, "across the walls the lines pull back: {pose:?}");
            assert!((pose.x() - 0.1).abs() < 1e-6, "along the walls nothing is known: {pose:?}");
        }
    }

    #[test]
    fn a_room_constrains_both_directions() {
        let mut a = aiding(AidingConfig::full_pose());
        a.step(&Pose2::identity(), &room());
        let (pose, report) = a.step(&Pose2::new(0.08, -0.05, 0.02), &room());
        assert_eq!(report.constrained_directions, 2);
        assert!(
            pose.x().abs() < 1e-3 && pose.y().abs() < 1e-3 && pose.heading().abs() < 1e-6,
            "{pose:?}"
        );
    }

    #[test]
    fn zero_d_rho_does_not_divide_by_zero() {
        let mut a = aiding(AidingConfig::paper());
        a.step(&Pose2::identity(), &room());
        let (pose, report) = a.step(&Pose2::identity(), &room());
        assert!(pose.is_finite() && report.heading_correction_rad.abs() < 1e-9, "{report:?}");
    }

    #[test]
    fn nan_or_huge_sources_never_produce_nan() {
        for mode in [AidingConfig::paper(), AidingConfig::full_pose(), AidingConfig::none()] {
            let mut a = aiding(mode);
            a.step(&Pose2::identity(), &room());
            let (pose, report) = a.step(&Pose2::new(f64::NAN, 0.0, 0.0), &room());
            assert_eq!(report.fallback, Some(Fallback::NonFiniteSource));
            assert_eq!(pose, Pose2::identity());
            let (pose, report) = a.step_increment(&Pose2::new(0.0, f64::INFINITY, 0.0), &room());
            assert_eq!(report.fallback, Some(Fallback::NonFiniteSource));
            assert!(pose.is_finite());
            let (pose, _) = a.step(&Pose2::new(1e300, -1e300, 1e10), &room());
            assert!(pose.is_finite(), "{pose:?}");
            let (pose, _) = a.step(&Pose2::new(1e300, 1e300, 0.0), &room());
            assert!(pose.is_finite(), "{pose:?}");
        }
    }

    /// The room's walls seen from `world_from_sensor` (sensor frame).
    fn room_seen_from(world_from_sensor: &Pose2) -> Vec<SensorLine> {
        walls_seen_from(&room(), world_from_sensor)
    }

    /// World-frame `walls` as the sensor at `world_from_sensor` sees them.
    fn walls_seen_from(walls: &[SensorLine], world_from_sensor: &Pose2) -> Vec<SensorLine> {
        let sensor_from_world = world_from_sensor.inverse();
        walls
            .iter()
            .map(|l| SensorLine {
                line: l.line.transformed(&sensor_from_world),
                moments: l.moments.transformed(&sensor_from_world),
            })
            .collect()
    }

    fn estimator() -> Aiding {
        aiding(AidingConfig::estimator())
    }

    /// A registration that measured `step` with about 0.02° and 0.3 mm of
    /// noise over 300 agreeing points.
    fn registered(step: Pose2) -> Registration {
        Registration {
            reference_from_current: step,
            information: Matrix3::identity() * 1e4,
            associated: 300,
            inliers: 300,
            points: 300,
        }
    }

    #[test]
    fn a_source_that_stopped_is_doubted_as_soon_as_it_turns_wrong() {
        // A minute's stop the registrations confirm, then a turn of 10° a
        // scan the source reports as 5°, with no line to match: only the
        // registrations can tell. Measured: 5.0° off after ten scans (the
        // first scan's 5°); 50° when every confirmation at the
        // stop lowered the registrations' scale on the source, which then
        // stayed trusted for a dozen scans of the turn.
        let mut a = estimator();
        let no_lines: [SensorLine; 0] = [];
        let mut t = 0.0;
        for _ in 0..300 {
            a.set_registration(Some(registered(Pose2::identity())));
            a.step_at(t, &Pose2::identity(), &no_lines);
            t += 0.2;
        }
        let (mut truth, mut source) = (Pose2::identity(), Pose2::identity());
        let mut pose = Pose2::identity();
        for _ in 0..10 {
            let turn = Pose2::new(0.0, 0.0, 10f64.to_radians());
            truth = truth.compose(&turn);
            source = source.compose(&Pose2::new(0.0, 0.0, 5f64.to_radians()));
            a.set_registration(Some(registered(turn)));
            pose = a.step_at(t, &source, &no_lines).0;
            t += 0.2;
        }
        let error = wrap_angle(pose.heading() - truth.heading()).to_degrees();
        assert!(error.abs() < 10.0, "{error:.1}° off after the turn");
    }

    #[test]
    fn the_estimator_leaves_a_good_source_unchanged() {
        let mut a = estimator();
        for k in 0..60 {
            let source = Pose2::new(0.01 * k as f64, 0.0, 0.001 * k as f64);
            let (pose, report) = a.step_at(0.1 * k as f64, &source, &room_seen_from(&source));
            assert!(
                (pose.x() - source.x()).abs() < 1e-3
                    && (pose.y() - source.y()).abs() < 1e-3
                    && (pose.heading() - source.heading()).abs() < 1e-4,
                "step {k}: {pose:?} vs {source:?} ({report:?})"
            );
        }
        // Confirmed from the third scan on, the walls correct the pose.
        assert_eq!(a.associations().iter().filter(|m| m.outcome == MatchOutcome::Used).count(), 3);
    }

    #[test]
    fn recovery_undoes_a_turn_the_source_got_wrong_by_20_degrees() {
        let mut config = AidingConfig::estimator();
        config.estimator.recovery = Some(crate::Recovery::standard());
        let mut with = aiding(config);
        let mut without = estimator();
        let truth = Pose2::new(0.2, 0.1, 0.0);
        for k in 0..5 {
            with.step_at(0.1 * k as f64, &truth, &room_seen_from(&truth));
            without.step_at(0.1 * k as f64, &truth, &room_seen_from(&truth));
        }
        // The sensor stays; the source says it turned 20° (a lagging
        // odometry after a fast turn back and forth).
        let source = Pose2::new(0.2, 0.1, 20f64.to_radians());
        let (pose, report) = with.step_at(0.5, &source, &room_seen_from(&truth));
        let change = report.recovery.expect("recovered");
        assert!((change.heading() + 20f64.to_radians()).abs() < 0.01, "{change:?}");
        assert!((pose.heading() - truth.heading()).abs() < 0.2f64.to_radians(), "{pose:?}");
        assert!(report.matches >= 2, "{report:?}");
        // Without recovery the gates hold nothing and the source's turn stays.
        let (pose, report) = without.step_at(0.5, &source, &room_seen_from(&truth));
        assert!(report.recovery.is_none() && report.matches == 0, "{report:?}");
        assert!((pose.heading() - source.heading()).abs() < 1e-9);
        // The source's next increment is right (no motion): nothing to
        // recover.
        let (pose, report) = with.step_at(0.6, &source, &room_seen_from(&truth));
        assert!(report.recovery.is_none(), "{report:?}");
        assert!((pose.heading() - truth.heading()).abs() < 0.2f64.to_radians());
    }

    #[test]
    fn the_estimator_pulls_a_biased_source_back_and_learns_the_bias() {
        let mut a = estimator();
        let (mut worst, mut late): (f64, f64) = (0.0, 0.0);
        for k in 0..200 {
            let t = 0.1 * k as f64;
            let truth = Pose2::new(0.005 * k as f64, 0.0, 0.0);
            // A gyro-like bias of 0.5°/s in the source.
            let source = Pose2::new(truth.x(), truth.y(), 0.5f64.to_radians() * t);
            let (pose, _) = a.step_at(t, &source, &room_seen_from(&truth));
            let err = (pose.heading() - truth.heading()).abs();
            worst = worst.max(err);
            if k > 100 {
                late = late.max(err);
            }
        }
        // Unaided, the heading would be 10° off at the end.
        assert!(worst < 0.2f64.to_radians(), "worst heading error {:.3}°", worst.to_degrees());
        let bias = a.calibration().heading_rate_bias_rad_s.to_degrees();
        assert!((bias - 0.5).abs() < 0.1, "bias estimate {bias:.3}°/s");
        // What is left is the map's own error: its lines absorbed the
        // observations placed while the bias was being learnt.
        assert!(
            late < 0.15f64.to_radians(),
            "heading error once the bias is learnt {:.3}°",
            late.to_degrees()
        );
    }

    /// A source whose steps are 3% too long (a wheel diameter off), back
    /// and forth in a room whose walls fix the position: the scale is
    /// learnt from the position corrections it causes, through its
    /// covariance with the pose, and once it is, the pose keeps to the
    /// truth.
    #[test]
    fn the_estimator_learns_a_speed_scale_error_from_position_corrections() {
        let mut a = estimator();
        let mut late: f64 = 0.0;
        let (mut x, mut source_x, mut dx) = (0.0, 0.0, 0.02);
        for k in 0..400 {
            if !(-1.0..=1.0).contains(&(x + dx)) {
                dx = -dx;
            }
            x += dx;
            source_x += 1.03 * dx;
            let truth = Pose2::new(x, 0.0, 0.0);
            let source = Pose2::new(source_x, 0.0, 0.0);
            let (pose, _) = a.step_at(0.1 * k as f64, &source, &room_seen_from(&truth));
            if k >= 200 {
                late = late.max((pose.x() - truth.x()).hypot(pose.y() - truth.y()));
            }
        }
        // Measured: 2.83% (sigma 0.31%).
        let c = a.calibration();
        assert!((c.speed_scale_error - 0.03).abs() < 0.005, "{c:?}");
        // Measured: 6.7 mm; 14.1 mm before the scale learnt (2026-12-04),
        // and unaided the position drifts 3 cm each way.
        assert!(late < 0.01, "worst position error over the last 200 steps {late:.4} m");
    }

    #[test]
    fn one_wrong_line_cannot_pull_the_pose() {
        let mut a = estimator();
        for k in 0..4 {
            a.step_at(0.1 * k as f64, &Pose2::identity(), &room_seen_from(&Pose2::identity()));
        }
        // The source is right; one extra line claims the east wall is 12 cm
        // nearer (a box face in front of it, say).
        let mut lines = room_seen_from(&Pose2::identity());
        lines.push(wall((1.88, -1.0), (1.88, 1.0)));
        let (pose, report) = a.step_at(0.4, &Pose2::identity(), &lines);
        assert!(pose.x().abs() < 2e-3 && pose.y().abs() < 2e-3, "{pose:?} {report:?}");
        assert!(report.matches >= 3, "{report:?}");
        assert!(report.rejected_joint + report.rejected_gate + report.ambiguous >= 1, "{report:?}");
    }

    /// Two scans stamped 10 ms apart whose poses differ by 30° (as in
    /// Intel's GMapping log): the velocity that deskews the next scan is not
    /// taken from them.
    #[test]
    fn a_turn_too_fast_for_its_stamps_leaves_the_velocity() {
        let mut a = estimator();
        let mut t = 0.0;
        for k in 0..5 {
            let source = Pose2::new(0.1 * k as f64, 0.0, 0.0);
            a.step_at(t, &source, &room_seen_from(&source));
            t += 1.0;
        }
        let before = a.velocity().expect("stamped steps give a velocity");
        assert!((before.vx_mps - 0.1).abs() < 0.02, "{before:?}");
        let turned = Pose2::new(0.4, 0.0, 30f64.to_radians());
        a.step_at(t - 1.0 + 0.01, &turned, &room_seen_from(&turned));
        let after = a.velocity().expect("the last velocity stays");
        assert!(after.yaw_rate_radps.abs() < 1.0, "{after:?}");
        assert!((after.vx_mps - before.vx_mps).abs() < 1e-12, "{after:?} {before:?}");
    }

    /// A corridor's two walls constrain neither the position along it nor
    /// anything the velocity's error could add there: at 40 Hz the
    /// along-track uncertainty must grow no faster than the accelerations
    /// allow. (Modelled as twice the pose's covariance, the velocity's
    /// error tripled the along-track variance every scan.)
    #[test]
    fn lidar_only_uncertainty_along_a_corridor_grows_slowly() {
        let corridor = [wall((-30.0, 1.0), (30.0, 1.0)), wall((-30.0, -1.0), (30.0, -1.0))];
        let mut a = estimator();
        let mut along = 0.0;
        for k in 0..80 {
            let truth = Pose2::new(0.025 * k as f64, 0.0, 0.0);
            let (pose, report) =
                a.step_without_source(Some(0.025 * k as f64), &walls_seen_from(&corridor, &truth));
            assert!((pose.y() - truth.y()).abs() < 0.01, "scan {k}: {pose:?}");
            along = report.covariance[(0, 0)].sqrt();
        }
        // Two seconds of the accelerations' floors: a few centimetres.
        assert!(along < 0.1, "along-track sigma {along} m");
    }

    #[test]
    fn lidar_only_mode_tracks_a_constant_motion() {
        let mut a = estimator();
        for k in 0..80 {
            let truth = Pose2::new(0.01 * k as f64, 0.002 * k as f64, 0.002 * k as f64);
            let (pose, report) =
                a.step_without_source(Some(0.025 * k as f64), &room_seen_from(&truth));
            assert_eq!(report.prediction, crate::Prediction::ConstantVelocity);
            assert!(
                (pose.x() - truth.x()).hypot(pose.y() - truth.y()) < 0.01
                    && (pose.heading() - truth.heading()).abs() < 0.2f64.to_radians(),
                "scan {k}: {pose:?} vs {truth:?}"
            );
        }
    }
}
