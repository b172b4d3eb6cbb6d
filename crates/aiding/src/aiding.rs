//! [`Aiding`]: the mapping and localization-aiding loop of the paper's
//! section 2.1, one scan's lines at a time.

use crate::{AidingConfig, AidingMode, Fallback, HeadingWeights, NormalConstraint, StepReport};
use crate::{heading_correction, rotate_step, solve_translation, weighted_offset};
use pcaline_fitting::Moments;
use pcaline_geometry::{ConfigError, LineSegment, Point2, Pose2, Vector2};
use pcaline_mapping::{LineMap, MapConfig};

/// A detected line in the sensor frame with the moments of its points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorLine {
    /// The line, sensor frame.
    pub line: LineSegment,
    /// Moments of its points, sensor frame.
    pub moments: Moments,
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
    last_source: Option<Pose2>,
}

impl Aiding {
    /// A loop with an empty map.
    pub fn new(config: AidingConfig, map: MapConfig) -> Result<Self, ConfigError> {
        config.validate()?;
        Ok(Aiding { config, map: LineMap::new(map)?, corrected: None, last_source: None })
    }

    /// A loop that continues from an existing map (for example one loaded
    /// from a file); the first pose is taken from the source as it is.
    pub fn with_map(config: AidingConfig, map: LineMap) -> Result<Self, ConfigError> {
        config.validate()?;
        Ok(Aiding { config, map, corrected: None, last_source: None })
    }

    /// The map built so far.
    pub fn map(&self) -> &LineMap {
        &self.map
    }

    /// The latest corrected pose, if any scan was processed.
    pub fn pose(&self) -> Option<Pose2> {
        self.corrected
    }

    /// Processes one scan given the source's absolute pose estimate
    /// (`world_from_sensor` as the localization source sees it). The source's
    /// motion since its previous pose is composed onto the corrected pose;
    /// the first pose is taken as it is.
    pub fn step(&mut self, source_pose: &Pose2, lines: &[SensorLine]) -> (Pose2, StepReport) {
        if !source_pose.is_finite() {
            return self.fall_back(Fallback::NonFiniteSource);
        }
        let increment = self.last_source.map(|s| s.between(source_pose));
        self.last_source = Some(*source_pose);
        match (self.corrected, increment) {
            (Some(_), Some(inc)) => self.step_increment(&inc, lines),
            _ => self.process(*source_pose, lines),
        }
    }

    /// Processes one scan given the source's motion since the previous scan
    /// (an odometry or inertial increment, in the previous body frame).
    pub fn step_increment(
        &mut self,
        increment: &Pose2,
        lines: &[SensorLine],
    ) -> (Pose2, StepReport) {
        if !increment.is_finite() {
            return self.fall_back(Fallback::NonFiniteSource);
        }
        let previous = self.corrected.unwrap_or_default();
        let predicted = previous.compose(increment);
        if !predicted.is_finite() {
            return self.fall_back(Fallback::NonFiniteSource);
        }
        self.process(predicted, lines)
    }

    /// Keeps the last corrected pose (or the identity) and reports why.
    fn fall_back(&mut self, why: Fallback) -> (Pose2, StepReport) {
        let pose = self.corrected.unwrap_or_default();
        (pose, StepReport { fallback: Some(why), ..StepReport::default() })
    }

    fn world_lines(&self, pose: &Pose2, lines: &[SensorLine]) -> Vec<(LineSegment, Moments)> {
        lines.iter().map(|l| (l.line.transformed(pose), l.moments.transformed(pose))).collect()
    }

    fn process(&mut self, predicted: Pose2, lines: &[SensorLine]) -> (Pose2, StepReport) {
        let mut report = StepReport::default();
        let mut pose = predicted;
        let previous = self.corrected;
        if self.config.mode != AidingMode::None && !self.map.is_empty() {
            let rounds = match self.config.mode {
                AidingMode::FullPose => self.config.iterations.max(1),
                _ => 1,
            };
            for round in 0..rounds {
                let viewpoint = Point2::new(pose.x, pose.y);
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
                            let var = l.covariance[(0, 0)]
                                + map_line.covariance[(0, 0)]
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
                        &Point2::new(prev.x, prev.y),
                        &Point2::new(pose.x, pose.y),
                        dgamma,
                    ),
                    // Later rounds rotate about the sensor (the step is already placed).
                    _ => Point2::new(pose.x, pose.y),
                };
                pose = Pose2::new(position.x, position.y, pose.heading + dgamma);
                report.heading_correction_rad += dgamma;
                if self.config.mode != AidingMode::FullPose {
                    continue;
                }
                // Translation from the matched lines' normal offsets.
                let viewpoint = Point2::new(pose.x, pose.y);
                let world = self.world_lines(&pose, lines);
                let constraints: Vec<NormalConstraint> = world
                    .iter()
                    .filter_map(|(l, _)| {
                        let m = self.map.find_match_seen_from(l, Some(&viewpoint))?;
                        let map_line = &self.map.lines()[m.index].line;
                        let n = map_line.normal();
                        let var = l.residual_std.powi(2) / l.n_points.max(1) as f64
                            + self.config.offset_floor_m.powi(2);
                        Some(NormalConstraint {
                            normal: n,
                            offset_m: map_line.d - n.dot(&l.centroid.coords),
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
                pose = Pose2::new(pose.x + t.x, pose.y + t.y, pose.heading);
                report.translation_correction_m += t;
                report.constrained_directions = fix.constrained_directions;
            }
        }
        if !pose.is_finite() {
            pose = predicted;
            report.fallback = Some(Fallback::NonFiniteCorrection);
        }
        let viewpoint = Point2::new(pose.x, pose.y);
        for (l, m) in self.world_lines(&pose, lines) {
            self.map.insert_seen_from(&l, &m, Some(&viewpoint));
        }
        self.corrected = Some(pose);
        (pose, report)
    }
}

impl Default for StepReport {
    fn default() -> Self {
        StepReport {
            matches: 0,
            heading_correction_rad: 0.0,
            translation_correction_m: Vector2::zeros(),
            constrained_directions: 0,
            fallback: None,
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

    #[test]
    fn no_matches_keeps_the_prediction_and_says_so() {
        let mut a = aiding(AidingConfig::full_pose());
        a.step(&Pose2::identity(), &room());
        let far = vec![wall((40.0, -2.0), (40.0, 2.0))];
        let (pose, report) = a.step(&Pose2::new(0.1, 0.0, 0.0), &far);
        assert_eq!(report.fallback, Some(Fallback::NoMatches));
        assert_eq!(pose, Pose2::new(0.1, 0.0, 0.0));
        let (pose, report) = a.step(&Pose2::new(0.2, 0.0, 0.0), &[]);
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
            assert!(pose.y.abs() < 1e-6, "across the walls the lines pull back: {pose:?}");
            assert!((pose.x - 0.1).abs() < 1e-6, "along the walls nothing is known: {pose:?}");
        }
    }

    #[test]
    fn a_room_constrains_both_directions() {
        let mut a = aiding(AidingConfig::full_pose());
        a.step(&Pose2::identity(), &room());
        let (pose, report) = a.step(&Pose2::new(0.08, -0.05, 0.02), &room());
        assert_eq!(report.constrained_directions, 2);
        assert!(
            pose.x.abs() < 1e-3 && pose.y.abs() < 1e-3 && pose.heading.abs() < 1e-6,
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
}
