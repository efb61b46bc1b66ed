"""hapticrom reference solver: axisymmetric Fourier-mode finite elements of layered tissue.

Public entry points, importable from here: :func:`load_scene` / :func:`scene_from_dict` to
read a scene (``fem.scene``), :func:`simulate` to solve it (``fem.simulation``). Importing
``fem`` itself is cheap: the names below are loaded on first use (no numpy, scipy, plotting or
VTK at import time).
"""

from __future__ import annotations

import importlib
from typing import Any

SOLVER_VERSION = "0.1.0"

# public name -> module that defines it (loaded lazily by __getattr__; no import of them here,
# not even for type checkers: the solver's modules import SOLVER_VERSION from this face, so
# the face importing them back would be a circle)
_LAZY = {
    "LoadKind": "fem.scene",
    "Scene": "fem.scene",
    "SceneError": "fem.scene",
    "dump_scene_toml": "fem.scene",
    "load_scene": "fem.scene",
    "scene_from_dict": "fem.scene",
    "scene_hash": "fem.scene",
    "scene_to_dict": "fem.scene",
    "Material": "fem.materials",
    "get_material": "fem.materials",
    "SimulationResult": "fem.simulation",
    "simulate": "fem.simulation",
    "SweepResult": "fem.sweep",
}

__all__ = [
    "SOLVER_VERSION",
    "LoadKind",
    "Material",
    "Scene",
    "SceneError",
    "SimulationResult",
    "SweepResult",
    "dump_scene_toml",
    "get_material",
    "load_scene",
    "scene_from_dict",
    "scene_hash",
    "scene_to_dict",
    "simulate",
]

def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'fem' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
