"""pcaline: PCA-based line detection from 2D LIDAR range data, a line map and
localization aiding, a simulated Hokuyo UTM-30LX-EW and evaluation against
ground truth, from numpy.

>>> import numpy as np, pcaline
>>> angles = np.radians(np.arange(-30, 30.25, 0.25))
>>> ranges = 2.0 / np.cos(angles)          # a wall 2 m ahead
>>> det = pcaline.LineDetector().detect(ranges, angles[0], np.radians(0.25))
>>> len(det.lines), round(float(det.lines.d[0]), 6)
(1, 2.0)

Submodules: :mod:`pcaline.sim` (scenes, mazes, the simulator) and
:mod:`pcaline.eval` (scoring against ground truth).
"""

from ._pcaline import (
    Detection,
    FormatError,
    LineDetector,
    Lines,
    LogReader,
    Mapper,
    Scan,
    Step,
    __version__,
    read_log,
)
from . import eval, sim

__all__ = [
    "Detection",
    "FormatError",
    "LineDetector",
    "Lines",
    "LogReader",
    "Mapper",
    "Scan",
    "Step",
    "__version__",
    "eval",
    "read_log",
    "sim",
]
