//! The source's systematic errors as states of the estimator (beyond the
//! paper): a heading-rate bias (a gyro's, or wheel odometry that turns too
//! much one way), a speed scale error (a wheel diameter off by a few
//! percent) and a latency (the pose written with a scan is the pose of a
//! little later: MIT CSAIL's odometry is about 0.1 s late).
//!
//! Each accepted correction of a step observes what is left of them in the
//! step. A heading correction over `dt` seconds observes the bias times
//! `dt` plus the latency times the change of turn rate since the last step
//! (a late source turns late: its increment carries `latency * (rate now -
//! rate before)` too much); one Kalman filter of the two states takes it.
//! The latency then corrects the whole increment: the heading by the
//! change of rate, the translation by the change of velocity and the turn
//! of the frame it is written in.
//! The scale is a state of the pose: its covariance with the pose is
//! carried through every prediction (each step moves the pose by `-step`
//! per unit of scale error), and each accepted pose correction moves it by
//! that covariance, as the augmented filter's gain does
//! ([`SourceCalibration::propagate_pose_scale`],
//! [`SourceCalibration::observe_pose`]). The next increments are corrected
//! with the estimates. Without them, a constant bias drifts the map with the
//! pose: the lines inserted a scan ago agree with the drift, and every
//! correction sees only the newest step's share of it.

use pcaline_geometry::{Matrix3, Pose2, Vector2, Vector3};

/// The source's motion over one step, as the latency correction needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Motion {
    /// Heading rate, rad/s.
    rate_rad_s: f64,
    /// Velocity in the step's start frame, m/s.
    velocity_m_s: Vector2<f64>,
    /// The step's turn, radians.
    turn_rad: f64,
}

/// A source step shorter than this (and turning less than
/// [`STILL_TURN_RAD`]) is no motion: a stopped platform, or a source that
/// stopped updating, metres.
pub const STILL_STEP_M: f64 = 1e-3;

/// See [`STILL_STEP_M`]: 0.01°, radians.
pub const STILL_TURN_RAD: f64 = std::f64::consts::PI / 18_000.0;

/// Whether the source's `increment` is no motion ([`STILL_STEP_M`],
/// [`STILL_TURN_RAD`]).
fn is_still(increment: &Pose2) -> bool {
    increment.x().hypot(increment.y()) < STILL_STEP_M && increment.heading().abs() < STILL_TURN_RAD
}

/// A latency beyond this is not a latency error, seconds.
const MAX_LATENCY_S: f64 = 0.5;

/// A step that turns faster than this (two turns a second, beyond any
/// platform this crate aids) did not take the time its stamps say: Intel's
/// GMapping log has eight steps of 10-20 ms that turn 28-34° (25-59 rad/s).
/// Such a step's duration is not used (as for an unstamped step), so no
/// rate, bias or latency is taken from it or corrected in it, rad/s.
pub const MAX_TURN_RATE_RAD_S: f64 = 2.0 * std::f64::consts::TAU;

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
    /// Standard deviation of the source's latency before any scan, seconds
    /// (the pose written with a scan is the pose this much later);
    /// `None`: no latency is estimated. Needs stamped scans.
    pub latency_std_s: Option<f64>,
    /// Random walk of the latency, seconds per square-root second.
    pub latency_walk_s_per_sqrt_s: f64,
}

