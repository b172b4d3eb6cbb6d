//! Localization and mapping against the truth (design, section 5): a
//! simulated run's scans, each detected once, fed to several aiding loops
//! side by side (no aiding, the paper's heading aiding, full-pose aiding),
//! each scored by its trajectory errors and its map's quality.

use crate::{MapQuality, TrajectoryErrors, VisibleWalls, map_quality, trajectory_errors};
use pcaline_aiding::{AidingConfig, Localizer, LoopClosing, LoopClosureConfig, SensorLine};
use pcaline_geometry::{ConfigError, Pose2, Twist2};
use pcaline_mapping::MapConfig;
use pcaline_sim::{SimFrame, Simulator};

/// Tolerances of a map line against its wall: rms endpoint distance, metres.
pub const MAP_TOLERANCE_M: f64 = 0.05;
/// Tolerances of a map line against its wall: direction, degrees.
pub const MAP_MAX_ANGLE_DEG: f64 = 2.0;

/// Several aiding loops run over one simulated run, each a [`Localizer`]
/// fed the same detected lines.
#[derive(Debug)]
pub struct AidedRun {
    /// The loops, in the order of the configurations given; the one with
    /// loop closure, if asked for ([`AidedRun::run_with_loop_closure`]),
    /// last.
    pub loops: Vec<Localizer>,
    /// Each loop's pose after every scan, in the order of
    /// [`AidedRun::loops`]; with loop closure, the graph's trajectory after
    /// a last optimization ([`Localizer::finish`]).
    pub estimates: Vec<Vec<Pose2>>,
    /// The wall length the sensor saw (5 cm bins).
    pub visible: VisibleWalls,
}

/// What [`AidedRun::run_observed`] shows after each frame.
#[derive(Debug, Clone, Copy)]
#[non_exhaustive]
pub struct RunStep<'a> {
    /// The simulated frame.
    pub frame: &'a SimFrame,
    /// Its lines, in the sensor frame.
    pub lines: &'a [SensorLine],
    /// The loops, in the order of [`AidedRun::loops`]: their poses and
    /// maps as they are after the frame (with loop closure, the online ones,
    /// before the run's last optimization).
    pub loops: &'a [Localizer],
}

impl RunStep<'_> {
    /// The loop with loop closure, when there is one.
    pub fn loop_closing(&self) -> Option<&LoopClosing> {
        loop_closing_of(self.loops)
    }
}

/// The first of `loops` that closes loops.
fn loop_closing_of(loops: &[Localizer]) -> Option<&LoopClosing> {
    loops.iter().find_map(Localizer::loop_closing)
}

/// Why [`AidedRun::run_observed`] failed.
#[derive(Debug)]
#[non_exhaustive]
pub enum ObservedRunError<E> {
    /// A configuration is invalid.
    Config(ConfigError),
    /// The observer returned an error.
    Stopped(E),
}

impl<E> From<ConfigError> for ObservedRunError<E> {
    fn from(e: ConfigError) -> Self {
        ObservedRunError::Config(e)
    }
}

/// One loop's score.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct AidedScore {
    /// Trajectory errors against the true poses.
    pub errors: TrajectoryErrors,
    /// The map against the true walls ([`MAP_TOLERANCE_M`], [`MAP_MAX_ANGLE_DEG`]).
    pub map: MapQuality,
}

impl AidedRun {
    /// Runs every frame of `sim` through `lines_of` (a detector: the frame's
    /// lines in the sensor frame, given the source's velocity over the last
    /// step for motion deskew) and feeds the lines, with the frame's
    /// odometry pose as the source, to one loop per configuration in `modes`,
    /// each with its own map built with `map`.
    pub fn run(
        sim: &Simulator,
        map: MapConfig,
        modes: &[AidingConfig],
        lines_of: impl FnMut(&SimFrame, Option<Twist2>) -> Vec<SensorLine>,
    ) -> Result<Self, ConfigError> {
        Self::run_with_loop_closure(sim, map, modes, None, lines_of)
    }

    /// As [`AidedRun::run`], with one more loop when `loop_closure` is given:
    /// that aiding with loop closure on top ([`LoopClosing`]). Its estimate,
    /// the trajectory of the graph after a last optimization, comes after
    /// the others in [`AidedRun::estimates`], and its score after theirs.
    pub fn run_with_loop_closure(
        sim: &Simulator,
        map: MapConfig,
        modes: &[AidingConfig],
        loop_closure: Option<(AidingConfig, LoopClosureConfig)>,
        lines_of: impl FnMut(&SimFrame, Option<Twist2>) -> Vec<SensorLine>,
    ) -> Result<Self, ConfigError> {
        let observe = |_: RunStep<'_>| Ok::<(), std::convert::Infallible>(());
        Self::run_observed(sim, map, modes, loop_closure, lines_of, observe).map_err(|e| match e {
            ObservedRunError::Config(c) => c,
            ObservedRunError::Stopped(never) => match never {},
        })
    }

