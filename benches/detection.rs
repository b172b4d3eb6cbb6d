//! Whole-scan detection on simulated 1081-beam scans (office and hall
//! scenes, UTM-30LX-EW noise) for both presets, and the stages of the
//! default pipeline: level 1, level 2, and the rest (fit, merge).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use pcaline::geometry::{BearingTable, ScanPoints};
use pcaline::segmentation::{BreakRule, level1_clusters, split_at_farthest};
use pcaline::{Config, LineDetector, RangeNoise, Scan};
use pcaline_sim::Simulator;
use std::hint::black_box;

fn scan_of(text: &str, name: &str) -> Scan {
    let scene = pcaline_io::parse_scene(std::path::Path::new(name), text).unwrap();
    let sim = Simulator::new(&scene, 1).unwrap();
    sim.frame(sim.len() / 3).unwrap().scan
}

fn detection(c: &mut Criterion) {
    let scans = [
        ("office", scan_of(include_str!("../sim-scenes/office-clutter.toml"), "office.toml")),
        ("hall", scan_of(include_str!("../sim-scenes/hall-pillars.toml"), "hall.toml")),
    ];
    let mut group = c.benchmark_group("detect_1081_beams");
    for (name, scan) in &scans {
        for (preset, config) in [("default", Config::default()), ("paper", Config::paper())] {
            let mut det = LineDetector::new(config).unwrap();
            group.bench_with_input(BenchmarkId::new(preset, name), scan, |b, s| {
                b.iter(|| black_box(det.detect(black_box(s)).lines.len()))
            });
        }
    }
    group.finish();

    let mut group = c.benchmark_group("stages_1081_beams");
    let (_, scan) = &scans[0];
    let mut table = BearingTable::default();
    let mut points = ScanPoints::default();
    group.bench_function("polar_to_cartesian", |b| {
        b.iter(|| {
            points.fill_from(black_box(scan), &mut table);
            black_box(points.len())
        })
    });
    points.fill_from(scan, &mut table);
    let rule = BreakRule::adaptive_utm30lx();
    let (mut breaks, mut clusters) = (Vec::new(), Vec::new());
    group.bench_function("level1_adaptive", |b| {
        b.iter(|| {
            level1_clusters(black_box(&points), &rule, 5, &mut breaks, &mut clusters);
            black_box(clusters.len())
        })
    });
    let (mut stack, mut subs) = (Vec::new(), Vec::new());
    let noise = RangeNoise::utm30lx();
    group.bench_function("level2_split", |b| {
        b.iter(|| {
            subs.clear();
            for c in &clusters {
                split_at_farthest(&points, c.clone(), &noise, 4.0, 0.0, &mut stack, &mut subs);
            }
            black_box(subs.len())
        })
    });
    group.finish();
}

criterion_group!(benches, detection);
criterion_main!(benches);