impl CalibrationConfig {
    /// A bias of 1°/s, a scale error of 2% (a wheel diameter off by a few
    /// millimetres) and a latency of 30 ms before any scan, slow random
    /// walks (0.001°/s per root second, 0.01% per root metre, 0.1 ms per
    /// root second). A 5% scale prior takes the simulated scenes to 0.7 cm
    /// instead of 0.9 cm, but lets early corrections teach Intel's own good
    /// poses a scale that moves them 0.10 m with loop closure
    /// (`docs/accuracy.md`). A wider latency prior (0.1 s)
    /// learns MIT CSAIL's 0.1 s as well, but lets early wrong matches
    /// through on fast turns: the paper detector's estimator run in
    /// `pcaline eval` went from 0.17° to 1.7° rms heading.
    pub const fn standard() -> Self {
        CalibrationConfig {
            heading_rate_bias_std_rad_s: Some(0.017_45),
            heading_rate_bias_walk_rad_s_per_sqrt_s: 1.745e-5,
            speed_scale_std: Some(0.02),
            speed_scale_walk_per_sqrt_m: 1e-4,
            latency_std_s: Some(0.03),
            latency_walk_s_per_sqrt_s: 1e-4,
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
    /// The source's latency, seconds.
    pub latency_s: f64,
    /// Its variance.
    pub latency_var: f64,
    /// Covariance of the bias and the latency, rad.
    pub bias_latency_cov: f64,
    /// Covariance of the pose's error (world x and y, metres; heading,
    /// radians) with the speed scale error.
    pub pose_scale_cov: Vector3<f64>,
    /// The source's motion over the last step.
    previous_motion: Option<Motion>,
    /// The change of heading rate the last step was corrected with, rad/s.
    rate_change_rad_s: f64,
    /// Whether the last step's duration was usable (stamped, positive, and
    /// not turning faster than [`MAX_TURN_RATE_RAD_S`]).
    step_timed: bool,
    /// Time since the source last moved (its steps since then all still:
    /// [`STILL_STEP_M`]), seconds.
    stale_s: f64,
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
            latency_s: 0.0,
            latency_var: config.latency_std_s.map_or(0.0, |s| s * s),
            bias_latency_cov: 0.0,
            pose_scale_cov: Vector3::zeros(),
            previous_motion: None,
            rate_change_rad_s: 0.0,
            step_timed: false,
            stale_s: 0.0,
        }
    }

