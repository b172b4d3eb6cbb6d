"""The Python package gives what the Rust command gives on the same scans:
the same lines to 1e-9 on every shared real log, and the same map after a
simulated run."""

import itertools
import json

import numpy as np
import pytest

import pcaline
from pcaline import sim
from conftest import cli_detections, run_cli

TOL = 1e-9

LOGS = [
    "single-scans/laser_scan_1.json",
    "single-scans/laser_scan_4.json",
    "intel/intel.gfs.log",
    "ros1/laser_scan_matcher_demo.bag",
    "utm30lx-ros2",
]


def assert_same_lines(lines: pcaline.Lines, records: list, where: str) -> None:
    assert len(lines) == len(records), where
    if not records:
        return
    def col(key):
        return np.array([r[key] for r in records], dtype=float)
    for name, ours, theirs in [
        ("alpha", lines.alpha, col("alpha_rad")),
        ("d", lines.d, col("d_m")),
        ("start", lines.start, np.array([r["start"] for r in records])),
        ("end", lines.end, np.array([r["end"] for r in records])),
        ("length", lines.length, col("length_m")),
        ("residual_std", lines.residual_std, col("residual_std_m")),
        ("residual_ratio", lines.residual_ratio, col("residual_ratio")),
        ("runs_z", lines.runs_z, col("runs_z")),
        ("bow_m", lines.bow_m, col("bow_m")),
    ]:
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=TOL, err_msg=f"{where}: {name}")
    assert (lines.n_points == col("n_points")).all(), where
    assert (lines.first_beam == col("first_beam")).all(), where
    assert (lines.last_beam == col("last_beam")).all(), where


@pytest.mark.parametrize("config", ["default", "paper", "adaptive"])
@pytest.mark.parametrize("log", LOGS)
def test_lines_of_every_scan_match_the_command(data, pcaline_bin, log, config):
    path = data / log
    expected = cli_detections(pcaline_bin, str(path), "--config", config)
    detector = pcaline.LineDetector(config)
    scans = list(pcaline.read_log(path))
    assert len(scans) == len(expected) > 0
    for k, (scan, record) in enumerate(zip(scans, expected)):
        assert scan.position == record["position"]
        assert_same_lines(detector.detect_scan(scan).lines, record["lines"], f"{log} scan {k}")


def test_numpy_input_in_any_form_gives_the_scan_lines(data, pcaline_bin):
    """float32, float64, a list and a strided view of the same ranges."""
    scan = next(iter(pcaline.read_log(data / "single-scans" / "laser_scan_2.json")))
    expected = cli_detections(pcaline_bin, str(data / "single-scans" / "laser_scan_2.json"))[0]
    header = (scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max)
    r32 = scan.ranges
    strided = np.repeat(r32, 2)[::2]
    assert not strided.flags["C_CONTIGUOUS"] or strided.strides != r32.strides
    detector = pcaline.LineDetector()
    for ranges in [r32, r32.astype(np.float64), r32.tolist(), strided]:
        assert_same_lines(detector.detect(ranges, *header).lines, expected["lines"], type(ranges).__name__)


def test_keyword_overrides_are_the_configuration_file(tmp_path, data, pcaline_bin):
    config = tmp_path / "strict.toml"
    config.write_text('preset = "default"\n[detector.fitting]\neth = 30.0\nmin_line_points = 12\n')
    log = data / "single-scans" / "laser_scan_3.json"
    expected = cli_detections(pcaline_bin, str(log), "--config", str(config))[0]["lines"]
    scan = next(iter(pcaline.read_log(log)))
    by_path = pcaline.LineDetector(fitting__eth=30.0, fitting__min_line_points=12)
    by_dict = pcaline.LineDetector("default", fitting={"eth": 30, "min_line_points": 12})
    by_file = pcaline.LineDetector(config)
    assert by_path.config == by_dict.config == by_file.config
    assert by_path.config != pcaline.LineDetector().config
    for detector in (by_path, by_dict, by_file):
        assert_same_lines(detector.detect_scan(scan).lines, expected, repr(detector))


def test_the_map_of_a_simulated_run_is_the_commands(root, tmp_path, pcaline_bin):
    """`pcaline run` (the embedded paper-like maze, seed 1, the default:
    estimator and loop closure) against `Mapper` fed the same frames."""
    run_cli(pcaline_bin, "run", "--seed", "1", "--out", str(tmp_path))
    expected = json.loads((tmp_path / "map.json").read_text())["lines"]
    simulator = sim.Simulator(sim.load_scene(root / "sim-scenes" / "paper-maze.toml"), seed=1)
    mapper = pcaline.Mapper()
    for k in range(len(simulator)):
        frame = simulator[k]
        mapper.step(frame.scan, frame.odometry_pose)
    assert mapper.optimize() is not None
    lines = mapper.map
    assert len(lines) == len(expected) > 0
    assert (lines.id == [r["id"] for r in expected]).all()
    assert lines.status == [r["status"] for r in expected]
    assert (lines.observations == [r["observations"] for r in expected]).all()
    assert (lines.n_points == [r["n_points"] for r in expected]).all()
    np.testing.assert_allclose(lines.alpha, [r["alpha"] for r in expected], rtol=0, atol=TOL)
    np.testing.assert_allclose(lines.d, [r["d"] for r in expected], rtol=0, atol=TOL)
    np.testing.assert_allclose(lines.start, [r["start"] for r in expected], rtol=0, atol=TOL)
    np.testing.assert_allclose(lines.end, [r["end"] for r in expected], rtol=0, atol=TOL)
    cov = np.array([r["covariance"] for r in expected]).reshape(-1, 2, 2)
    np.testing.assert_allclose(lines.covariance, cov, rtol=0, atol=TOL)


def test_a_csv_log_reads_and_detects_as_the_command_reads_it(data, pcaline_bin, tmp_path):
    """The UTM-30LX-EW bag's first scans written as CSV (float32 ranges
    written exactly), read back by read_log and compared with the bag and
    with `pcaline detect` on the CSV."""
    scans = list(itertools.islice(pcaline.read_log(data / "utm30lx-ros2"), 20))
    csv = tmp_path / "scans.csv"
    with csv.open("w") as f:
        f.write("stamp_s,angle_min,angle_increment,range_min,range_max,ranges...\n")
        for s in scans:
            head = [s.stamp, s.angle_min, s.angle_increment, s.range_min, s.range_max]
            cells = [repr(float(v)) for v in head] + [repr(float(r)) for r in s.ranges]
            f.write(",".join(cells) + "\n")
    back = list(pcaline.read_log(csv))
    assert len(back) == len(scans)
    for a, b in zip(scans, back):
        valid = np.isfinite(a.ranges)
        assert (np.isfinite(b.ranges) == valid).all()
        assert (a.ranges[valid] == b.ranges[valid]).all()
        assert (a.angle_min, a.angle_increment) == (b.angle_min, b.angle_increment)
    expected = cli_detections(pcaline_bin, str(csv))
    detector = pcaline.LineDetector()
    for k, (scan, record) in enumerate(zip(back, expected)):
        assert_same_lines(detector.detect_scan(scan).lines, record["lines"], f"csv scan {k}")
