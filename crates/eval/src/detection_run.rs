//! The detection evaluation over scenes, seeds and a noise level.

use crate::{DetectionCriteria, DetectionScore, true_walls};
use pcaline_fitting::{Moments, fit_pca};
use pcaline_geometry::{LineSegment, Point2, point_segment_distance, polar_to_cartesian};
use pcaline_sim::{Scene, SceneError, SimFrame, Simulator, World};
use std::time::Instant;

/// A detector under evaluation: a simulated frame in (a real detector looks
/// at `frame.scan` only; [`oracle_lines`] uses the ground truth), its lines
/// (sensor frame) out.
pub type DetectFn<'a> = dyn FnMut(&SimFrame, &World) -> Vec<LineSegment> + 'a;

/// The lines a perfect segmentation would give: one PCA fit to the noisy
/// returns of each true wall run of at least `criteria.min_beams` beams and
/// `criteria.min_extent_m`, reported when its orientation standard
/// deviation predicted from `sigma_m` is at most `max_alpha_std_rad`. It
/// bounds what any detector fitting each wall on its own points can score.
pub fn oracle_lines(
    frame: &SimFrame,
    world: &World,
    criteria: &DetectionCriteria,
    sigma_m: f64,
    max_alpha_std_rad: f64,
) -> Vec<LineSegment> {
    frame
        .surface_runs(criteria.min_beams, world.surfaces())
        .iter()
        .filter_map(|run| {
            let points: Vec<Point2<f64>> = (run.first_beam..=run.last_beam)
                .filter(|&i| frame.scan.is_valid_range(frame.scan.ranges[i]))
                .map(|i| polar_to_cartesian(f64::from(frame.scan.ranges[i]), frame.scan.angle(i)))
                .collect();
            let moments = Moments::from_points(&points);
            let line = fit_pca(&points)?;
            let std = sigma_m / (moments.n as f64 * moments.eigen().lambda_max).sqrt();
            (line.length() >= criteria.min_extent_m && std <= max_alpha_std_rad).then_some(line)
        })
        .collect()
}

/// Which beam faults the evaluation's sensor has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum FaultMode {
    /// None: no outliers, dropouts or mixed pixels, whatever the scene says
    /// (the protocol's default).
    #[default]
    Off,
    /// Each scene's own fault probabilities; a scene that sets none gets
    /// [`FaultMode::TYPICAL`].
    On,
}

impl FaultMode {
    /// The faults of [`FaultMode::On`] for a scene without its own: 0.5%
    /// outliers, 1% dropouts, and a mixed pixel at 30% of depth edges.
    pub const TYPICAL: [f64; 3] = [0.005, 0.01, 0.3];

    /// Applies the mode to `scene`'s sensor.
    pub fn apply(self, scene: &mut Scene) {
        let s = &mut scene.sensor;
        let own = [s.outlier_probability, s.dropout_probability, s.mixed_pixel_probability];
        let [outlier, dropout, mixed] = match self {
            FaultMode::Off => [0.0; 3],
            FaultMode::On if own.iter().any(|&p| p > 0.0) => own,
            FaultMode::On => Self::TYPICAL,
        };
        (s.outlier_probability, s.dropout_probability, s.mixed_pixel_probability) =
            (outlier, dropout, mixed);
    }
}

/// What to evaluate on.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct DetectionEval {
    /// Range noise sigma of the simulated sensor, metres.
    pub sigma_m: f64,
    /// Range resolution of the simulated sensor, metres (0: none).
    pub range_resolution_m: f64,
    /// Beam faults.
    pub faults: FaultMode,
    /// Keep each scene's motion skew and tilt (otherwise every beam of a
    /// scan is taken at one level pose).
    pub keep_motion: bool,
    /// Seeds per scene.
    pub seeds: u64,
    /// Scans per scene and seed, evenly spread along the trajectory.
    pub scans: usize,
    /// The matching rule.
    pub criteria: DetectionCriteria,
}

impl DetectionEval {
    /// `scans` scans per scene and seed, seeds 1 to `seeds`, range noise
    /// `sigma_m`; no range grid, no faults, level scans without motion skew,
    /// and the default matching rule ([`DetectionCriteria::default`]).
    pub fn new(sigma_m: f64, seeds: u64, scans: usize) -> Self {
        DetectionEval {
            sigma_m,
            range_resolution_m: 0.0,
            faults: FaultMode::Off,
            keep_motion: false,
            seeds,
            scans,
            criteria: DetectionCriteria::default(),
        }
    }
}

/// The score of one detector and its time per scan.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct DetectorResult {
    /// The score.
    pub score: DetectionScore,
    /// Of every detected line, the rms distance of 16 evenly spaced points of
    /// it from the nearest wall of the world, metres ([`surface_rms_m`]).
    pub surface_rms_m: Vec<f64>,
    /// Mean detection time per scan, microseconds (of this run, not a benchmark).
    pub time_per_scan_us: f64,
}