    /// The increment with the estimated errors removed, and the variance
    /// their uncertainty adds to the predicted heading and along the step.
    /// `dt_s` is the step's duration when known; a step turning faster
    /// than [`MAX_TURN_RATE_RAD_S`] over it is taken as unstamped, here and
    /// in the [`SourceCalibration::observe`] that follows. A step without
    /// motion ([`STILL_STEP_M`], [`STILL_TURN_RAD`]: a stopped platform, or
    /// a source that stopped updating) gets no latency correction and is not
    /// the next step's reference rate; the next step that moves is taken
    /// over the whole time since the source last moved (a stalled source
    /// catching up gives the turn of all those steps in one). The random
    /// walks are added to the variances here.
    pub fn correct(
        &mut self,
        config: &CalibrationConfig,
        increment: &Pose2,
        dt_s: Option<f64>,
    ) -> (Pose2, f64, f64) {
        let dt_s =
            dt_s.filter(|dt| *dt > 0.0 && increment.heading().abs() <= MAX_TURN_RATE_RAD_S * dt);
        self.step_timed = dt_s.is_some();
        let mut inc = *increment;
        let (mut var_heading, mut var_along) = (0.0, 0.0);
        if let (Some(_), Some(dt)) = (config.heading_rate_bias_std_rad_s, dt_s) {
            self.heading_rate_bias_var +=
                config.heading_rate_bias_walk_rad_s_per_sqrt_s.powi(2) * dt;
            inc = Pose2::new(inc.x(), inc.y(), inc.heading() - self.heading_rate_bias_rad_s * dt);
            var_heading = self.heading_rate_bias_var * dt * dt;
        }
        self.rate_change_rad_s = 0.0;
        match (config.latency_std_s, dt_s) {
            (Some(_), Some(dt)) if is_still(increment) => {
                // The source did not move: a stopped platform, or a source
                // that stopped updating. Its step says nothing of a
                // change of rate; the motion before it stays the reference.
                self.latency_var += config.latency_walk_s_per_sqrt_s.powi(2) * dt;
                self.stale_s += dt;
            }
            (Some(_), Some(dt)) => {
                self.latency_var += config.latency_walk_s_per_sqrt_s.powi(2) * dt;
                // After still steps, the source's step may span them all
                // (a stalled source catching up): its rate is
                // taken over the whole time since it last moved.
                let span = dt + std::mem::take(&mut self.stale_s);
                let rate = inc.heading() / span;
                let velocity = Vector2::new(inc.x(), inc.y()) / span;
                let tau = self.latency_s;
                let mut t = Vector2::new(inc.x(), inc.y());
                let mut change = 0.0;
                if let Some(previous) = self.previous_motion {
                    change = rate - previous.rate_rad_s;
                    // The source's previous pose is the pose `latency`
                    // later: turned by latency * rate and moved by latency
                    // * velocity; its increment carries the change of both.
                    let turned =
                        |angle: f64, v: &Vector2<f64>| Pose2::new(0.0, 0.0, angle).rotate(v);
                    let previous_velocity = turned(-previous.turn_rad, &previous.velocity_m_s);
                    t = turned(tau * previous.rate_rad_s, &t)
                        - (velocity - previous_velocity) * tau;
                }
                self.previous_motion = Some(Motion {
                    rate_rad_s: rate,
                    velocity_m_s: velocity,
                    turn_rad: inc.heading(),
                });
                self.rate_change_rad_s = change;
                // The source's heading is the heading `latency` later: its
                // increment carries latency times the change of rate.
                inc = Pose2::new(t.x, t.y, inc.heading() - tau * change);
                let bias_dt = if config.heading_rate_bias_std_rad_s.is_some() { dt } else { 0.0 };
                // The latency's uncertainty over the change of rate, and its
                // covariance with the bias, join the bias's (a failed
                // source's jump widens it too: recovery judges the jump
                // without it).
                var_heading = var_heading
                    + 2.0 * self.bias_latency_cov * bias_dt * change
                    + self.latency_var * change * change;
            }
            _ => {
                self.previous_motion = None;
                self.stale_s = 0.0;
            }
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

    /// Learns the heading-rate bias and the latency from an accepted
    /// update of a step that [`SourceCalibration::correct`] took as timed:
    /// the heading correction over `dt_s` seconds, with the prior and
    /// posterior pose covariances. (The speed scale learns from the whole
    /// pose correction: [`SourceCalibration::observe_pose`].)
    pub fn observe(
        &mut self,
        config: &CalibrationConfig,
        dt_s: Option<f64>,
        heading: f64,
        prior: &Matrix3<f64>,
        posterior: &Matrix3<f64>,
    ) {
        // Only a step that [`SourceCalibration::correct`] timed teaches the
        // bias and latency (not a source's jump, which skips it).
        let dt_s = dt_s.filter(|_| std::mem::take(&mut self.step_timed));
        if let (Some(dt), Some((z, r))) =
            (dt_s, as_measurement(heading, prior[(2, 2)], posterior[(2, 2)]))
            && dt > 0.0
        {
            // The heading error of the prediction is (bias left) * dt +
            // (latency left) * (change of rate) plus the step's own noise:
            // one measurement of the two states, a joint Kalman update.
            let h_b = if config.heading_rate_bias_std_rad_s.is_some() { dt } else { 0.0 };
            let h_l = if config.latency_std_s.is_some() { self.rate_change_rad_s } else { 0.0 };
            let (pbb, pll, pbl) =
                (self.heading_rate_bias_var, self.latency_var, self.bias_latency_cov);
            let (phb, phl) = (pbb * h_b + pbl * h_l, pbl * h_b + pll * h_l);
            let s = h_b * phb + h_l * phl + r + prior[(2, 2)];
            if s > 0.0 && s.is_finite() {
                let y = -z;
                let (kb, kl) = (phb / s, phl / s);
                self.heading_rate_bias_rad_s += kb * y;
                self.latency_s += kl * y;
                self.heading_rate_bias_var = pbb - kb * phb;
                self.latency_var = pll - kl * phl;
                self.bias_latency_cov = pbl - kb * phl;
            }
        }
        if !(self.heading_rate_bias_rad_s.is_finite()
            && self.speed_scale_error.is_finite()
            && self.latency_s.is_finite())
        {
            *self = SourceCalibration::new(config);
        }
        // A scale error beyond 50% is not a calibration error.
        self.speed_scale_error = self.speed_scale_error.clamp(-0.5, 0.5);
        self.latency_s = self.latency_s.clamp(-MAX_LATENCY_S, MAX_LATENCY_S);
    }
}

impl SourceCalibration {
    /// Carries the covariance of the pose with the speed scale error
    /// through a prediction that composed a step of `step_world` (the
    /// corrected increment's translation, world frame, metres) onto the
    /// pose, and adds its cross terms to the predicted `covariance` (which
    /// already holds the scale's own variance along the step).
    ///
    /// The scale enters the step as `-step_world` per unit of scale error,
    /// and the previous pose's heading error turns the step (the motion
    /// Jacobian). Edge cases: with the scale off, or a step the scale did
    /// not correct (`scaled` false: a source's jump, no source), only the
    /// heading's lever arm carries the covariance; a step whose terms are
    /// not finite resets the covariance to zero and adds nothing.
    pub fn propagate_pose_scale(
        &mut self,
        config: &CalibrationConfig,
        step_world: &Vector2<f64>,
        scaled: bool,
        covariance: &mut Matrix3<f64>,
    ) {
        let c = self.pose_scale_cov;
        let turned = Vector3::new(c.x - step_world.y * c.z, c.y + step_world.x * c.z, c.z);
        if !turned.iter().all(|v| v.is_finite()) {
            // A step too large to carry (a source's 1e300 m): the
            // correlation is forgotten, never made NaN.
            self.pose_scale_cov = Vector3::zeros();
            return;
        }
        if config.speed_scale_std.is_none() || !scaled {
            self.pose_scale_cov = turned;
            return;
        }
        let g = Vector3::new(-step_world.x, -step_world.y, 0.0);
        let cross = turned * g.transpose() + g * turned.transpose();
        let next = turned + g * self.speed_scale_var;
        if cross.iter().all(|v| v.is_finite()) && next.iter().all(|v| v.is_finite()) {
            *covariance += cross;
            self.pose_scale_cov = next;
        } else {
            self.pose_scale_cov = Vector3::zeros();
        }
    }

    /// Learns the speed scale from an accepted pose correction
    /// (`correction`: the update minus the prediction, world x, y and
    /// heading), with the prior and posterior pose covariances: the scale
    /// is the pose's augmented state, and a measurement of the pose moves
    /// it by its covariance with the pose. Edge cases: a singular prior
    /// teaches nothing; the variance never falls below a millionth of
    /// itself.
    pub fn observe_pose(
        &mut self,
        config: &CalibrationConfig,
        correction: &Vector3<f64>,
        prior: &Matrix3<f64>,
        posterior: &Matrix3<f64>,
    ) {
        if config.speed_scale_std.is_none() {
            return;
        }
        let Some(prior_inv) = prior.try_inverse() else { return };
        let w = prior_inv * self.pose_scale_cov;
        let reduction = (w.transpose() * (prior - posterior) * w)[(0, 0)];
        let scale = self.speed_scale_error + w.dot(correction);
        let var = (self.speed_scale_var - reduction).max(self.speed_scale_var * 1e-6);
        let cov = posterior * w;
        if scale.is_finite() && var.is_finite() && cov.iter().all(|v| v.is_finite()) {
            // A scale error beyond 50% is not a calibration error.
            self.speed_scale_error = scale.clamp(-0.5, 0.5);
            self.speed_scale_var = var;
            self.pose_scale_cov = cov;
        }
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
            cal.observe(&config, Some(1.0), correction, &prior, &post);
        }
        assert!((cal.heading_rate_bias_rad_s - bias).abs() < 2e-4, "{cal:?}");
    }

    /// A source whose heading is the true heading 0.1 s later (MIT CSAIL's
    /// odometry): the latency is learnt from the corrections of a weaving
    /// path, and the bias stays near zero.
    #[test]
    fn a_late_source_teaches_its_latency() {
        let config = CalibrationConfig::standard();
        let mut cal = SourceCalibration::new(&config);
        let (latency, dt) = (0.1, 0.2);
        let heading = |t: f64| 2.0 * (0.5 * t).sin();
        for k in 1..600 {
            let t = k as f64 * dt;
            let truth = heading(t) - heading(t - dt);
            let source = heading(t + latency) - heading(t - dt + latency);
            let (inc, _, _) = cal.correct(&config, &Pose2::new(0.0, 0.0, source), Some(dt));
            let prior = Matrix3::from_diagonal(&[1e-4, 1e-4, 1e-4].into());
            let post = Matrix3::from_diagonal(&[1e-4, 1e-4, 1e-6].into());
            let correction = -(inc.heading() - truth);
            cal.observe(&config, Some(dt), correction, &prior, &post);
        }
        assert!((cal.latency_s - latency).abs() < 0.01, "{cal:?}");
        assert!(cal.heading_rate_bias_rad_s.abs() < 1e-3, "{cal:?}");
        // Straight ahead at constant speed a late source is right: its
        // increments are left as they are.
        let mut steady = SourceCalibration::new(&config);
        steady.latency_s = 0.1;
        for _ in 0..3 {
            let step = Pose2::new(0.5, 0.0, 0.0);
            let (inc, _, _) = steady.correct(&config, &step, Some(dt));
            assert!((inc.x() - 0.5).abs() < 1e-9 && inc.y().abs() < 1e-9, "{inc:?}");
        }
        // With the latency state off, nothing is learnt or corrected for it.
        let mut config = config;
        config.latency_std_s = None;
        let mut cal = SourceCalibration::new(&config);
        let (inc, _, _) = cal.correct(&config, &Pose2::new(0.0, 0.0, 0.3), Some(dt));
        assert_eq!(inc.heading(), 0.3);
        assert_eq!(cal.latency_s, 0.0);
    }

    /// Intel's GMapping log has steps 10 ms apart that turn 30°: such a
    /// step's stamps are not its poses' times. It is neither corrected for
    /// latency nor learnt from, and the next step's change of rate is not
    /// taken against it.
    #[test]
    fn a_step_turning_faster_than_any_platform_is_taken_as_unstamped() {
        let config = CalibrationConfig::standard();
        let mut cal = SourceCalibration::new(&config);
        cal.latency_s = 0.05;
        let prior = Matrix3::from_diagonal(&[1e-4, 1e-4, 1e-4].into());
        let post = Matrix3::from_diagonal(&[1e-4, 1e-4, 1e-6].into());
        let steady = Pose2::new(0.3, 0.0, 0.02);
        let _ = cal.correct(&config, &steady, Some(1.0));
        let glitch = Pose2::new(0.0, 0.0, 30f64.to_radians());
        let (inc, var_heading, _) = cal.correct(&config, &glitch, Some(0.01));
        assert_eq!(inc.heading(), glitch.heading());
        assert_eq!(var_heading, 0.0);
        let before = cal;
        cal.observe(&config, Some(0.01), 0.1, &prior, &post);
        assert_eq!(cal.latency_s, before.latency_s);
        assert_eq!(cal.heading_rate_bias_rad_s, before.heading_rate_bias_rad_s);
        // The next step has no rate to change from.
        let (inc, _, _) = cal.correct(&config, &steady, Some(1.0));
        assert_eq!(inc.heading(), steady.heading());
        // The same turn over a second is a turn, corrected for latency.
        let _ = cal.correct(&config, &steady, Some(1.0));
        let (inc, _, _) = cal.correct(&config, &glitch, Some(1.0));
        assert!((inc.heading() - glitch.heading()).abs() > 1e-3, "{inc:?}");
    }

    /// MIT CSAIL's raw odometry stays the same for four scans during a
    /// turn, then gives the whole turn in one step. The step spans the
    /// stalled ones: its rate is the turn's, not five times it, so the
    /// latency takes nothing off it (taking `latency * change` off it
    /// turned the estimate 31° instead of 85° at scan 1584), nor off the
    /// next step.
    #[test]
    fn a_stalled_source_catching_up_is_not_taken_for_a_change_of_rate() {
        let config = CalibrationConfig::standard();
        let (rate, dt) = (1.0, 0.2);
        let turning = Pose2::new(0.0, 0.0, rate * dt);
        let mut cal = SourceCalibration::new(&config);
        cal.latency_s = 0.1;
        for _ in 0..3 {
            let _ = cal.correct(&config, &turning, Some(dt));
        }
        for _ in 0..4 {
            let (inc, _, _) = cal.correct(&config, &Pose2::identity(), Some(dt));
            assert_eq!(inc.heading(), 0.0, "a still step is left as it is");
        }
        let catch_up = Pose2::new(0.0, 0.0, 5.0 * rate * dt);
        let (inc, _, _) = cal.correct(&config, &catch_up, Some(dt));
        assert!((inc.heading() - catch_up.heading()).abs() < 1e-12, "{inc:?}");
        let (inc, _, _) = cal.correct(&config, &turning, Some(dt));
        assert!((inc.heading() - turning.heading()).abs() < 1e-12, "{inc:?}");
        // A real change of rate after the still steps is still corrected.
        for _ in 0..2 {
            let _ = cal.correct(&config, &Pose2::identity(), Some(dt));
        }
        let faster = Pose2::new(0.0, 0.0, 3.0 * 3.0 * rate * dt);
        let (inc, _, _) = cal.correct(&config, &faster, Some(dt));
        assert!((inc.heading() - (faster.heading() - 0.1 * (3.0 - 1.0))).abs() < 1e-9, "{inc:?}");
    }

    /// Steps along x that the source makes 3% too long, and a position
    /// measured to 1 cm after each: the augmented update learns the scale,
    /// and its covariance with the pose follows the steps.
    #[test]
    fn the_speed_scale_is_learnt_from_pose_corrections() {
        let config = CalibrationConfig::standard();
        let mut cal = SourceCalibration::new(&config);
        let measurement = Matrix3::from_diagonal(&[1e-4, 1e-4, 1e-6].into());
        let (mut truth, mut estimate) = (0.0, 0.0);
        let mut covariance = Matrix3::from_diagonal(&[1e-4, 1e-4, 1e-6].into());
        for _ in 0..300 {
            truth += 0.1;
            let (inc, _, var_along) = cal.correct(&config, &Pose2::new(0.103, 0.0, 0.0), None);
            estimate += inc.x();
            let step = Vector2::new(inc.x(), inc.y());
            let mut prior = covariance + Matrix3::from_diagonal(&[1e-6, 1e-6, 1e-8].into());
            prior[(0, 0)] += var_along;
            cal.propagate_pose_scale(&config, &step, true, &mut prior);
            let Some(posterior) =
                (prior.try_inverse().unwrap() + measurement.try_inverse().unwrap()).try_inverse()
            else {
                panic!("singular")
            };
            let correction = posterior
                * measurement.try_inverse().unwrap()
                * Vector3::new(truth - estimate, 0.0, 0.0);
            cal.observe_pose(&config, &correction, &prior, &posterior);
            estimate += correction.x;
            covariance = posterior;
        }
        assert!((cal.speed_scale_error - 0.03).abs() < 0.003, "{cal:?}");
        assert!(cal.speed_scale_var.sqrt() < 0.003, "{cal:?}");
        // With the scale off, nothing is learnt and no cross terms appear.
        let mut off = config;
        off.speed_scale_std = None;
        let mut cal = SourceCalibration::new(&off);
        let mut prior = Matrix3::identity();
        cal.propagate_pose_scale(&off, &Vector2::new(0.1, 0.0), true, &mut prior);
        cal.observe_pose(&off, &Vector3::new(0.01, 0.0, 0.0), &prior, &(prior * 0.5));
        assert_eq!(prior, Matrix3::identity());
        assert_eq!(cal.speed_scale_error, 0.0);
    }

    #[test]
    fn steps_too_large_to_carry_never_make_nan() {
        let config = CalibrationConfig::standard();
        let mut cal = SourceCalibration::new(&config);
        cal.pose_scale_cov = Vector3::new(1e-4, 0.0, 1e-5);
        for step in [Vector2::new(1e300, 1e300), Vector2::new(f64::NAN, 0.0)] {
            let mut covariance = Matrix3::identity();
            cal.propagate_pose_scale(&config, &step, true, &mut covariance);
            assert_eq!(covariance, Matrix3::identity());
            assert_eq!(cal.pose_scale_cov, Vector3::zeros());
            cal.pose_scale_cov = Vector3::new(1e-4, 0.0, 1e-5);
        }
        // A non-finite correction teaches nothing.
        let prior = Matrix3::identity();
        cal.observe_pose(&config, &Vector3::new(f64::NAN, 0.0, 0.0), &prior, &(prior * 0.5));
        assert_eq!(cal.speed_scale_error, 0.0);
    }

    #[test]
    fn a_correction_without_information_teaches_nothing() {
        assert!(as_measurement(0.1, 1.0, 1.0).is_none());
        assert!(as_measurement(f64::NAN, 1.0, 0.5).is_none());
        let (z, r) = as_measurement(0.05, 1.0, 0.5).unwrap();
        assert!((z - 0.1).abs() < 1e-12 && (r - 1.0).abs() < 1e-12);
    }
}
