"""Bad input gets a Python exception that names the argument, field or file:
`ValueError` for arguments and configurations, `pcaline.FormatError` (a
`ValueError`) for malformed files; never a Rust panic."""

import math

import numpy as np
import pytest

import pcaline
from pcaline import eval, sim

HEADER = (-1.0, 0.01)


@pytest.fixture(scope="module")
def detector():
    return pcaline.LineDetector()


def test_format_error_is_a_value_error():
    assert issubclass(pcaline.FormatError, ValueError)


@pytest.mark.parametrize(
    "ranges, message",
    [
        (np.zeros((3, 3)), "1-D"),
        (np.zeros((0, 2)), "1-D"),
        (np.array(["a", "b"]), "dtype"),
        (np.array([1 + 2j]), "dtype"),
        (np.array([object()]), "dtype"),
        ([1.0, "x"], "sequence of numbers"),
        ("1,2,3", "sequence of numbers"),
        (None, "sequence of numbers"),
        ({"a": 1}, "sequence of numbers"),
    ],
)
def test_bad_arrays_are_value_errors_naming_the_argument(detector, ranges, message):
    with pytest.raises(ValueError, match=message) as e:
        detector.detect(ranges, *HEADER)
    assert "ranges" in str(e.value)


@pytest.mark.parametrize(
    "ranges",
    [
        np.array([], dtype=np.float32),
        np.full(500, np.nan),
        np.full(500, np.inf),
        np.full(500, -1.0),
        np.array([np.nan, 1.0, np.inf, -np.inf, 1e30, 0.0] * 50),
        np.arange(500, dtype=np.int64),
        np.arange(500, dtype=np.float16),
    ],
)
def test_invalid_ranges_are_data_not_errors(detector, ranges):
    det = detector.detect(ranges, *HEADER, range_min=0.1, range_max=30.0)
    assert len(det.lines) <= 1
    assert np.isfinite(det.points).all()
    assert (det.point_ranges >= 0.1).all() and (det.point_ranges <= 30.0).all()


@pytest.mark.parametrize(
    "header, message",
    [
        ((math.nan, 0.01), "angle_min"),
        ((0.0, 0.0), "angle_increment"),
        ((0.0, math.inf), "angle_increment"),
        ((0.0, 1.0), "more than a turn"),
    ],
)
def test_impossible_headers_are_value_errors(detector, header, message):
    with pytest.raises(ValueError, match=message):
        detector.detect(np.ones(100), *header)


def test_range_limits_and_stamp_are_checked(detector):
    with pytest.raises(ValueError, match="range_max"):
        detector.detect(np.ones(10), *HEADER, range_min=5.0, range_max=1.0)
    with pytest.raises(ValueError, match="range_min"):
        detector.detect(np.ones(10), *HEADER, range_min=-1.0)
    with pytest.raises(ValueError, match="stamp"):
        detector.detect(np.ones(10), *HEADER, stamp=math.nan)
    with pytest.raises(ValueError, match="range_max"):
        pcaline.Scan(np.ones(10), *HEADER, range_max=math.nan)


@pytest.mark.parametrize(
    "config, overrides, message",
    [
        ("no-such-preset", {}, "neither a preset"),
        ("default", {"fitting__eht": 30}, "detector.fitting.eht"),
        ("default", {"fitting__eth": "x"}, "detector.fitting.eth"),
        ("default", {"fitting__eth": -1}, "`detector.fitting.eth`"),
        ("default", {"fitting": {"eth": [1, 2]}}, "detector.fitting.eth"),
        ("default", {"fitting__eth": object()}, "fitting__eth"),
        (3, {}, "preset name or a configuration file"),
    ],
)
def test_bad_configurations_name_the_field(config, overrides, message):
    with pytest.raises(ValueError, match=message):
        pcaline.LineDetector(config, **overrides)


def test_a_malformed_configuration_file_names_the_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('preset = "default"\n[detector.fitting]\neth = \n')
    with pytest.raises(ValueError, match="bad.toml"):
        pcaline.LineDetector(bad)
    with pytest.raises(ValueError, match="map.max_offset_mm"):
        pcaline.Mapper(map__max_offset_mm=0.2)
    with pytest.raises(ValueError, match="aiding"):
        pcaline.Mapper(aiding="kalman")


def test_a_malformed_log_is_a_format_error_naming_file_and_line(tmp_path):
    log = tmp_path / "bad.clf"
    ranges = " ".join(["1.0"] * 180)
    good = f"FLASER 180 {ranges} 0 0 0 0 0 0 1.0 host 1.0"
    bad = good.replace("1.0 1.0 1.0", "1.0 oops 1.0", 1)
    log.write_text(f"{good}\n{good}\n{bad}\n")
    reader = pcaline.read_log(log)
    first = [next(reader), next(reader)]
    assert [s.position for s in first] == [1, 2]
    with pytest.raises(pcaline.FormatError, match=r"bad\.clf:3"):
        next(reader)


def test_missing_files_and_bad_options(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing.bag"):
        pcaline.read_log(tmp_path / "nothing.bag")
    (tmp_path / "x.clf").write_text("")
    with pytest.raises(ValueError, match="format"):
        pcaline.read_log(tmp_path / "x.clf", format="rosbag")
    with pytest.raises(ValueError, match="fov"):
        pcaline.read_log(tmp_path / "x.clf", fov=400)
    with pytest.raises(ValueError, match="max_range"):
        pcaline.read_log(tmp_path / "x.clf", max_range=-1)
    with pytest.raises(FileNotFoundError):
        sim.load_scene(tmp_path / "none.toml")
    scene = tmp_path / "scene.toml"
    scene.write_text('name = "x"\n[[walls]]\npoints = [[0, 0]]\n')
    with pytest.raises(pcaline.FormatError, match="scene.toml"):
        sim.load_scene(scene)


def test_mismatched_lengths_are_value_errors():
    with pytest.raises(ValueError, match="as many"):
        pcaline.Lines.from_endpoints(np.zeros((3, 2)), np.ones((2, 2)))
    with pytest.raises(ValueError, match=r"\(n, 2\)"):
        pcaline.Lines.from_endpoints(np.zeros((3, 3)), np.ones((3, 3)))
    with pytest.raises(ValueError, match="do not make a line"):
        pcaline.Lines.from_endpoints([[0.0, 0.0]], [[0.0, 0.0]])
    with pytest.raises(ValueError, match="as many"):
        eval.trajectory_errors(np.zeros((3, 3)), np.zeros((4, 3)))
    with pytest.raises(ValueError, match=r"truth\[0\]"):
        eval.trajectory_errors([(0, 0, 0)], [(math.nan, 0, 0)])
    with pytest.raises(ValueError, match="min_overlap"):
        eval.DetectionScore(min_overlap=2.0)


def test_mapper_and_simulator_arguments_are_checked(tmp_path):
    mapper = pcaline.Mapper()
    scan = pcaline.Scan(np.ones(100), *HEADER)
    with pytest.raises(ValueError, match="pose"):
        mapper.step(scan, (0.0, math.inf, 0.0))
    with pytest.raises(ValueError, match="cols"):
        sim.generate_maze(1, cols=0)
    simulator = sim.Simulator(sim.generate_maze(3, cols=2, rows=2))
    with pytest.raises(IndexError):
        simulator[len(simulator)]
