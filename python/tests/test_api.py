"""What the package does on its own: detection internals, logs, the mapper,
the simulator and the evaluation."""

import itertools

import numpy as np
import pytest

import pcaline
from pcaline import eval, sim


def wall_scan(d_m=2.0, half_fov_deg=30.0, step_deg=0.25):
    angles = np.radians(np.arange(-half_fov_deg, half_fov_deg + step_deg / 2, step_deg))
    return (d_m / np.cos(angles)).astype(np.float32), angles[0], np.radians(step_deg)


def test_a_wall_is_one_line_with_its_points_and_clusters():
    ranges, a0, inc = wall_scan()
    det = pcaline.LineDetector("paper").detect(ranges, a0, inc, 0.1, 30.0, stamp=12.5)
    lines = det.lines
    assert len(det) == len(lines) == 1
    assert abs(lines.d[0] - 2.0) < 1e-6 and abs(lines.alpha[0]) < 1e-6
    assert len(det.points) == len(ranges)
    # The paper's fit leaves out a few points near each end (its corner
    # window); the line still spans every beam.
    assert 0.9 * len(ranges) <= lines.n_points[0] <= len(ranges)
    assert (lines.first_beam[0], lines.last_beam[0]) == (0, len(ranges) - 1)
    assert det.clusters.tolist() == [[0, len(ranges)]]
    assert det.noise is None  # the paper uses no noise model
    np.testing.assert_allclose(lines.segments_xy[0], [lines.start[0], lines.end[0]])
    assert lines.covariance.shape == (1, 2, 2) and lines.id is None


def test_detection_structure_is_consistent_on_a_simulated_scan():
    simulator = sim.Simulator(sim.generate_maze(7), seed=1)
    det = pcaline.LineDetector().detect_scan(simulator[100].scan)
    n = len(det.points)
    assert len(det.lines) > 0 and det.noise is not None
    assert ((det.clusters[:, 0] < det.clusters[:, 1]) & (det.clusters[:, 1] <= n)).all()
    starts = set(det.sub_clusters[:, 0].tolist())
    assert set(det.level2_breaks.tolist()) <= starts
    assert set(det.level2_breaks.tolist()).isdisjoint(det.clusters[:, 0].tolist())
    beams = det.point_beams
    assert (np.diff(beams.astype(int)) > 0).all()
    for k in range(len(det.lines)):
        first, last = det.lines.first_point[k], det.lines.last_point[k]
        assert beams[first] == det.lines.first_beam[k] and beams[last] == det.lines.last_beam[k]


def test_read_log_streams_and_stops_early(data):
    reader = pcaline.read_log(data / "intel" / "intel.gfs.log")
    first = list(itertools.islice(reader, 5))
    assert [s.position for s in first] == sorted(s.position for s in first)
    assert all(s.pose is not None and s.stamp is not None for s in first)
    assert first[0].ranges.dtype == np.float32 and len(first[0]) == 180
    del reader  # the reader thread stops at its next scan
    bag = list(pcaline.read_log(data / "ros1" / "laser_scan_matcher_demo.bag"))
    assert len(bag) > 100 and all(s.pose is None for s in bag)


def test_mapper_corrects_a_drifting_source_and_builds_a_map(root):
    simulator = sim.Simulator(sim.load_scene(root / "sim-scenes" / "paper-maze.toml"), seed=2)
    mapper = pcaline.Mapper(loop_closure=False)
    assert mapper.pose is None and mapper.trajectory() is None
    poses = []
    for k in range(len(simulator)):
        frame = simulator[k]
        step = mapper.step(frame.scan, frame.odometry_pose)
        poses.append(step.pose)
    assert mapper.optimize() is None
    errors = eval.trajectory_errors(np.array(poses), simulator.true_poses)
    raw = eval.trajectory_errors(simulator.odometry_poses, simulator.true_poses)
    assert errors["heading_rms_rad"] < raw["heading_rms_rad"]
    assert errors["position_rms_m"] < 0.1
    report = step.report
    assert report["matches"] > 0 and report["covariance"].shape == (3, 3)
    assert set(mapper.map.status) <= {"tentative", "confirmed", "not-straight"}
    assert len(step.lines) > 0 and step.lines.first_beam is not None


