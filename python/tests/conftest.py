"""Shared fixtures: the repository, the `pcaline` binary the Python results
are compared with, and the shared real logs.

Missing data or a missing binary is a loud skip, counted in pytest's
summary; with ``CI=true`` it is a failure.
"""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
IN_CI = os.environ.get("CI") == "true"


def _missing(what: str):
    if IN_CI:
        pytest.fail(f"{what} (CI=true: required)")
    pytest.skip(f"SKIPPED, {what}")


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def pcaline_bin() -> pathlib.Path:
    """The command-line tool: $PCALINE_BIN, else target/release/pcaline."""
    path = pathlib.Path(os.environ.get("PCALINE_BIN", ROOT / "target" / "release" / "pcaline"))
    if not path.is_file():
        _missing(f"no pcaline binary at {path} (cargo build --release -p pcaline-cli)")
    return path


@pytest.fixture(scope="session")
def data() -> pathlib.Path:
    """The shared real logs: $PCALINE_DATA, else ../shared/data."""
    path = pathlib.Path(os.environ.get("PCALINE_DATA", ROOT.parent / "shared" / "data"))
    if not path.is_dir():
        _missing(f"no shared data at {path} (set PCALINE_DATA)")
    return path


def run_cli(binary: pathlib.Path, *args: str) -> str:
    """Runs the pcaline binary; its stdout."""
    done = subprocess.run(
        [str(binary), "-q", *args], capture_output=True, text=True, check=False, cwd=ROOT
    )
    assert done.returncode == 0, f"pcaline {' '.join(args)}: {done.stderr}"
    return done.stdout


def cli_detections(binary: pathlib.Path, *args: str) -> list:
    """`pcaline detect ARGS` as a list of per-scan records (JSON Lines)."""
    return [json.loads(line) for line in run_cli(binary, "detect", *args).splitlines()]
