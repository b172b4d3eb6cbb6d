//! Loop closure end to end on the MIT CSAIL log: its raw odometry drifts by
//! tens of degrees and metres, and the robot returns to corridors it mapped
//! long before. With loop closure the heading must come out ahead of the
//! estimator alone, on the log as it is and on average over the sensitivity
//! runs (the odometry plus a tiny seeded random walk), and no accepted loop
//! may be off the corrected poses by 1 m or more on the log as it is (in
//! a few sensitivity runs loops metres off a repeated corridor stand: a
//! known defect, an ignored test);
//! fed the log's own corrected poses, it must leave them essentially
//! unchanged (closer than the estimator alone). The twin-room false loop is
//! a unit test of `pcaline_aiding::LoopClosing`; the full tables are
//! `pcaline eval --real`.

mod support;
use support::data;

use pcaline::aiding::{
    Aiding, AidingConfig, LoopClosing, LoopClosureConfig, LoopOutcome, SensorLine,
};
use pcaline::mapping::MapConfig;
use pcaline::{Config, LineDetector, Pose2};
use pcaline_eval::{
    AidedRun, LoopCheck, SENSITIVITY_SEEDS, aligned_trajectory_errors, perturbed,
    reference_by_source, rigidly_aligned_trajectory_errors, trajectory_errors,
};
use pcaline_io::{CarmenOptions, CarmenReader, LogRecord, read_scan_pairs};
use pcaline_sim::{MazeConfig, OdometrySpec, Simulator, generate_maze};
use std::path::Path;

/// Runs the estimator with loop closure over a CARMEN log with `source`
/// picking the source pose of each scan; returns the optimized trajectory
/// and the loop closing itself (its loops and keyframes).
fn run(log: &Path, source: impl Fn(&pcaline_io::ScanRecord) -> Pose2) -> (Vec<Pose2>, LoopClosing) {
    let scans = read(log);
    let sources: Vec<Pose2> = scans.iter().map(|s| source(&s.record)).collect();
    run_lines(&scans, &sources)
}

/// A log's scans: each record with its detected lines.
struct Scan {
    record: pcaline_io::ScanRecord,
    lines: Vec<SensorLine>,
}

fn read(log: &Path) -> Vec<Scan> {
    let mut detector = LineDetector::new(Config::default()).unwrap();
    CarmenReader::open(log, CarmenOptions::default())
        .unwrap()
        .filter_map(|r| match r.unwrap() {
            LogRecord::Scan(s) => {
                let lines = detector.detect(&s.scan).lines.iter().map(SensorLine::from).collect();
                Some(Scan { record: s, lines })
            }
            _ => None,
        })
        .collect()
}

/// The estimator with loop closure over `scans` with `sources`.
fn run_lines(scans: &[Scan], sources: &[Pose2]) -> (Vec<Pose2>, LoopClosing) {
    run_lines_with(scans, sources, LoopClosureConfig::standard())
}

/// [`run_lines`] with a loop-closure configuration.
fn run_lines_with(
    scans: &[Scan],
    sources: &[Pose2],
    config: LoopClosureConfig,
) -> (Vec<Pose2>, LoopClosing) {
    let mut slam =
        LoopClosing::new(AidingConfig::estimator(), MapConfig::default(), config).unwrap();
    for (s, source) in scans.iter().zip(sources) {
        slam.step_at(s.record.scan.stamp_s.unwrap(), source, &s.lines);
    }
    slam.optimize();
    (slam.trajectory().into_iter().map(Option::unwrap).collect(), slam)
}

/// The estimator alone over `scans` with `sources`.
fn run_alone(scans: &[Scan], sources: &[Pose2]) -> Vec<Pose2> {
    let mut aiding = Aiding::new(AidingConfig::estimator(), MapConfig::default()).unwrap();
    scans
        .iter()
        .zip(sources)
        .map(|(s, source)| aiding.step_at(s.record.scan.stamp_s.unwrap(), source, &s.lines).0)
        .collect()
}

