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
                let world = self.world_lines(&pose, lines);
                let matches: Vec<_> = world
                    .iter()
                    .filter_map(|(l, _)| self.map.find_match(l).map(|m| (l, m)))
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
                let world = self.world_lines(&pose, lines);
                let constraints: Vec<NormalConstraint> = world
                    .iter()
                    .filter_map(|(l, _)| {
                        let m = self.map.find_match(l)?;
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
        for (l, m) in self.world_lines(&pose, lines) {
            self.map.insert(&l, &m);
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
