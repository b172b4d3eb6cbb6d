//! Property tests of the simulator: exact geometry without noise, noise
//! statistics, faults, and bit-identical seeding.

use pcaline_geometry::{Point2, Pose2, RangeNoise};
use pcaline_sim::{Fault, MazeConfig, Scene, Simulator, WallStyle, generate_maze};
use proptest::prelude::*;

fn maze(seed: u64, walls: WallStyle) -> Scene {
    let mut config = MazeConfig::small("prop").with_grid(4, 3);
    config.walls = walls;
    generate_maze(&config, seed).unwrap()
}

fn noiseless(mut scene: Scene) -> Scene {
    scene.sensor.range_sigma_m = Some(0.0);
    scene
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn noiseless_points_lie_on_their_walls(seed in 0u64..10_000, pick in 0.0f64..1.0, single in any::<bool>()) {
        let style = if single { WallStyle::Single } else { WallStyle::Double { thickness_m: 0.1 } };
        let scene = noiseless(maze(seed, style));
        let sim = Simulator::new(&scene, seed).unwrap();
        let frame = sim.frame(((sim.len() - 1) as f64 * pick) as usize).unwrap();
        let max = frame.scan.range_max;
        for (i, (&r, truth)) in frame.scan.ranges.iter().zip(&frame.beams).enumerate() {
            match truth.wall {
                None => prop_assert!(r == f32::INFINITY, "beam {i}: no hit must be +inf, is {r}"),
                Some(w) => {
                    prop_assert!(r <= max, "beam {i}: {r} beyond range_max");
                    let wall = &sim.world().walls()[w as usize];
                    let p = frame.true_pose.transform_point(&pcaline_geometry::polar_to_cartesian(
                        f64::from(r), frame.scan.angle(i)));
                    let e = (wall.b - wall.a).normalize();
                    let off = p - wall.a;
                    let dist = (off.x * e.y - off.y * e.x).abs();
                    let along = off.dot(&e);
                    prop_assert!(dist < 1e-4, "beam {i}: {dist} m off its wall");
                    prop_assert!(along > -1e-4 && along < (wall.b - wall.a).norm() + 1e-4);
                }
            }
        }
    }
}

/// A corridor 3 m wide and 40 m long around the origin: one pose at the
/// origin sees the side walls from 1.5 m to beyond 10 m.
fn long_corridor() -> Scene {
    let mut scene = maze(1, WallStyle::Single);
    scene.walls = vec![pcaline_sim::Shape {
        name: "corridor".into(),
        points: vec![[-2.0, -1.5], [38.0, -1.5], [38.0, 1.5], [-2.0, 1.5]],
        closed: true,
    }];
    scene.obstacles.clear();
    scene.trajectory.start = pcaline_sim::StartPose { x: 0.0, y: 0.0, heading_deg: 0.0 };
    scene.trajectory.waypoints = vec![[1.0, 0.0]];
    scene
}

#[test]
fn noise_statistics_match_the_configured_sigma() {
    let scene = long_corridor();
    for (noise, expect) in
        [(RangeNoise::constant(0.04), [0.04, 0.04]), (RangeNoise::utm30lx(), [0.01, 0.03])]
    {
        let mut sensor = scene.sensor_model();
        sensor.noise = noise;
        let sim = Simulator::from_parts(
            scene.world(),
            sensor,
            scene.trajectory(),
            scene.odometry_model(),
            11,
        )
        .unwrap();
        let (mut near, mut far) = (Vec::new(), Vec::new());
        for k in 0..400u64 {
            let (scan, beams) = sim.scan_at(&Pose2::identity(), 0.0, k);
            for (r, b) in scan.ranges.iter().zip(&beams) {
                if b.wall.is_some() {
                    let e = f64::from(*r) - b.range_m;
                    if b.range_m < 9.5 {
                        near.push(e)
                    } else if b.range_m > 10.5 {
                        far.push(e)
                    }
                }
            }
        }
        for (errors, sigma) in [(near, expect[0]), (far, expect[1])] {
            let n = errors.len() as f64;
            assert!(n > 10_000.0, "only {n} samples");
            let mean = errors.iter().sum::<f64>() / n;
            let std = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            assert!(mean.abs() < 4.0 * sigma / n.sqrt() + 1e-6, "mean {mean}");
            assert!((std / sigma - 1.0).abs() < 0.03, "std {std} vs sigma {sigma}");
        }
    }
}