#[test]
fn csail_raw_odometry_heading_is_ahead_of_the_estimator_alone() {
    let Some(dir) = data("mit-csail") else { return };
    let pairs = read_scan_pairs(&dir.join("csail_corrected_to_raw_pairs.txt")).unwrap();
    let log = dir.join("mit-csail.clf");
    let (poses, slam) = run(&log, |s| s.odometry.or(s.pose).unwrap());
    // Every accepted loop against the corrected poses, carried from the
    // nearest paired scan (at most 5 scans away) by the raw odometry.
    let odometry: Vec<Pose2> = CarmenReader::open(&log, CarmenOptions::default())
        .unwrap()
        .filter_map(|r| match r.unwrap() {
            LogRecord::Scan(s) => Some(s.odometry.unwrap()),
            _ => None,
        })
        .collect();
    let corrected: Vec<(usize, Pose2)> =
        pairs.iter().map(|p| (p.raw_index, p.corrected_pose)).collect();
    let reference = reference_by_source(&corrected, &odometry, 5);
    let scans: Vec<usize> = slam.keyframes().iter().map(|k| k.scan).collect();
    let check = LoopCheck::of(slam.loops(), &scans, &reference);
    // The look-alike places of the known defect below (a loop shifted
    // about 2 m along a repeated corridor) stood in about a quarter of the
    // draws before the look-alike place search became the default
    // (2026-12-04, fifteenth session; 29 of 96 sensitivity runs, 3 with
    // it), on this one too (a pair 2.0 m off, keyframes ~590 -> ~151, so
    // this bound was 2.5 m). Measured now: at most 0.48 m off.
    for (m, deg) in &check.standing_errors {
        assert!(*m < 1.0, "a false loop stands: off by {m} m, {deg}°: {check:?}");
    }
    let (accepted, checked) = (check.standing + check.unchecked, check.standing);
    let picked: Vec<Pose2> = pairs.iter().map(|p| poses[p.raw_index]).collect();
    let reference: Vec<Pose2> = pairs.iter().map(|p| p.corrected_pose).collect();
    let e = rigidly_aligned_trajectory_errors(&picked, &reference).unwrap();
    let first = aligned_trajectory_errors(&picked, &reference).unwrap();
    // One draw (the sensitivity tests below): its bounds hold for the log
    // as it is, not for every perturbation of it (the sensitivity runs
    // range 9.5-17.7° rigid).
    // Rigidly aligned: the estimator alone 12.8° / 4.9 m, raw odometry
    // 22.1° / 8.7 m. Measured with loops: 8.4° / 1.8 m rigid
    // (`pcaline eval --real`; 8.8° / 2.3 m before the look-alike place
    // search became the default, 2026-12-04, fifteenth session; 9.7° /
    // 2.0 m, 10.6° at the first pair, before place recognition); before the speed scale learnt
    // (2026-12-04) 12.9° / 3.1 m and 13.3°, 9 loops checked. With the
    // chain's noise floored at a quarter of the wheel-odometry model
    // (before 2026-12-04): 13.2° / 4.3 m and 13 loops; at the learnt scale
    // the optimizer switches more loops off, nearly all of them wrong.
    assert!(checked >= 7, "{checked} of {accepted} loops checked");
    assert!(e.heading_rms_rad.to_degrees() < 14.0, "{e:?}");
    assert!(first.heading_rms_rad.to_degrees() < 16.0, "{first:?}");
    assert!(e.position_rms_m < 5.0, "{e:?}");
}

/// MIT CSAIL's raw odometry is short: over the scans with corrected poses
/// its path is 2.2% shorter than the corrected path. The estimator learns
/// that speed scale error from the line matches alone, with or without loop
/// closure, and with a standard deviation that covers what is left.
#[test]
fn csail_raw_odometry_teaches_its_speed_scale() {
    let Some(dir) = data("mit-csail") else { return };
    let pairs = read_scan_pairs(&dir.join("csail_corrected_to_raw_pairs.txt")).unwrap();
    let length = |poses: &[Pose2]| -> f64 {
        poses.windows(2).map(|w| (w[1].x() - w[0].x()).hypot(w[1].y() - w[0].y())).sum()
    };
    let raw: Vec<Pose2> = pairs.iter().map(|p| p.raw_pose).collect();
    let corrected: Vec<Pose2> = pairs.iter().map(|p| p.corrected_pose).collect();
    // The source's steps are too long by this fraction (negative: short).
    let truth = length(&raw) / length(&corrected) - 1.0;
    assert!((truth + 0.0223).abs() < 1e-3, "{truth}");
    let scans = read(&dir.join("mit-csail.clf"));
    let sources: Vec<Pose2> = scans.iter().map(|s| s.record.odometry.unwrap()).collect();
    let mut aiding = Aiding::new(AidingConfig::estimator(), MapConfig::default()).unwrap();
    for (s, source) in scans.iter().zip(&sources) {
        aiding.step_at(s.record.scan.stamp_s.unwrap(), source, &s.lines);
    }
    let (_, slam) = run_lines(&scans, &sources);
    // Measured: -2.23% ± 0.09% alone, -2.48% ± 0.11% with loop closure
    // (-2.23% ± 0.10% with loop searches 5 keyframes apart, before
    // 2026-12-05; before 2026-12-04 the scale did not learn: 0%).
    for (name, c) in [("alone", aiding.calibration()), ("with loops", slam.aiding().calibration())]
    {
        let (scale, sigma) = (c.speed_scale_error, c.speed_scale_var.sqrt());
        assert!(
            (scale - truth).abs() < 0.003 && (scale - truth).abs() < 3.0 * sigma.max(0.001),
            "{name}: learnt {:.2}% ± {:.2}%, the corrected path says {:.2}%",
            100.0 * scale,
            100.0 * sigma,
            100.0 * truth
        );
    }
}