def test_paper_aiding_and_lidar_only_mode_run():
    simulator = sim.Simulator(sim.generate_maze(5, cols=2, rows=2), seed=3)
    paper = pcaline.Mapper("paper", aiding="paper", loop_closure=False)
    alone = pcaline.Mapper(loop_closure=False)
    for k in range(0, len(simulator), 2):
        frame = simulator[k]
        paper.step(frame.scan, frame.odometry_pose)
        alone.step(frame.scan)
    assert len(paper.map) > 0 and len(alone.map) > 0
    x, y, _ = alone.pose
    assert np.isfinite([x, y]).all()


def test_the_simulator_is_seeded_and_its_truth_is_exact(tmp_path):
    scene = sim.generate_maze(11, cols=3, rows=2)
    a, b = sim.Simulator(scene, seed=4), sim.Simulator(scene, seed=4)
    k = len(a) // 2
    assert (a[k].scan.ranges == b[k].scan.ranges).all()
    assert (a[k].scan.ranges != sim.Simulator(scene, seed=5)[k].scan.ranges).any()
    frame = a[k]
    hit = frame.beam_wall >= 0
    x, y, _ = frame.true_pose
    dist = np.hypot(frame.beam_point[hit, 0] - x, frame.beam_point[hit, 1] - y)
    np.testing.assert_allclose(dist, frame.beam_true_range[hit], atol=1e-9)
    assert np.isnan(frame.beam_point[~hit]).all()
    assert frame.scan.stamp == frame.time and frame.scan.odometry == frame.odometry_pose
    path = tmp_path / "maze.toml"
    scene.save(path)
    again = sim.Simulator(sim.load_scene(path), seed=4)
    assert (again[k].scan.ranges == frame.scan.ranges).all()
    np.testing.assert_array_equal(again.walls, a.walls)


def test_scoring_follows_the_protocol():
    simulator = sim.Simulator(sim.generate_maze(7), seed=1)
    detector = pcaline.LineDetector()
    score, same, oracle = eval.DetectionScore(), eval.DetectionScore(), eval.DetectionScore()
    for k in range(0, len(simulator), 200):
        frame = simulator[k]
        lines = detector.detect_scan(frame.scan).lines
        score.add(frame, lines)
        same.add(frame, pcaline.Lines.from_endpoints(lines.start, lines.end))
        oracle.add(frame, eval.true_walls(frame))
    assert score.counts["scans"] == len(range(0, len(simulator), 200))
    assert score.recall > 0.9 and score.false_positive_fraction < 0.05
    assert oracle.recall == 1.0 and oracle.false_positive_fraction == 0.0
    assert same.counts == score.counts
    assert oracle.alpha_error[1] < 1e-9


def test_a_mount_returns_the_vehicles_pose():
    """LIDAR-only mode works in the sensor's frame: a mount changes only the
    poses returned, by exactly the mount."""
    simulator = sim.Simulator(sim.generate_maze(5, cols=2, rows=2), seed=3)
    plain = pcaline.Mapper(loop_closure=False)
    mounted = pcaline.Mapper(loop_closure=False, mount=(0.3, 0.0, np.pi / 2))
    for k in range(0, 60, 3):
        scan = simulator[k].scan
        (x, y, h), (vx, vy, vh) = plain.step(scan).pose, mounted.step(scan).pose
        # vehicle = sensor o inverse(mount): 0.3 m behind the sensor's x axis,
        # turned a quarter back.
        back = h - np.pi / 2
        np.testing.assert_allclose([vx, vy], [x - 0.3 * np.cos(back), y - 0.3 * np.sin(back)], atol=1e-9)
        assert abs(np.angle(np.exp(1j * (vh - back)))) < 1e-9
    with pytest.raises(ValueError, match="mount"):
        pcaline.Mapper(mount=(0.0, float("nan"), 0.0))
