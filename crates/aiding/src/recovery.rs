//! [`recover`]: a new prediction when the source's is wrong by more than
//! its gates allow.
//!
//! The estimator matches a scan's lines within gates derived from the
//! predicted covariance. A source whose error is far outside its own noise
//! model (odometry that lags the scans and is tens of degrees off after a
//! fast turn, a wheel that slipped) leaves every line outside its gate: the
//! scan corrects nothing, its lines enter the map where the source put them,
//! and the next scans match those. Recovery aligns the scan's lines with the
//! map lines around the prediction without a good prior ([`align_lines`],
//! line pairs then least squares, within a wide bound) and offers the result
//! as a new prediction only when it lays clearly more wall over the map than
//! the prediction does, constrains both directions and is not ambiguous.

use crate::{Alignment, AlignmentConfig, AlignmentPrior, align_lines, laid_length};
use pcaline_geometry::{ConfigError, LineSegment, Matrix3, Pose2, Vector3};

/// Tuning of [`recover`] (`aiding.estimator.recovery` in a configuration
/// file).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct Recovery {
    /// Map lines passing within this of the predicted position take part,
    /// metres.
    pub map_radius_m: f64,
    /// The new prediction lies at most this far from the source's, metres ...
    pub radius_m: f64,
    /// ... and turned from it by at most this, radians.
    pub max_rotation_rad: f64,
    /// It must lay at least this much more wall over the map than the
    /// source's prediction does, metres ...
    pub min_gain_m: f64,
    /// ... and at least this fraction of the scan's line length,
    pub min_matched_fraction: f64,
    /// with at least this much matched wall across its weakest direction,
    /// metres (a corridor's length is not observed),
    pub min_weakest_direction_m: f64,
    /// an rms endpoint distance of at most this, metres,
    pub max_rms_m: f64,
    /// and no placement at least 0.5 m or 5° away laying more than this
    /// fraction of its length (repeated structure).
    pub max_runner_up: f64,
    /// The new prediction is taken only when its change is at least this
    /// squared Mahalanobis distance from the source's under the predicted
    /// covariance (three degrees of freedom): beyond the gates, since a
    /// change the covariance allows is the update's to make.
    pub min_change_chi2: f64,
    /// The alignment's hypotheses and matching rule.
    pub alignment: AlignmentConfig,
}

impl Recovery {
    /// Map lines within 15 m; a new prediction at most 1 m and 30° from the
    /// source's, laying at least 1 m more wall and half the scan's line
    /// length, with 0.5 m of wall across its weakest direction, an rms of
    /// at most 4 cm and no runner-up above 0.7 of its length, taken only 10
    /// standard deviations (chi² 100) from the source's.
    pub const fn standard() -> Self {
        Recovery {
            map_radius_m: 15.0,
            radius_m: 1.0,
            max_rotation_rad: std::f64::consts::FRAC_PI_6,
            min_gain_m: 1.0,
            min_matched_fraction: 0.5,
            min_weakest_direction_m: 0.5,
            max_rms_m: 0.04,
            max_runner_up: 0.7,
            min_change_chi2: 100.0,
            alignment: AlignmentConfig::standard(),
        }
    }

    /// Checks every field; errors name `prefix.field`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        ConfigError::positive_fields(
            prefix,
            &[
                ("map_radius_m", self.map_radius_m),
                ("radius_m", self.radius_m),
                ("max_rotation_rad", self.max_rotation_rad),
                ("min_gain_m", self.min_gain_m),
                ("max_rms_m", self.max_rms_m),
                ("min_change_chi2", self.min_change_chi2),
            ],
        )?;
        for (name, v) in [
            ("min_matched_fraction", self.min_matched_fraction),
            ("max_runner_up", self.max_runner_up),
        ] {
            ConfigError::check_field(
                (0.0..=1.0).contains(&v),
                prefix,
                name,
                v,
                "must be in [0, 1]",
            )?;
        }
        ConfigError::check_field(
            self.min_weakest_direction_m >= 0.0 && self.min_weakest_direction_m.is_finite(),
            prefix,
            "min_weakest_direction_m",
            self.min_weakest_direction_m,
            "must be finite and >= 0",
        )?;
        self.alignment.validate(&format!("{prefix}.alignment"))
    }
}

