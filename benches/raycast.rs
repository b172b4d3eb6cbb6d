//! Ray casting: one 1081-beam UTM-30LX-EW scan against generated worlds of
//! about 50, 1,000 and 10,000 wall segments; the whole simulated scan (casting,
//! noise, ground truth) and the casting alone (coherent: each beam tests the
//! previous beam's wall first, as the simulator does).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use pcaline::{Point2, Vector2};
use pcaline_sim::{MazeConfig, Simulator, WallStyle, generate_maze};
use std::hint::black_box;

fn world(cols: usize, rows: usize) -> Simulator {
    let mut config = MazeConfig::small("bench");
    (config.cols, config.rows, config.clutter) = (cols, rows, cols * rows / 4);
    config.walls = WallStyle::Double { thickness_m: 0.1 };
    let scene = generate_maze(&config, 1).expect("valid maze");
    Simulator::new(&scene, 1).expect("valid scene")
}

fn raycast(c: &mut Criterion) {
    let mut group = c.benchmark_group("simulated_scan_1081_beams");
    let worlds: Vec<_> =
        [(2, 3), (13, 12), (42, 40)].into_iter().map(|(c, r)| world(c, r)).collect();
    for sim in &worlds {
        let walls = sim.world().walls().len();
        let pose = sim.true_poses()[sim.len() / 2];
        group.bench_with_input(BenchmarkId::from_parameter(walls), sim, |b, sim| {
            b.iter(|| black_box(sim.scan_at(black_box(&pose), 0.0, 0)))
        });
    }
    group.finish();
    let mut group = c.benchmark_group("raycast_1081_beams");
    for sim in &worlds {
        let walls = sim.world().walls().len();
        let pose = sim.true_poses()[sim.len() / 2];
        let origin = Point2::new(pose.x(), pose.y());
        let dirs: Vec<Vector2<f64>> = (0..1081)
            .map(|i| {
                let a = pose.heading() - 135f64.to_radians() + i as f64 * 0.25f64.to_radians();
                Vector2::new(a.cos(), a.sin())
            })
            .collect();
        group.bench_with_input(BenchmarkId::from_parameter(walls), sim, |b, sim| {
            b.iter(|| {
                // As the simulator casts: each beam first tests the previous beam's wall.
                let (mut sum, mut hint) = (0.0, None);
                for d in &dirs {
                    if let Some(h) = sim.world().cast_hinted(&origin, d, 30.0, hint) {
                        sum += h.distance_m;
                        hint = Some(h.wall);
                    }
                }
                black_box(sum)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, raycast);
criterion_main!(benches);