/// One sensitivity run on MIT CSAIL's raw odometry: loop closure's and the
/// estimator alone's rigid heading rms, degrees, and loop closure's loops
/// against the corrected poses.
struct SeedRun {
    seed: u64,
    with_loops_deg: f64,
    alone_deg: f64,
    loops: LoopCheck,
}

/// The sensitivity runs (`pcaline_eval::perturbed`, seeds 1-8) on MIT
/// CSAIL's raw odometry, as `pcaline eval --real --drift-grid` runs them.
fn csail_sensitivity_runs(dir: &Path, config: LoopClosureConfig, seeds: &[u64]) -> Vec<SeedRun> {
    let pairs = read_scan_pairs(&dir.join("csail_corrected_to_raw_pairs.txt")).unwrap();
    let scans = read(&dir.join("mit-csail.clf"));
    let odometry: Vec<Pose2> = scans.iter().map(|s| s.record.odometry.unwrap()).collect();
    let times: Vec<f64> = scans.iter().map(|s| s.record.scan.stamp_s.unwrap()).collect();
    let corrected: Vec<(usize, Pose2)> =
        pairs.iter().map(|p| (p.raw_index, p.corrected_pose)).collect();
    let reference = reference_by_source(&corrected, &odometry, 5);
    let truth: Vec<Pose2> = pairs.iter().map(|p| p.corrected_pose).collect();
    let rigid_heading_deg = |poses: &[Pose2]| {
        let picked: Vec<Pose2> = pairs.iter().map(|p| poses[p.raw_index]).collect();
        rigidly_aligned_trajectory_errors(&picked, &truth).unwrap().heading_rms_rad.to_degrees()
    };
    seeds
        .iter()
        .map(|&seed| {
            let sources = perturbed(&odometry, &times, seed);
            let (poses, slam) = run_lines_with(&scans, &sources, config);
            let keyframes: Vec<usize> = slam.keyframes().iter().map(|k| k.scan).collect();
            SeedRun {
                seed,
                with_loops_deg: rigid_heading_deg(&poses),
                alone_deg: rigid_heading_deg(&run_alone(&scans, &sources)),
                loops: LoopCheck::of(slam.loops(), &keyframes, &reference),
            }
        })
        .collect()
}

/// On MIT CSAIL's raw odometry a whole-log figure is one draw: a random
/// walk of 1-2 cm and 0.01° added to the odometry moves loop closure's
/// rigid heading rms anywhere in 7-19° (`docs/accuracy.md`, "How far one
/// run can be trusted"). Over 32 sensitivity runs (eight are too few to
/// rank two methods 1-2° apart), loop closure's mean heading error must
/// stay below the estimator alone's, and every run must check loops.
#[test]
fn csail_loop_closure_is_ahead_over_the_sensitivity_runs() {
    let Some(dir) = data("mit-csail") else { return };
    let seeds: Vec<u64> = (1..=32).collect();
    let runs = csail_sensitivity_runs(&dir, LoopClosureConfig::standard(), &seeds);
    let mean = |f: fn(&SeedRun) -> f64| runs.iter().map(f).sum::<f64>() / runs.len() as f64;
    let (with_loops, alone) = (mean(|r| r.with_loops_deg), mean(|r| r.alone_deg));
    // Measured (seeds 1-32): with loops 9.69° mean, the estimator alone
    // 13.29°; raw odometry 22.1°. Without the look-alike place search
    // (before 2026-12-04, fifteenth session) 10.60° with loops, and over
    // seeds 33-96 11.09° (9.72° with it). Without place recognition (before
    // 2026-12-04, fourteenth session) 12.75° with loops, and over seeds
    // 33-96 13.47° (11.09° with it) against 13.27° alone. Before the speed
    // scale learnt (2026-12-04): 12.28° and 14.69°.
    // With loop searches 8 keyframes apart (2026-12-05): 9.71° with loops;
    // over seeds 33-96 9.92° (9.72° 5 apart), with no loop 0.5 m off in any
    // of the 96 runs (3 runs 5 apart). With the alignment matching only
    // lines facing the same way (2026-12-05, eighteenth session): 9.46°
    // (range 7.98-14.16°, 7.98-19.65° before).
    assert!(with_loops < alone, "with loops {with_loops:.2}°, alone {alone:.2}°");
    assert!(with_loops < 12.0, "with loops {with_loops:.2}°");
    // Every run closes loops. Measured: 4 standing and checked at seed 31,
    // the fewest (`pcaline eval --real --drift-grid --sensitivity-seeds 32`
    // counts 3 there), median 9; with searches 5 keyframes apart at least
    // 6, median 12.
    for r in &runs {
        assert!(r.loops.standing >= 3, "seed {}: {:?}", r.seed, r.loops);
    }
}

