//! Whole-scan detection on simulated 1081-beam scans (office and hall
//! scenes, UTM-30LX-EW noise) and on a real 361-beam CARMEN scan, for both
//! presets, and the stages of the default pipeline: level 1, level 2, and
//! the rest (fit, merge).

#![allow(clippy::print_stderr)] // the loud report of a missing dataset

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use pcaline::geometry::{BearingTable, ScanPoints, SensorProfile};
use pcaline::segmentation::{
    BreakRule, NoiseEstimation, estimate_range_noise, level1_clusters, split_at_farthest,
};
use pcaline::{Config, LineDetector, RangeNoise, Scan};
use pcaline_sim::Simulator;
use std::hint::black_box;

fn scan_of(text: &str, name: &str) -> Scan {
    let scene = pcaline_io::parse_scene(std::path::Path::new(name), text).unwrap();
    let sim = Simulator::new(&scene, 1).unwrap();
    sim.frame(sim.len() / 3).unwrap().scan
}

/// The office scene's scan at range noise `sigma_m` (constant).
fn office_at(sigma_m: f64) -> Scan {
    let text = include_str!("../sim-scenes/office-clutter.toml");
    let mut scene = pcaline_io::parse_scene(std::path::Path::new("office.toml"), text).unwrap();
    scene.sensor.range_sigma_m = Some(sigma_m);
    let sim = Simulator::new(&scene, 1).unwrap();
    sim.frame(sim.len() / 3).unwrap().scan
}

/// Detection time against range noise: the same scan at 10 mm and 30 mm,
/// for the default (estimating the noise), the datasheet detector (told
/// the UTM-30LX-EW's, the default before 2026-12-05) and the adaptive one.
fn detection_by_noise(c: &mut Criterion) {
    let mut group = c.benchmark_group("detect_by_noise");
    for sigma_mm in [10.0, 30.0] {
        let scan = office_at(sigma_mm / 1000.0);
        for (preset, config) in [
            ("default", Config::default()),
            ("datasheet", Config::datasheet(SensorProfile::Utm30lxEw)),
            ("adaptive", Config::adaptive()),
        ] {
            let mut det = LineDetector::new(config).unwrap();
            group.bench_with_input(BenchmarkId::new(preset, sigma_mm), &scan, |b, s| {
                b.iter(|| black_box(det.detect(black_box(s)).lines.len()))
            });
        }
    }
    group.finish();
}

/// The same against range noise over a stream: 100 successive frames of
/// the office and the hall scenes at a constant 10 mm and 30 mm (time per
/// frame is the reported time over 100). One scan is one draw of the geometry and the
/// noise; at 30 mm the bench's single scan happens to be split into four
/// more pieces than at 10 mm (a 6-point fragment joins a wall's cluster).
fn detection_by_noise_stream(c: &mut Criterion) {
    let mut group = c.benchmark_group("detect_100_frames_by_noise");
    let scenes = [
        ("office", include_str!("../sim-scenes/office-clutter.toml")),
        ("hall", include_str!("../sim-scenes/hall-pillars.toml")),
    ];
    for (name, text) in scenes {
        for sigma_mm in [10.0, 30.0] {
            let path = std::path::Path::new("scene.toml");
            let mut scene = pcaline_io::parse_scene(path, text).unwrap();
            scene.sensor.range_sigma_m = Some(sigma_mm / 1000.0);
            let sim = Simulator::new(&scene, 1).unwrap();
            let scans: Vec<Scan> =
                (0..100.min(sim.len())).map(|i| sim.frame(i).unwrap().scan).collect();
            for (preset, config) in [
                ("default", Config::default()),
                ("datasheet", Config::datasheet(SensorProfile::Utm30lxEw)),
            ] {
                let mut det = LineDetector::new(config).unwrap();
                let id = BenchmarkId::new(format!("{preset}/{name}"), sigma_mm);
                group.bench_with_input(id, &scans, |b, scans| {
                    b.iter(|| {
                        scans.iter().map(|s| det.detect(black_box(s)).lines.len()).sum::<usize>()
                    })
                });
            }
        }
    }
    group.finish();
}

fn detection(c: &mut Criterion) {
    let scans = [
        ("office", scan_of(include_str!("../sim-scenes/office-clutter.toml"), "office.toml")),
        ("hall", scan_of(include_str!("../sim-scenes/hall-pillars.toml"), "hall.toml")),
    ];
    // A real 361-beam CARMEN scan (SICK, 0.5°) from the MIT CSAIL log.
    let data =
        std::env::var_os("PCALINE_DATA").map(std::path::PathBuf::from).unwrap_or_else(|| {
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data")
        });
    let mut carmen = None;
    let log = data.join("mit-csail/mit-csail.clf");
    if let Ok(reader) = pcaline_io::CarmenReader::open(&log, Default::default()) {
        carmen = reader.filter_map(Result::ok).find_map(|r| match r {
            pcaline_io::LogRecord::Scan(s) => Some(s.scan),
            _ => None,
        });
    }
    match &carmen {
        Some(scan) => {
            let mut group = c.benchmark_group("detect_361_beams_carmen");
            for (preset, config) in [("default", Config::default()), ("paper", Config::paper())] {
                let mut det = LineDetector::new(config).unwrap();
                group.bench_function(preset, |b| {
                    b.iter(|| black_box(det.detect(black_box(scan)).lines.len()))
                });
            }
            group.finish();
        }
        None => {
            eprintln!("!!! {} not found (set PCALINE_DATA): CARMEN bench skipped", log.display())
        }
    }

    let mut group = c.benchmark_group("detect_1081_beams");
    let datasheet = Config::datasheet(SensorProfile::Utm30lxEw);
    for (name, scan) in &scans {
        for (preset, config) in
            [("default", Config::default()), ("datasheet", datasheet), ("paper", Config::paper())]
        {
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
    // The split's input, also when a filter leaves level 1's bench out.
    level1_clusters(&points, &rule, 5, &mut breaks, &mut clusters);
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
    let mut scratch = pcaline::segmentation::NoiseScratch::default();
    group.bench_function("noise_estimate", |b| {
        b.iter(|| {
            black_box(estimate_range_noise(
                black_box(&points),
                &noise,
                &NoiseEstimation::standard(),
                0.0,
                &mut scratch,
            ))
        })
    });
    group.finish();
}

criterion_group!(benches, detection, detection_by_noise, detection_by_noise_stream);
criterion_main!(benches);
