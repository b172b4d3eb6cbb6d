//! Map update and aiding per scan (the paper's heading aiding, full-pose
//! aiding and the estimator), against maps of 100, 10,000 and 100,000
//! lines. The maze's own lines are in the map; the rest are filler lines at
//! the maze's density over a growing area, so the bench shows whether the
//! spatial index keeps the cost independent of the map's size. Two groups:
//! one step on a fresh (cold) copy of the map, and 50 consecutive scans
//! stepped on one copy (warm, as in a log), per scan.

use criterion::{BatchSize, BenchmarkId, Criterion, criterion_group, criterion_main};
use pcaline::aiding::{Aiding, AidingConfig, SensorLine};
use pcaline::fitting::{Moments, line_from_moments};
use pcaline::mapping::{LineMap, MapConfig};
use pcaline::{Config, LineDetector, Point2, Pose2};
use pcaline_sim::Simulator;
use std::hint::black_box;

fn maze_lines() -> (Vec<(Pose2, Vec<SensorLine>)>, LineMap) {
    let text = include_str!("../sim-scenes/paper-maze.toml");
    let scene = pcaline_io::parse_scene(std::path::Path::new("paper-maze.toml"), text).unwrap();
    let sim = Simulator::new(&scene, 1).unwrap();
    let mut detector = LineDetector::new(Config::default()).unwrap();
    let mut map = LineMap::new(MapConfig::default()).unwrap();
    let mut scans = Vec::new();
    for frame in sim.frames().take(200) {
        let lines: Vec<SensorLine> =
            detector.detect(&frame.scan).lines.iter().map(SensorLine::from).collect();
        for l in &lines {
            map.insert(
                &l.line.transformed(&frame.true_pose),
                &l.moments.transformed(&frame.true_pose),
            );
        }
        scans.push((frame.true_pose, lines));
    }
    (scans, map)
}

/// `map` plus filler lines up to `total`, 1 m long, one per 4 m² (about the
/// maze's density), east of the maze.
fn with_filler(map: &LineMap, total: usize) -> LineMap {
    let mut map = map.clone();
    let side = ((total as f64) * 4.0).sqrt();
    let mut k = 0u64;
    while map.len() < total {
        // A deterministic low-discrepancy placement.
        k += 1;
        let u = (k as f64 * 0.618_033_988_75).fract();
        let v = (k as f64 * 0.754_877_666_25).fract();
        let (x, y) = (20.0 + u * side, v * side);
        let a = (k as f64 * 0.381_966).fract() * std::f64::consts::PI;
        let pts: Vec<_> = (0..10)
            .map(|i| Point2::new(x + a.cos() * i as f64 * 0.1, y + a.sin() * i as f64 * 0.1))
            .collect();
        let m = Moments::from_points(&pts);
        let line = line_from_moments(&m, &pts[0], &pts[9]).unwrap();
        if map.find_match(&line).is_none() {
            // Seen in three scans: confirmed, so it neither expires nor
            // is skipped by the estimator.
            for _ in 0..3 {
                map.insert(&line, &m);
            }
        }
    }
    map
}

/// The three loops benched, each on its own copy of `map` and primed with
/// one scan (`pose`, `lines`), so the measured step has a prior and a
/// covariance.
fn primed(map: &LineMap, pose: &Pose2, lines: &[SensorLine]) -> [(&'static str, Aiding); 3] {
    [
        ("heading", AidingConfig::heading()),
        ("full_pose", AidingConfig::full_pose()),
        ("estimator", AidingConfig::estimator()),
    ]
    .map(|(name, config)| {
        let mut aiding = Aiding::with_map(config, map.clone()).unwrap();
        aiding.step_at(0.0, pose, lines);
        (name, aiding)
    })
}

fn mapping(c: &mut Criterion) {
    let (scans, base) = maze_lines();
    let (before, before_lines) = scans[149].clone();
    let (pose, lines) = scans[150].clone();
    let mut group = c.benchmark_group("map_update_and_aiding_per_scan");
    for total in [100, 10_000, 100_000] {
        let map = with_filler(&base, total);
        for (name, aiding) in primed(&map, &before, &before_lines) {
            group.bench_with_input(BenchmarkId::new(name, total), &aiding, |b, aiding| {
                b.iter_batched_ref(
                    || aiding.clone(),
                    |a| black_box(a.step_at(0.025, &pose, &lines)),
                    BatchSize::LargeInput,
                )
            });
        }
    }
    group.finish();

    // The same, over a run: 50 consecutive scans stepped in order on one
    // copy of the map (the copy is not timed), the time divided by 50. The
    // lines near the vehicle stay in cache from scan to scan, as in a log.
    let run = &scans[150..200];
    let mut group = c.benchmark_group("map_update_and_aiding_per_scan_over_50_scans");
    for total in [100, 10_000, 100_000] {
        let map = with_filler(&base, total);
        for (name, aiding) in primed(&map, &before, &before_lines) {
            group.bench_with_input(BenchmarkId::new(name, total), &aiding, |b, aiding| {
                b.iter_custom(|iterations| {
                    let mut total = std::time::Duration::ZERO;
                    for _ in 0..iterations.div_ceil(run.len() as u64) {
                        let mut a = aiding.clone();
                        let start = std::time::Instant::now();
                        for (k, (pose, lines)) in run.iter().enumerate() {
                            black_box(a.step_at(0.025 * (k + 1) as f64, pose, lines));
                        }
                        total += start.elapsed();
                    }
                    // Per step: `iterations` steps' worth of time.
                    total.mul_f64(
                        iterations as f64
                            / (iterations.div_ceil(run.len() as u64) * run.len() as u64) as f64,
                    )
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, mapping);
criterion_main!(benches);