/// No sensitivity run keeps a false loop: a loop the corrected poses
/// contradict by 0.5 m or more. Seeds 1-8, and seed 35: there keyframes
/// 545-546 (a local candidate, the search radius capped at 8 m against a
/// 54 m uncertainty; another place matched 66% as much wall, under the
/// look-alike limit of 70%) aligned 34 m and 62° off to keyframe 61 and,
/// one keyframe apart, confirmed each other; the run ended 30° off. Since
/// 2026-12-05 (nineteenth session) a loop whose prior does not vouch for
/// the place is confirmed only by a loop from independent local lines
/// (`LoopClosureConfig::independent_confirm_keyframes`), and no run of 96
/// keeps a false loop (`pcaline eval --real --drift-grid
/// --sensitivity-seeds 96`; the worst standing loop 0.49 m off). Seed 35
/// fails with `independent_confirm_keyframes` 0. The eval counted seed 35
/// only once its false-loop check carried the corrected poses over 5 scans
/// instead of 2, as this test always has. Before loop searches were spaced
/// 8 keyframes apart (`LoopClosureConfig::loop_spacing_keyframes`), seed 5
/// kept a pair 6.2 m off, two neighbouring keyframes aligned to a look-alike
/// place along a repeated corridor, each confirming the other.
#[test]
fn csail_no_false_loop_stands_in_any_sensitivity_run() {
    let Some(dir) = data("mit-csail") else { return };
    let seeds: Vec<u64> = SENSITIVITY_SEEDS.iter().copied().chain([35]).collect();
    for r in csail_sensitivity_runs(&dir, LoopClosureConfig::standard(), &seeds) {
        for (m, deg) in &r.loops.standing_errors {
            assert!(*m < 0.5, "seed {}: a false loop stands: off by {m} m, {deg}°", r.seed);
        }
    }
}

/// The look-alike place search (`LoopClosureConfig::place_search_scale`,
/// 1 by default) pays over 32 sensitivity runs: loop closure's mean rigid
/// heading rms is lower with it than without it, and with it no run keeps a
/// false loop (0.5 m or more off the corrected poses).
///
/// Measured (2026-12-05, twentieth session, after a stalled source's
/// catch-up stopped being read as a change of rate): with the search 8.83°,
/// without it 9.04°; without it seed 19 keeps three loops 8.2 m off (the
/// sided alignment alone no longer refuses them all), with it no run keeps
/// one (nineteenth session: 9.30° and 9.66°, no false loop either way).
/// Eighteenth session: with the search 9.46°,
/// without it 10.85°, and no false loop in any run either way. Before the
/// sided alignment, without the search 11.20° with a false loop in 3 of the
/// 32 runs (the worst 13.7 m off), with it 9.71° and none; at seeds 1-8,
/// seed 5 kept a pair 6.2 m off with the search at scale 4 (2026-12-03),
/// seeds 5 and 6 without it.
#[test]
fn csail_the_place_search_pays_over_the_sensitivity_runs() {
    let Some(dir) = data("mit-csail") else { return };
    let seeds: Vec<u64> = (1..=32).collect();
    let mut off = LoopClosureConfig::standard();
    off.place_search_scale = 0.0;
    let with = csail_sensitivity_runs(&dir, LoopClosureConfig::standard(), &seeds);
    let without = csail_sensitivity_runs(&dir, off, &seeds);
    let mean = |runs: &[SeedRun]| runs.iter().map(|r| r.with_loops_deg).sum::<f64>() / 32.0;
    let (with_deg, without_deg) = (mean(&with), mean(&without));
    assert!(with_deg < without_deg, "with the search {with_deg:.2}°, without {without_deg:.2}°");
    for r in &with {
        for (m, deg) in &r.loops.standing_errors {
            assert!(*m < 0.5, "seed {}: a false loop stands: off by {m} m, {deg}°", r.seed);
        }
    }
}