/// Runs every detector on the same simulated scans of every scene: for each
/// scene and seed, `scans` scans with range noise `sigma_m`, range
/// resolution `range_resolution_m`, the faults of `faults`, and motion skew
/// and tilt only with `keep_motion`.
/// `detectors` map a scan to its lines (sensor frame).
pub fn evaluate_detectors(
    scenes: &[Scene],
    eval: &DetectionEval,
    detectors: &mut [&mut DetectFn<'_>],
) -> Result<Vec<DetectorResult>, SceneError> {
    let mut results: Vec<DetectorResult> = detectors
        .iter()
        .map(|_| DetectorResult {
            score: DetectionScore::default(),
            surface_rms_m: Vec::new(),
            time_per_scan_us: 0.0,
        })
        .collect();
    let mut scans = 0usize;
    for scene in scenes {
        let mut scene = scene.clone();
        scene.sensor.range_sigma_m = Some(eval.sigma_m);
        scene.sensor.range_resolution_m = Some(eval.range_resolution_m);
        eval.faults.apply(&mut scene);
        if !eval.keep_motion {
            scene.sensor.motion_skew = false;
            scene.sensor.tilt = None;
        }
        for seed in 1..=eval.seeds {
            let sim = Simulator::new(&scene, seed)?;
            let step = (sim.len() / eval.scans.max(1)).max(1);
            for k in (0..sim.len()).step_by(step).take(eval.scans) {
                let Some(frame) = sim.frame(k) else { continue };
                let truth = true_walls(&frame, sim.world(), &eval.criteria);
                scans += 1;
                for (detect, result) in detectors.iter_mut().zip(results.iter_mut()) {
                    let t0 = Instant::now();
                    let lines = detect(&frame, sim.world());
                    result.time_per_scan_us += t0.elapsed().as_secs_f64() * 1e6;
                    result.score.add_scan(&truth, &lines, &eval.criteria);
                    result.surface_rms_m.extend(
                        lines
                            .iter()
                            .map(|l| surface_rms_m(&l.transformed(&frame.true_pose), sim.world())),
                    );
                }
            }
        }
    }
    for r in &mut results {
        r.time_per_scan_us /= scans.max(1) as f64;
    }
    Ok(results)
}

/// How far `line` (world frame) lies from the surfaces of `world`: the rms
/// over 16 evenly spaced points from its start to its end of the distance
/// to the nearest wall. 0 for a line on a wall; a chord of a curved wall
/// drawn as short segments lies off it by about a third of its sagitta.
pub fn surface_rms_m(line: &LineSegment, world: &World) -> f64 {
    const SAMPLES: usize = 16;
    let mut sum = 0.0;
    for k in 0..SAMPLES {
        let t = k as f64 / (SAMPLES - 1) as f64;
        let p = line.start() + (line.end() - line.start()) * t;
        let nearest = world
            .walls()
            .iter()
            .map(|w| point_segment_distance(&p, &w.a, &w.b))
            .fold(f64::INFINITY, f64::min);
        sum += nearest * nearest;
    }
    (sum / SAMPLES as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_sim::{MazeConfig, generate_maze};

    #[test]
    fn fault_modes_are_explicit() {
        let mut scene = generate_maze(&MazeConfig::small("t"), 1).unwrap();
        FaultMode::On.apply(&mut scene);
        let s = &scene.sensor;
        let typical = [s.outlier_probability, s.dropout_probability, s.mixed_pixel_probability];
        assert_eq!(typical, FaultMode::TYPICAL);
        scene.sensor.dropout_probability = 0.2;
        FaultMode::On.apply(&mut scene);
        assert_eq!(scene.sensor.dropout_probability, 0.2, "a scene's own faults are kept");
        FaultMode::Off.apply(&mut scene);
        let s = &scene.sensor;
        assert_eq!(
            [s.outlier_probability, s.dropout_probability, s.mixed_pixel_probability],
            [0.0; 3]
        );
    }

    /// Without noise a perfect segmentation finds every true wall and nothing
    /// else; a detector that finds nothing scores recall 0.
    #[test]
    fn the_noise_free_oracle_scores_perfectly() {
        let scene = generate_maze(&MazeConfig::small("t").with_max_waypoints(4), 2).unwrap();
        let eval = DetectionEval::new(0.0, 1, 10);
        let criteria = eval.criteria;
        let mut oracle =
            |f: &SimFrame, w: &World| oracle_lines(f, w, &criteria, 0.0, f64::INFINITY);
        let mut nothing = |_: &SimFrame, _: &World| Vec::new();
        let r = evaluate_detectors(&[scene], &eval, &mut [&mut oracle, &mut nothing]).unwrap();
        let (o, n) = (&r[0].score, &r[1].score);
        assert!(o.true_walls > 20, "{o:?}");
        assert_eq!((o.recall(), o.false_positive_fraction(), o.fragmentation()), (1.0, 0.0, 1.0));
        assert_eq!(n.recall(), 0.0);
    }
}