#[test]
fn faults_are_applied_and_recorded() {
    let mut scene = maze(5, WallStyle::Single);
    scene.sensor.dropout_probability = 1.0;
    let sim = Simulator::new(&scene, 1).unwrap();
    let f = sim.frame(0).unwrap();
    for (r, b) in f.scan.ranges.iter().zip(&f.beams) {
        assert_eq!(*r, f32::INFINITY);
        if b.wall.is_some() {
            assert_eq!(b.fault, Fault::Dropout);
        }
    }
    let mut scene = maze(5, WallStyle::Single);
    scene.sensor.outlier_probability = 0.2;
    scene.sensor.mixed_pixel_probability = 0.5;
    let sim = Simulator::new(&scene, 1).unwrap();
    let f = sim.frame(3).unwrap();
    let outliers =
        f.beams.iter().filter(|b| matches!(b.fault, Fault::Displaced | Fault::Clutter)).count();
    let hits = f.beams.iter().filter(|b| b.wall.is_some()).count();
    let rate = outliers as f64 / hits as f64;
    assert!((0.1..0.3).contains(&rate), "outlier rate {rate}");
}

#[test]
fn same_seed_same_scans_in_any_order() {
    let mut scene = maze(9, WallStyle::Double { thickness_m: 0.1 });
    scene.sensor.outlier_probability = 0.05;
    scene.sensor.motion_skew = true;
    scene.odometry.heading_random_walk_deg_sqrt_s = 0.1;
    let a = Simulator::new(&scene, 77).unwrap();
    let b = Simulator::new(&scene, 77).unwrap();
    let forward: Vec<_> = a.frames().take(20).collect();
    let backward: Vec<_> = (0..20).rev().map(|k| b.frame(k).unwrap()).collect();
    for (x, y) in forward.iter().zip(backward.iter().rev()) {
        assert_eq!(x, y);
        let bits = |f: &pcaline_sim::SimFrame| {
            f.scan.ranges.iter().map(|r| r.to_bits()).collect::<Vec<_>>()
        };
        assert_eq!(bits(x), bits(y));
    }
    let c = Simulator::new(&scene, 78).unwrap();
    assert_ne!(a.frame(3).unwrap().scan.ranges, c.frame(3).unwrap().scan.ranges);
}

#[test]
fn wall_runs_follow_valid_consecutive_beams() {
    let scene = noiseless(maze(2, WallStyle::Single));
    let sim = Simulator::new(&scene, 2).unwrap();
    let f = sim.frame(0).unwrap();
    let runs = f.wall_runs(10);
    assert!(!runs.is_empty());
    for r in &runs {
        assert!(r.last_beam + 1 - r.first_beam >= 10);
        for b in r.first_beam..=r.last_beam {
            assert_eq!(f.beams[b].wall, Some(r.wall));
        }
    }
    let _ = Point2::<f64>::origin();
}

/// A sensor with a range resolution publishes multiples of it, within half a
/// step of the unrounded range.
#[test]
fn ranges_are_rounded_to_the_resolution() {
    let mut scene = maze(7, WallStyle::Single);
    scene.sensor.range_resolution_m = Some(0.05);
    let rounded = Simulator::new(&scene, 3).unwrap();
    scene.sensor.range_resolution_m = Some(0.0);
    let exact = Simulator::new(&scene, 3).unwrap();
    let (a, b) = (rounded.frame(5).unwrap(), exact.frame(5).unwrap());
    let mut finite = 0;
    for (&r, &e) in a.scan.ranges.iter().zip(&b.scan.ranges) {
        if r.is_finite() {
            finite += 1;
            let steps = f64::from(r) / 0.05;
            assert!((steps - steps.round()).abs() < 1e-4, "{r} is not a multiple of 5 cm");
            assert!((r - e).abs() <= 0.025 + 1e-5, "{r} rounded from {e}");
        }
    }
    assert!(finite > 100);
    let mut bad = scene.clone();
    bad.sensor.range_resolution_m = Some(-0.01);
    let e = bad.validate().unwrap_err().to_string();
    assert!(e.contains("range_resolution_m"), "{e}");
}
