"""hapticrom reference solver: axisymmetric Fourier-mode finite elements of layered tissue.

Public entry points: ``fem.scene.load_scene`` / ``scene_from_dict`` to read a scene and
``fem.simulate.simulate`` to solve it. Importing ``fem`` itself is cheap (no plotting, no VTK).
"""

SOLVER_VERSION = "0.1.0"

__all__ = ["SOLVER_VERSION"]
