//! The detection evaluation over scenes, seeds and a noise level.

use crate::{DetectionCriteria, DetectionScore, true_walls};
use pcaline_geometry::{LineSegment, Scan};
use pcaline_sim::{Scene, SceneError, Simulator};
use std::time::Instant;

/// A detector under evaluation: a scan in, its lines (sensor frame) out.
pub type DetectFn<'a> = dyn FnMut(&Scan) -> Vec<LineSegment> + 'a;

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
                    let lines = detect(&frame.scan);
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