impl Default for Recovery {
    fn default() -> Self {
        Self::standard()
    }
}

/// What [`recover`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Recovered {
    /// The new prediction of the sensor's pose.
    pub world_from_sensor: Pose2,
    /// Its covariance, `(x, y, heading)`: the predicted one widened by the
    /// change in each coordinate, so the change is about one standard
    /// deviation.
    pub covariance: Matrix3<f64>,
    /// The alignment of the scan's lines with the map, in the frame of the
    /// source's prediction (`candidate_from_current` is
    /// `predicted_from_sensor`).
    pub alignment: Alignment,
    /// The wall the source's prediction lays over the map, metres.
    pub laid_at_prediction_m: f64,
}

/// A new prediction of the sensor's pose from the scan's `lines` (sensor
/// frame) and the `map` lines near the prediction (world frame), when the
/// source's `predicted` pose (covariance `predicted_cov`, `(x, y,
/// heading)`) is clearly wrong; `None` when it is not, or when the scan
/// cannot say better (fewer than two usable lines in either set, no
/// hypothesis within the bound, too little wall laid, one direction
/// unconstrained, a large residual, a runner-up placement, or a change
/// within [`Recovery::min_change_chi2`]; a singular covariance allows no
/// change, so any clear one is taken).
///
/// The prediction's own placement is scored as a hypothesis, so a right
/// prediction is kept; only a placement that lays
/// [`Recovery::min_gain_m`] more wall replaces it.
///
/// ```
/// use pcaline_aiding::{Recovery, recover};
/// use pcaline_geometry::{LineSegment, Matrix3, Point2, Pose2, Vector3};
///
/// let room = [
///     LineSegment::between(Point2::new(-2.0, -2.0), Point2::new(4.0, -2.0)),
///     LineSegment::between(Point2::new(4.0, -2.0), Point2::new(4.0, 3.0)),
///     LineSegment::between(Point2::new(4.0, 3.0), Point2::new(-2.0, 3.0)),
/// ];
/// // The sensor is at the origin; the source says it turned by 20°.
/// let seen: Vec<_> = room.to_vec();
/// let predicted = Pose2::new(0.1, 0.0, 20f64.to_radians());
/// // The source claims 1 cm and 0.6° (one standard deviation).
/// let cov = Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 1e-4));
/// let r = recover(&predicted, &cov, &seen, &room, &Recovery::standard()).unwrap();
/// assert!(r.world_from_sensor.heading().abs() < 1e-6);
/// assert!(r.world_from_sensor.x().abs() < 1e-6);
/// // A right prediction is kept.
/// assert!(recover(&Pose2::identity(), &cov, &seen, &room, &Recovery::standard()).is_none());
/// ```
pub fn recover(
    predicted: &Pose2,
    predicted_cov: &Matrix3<f64>,
    lines: &[LineSegment],
    map: &[LineSegment],
    config: &Recovery,
) -> Option<Recovered> {
    let predicted_from_world = predicted.inverse();
    let local: Vec<LineSegment> =
        map.iter().map(|l| l.transformed(&predicted_from_world)).collect();
    let prior = AlignmentPrior {
        candidate_from_current: Pose2::identity(),
        radius_m: config.radius_m,
        max_rotation_rad: config.max_rotation_rad,
    };
    let a = align_lines(lines, &local, Some(&prior), &config.alignment)?;
    let laid = laid_length(lines, &local, &Pose2::identity(), &config.alignment);
    let t = a.candidate_from_current;
    let within =
        t.x().hypot(t.y()) <= config.radius_m && t.heading().abs() <= config.max_rotation_rad;
    let better = within
        && a.matched_length_m >= laid + config.min_gain_m
        && a.matched_length_m >= config.min_matched_fraction * a.current_length_m
        && a.weakest_direction_m >= config.min_weakest_direction_m
        && a.rms_m <= config.max_rms_m
        && a.runner_up_length_m <= config.max_runner_up * a.matched_length_m;
    let world_from_sensor = predicted.compose(&t);
    if !(better && world_from_sensor.is_finite()) {
        return None;
    }
    // The change as the prediction sees it (the composed pose's heading is
    // wrapped, so it is taken back from it rather than from `t`).
    let change = predicted.between(&world_from_sensor);
    let in_world = Vector3::new(
        world_from_sensor.x() - predicted.x(),
        world_from_sensor.y() - predicted.y(),
        change.heading(),
    );
    let d2 =
        predicted_cov.try_inverse().map_or(f64::INFINITY, |inv| in_world.dot(&(inv * in_world)));
    if d2.is_nan() || d2 < config.min_change_chi2 {
        return None;
    }
    let shift2 = change.x().powi(2) + change.y().powi(2);
    let covariance = predicted_cov
        + Matrix3::from_diagonal(&Vector3::new(shift2, shift2, change.heading().powi(2)));
    Some(Recovered { world_from_sensor, covariance, alignment: a, laid_at_prediction_m: laid })
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::Point2;

    /// A source that claims 1 cm and 0.6° (one standard deviation).
    const TIGHT: Matrix3<f64> = Matrix3::new(1e-4, 0.0, 0.0, 0.0, 1e-4, 0.0, 0.0, 0.0, 1e-4);

    fn seg(p: (f64, f64), q: (f64, f64)) -> LineSegment {
        LineSegment::between(Point2::new(p.0, p.1), Point2::new(q.0, q.1))
    }

    fn room() -> Vec<LineSegment> {
        vec![
            seg((-2.0, -2.0), (4.0, -2.0)),
            seg((4.0, -2.0), (4.0, 3.0)),
            seg((4.0, 3.0), (-2.0, 3.0)),
        ]
    }

    fn seen_from(world_from_sensor: &Pose2) -> Vec<LineSegment> {
        room().iter().map(|l| l.transformed(&world_from_sensor.inverse())).collect()
    }

    #[test]
    fn a_source_off_by_a_fast_turn_is_recovered() {
        let truth = Pose2::new(0.5, 0.3, 0.4);
        let predicted = Pose2::new(0.8, 0.1, 0.4 - 25f64.to_radians());
        let r = recover(&predicted, &TIGHT, &seen_from(&truth), &room(), &Recovery::standard())
            .unwrap();
        let e = truth.between(&r.world_from_sensor);
        assert!(e.x().hypot(e.y()) < 1e-6 && e.heading().abs() < 1e-6, "{e:?}");
        assert!(r.alignment.matched_length_m > r.laid_at_prediction_m + 1.0);
    }

    #[test]
    fn beyond_the_bound_or_in_a_corridor_nothing_is_recovered() {
        let truth = Pose2::new(0.5, 0.3, 0.4);
        let far = Pose2::new(0.5, 0.3, 0.4 - 45f64.to_radians());
        assert!(
            recover(&far, &TIGHT, &seen_from(&truth), &room(), &Recovery::standard()).is_none()
        );
        let corridor = vec![seg((-10.0, -1.0), (10.0, -1.0)), seg((-10.0, 1.0), (10.0, 1.0))];
        let seen: Vec<_> =
            corridor.iter().map(|l| l.transformed(&Pose2::new(2.0, 0.0, 0.0).inverse())).collect();
        let predicted = Pose2::new(0.0, 0.0, 0.1);
        assert!(recover(&predicted, &TIGHT, &seen, &corridor, &Recovery::standard()).is_none());
    }

    #[test]
    fn degenerate_input_gives_none() {
        let nan = seg((f64::NAN, 0.0), (1.0, 0.0));
        assert!(
            recover(&Pose2::identity(), &TIGHT, &[nan, nan], &room(), &Recovery::standard())
                .is_none()
        );
        assert!(recover(&Pose2::identity(), &TIGHT, &room(), &[], &Recovery::standard()).is_none());
    }

    #[test]
    fn validation_names_the_field() {
        let mut r = Recovery::standard();
        r.max_runner_up = 2.0;
        let e = r.validate("aiding.estimator.recovery").unwrap_err().to_string();
        assert!(e.contains("aiding.estimator.recovery.max_runner_up"), "{e}");
    }
}
