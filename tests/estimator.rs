//! The estimator (the default aiding) end to end: on the real logs, where a
//! good source must come out essentially unchanged and a drifting one must
//! be pulled back, and on simulated scenes built for the failure modes the
//! real logs showed (a curved wall, fast turns with motion skew, clutter on
//! thin legs). Seeded; the heavy grids are `pcaline eval --real --drift-grid`.

mod support;
use support::data;

use pcaline::aiding::{AidingConfig, Fallback};
use pcaline::{Mapper, MapperConfig, Pose2};
use pcaline_eval::{VisibleWalls, aligned_trajectory_errors, map_quality, trajectory_errors};
use pcaline_io::{CarmenOptions, CarmenReader, LogRecord};
use pcaline_sim::{OdometryModel, Simulator};
use std::path::Path;

/// The scans of a CARMEN log with their own (corrected) poses.
fn carmen(path: &Path) -> Vec<(pcaline::Scan, Pose2)> {
    CarmenReader::open(path, CarmenOptions::default())
        .unwrap()
        .filter_map(|r| match r.unwrap() {
            LogRecord::Scan(s) => Some((s.scan.clone(), s.pose.unwrap())),
            _ => None,
        })
        .collect()
}

fn run_log(scans: &[(pcaline::Scan, Pose2)], source: &[Pose2]) -> Vec<Pose2> {
    let mut mapper = Mapper::new(MapperConfig::default()).unwrap();
    scans
        .iter()
        .zip(source)
        .map(|((scan, _), p)| {
            let step = mapper.process(scan, p);
            assert!(step.pose.is_finite());
            step.pose
        })
        .collect()
}

#[test]
fn good_sources_come_out_essentially_unchanged() {
    // Measured, the mapper's poses as it returns them scan by scan (loop
    // closure on): Intel 0.74° / 0.154 m, CSAIL 0.54° / 0.066 m (a scan
    // whose stamp goes backwards once started a keyframe and an
    // optimization from its guessed pose: Intel 1.28°). The paper's aiding
    // moved Intel's by 44° / 8.7 m, full-pose by 18° / 3.4 m.
    for (rel, max_heading_deg, max_position_m) in
        [("intel/intel.gfs.log", 1.0, 0.25), ("mit-csail/csail.corrected.log", 1.0, 0.2)]
    {
        let Some(path) = data(rel) else { continue };
        let scans = carmen(&path);
        let own: Vec<Pose2> = scans.iter().map(|s| s.1).collect();
        let e = trajectory_errors(&run_log(&scans, &own), &own).unwrap();
        assert!(
            e.heading_rms_rad.to_degrees() <= max_heading_deg && e.position_rms_m <= max_position_m,
            "{rel}: moved {:.2}° / {:.3} m",
            e.heading_rms_rad.to_degrees(),
            e.position_rms_m
        );
    }
}

#[test]
fn a_drifting_source_is_pulled_back() {
    let Some(path) = data("intel/intel.gfs.log") else { return };
    let scans = carmen(&path);
    let truth: Vec<Pose2> = scans.iter().map(|s| s.1).collect();
    let times: Vec<f64> = scans.iter().map(|s| s.0.stamp_s.unwrap()).collect();
    let model = OdometryModel {
        heading_rate_bias_rad_s: 0.3f64.to_radians(),
        heading_random_walk_rad_sqrt_s: 0.002,
        speed_scale_error: 0.03,
        position_random_walk_m_sqrt_s: 0.005,
    };
    let drifted = model.corrupt_stamped(&truth, &times, 1);
    let raw = aligned_trajectory_errors(&drifted, &truth).unwrap();
    let aided = aligned_trajectory_errors(&run_log(&scans, &drifted), &truth).unwrap();
    assert!(raw.heading_rms_rad > 50f64.to_radians(), "{raw:?}");
    assert!(
        aided.heading_rms_rad < 6f64.to_radians() && aided.position_rms_m < 2.5,
        "aided {:.2}° / {:.2} m (raw {:.1}° / {:.1} m)",
        aided.heading_rms_rad.to_degrees(),
        aided.position_rms_m,
        raw.heading_rms_rad.to_degrees(),
        raw.position_rms_m
    );
}