/// The log's own corrected poses fed as the source through the estimator
/// with loop closure: how far they are moved, and the loop closing.
fn own_poses_moved(log: &Path) -> (pcaline_eval::TrajectoryErrors, LoopClosing) {
    let source: Vec<Pose2> = CarmenReader::open(log, CarmenOptions::default())
        .unwrap()
        .filter_map(|r| match r.unwrap() {
            LogRecord::Scan(s) => s.pose,
            _ => None,
        })
        .collect();
    let (poses, slam) = run(log, |s| s.pose.unwrap());
    (trajectory_errors(&poses, &source).unwrap(), slam)
}

#[test]
fn csail_own_poses_stay_where_they_are() {
    let Some(dir) = data("mit-csail") else { return };
    let (e, _) = own_poses_moved(&dir.join("csail.corrected.log"));
    // Measured: 0.56° / 0.074 m (`pcaline eval --real`; 0.081 m before the
    // look-alike place search became the default, 2026-12-04; the estimator
    // alone 0.75° / 0.25 m; 0.59°
    // / 0.076 m and 0.58° / 0.11 m before the speed scale learnt,
    // 2026-12-04).
    assert!(e.heading_rms_rad.to_degrees() < 1.0, "{e:?}");
    assert!(e.position_rms_m < 0.10, "{e:?}");
}

/// Issue "Aiding that does no harm": the default `pcaline map` (estimator
/// and loop closure) fed Intel's own GMapping-corrected poses must move them
/// by at most 1° heading rms and 0.10 m position rms. Intel's loops are many
/// (about 150), and a chain looser than the source deserves let the few
/// wrong ones bend it (0.82° / 0.18 m with the chain's noise floored at a
/// quarter of the wheel-odometry model, before 2026-12-04).
#[test]
fn intel_own_poses_stay_where_they_are() {
    let Some(dir) = data("intel") else { return };
    let (e, slam) = own_poses_moved(&dir.join("intel.gfs.log"));
    // Measured: 0.40° / 0.088 m with `pcaline eval --real` (0.41° / 0.091
    // m before the look-alike place search became the default,
    // 2026-12-04); 0.37° / 0.088 m, 148 loops standing (the estimator alone
    // 0.69° / 0.144 m); 0.41° / 0.070 m before the speed scale learnt
    // (2026-12-04), 0.37° / 0.101 m with its prior at 5% instead of 2%.
    assert!(e.heading_rms_rad.to_degrees() < 1.0, "{e:?}");
    assert!(e.position_rms_m < 0.10, "{e:?}");
    let standing = slam.loops().iter().filter(|l| l.outcome == LoopOutcome::Accepted).count();
    assert!(standing >= 50, "{standing} loops standing");
}

