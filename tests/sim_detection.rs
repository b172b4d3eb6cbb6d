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
            let truth = pcaline::LineSegment::between(a, b);
            // The part of the wall this run saw, in the sensor frame.
            let seen =
                |beam: usize| sensor_from_world.transform_point(&frame.beams[beam].point.unwrap());
            let (p0, p1) = (seen(run.first_beam), seen(run.last_beam));
            let found = lines.iter().any(|l| {
                let along = |p: &Point2<f64>| (p - l.start()).dot(&l.direction());
                let (d0, d1) = (
                    along(&l.start()).min(along(&l.end())),
                    along(&l.start()).max(along(&l.end())),
                );
                let (s0, s1) = (along(&p0).min(along(&p1)), along(&p0).max(along(&p1)));
                let overlap = (d1.min(s1) - d0.max(s0)).max(0.0);
                line_angle_diff(l.alpha(), truth.alpha()).abs() < 0.1f64.to_radians()
                    && truth.signed_distance(&l.start()).abs() < 0.005
                    && truth.signed_distance(&l.end()).abs() < 0.005
                    && truth.signed_distance(&l.centroid()).abs() < 0.005
                    && overlap >= 0.5 * (s1 - s0)
            });
            assert!(found, "scan {k}: run {run:?} of wall {wall:?} not found among {lines:#?}");
            checked += 1;
        }
    }
    assert!(checked > 50, "only {checked} runs checked");
}

/// The protocol scores a wall the same whether the scene draws it whole or as
/// collinear pieces end to end: the pieces are one visible surface.
#[test]
fn a_wall_drawn_in_pieces_scores_as_one() {
    use pcaline_eval::{DetectFn, DetectionEval, evaluate_detectors};
    let room = |pieces: usize| {
        // A 6 x 4 m room, each side cut into `pieces` equal collinear segments.
        let corners = [[0.0, 0.0], [6.0, 0.0], [6.0, 4.0], [0.0, 4.0]];
        let mut points = Vec::new();
        for k in 0..4 {
            let (a, b): ([f64; 2], [f64; 2]) = (corners[k], corners[(k + 1) % 4]);
            for i in 0..pieces {
                let t = i as f64 / pieces as f64;
                points.push(format!(
                    "[{}, {}]",
                    a[0] + t * (b[0] - a[0]),
                    a[1] + t * (b[1] - a[1])
                ));
            }
        }
        let text = format!(
            "name = \"room\"\n[[walls]]\nclosed = true\npoints = [{}]\n[trajectory]\nstart = {{ x = 1.5, y = 1.0, heading_deg = 0.0 }}\nspeed_m_s = 0.5\nwaypoints = [[1.5, 1.0], [4.5, 1.0], [4.5, 3.0]]\n",
            points.join(", ")
        );
        pcaline_io::parse_scene(Path::new("room.toml"), &text).unwrap()
    };
    let eval = DetectionEval::new(0.01, 1, 20);
    let recall = |pieces| {
        let mut detector = LineDetector::new(Config::default()).unwrap();
        let mut detect = |f: &pcaline_sim::SimFrame, _: &pcaline_sim::World| {
            detector.detect(&f.scan).lines.iter().map(|l| l.line).collect::<Vec<_>>()
        };
        let mut refs: Vec<&mut DetectFn<'_>> = vec![&mut detect];
        let r = evaluate_detectors(&[room(pieces)], &eval, &mut refs).unwrap();
        (r[0].score.recall(), r[0].score.true_walls)
    };
    let (whole, split) = (recall(1), recall(3));
    assert!(whole.0 > 0.95, "whole: {whole:?}");
    assert_eq!(whole.1, split.1, "the same visible walls: {whole:?} {split:?}");
    assert!((whole.0 - split.0).abs() < 1e-9, "whole {whole:?}, split {split:?}");
}
