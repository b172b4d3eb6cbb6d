//! The whole `pcaline run` pipeline per scan on the default maze: simulate a
//! scan, detect its lines, and update map and pose (full-pose aiding), from
//! the state after 400 scans.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use pcaline::{Mapper, MapperConfig};
use pcaline_sim::Simulator;
use std::hint::black_box;

fn run(c: &mut Criterion) {
    let text = include_str!("../sim-scenes/paper-maze.toml");
    let scene = pcaline_io::parse_scene(std::path::Path::new("paper-maze.toml"), text).unwrap();
    let sim = Simulator::new(&scene, 1).unwrap();
    let mut mapper = Mapper::new(MapperConfig::default()).unwrap();
    for frame in sim.frames().take(400) {
        mapper.process(&frame.scan, &frame.odometry_pose);
    }
    let mut group = c.benchmark_group("run_per_scan");
    group.bench_function("simulate", |b| b.iter(|| black_box(sim.frame(black_box(400)))));
    let frame = sim.frame(400).unwrap();
    group.bench_function("detect_map_aid", |b| {
        b.iter_batched_ref(
            || mapper.clone(),
            |m| black_box(m.process(&frame.scan, &frame.odometry_pose)),
            BatchSize::SmallInput,
        )
    });
    group.bench_function("simulate_detect_map_aid", |b| {
        b.iter_batched_ref(
            || mapper.clone(),
            |m| {
                let f = sim.frame(400).unwrap();
                black_box(m.process(&f.scan, &f.odometry_pose))
            },
            BatchSize::SmallInput,
        )
    });
    group.finish();
}

criterion_group!(benches, run);
criterion_main!(benches);