    /// As [`AidedRun::run_with_loop_closure`], with `observe` called after
    /// every frame with what the loops made of it ([`RunStep`]): to stream a
    /// run as it goes. An error from `observe` stops the run and is returned
    /// ([`ObservedRunError::Stopped`]).
    pub fn run_observed<E>(
        sim: &Simulator,
        map: MapConfig,
        modes: &[AidingConfig],
        loop_closure: Option<(AidingConfig, LoopClosureConfig)>,
        mut lines_of: impl FnMut(&SimFrame, Option<Twist2>) -> Vec<SensorLine>,
        mut observe: impl FnMut(RunStep<'_>) -> Result<(), E>,
    ) -> Result<Self, ObservedRunError<E>> {
        let mut loops = modes
            .iter()
            .map(|a| (*a, None))
            .chain(loop_closure.map(|(a, l)| (a, Some(l))))
            .map(|(a, l)| Localizer::new(a, map, l))
            .collect::<Result<Vec<_>, _>>()?;
        let mut estimates: Vec<Vec<Pose2>> = loops.iter().map(|_| Vec::new()).collect();
        let mut visible = VisibleWalls::new(sim.world().walls(), 0.05);
        let mut last: Option<(f64, Pose2)> = None;
        for frame in sim.frames() {
            let velocity =
                last.and_then(|(t, p)| p.velocity_to(&frame.odometry_pose, frame.time_s - t));
            last = Some((frame.time_s, frame.odometry_pose));
            let lines = lines_of(&frame, velocity);
            for (localizer, out) in loops.iter_mut().zip(estimates.iter_mut()) {
                out.push(localizer.step_scan(&frame.scan, &frame.odometry_pose, &lines).0);
            }
            observe(RunStep { frame: &frame, lines: &lines, loops: &loops })
                .map_err(ObservedRunError::Stopped)?;
            visible.observe(&frame);
        }
        for (localizer, out) in loops.iter_mut().zip(estimates.iter_mut()) {
            if let Some(optimized) = localizer.finish() {
                *out = optimized.into_iter().map(Option::unwrap_or_default).collect();
            }
        }
        Ok(AidedRun { loops, estimates, visible })
    }

    /// The loop with loop closure, when there is one.
    pub fn loop_closing(&self) -> Option<&LoopClosing> {
        loop_closing_of(&self.loops)
    }

    /// Each loop's errors against `truth` (the run's true poses) and its map's
    /// quality; `None` when the run had no scan.
    pub fn scores(&self, truth: &[Pose2]) -> Option<Vec<AidedScore>> {
        self.loops
            .iter()
            .map(Localizer::map)
            .zip(&self.estimates)
            .map(|(map, est)| {
                Some(AidedScore {
                    errors: trajectory_errors(est, truth)?,
                    map: map_quality(
                        map.lines(),
                        &self.visible,
                        MAP_TOLERANCE_M,
                        MAP_MAX_ANGLE_DEG.to_radians(),
                    ),
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_fitting::Moments;
    use pcaline_fitting::fit_pca;
    use pcaline_geometry::polar_to_cartesian;
    use pcaline_sim::{MazeConfig, generate_maze};

    /// A detector that knows the truth: one line per wall run, fitted to the
    /// run's noise-free returns. With perfect lines, full-pose aiding must
    /// remove the odometry drift and map only true walls.
    #[test]
    fn perfect_lines_let_full_pose_aiding_remove_the_drift() {
        let mut scene =
            generate_maze(&MazeConfig::small("eval-test").with_max_waypoints(6), 3).unwrap();
        scene.sensor.range_sigma_m = Some(0.0);
        scene.sensor.motion_skew = false;
        scene.odometry.heading_rate_bias_deg_s = 0.3;
        scene.odometry.speed_scale_error = 0.0;
        let sim = Simulator::new(&scene, 1).unwrap();
        let run = AidedRun::run(
            &sim,
            MapConfig::default(),
            &[AidingConfig::none(), AidingConfig::full_pose()],
            |frame, _| {
                frame
                    .wall_runs(10)
                    .iter()
                    .filter_map(|r| {
                        let points: Vec<_> = (r.first_beam..=r.last_beam)
                            .map(|i| {
                                polar_to_cartesian(frame.beams[i].range_m, frame.scan.angle(i))
                            })
                            .collect();
                        let line = fit_pca(&points)?;
                        Some(SensorLine { line, moments: Moments::from_points(&points) })
                    })
                    .collect()
            },
        )
        .unwrap();
        let scores = run.scores(sim.true_poses()).unwrap();
        let (unaided, full) = (&scores[0].errors, &scores[1].errors);
        assert!(unaided.heading_rms_rad > 2f64.to_radians(), "{unaided:?}");
        assert!(full.heading_rms_rad < 0.01f64.to_radians(), "{full:?}");
        assert!(full.position_rms_m < 0.002, "{full:?}");
        assert_eq!(scores[1].map.spurious, 0, "{:?}", scores[1].map);
        assert!(scores[1].map.covered_fraction > 0.95, "{:?}", scores[1].map);
    }
}