/// The shipped large building (a generated 40 x 30 cell maze of identical
/// 3 m cells, exact odometry): every cell's walls line up with its
/// neighbours' one cell away, the worst case for false loops. Its path never
/// comes back to a place, so every loop found there is false, and none may
/// even enter the graph (not as a loop the optimizer then switches off);
/// the trajectory must be as good as the estimator's alone.
#[test]
fn the_large_building_closes_no_false_loop() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sim-scenes/large-building.json");
    let scene = pcaline_io::read_scene(&path).unwrap();
    let sim = pcaline_sim::Simulator::new(&scene, 1).unwrap();
    let truth = sim.true_poses();
    // No true pose lies within 1 m of one 8 m or more of travel earlier (the
    // loop search's `min_loop_path_m`): the scene has no right loop to close.
    let mut travelled = vec![0.0f64];
    for w in truth.windows(2) {
        let d = w[0].between(&w[1]);
        travelled.push(travelled.last().unwrap() + d.x().hypot(d.y()));
    }
    let revisit = (0..truth.len()).step_by(10).find(|&i| {
        (0..i).any(|j| {
            let d = truth[j].between(&truth[i]);
            travelled[i] - travelled[j] >= 8.0 && d.x().hypot(d.y()) < 1.0
        })
    });
    assert_eq!(revisit, None, "the scene comes back to a place");

    let mut detector = LineDetector::new(Config::default()).unwrap();
    let estimator = AidingConfig::estimator();
    let run = pcaline_eval::AidedRun::run_with_loop_closure(
        &sim,
        MapConfig::default(),
        &[estimator],
        Some((estimator, LoopClosureConfig::standard())),
        |frame, velocity| {
            detector
                .detect_moving(&frame.scan, velocity.as_ref())
                .lines
                .iter()
                .map(SensorLine::from)
                .collect()
        },
    )
    .unwrap();
    let slam = run.loop_closing().unwrap();
    // Measured (2026-12-05): 8 loops verified, each a twin cell 3-4.2 m from
    // where the estimate places the scan, all refused by the look-alike place
    // search. Without it two of them were confirmed into the graph and
    // switched off by the optimizer.
    for r in slam.loops() {
        assert!(r.edge.is_none(), "a false loop entered the graph: {r:?}");
    }
    let scores = run.scores(truth).unwrap();
    let (alone, loops) = (&scores[0].errors, &scores[1].errors);
    // Measured: 5.3 cm both (`pcaline run`); 4.8 cm before the place search,
    // from the map rebuilt after the two false loops' optimizations.
    assert!(loops.position_rms_m < alone.position_rms_m + 0.01, "{alone:?} {loops:?}");
    assert!(loops.heading_rms_rad < alone.heading_rms_rad + 0.01f64.to_radians());
}

/// A generated maze of walls 10 cm thick (seed 104, 4 x 5 cells, extra
/// openings at 0.3, as `pcaline scene generate --seed 104 --cols 4 --rows 5
/// --loops 0.3` writes it) driven with a drifting odometry (0.3°/s of
/// heading-rate bias, 2% speed scale). The estimator alone keeps the heading
/// within a few hundredths of a degree, so every loop closed must agree
/// with the truth as well, or the graph does harm. Before the alignment
/// matched only lines facing the same way (`Facing::Same`), the least
/// squares let a wall's near face match its far face, the loops placed
/// keyframes 1-4 cm and 0.1-0.3° off, and the optimized heading rms was
/// 0.089° against the estimator's 0.032° alone (now 0.025°).
#[test]
fn loops_in_a_maze_of_thick_walls_agree_with_the_truth() {
    let mut maze = MazeConfig::small("thick-walls").with_grid(4, 5);
    maze.loop_probability = 0.3;
    let mut scene = generate_maze(&maze, 104).unwrap();
    scene.odometry = OdometrySpec {
        heading_rate_bias_deg_s: 0.3,
        heading_random_walk_deg_sqrt_s: 0.02,
        speed_scale_error: 0.02,
        position_random_walk_m_sqrt_s: 0.003,
    };
    let sim = Simulator::new(&scene, 1).unwrap();
    let mut detector = LineDetector::new(Config::default()).unwrap();
    let mut truth = Vec::new();
    // The estimator with loop closure alone (no other mode), as `pcaline
    // run` feeds it: deskewed lines, the odometry as the source.
    let run = AidedRun::run_with_loop_closure(
        &sim,
        MapConfig::default(),
        &[],
        Some((AidingConfig::estimator(), LoopClosureConfig::standard())),
        |frame, velocity| {
            truth.push(frame.true_pose);
            let detection = detector.detect_moving(&frame.scan, velocity.as_ref());
            detection.lines.iter().map(SensorLine::from).collect()
        },
    )
    .unwrap();
    let slam = run.loop_closing().unwrap();
    let scans: Vec<usize> = slam.keyframes().iter().map(|k| k.scan).collect();
    let reference: Vec<Option<Pose2>> = truth.iter().copied().map(Some).collect();
    let check = LoopCheck::of(slam.loops(), &scans, &reference);
    assert!(check.standing >= 6, "{check:?}");
    for (m, deg) in &check.standing_errors {
        assert!(*m < 0.01 && *deg < 0.1, "a loop {m} m, {deg}° off the truth: {check:?}");
    }
    let poses = &run.estimates[0];
    let e = trajectory_errors(poses, &truth).unwrap();
    assert!(e.heading_rms_rad.to_degrees() < 0.04, "{e:?}");
}
