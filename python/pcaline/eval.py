"""Scoring against ground truth with the project's protocol (``pcaline eval``).

>>> import pcaline
>>> from pcaline import sim, eval
>>> simulator = sim.Simulator(sim.generate_maze(7), seed=1)
>>> detector, score = pcaline.LineDetector(), eval.DetectionScore()
>>> for k in range(0, len(simulator), 50):
...     frame = simulator[k]
...     score.add(frame, detector.detect_scan(frame.scan).lines)
>>> score.recall > 0.8
True
"""

from ._pcaline import DetectionScore, trajectory_errors, true_walls

__all__ = ["DetectionScore", "trajectory_errors", "true_walls"]
