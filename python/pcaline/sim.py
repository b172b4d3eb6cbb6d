"""Scenes and the simulated Hokuyo UTM-30LX-EW with exact ground truth.

>>> from pcaline import sim
>>> scene = sim.generate_maze(7)
>>> simulator = sim.Simulator(scene, seed=1)
>>> frame = simulator[0]
>>> len(frame.scan), int((frame.beam_wall >= 0).sum()) > 0
(1081, True)
"""

from ._pcaline import Frame, Scene, Simulator, generate_maze

load_scene = Scene.load
"""Loads a scene file (TOML, or JSON by extension); the same as ``Scene.load``."""

__all__ = ["Frame", "Scene", "Simulator", "generate_maze", "load_scene"]