/// A scene of `sim-scenes`, run with the default mapper: errors of the
/// estimate, map lines off every wall, map lines per surface seen.
fn scene(name: &str, seed: u64) -> (f64, f64, usize, f64) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sim-scenes").join(name);
    let sim = Simulator::new(&pcaline_io::read_scene(&path).unwrap(), seed).unwrap();
    let mut mapper = Mapper::new(MapperConfig::default()).unwrap();
    let mut visible = VisibleWalls::new(sim.world().walls(), 0.05);
    let poses: Vec<Pose2> = sim
        .frames()
        .map(|frame| {
            visible.observe(&frame);
            mapper.process(&frame.scan, &frame.odometry_pose).pose
        })
        .collect();
    let e = trajectory_errors(&poses, sim.true_poses()).unwrap();
    let q = map_quality(mapper.map().lines(), &visible, 0.05, 2f64.to_radians());
    let per_wall = q.lines as f64 / visible.surfaces_seen(0.3).max(1) as f64;
    (e.heading_rms_rad.to_degrees(), e.position_rms_m, q.spurious, per_wall)
}

#[test]
fn failure_mode_scenes_hold_the_pose_and_keep_the_map_clean() {
    // Measured here (the default `Mapper`, seed 1): curved wall 0.056° /
    // 0.6 cm, fast turns 0.044° / 0.5 cm, leg clutter 0.015° / 0.5 cm, every
    // map line on a wall; 3.86, 1.17 and 1.0 map lines per surface seen.
    // Before the speed scale learnt (2026-12-04), with pcaline run: 0.14° /
    // 1.1 cm, 0.03° / 2.0 cm (16 lines off the walls before deskew) and
    // 0.05° / 1.4 cm; fast turns then held 1.0 line per surface.
    //
    // The curved wall is held in the map as chords (4.3 map lines per surface
    // seen): each chord's own observations already carry the curvature, so
    // the map's straightness test does not flag them; that needs the
    // detector's straightness statistic. The other scenes keep at most 1.2.
    for (name, max_lines_per_surface) in [
        ("curved-wall.toml", None),
        ("fast-turns.toml", Some(1.2)),
        ("leg-clutter.toml", Some(1.2)),
    ] {
        let (heading_deg, position_m, off_wall, per_surface) = scene(name, 1);
        assert!(
            heading_deg <= 0.2 && position_m <= 0.03,
            "{name}: {heading_deg:.3}° / {position_m:.3} m"
        );
        assert_eq!(off_wall, 0, "{name}: map lines off every wall");
        if let Some(max) = max_lines_per_surface {
            assert!(per_surface <= max, "{name}: {per_surface:.2} map lines per surface seen");
        }
    }
}

#[test]
fn bad_sources_get_reported_fallbacks_never_nan() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sim-scenes/paper-maze.toml");
    let mut scene = pcaline_io::read_scene(&path).unwrap();
    scene.odometry = Default::default();
    let sim = Simulator::new(&scene, 3).unwrap();
    let mut mapper = Mapper::new(MapperConfig::default()).unwrap();
    for (k, frame) in sim.frames().take(300).enumerate() {
        let mut source = frame.true_pose;
        let mut scan = frame.scan.clone();
        let expected = match k {
            100 => {
                source = Pose2::new(f64::NAN, 0.0, 0.0);
                Some(Fallback::NonFiniteSource)
            }
            150 => {
                // A 10 m teleport of the source.
                source = Pose2::new(source.x() + 10.0, source.y(), source.heading());
                Some(Fallback::SourceJump)
            }
            200 => {
                scan.stamp_s = Some(-1.0);
                Some(Fallback::StampBackwards)
            }
            _ => None,
        };
        let step = mapper.process(&scan, &source);
        assert!(step.pose.is_finite(), "scan {k}: {step:?}");
        if let Some(why) = expected {
            assert_eq!(step.report.fallback, Some(why), "scan {k}");
        }
        if k == 151 {
            // The jump is not followed: the source's next increment is, from
            // the pose the estimator kept.
            let err =
                (step.pose.x() - frame.true_pose.x()).hypot(step.pose.y() - frame.true_pose.y());
            assert!(err < 0.2, "scan {k}: {err:.3} m off after a 10 m source jump");
        }
    }
    let end = mapper.pose().unwrap();
    let truth = sim.true_poses()[299];
    assert!((end.x() - truth.x()).hypot(end.y() - truth.y()) < 0.1, "{end:?} vs {truth:?}");
    // The paper's preset is kept exactly, for reproduction.
    assert_eq!(MapperConfig::paper().aiding, AidingConfig::paper());
}
