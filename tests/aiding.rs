//! End-to-end localization aiding on the simulated maze (paper section 2.1):
//! a drifting odometry, the paper's heading aiding, full-pose aiding, and the
//! map they build, all against exact ground truth. Seeded.

use pcaline::aiding::AidingConfig;
use pcaline::{Mapper, MapperConfig, Pose2};
use pcaline_eval::{TrajectoryErrors, VisibleWalls, map_quality, trajectory_errors};
use pcaline_sim::{Scene, Simulator};
use std::path::Path;

fn maze() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sim-scenes/paper-maze.toml");
    pcaline_io::read_scene(&path).unwrap()
}

struct Run {
    unaided: TrajectoryErrors,
    aided: TrajectoryErrors,
    mapper: Mapper,
    visible: VisibleWalls,
    duration_s: f64,
}

fn run(scene: &Scene, seed: u64, config: MapperConfig) -> Run {
    let sim = Simulator::new(scene, seed).unwrap();
    let mut mapper = Mapper::new(config).unwrap();
    let mut visible = VisibleWalls::new(sim.world().walls(), 0.05);
    let mut aided = Vec::with_capacity(sim.len());
    for frame in sim.frames() {
        let step = mapper.process(&frame.scan, &frame.odometry_pose);
        assert!(step.pose.is_finite());
        aided.push(step.pose);
        visible.observe(&frame);
    }
    Run {
        unaided: trajectory_errors(sim.odometry_poses(), sim.true_poses()).unwrap(),
        aided: trajectory_errors(&aided, sim.true_poses()).unwrap(),
        mapper,
        visible,
        duration_s: sim.len() as f64 / sim.sensor().rate_hz,
    }
}

/// The paper's aiding (heading only, eq. 11, 12, 14) on the default detector
/// and map, with inverse-variance weights. The full paper preset (its
/// detector's short noisy pieces, its 15° / 1 m gates, eq. 13's 1/d_rho²
/// weights) is measured by `pcaline eval`: the closest match dominates the
/// weights however noisy its lines are.
fn heading_aiding() -> MapperConfig {
    MapperConfig::default().with_aiding(AidingConfig::heading())
}

#[test]
fn paper_heading_aiding_bounds_a_pure_heading_bias() {
    let mut scene = maze();
    scene.odometry = Default::default();
    scene.odometry.heading_rate_bias_deg_s = 0.5;
    // Eq. 11-14 exactly (eq. 13's 1/d_rho² weights), and with inverse-variance
    // weights, both on the default detector and map.
    let exact = MapperConfig::default().with_aiding(AidingConfig::paper());
    for config in [exact, heading_aiding()] {
        let r = run(&scene, 1, config);
        assert!(r.duration_s >= 60.0);
        assert!(
            r.aided.heading_rms_rad < 1f64.to_radians(),
            "aided heading rms {:.2}° ({:?})",
            r.aided.heading_rms_rad.to_degrees(),
            config.aiding.heading_weights
        );
        assert!(
            r.unaided.heading_rms_rad > 10f64.to_radians(),
            "unaided {:.2}°",
            r.unaided.heading_rms_rad.to_degrees()
        );
    }
}

#[test]
fn the_default_estimator_bounds_the_position() {
    let scene = maze(); // heading-rate bias, speed scale error, random walks
    let full = run(&scene, 2, MapperConfig::default());
    let heading = run(&scene, 2, heading_aiding());
    assert!(
        full.aided.position_rms_m * 5.0 < full.unaided.position_rms_m,
        "full-pose {:.3} m vs unaided {:.3} m",
        full.aided.position_rms_m,
        full.unaided.position_rms_m
    );
    assert!(full.aided.heading_rms_rad < 1f64.to_radians());
    // Heading-only aiding bounds the heading, but the speed scale error still
    // moves the position: the gap full-pose aiding closes.
    assert!(heading.aided.heading_rms_rad < 1f64.to_radians());
    assert!(
        full.aided.position_rms_m * 5.0 < heading.aided.position_rms_m,
        "full-pose {:.3} m vs heading-only {:.3} m",
        full.aided.position_rms_m,
        heading.aided.position_rms_m
    );
}

#[test]
fn the_map_lies_on_the_walls_and_covers_them() {
    let r = run(&maze(), 3, MapperConfig::default());
    let q = map_quality(r.mapper.map().lines(), &r.visible, 0.05, 2f64.to_radians());
    let worst = q.line_errors_m.iter().copied().fold(0.0, f64::max);
    assert!(worst <= 0.05, "a map line is {worst:.3} m (rms) from every wall");
    assert!(q.covered_fraction >= 0.9, "covered {:.3}", q.covered_fraction);
}

#[test]
fn perfect_source_needs_no_correction() {
    let mut scene = maze();
    scene.odometry = Default::default();
    let sim = Simulator::new(&scene, 4).unwrap();
    let mut mapper = Mapper::new(MapperConfig::default()).unwrap();
    for frame in sim.frames().take(400) {
        let step = mapper.process(&frame.scan, &frame.true_pose);
        assert!(
            step.report.heading_correction_rad.abs() < 0.2f64.to_radians(),
            "{:?}",
            step.report
        );
        assert!(step.report.translation_correction_m.norm() < 0.02, "{:?}", step.report);
    }
}

#[test]
fn a_known_rotation_of_the_source_is_undone() {
    let mut scene = maze();
    scene.odometry = Default::default();
    let sim = Simulator::new(&scene, 5).unwrap();
    let mut mapper = Mapper::new(heading_aiding()).unwrap();
    for (k, frame) in sim.frames().take(200).enumerate() {
        // From scan 100 on, the source's heading jumps by 3°.
        let mut source = frame.true_pose;
        if k >= 100 {
            source = Pose2::new(source.x(), source.y(), source.heading() + 3f64.to_radians());
        }
        let step = mapper.process(&frame.scan, &source);
        if k == 100 {
            assert!(
                (step.report.heading_correction_rad + 3f64.to_radians()).abs()
                    < 0.2f64.to_radians(),
                "{:?}",
                step.report
            );
        }
        let err = pcaline::geometry::wrap_angle(step.pose.heading() - frame.true_pose.heading());
        assert!(
            err.abs() < 0.3f64.to_radians(),
            "scan {k}: heading error {:.3}°",
            err.to_degrees()
        );
    }
}
