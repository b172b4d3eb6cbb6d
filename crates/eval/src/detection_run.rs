//! The detection evaluation over scenes, seeds and a noise level.

use crate::{DetectionCriteria, DetectionScore, true_walls};
use pcaline_fitting::{Moments, fit_pca};
use pcaline_geometry::{LineSegment, Point2, polar_to_cartesian};
use pcaline_sim::{Scene, SceneError, SimFrame, Simulator};
use std::time::Instant;

/// A detector under evaluation: a simulated frame in (a real detector looks
/// at `frame.scan` only; [`oracle_lines`] uses the ground truth), its lines
/// (sensor frame) out.
pub type DetectFn<'a> = dyn FnMut(&SimFrame) -> Vec<LineSegment> + 'a;

/// The lines a perfect segmentation would give: one PCA fit to the noisy
/// returns of each true wall run of at least `criteria.min_beams` beams and
/// `criteria.min_extent_m`, reported when its orientation standard
/// deviation predicted from `sigma_m` is at most `max_alpha_std_rad`. It
/// bounds what any detector fitting each wall on its own points can score.
pub fn oracle_lines(
    frame: &SimFrame,
    criteria: &DetectionCriteria,
    sigma_m: f64,
    max_alpha_std_rad: f64,
) -> Vec<LineSegment> {
    frame
        .wall_runs(criteria.min_beams)
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

/// What to evaluate on.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectionEval {
    /// Range noise sigma of the simulated sensor, metres.
    pub sigma_m: f64,
    /// Seeds per scene.
    pub seeds: u64,
    /// Scans per scene and seed, evenly spread along the trajectory.
    pub scans: usize,
    /// The matching rule.
    pub criteria: DetectionCriteria,
}

/// The score of one detector and its time per scan.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectorResult {
    /// The score.
    pub score: DetectionScore,
    /// Mean detection time per scan, microseconds (of this run, not a benchmark).
    pub time_per_scan_us: f64,
}

/// Runs every detector on the same simulated scans of every scene: for each
/// scene and seed, `scans` scans with range noise `sigma_m` and no faults.
/// `detectors` map a scan to its lines (sensor frame).
pub fn evaluate_detectors(
    scenes: &[Scene],
    eval: &DetectionEval,
    detectors: &mut [&mut DetectFn<'_>],
) -> Result<Vec<DetectorResult>, SceneError> {
    let mut results: Vec<DetectorResult> = detectors
        .iter()
        .map(|_| DetectorResult { score: DetectionScore::default(), time_per_scan_us: 0.0 })
        .collect();
    let mut scans = 0usize;
    for scene in scenes {
        let mut scene = scene.clone();
        scene.sensor.range_sigma_m = Some(eval.sigma_m);
        scene.sensor.motion_skew = false;
        scene.sensor.tilt = None;
        for seed in 1..=eval.seeds {
            let sim = Simulator::new(&scene, seed)?;
            let step = (sim.len() / eval.scans.max(1)).max(1);
            for k in (0..sim.len()).step_by(step).take(eval.scans) {
                let Some(frame) = sim.frame(k) else { continue };
                let truth = true_walls(&frame, sim.world(), &eval.criteria);
                scans += 1;
                for (detect, result) in detectors.iter_mut().zip(results.iter_mut()) {
                    let t0 = Instant::now();
                    let lines = detect(&frame);
                    result.time_per_scan_us += t0.elapsed().as_secs_f64() * 1e6;
                    result.score.add_scan(&truth, &lines, &eval.criteria);
                }
            }
        }
    }
    for r in &mut results {
        r.time_per_scan_us /= scans.max(1) as f64;
    }
    Ok(results)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_sim::{MazeConfig, generate_maze};

    /// Without noise a perfect segmentation finds every true wall and nothing
    /// else; a detector that finds nothing scores recall 0.
    #[test]
    fn the_noise_free_oracle_scores_perfectly() {
        let scene =
            generate_maze(&MazeConfig { max_waypoints: Some(4), ..MazeConfig::small("t") }, 2)
                .unwrap();
        let eval = DetectionEval {
            sigma_m: 0.0,
            seeds: 1,
            scans: 10,
            criteria: DetectionCriteria::default(),
        };
        let criteria = eval.criteria;
        let mut oracle = |f: &SimFrame| oracle_lines(f, &criteria, 0.0, f64::INFINITY);
        let mut nothing = |_: &SimFrame| Vec::new();
        let r = evaluate_detectors(&[scene], &eval, &mut [&mut oracle, &mut nothing]).unwrap();
        let (o, n) = (&r[0].score, &r[1].score);
        assert!(o.true_walls > 20, "{o:?}");
        assert_eq!((o.recall(), o.false_positive_fraction(), o.fragmentation()), (1.0, 0.0, 1.0));
        assert_eq!(n.recall(), 0.0);
    }
}
