//! The detector on simulated scans against exact ground truth: with zero
//! noise, every ground-truth wall run of at least 10 beams in the corridor is
//! found within 0.1° and 5 mm.

use pcaline::{Config, LineDetector, Point2, RangeNoise, geometry::line_angle_diff};
use pcaline_sim::Simulator;
use std::path::Path;

#[test]
fn noiseless_corridor_runs_are_all_detected() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sim-scenes/corridor-doors.toml");
    let mut scene = pcaline_io::read_scene(&path).unwrap();
    scene.sensor.range_sigma_m = Some(0.0);
    let sim = Simulator::new(&scene, 1).unwrap();
    // The detector is told the true noise (1 mm stands for "none": f32 ranges
    // carry micrometres of rounding); with the UTM-30LX-EW model it would
    // rightly keep a corner point 9 cm off a wall 23 m away, within its 4
    // sigma. The paper preset is not held to this: without corner refinement
    // the corner point tilts short walls by tenths of a degree (`pcaline eval`
    // measures both presets).
    // Every run counts here, so the minimum line support is off.
    let mut config = Config::noise_aware(RangeNoise::constant(0.001));
    config.fitting.min_line_points = 0;
    config.fitting.min_line_length_m = 0.0;
    for (name, config) in [("noise-aware, 1 mm, all lengths", config)] {
        let mut detector = LineDetector::new(config).unwrap();
        let mut checked = 0;
        for k in (0..sim.len()).step_by(40) {
            let frame = sim.frame(k).unwrap();
            let sensor_from_world = frame.true_pose.inverse();
            let lines: Vec<_> = detector.detect(&frame.scan).lines.iter().map(|l| l.line).collect();
            for run in frame.wall_runs(10) {
                let wall = &sim.world().walls()[run.wall as usize];
                let (a, b) = (
                    sensor_from_world.transform_point(&wall.a),
                    sensor_from_world.transform_point(&wall.b),
                );
                let truth = pcaline::LineSegment::through(
                    Point2::from((a.coords + b.coords) / 2.0),
                    b - a,
                    a,
                    b,
                );
                let found = lines.iter().any(|l| {
                    line_angle_diff(l.alpha, truth.alpha).abs() < 0.1f64.to_radians()
                        && l.signed_distance(&l.project(&a)).abs() < 1e-9
                        && (truth.signed_distance(&l.start).abs() < 0.005)
                        && (truth.signed_distance(&l.end).abs() < 0.005)
                        && l.centroid.coords.dot(&truth.normal()) - truth.d < 0.005
                });
                assert!(
                    found,
                    "{name}, scan {k}: run {run:?} of wall {wall:?} not found among {lines:#?}"
                );
                checked += 1;
            }
        }
        assert!(checked > 50, "{name}: only {checked} runs checked");
    }
}
