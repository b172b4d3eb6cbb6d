"""Python's calling overhead on line detection, measured against Rust.

The scan is the detection bench's 1081-beam scan (benches/detection.rs: the
office scene, seed 1, the frame a third of the way along), given as a
float32 numpy array. In the same process, interleaved, it times

- ``LineDetector.detect(ranges, ...)`` called from Python, result included;
- the same detection looped in Rust (``_seconds_per_detection``).

and prints the per-call times and their ratio (the target: <= 2x). The
machine is noisy: the ratio is the median of several rounds, each round
timing both sides back to back.

    python python/bench/overhead.py [--rounds 15] [--calls 2000]
"""

import argparse
import pathlib
import statistics
import time

import numpy as np

import pcaline
from pcaline import sim

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--config", default="default")
    parser.add_argument("--dtype", default="float32", choices=["float32", "float64"])
    args = parser.parse_args()

    simulator = sim.Simulator(sim.load_scene(ROOT / "sim-scenes" / "office-clutter.toml"), seed=1)
    scan = simulator[len(simulator) // 3].scan
    ranges = np.ascontiguousarray(scan.ranges, dtype=args.dtype)
    header = (scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max)
    detector = pcaline.LineDetector(args.config)
    lines = len(detector.detect(ranges, *header).lines)

    python_us, rust_us = [], []
    for _ in range(args.rounds):
        start = time.perf_counter()
        for _ in range(args.calls):
            detector.detect(ranges, *header)
        python_us.append((time.perf_counter() - start) / args.calls * 1e6)
        rust_us.append(detector._seconds_per_detection(scan, args.calls) * 1e6)
    ratios = [p / r for p, r in zip(python_us, rust_us)]
    print(f"scan: {len(ranges)} beams ({args.dtype}), {lines} lines, config {args.config!r}")
    print(f"python detect(): {statistics.median(python_us):8.2f} us per call (median of {args.rounds} rounds)")
    print(f"rust detect():   {statistics.median(rust_us):8.2f} us per call")
    print(f"ratio python/rust: {statistics.median(ratios):.3f} (rounds: {min(ratios):.3f}-{max(ratios):.3f})")


if __name__ == "__main__":
    main()
