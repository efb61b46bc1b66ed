"""Which solver produced a dataset: its version and a numerical fingerprint.

A dataset records the solver that computed it so that rows from different solvers are never
mixed silently. Hashing the solver's source text (as earlier versions did) flagged every
docstring edit as a new solver; what matters is the numbers. The fingerprint solves a few small
canonical scenes that exercise the code paths a dataset uses (a static normal patch, a harmonic
tangential patch through the PML, a haptic unit with a silicone ring), rounds every output to
:data:`FINGERPRINT_DIGITS` significant digits and hashes them. Round-off from a reordered
factorisation does not change it; a change of physics, defaults or discretisation does.

Entries written before the fingerprint existed carry ``source_sha256`` instead; they are read
as they are and compared by that key (:func:`solver_key`).
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import subprocess
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

import fem
from fem.scene import scene_from_dict
from fem.simulation import simulate

__all__ = ["FINGERPRINT_DIGITS", "same_solver", "solver_fingerprint", "solver_info",
           "solver_key"]

#: Significant digits kept of every fingerprint output: far above round-off (1e-12 relative)
#: and far below any physical change worth recording.
FINGERPRINT_DIGITS = 6

_COARSE = {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1}
#: The canonical scenes (TOML-shaped dicts); small meshes, well under a second in all.
FINGERPRINT_SCENES: tuple[dict[str, Any], ...] = (
    {"analysis": {"kind": "static"}, "mesh": _COARSE, "tissue": {"radius_mm": 30.0},
     "load": {"kind": "pressure_patch", "direction": "normal", "radius_mm": 2.0}},
    {"analysis": {"kind": "harmonic", "frequency_hz": 150.0}, "mesh": _COARSE,
     "tissue": {"radius_mm": 30.0},
     "load": {"kind": "pressure_patch", "direction": "tangential", "radius_mm": 2.0}},
    {"analysis": {"kind": "harmonic", "frequency_hz": 120.0}, "mesh": _COARSE,
     "tissue": {"radius_mm": 30.0}, "load": {"kind": "unit"},
     "unit": {"encapsulation": [{"material": "dragon-skin-10-medium"}]}},
)


def _rounded(values: np.ndarray) -> list[str]:
    return [f"{v:.{FINGERPRINT_DIGITS - 1}e}" for v in np.asarray(values, dtype=float).ravel()]


@functools.cache
def solver_fingerprint() -> str:
    """sha256 of the rounded surface amplitudes of :data:`FINGERPRINT_SCENES` (computed once
    per process)."""
    outputs = []
    for scene in FINGERPRINT_SCENES:
        res = simulate(scene_from_dict(scene))
        outputs.append(_rounded(np.abs(res.U)))
        if res.center_amplitude_um is not None:
            outputs.append(_rounded(np.array([res.center_amplitude_um, res.edge_amplitude_um])))
    return hashlib.sha256(json.dumps(outputs).encode()).hexdigest()


def solver_info(git: bool = True) -> dict[str, Any]:
    """Identity of the installed solver: ``version`` (``fem.SOLVER_VERSION``),
    ``fingerprint`` (:func:`solver_fingerprint`), ``hash`` (its first 12 hex digits, stored per
    row) and ``git_revision`` (HEAD of the repository holding fem, "+dirty" with uncommitted
    changes under fem/; "unknown" outside git or with ``git=False``)."""
    fingerprint = solver_fingerprint()
    root = Path(fem.__file__).resolve().parent
    return {"version": str(fem.SOLVER_VERSION), "fingerprint": fingerprint,
            "hash": fingerprint[:12], "git_revision": _git_revision(root) if git else "unknown"}


def solver_key(entry: Mapping[str, Any]) -> tuple[str | None, str | None]:
    """(version, fingerprint) of a manifest solver entry; entries from before the fingerprint
    existed give (version, source_sha256)."""
    return entry.get("version"), entry.get("fingerprint") or entry.get("source_sha256")


def same_solver(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    """Whether two solver entries describe the same solver."""
    return solver_key(a) == solver_key(b)


def _git_revision(fem_dir: Path) -> str:
    # GIT_OPTIONAL_LOCKS=0: `git status` must not write to the index of the user's repository.
    env = {**os.environ, "GIT_OPTIONAL_LOCKS": "0"}
    try:
        rev = subprocess.run(["git", "-C", str(fem_dir), "rev-parse", "HEAD"], env=env,
                             capture_output=True, text=True, timeout=10)
        if rev.returncode != 0:
            return "unknown"
        dirty = subprocess.run(["git", "-C", str(fem_dir), "status", "--porcelain",
                                "--untracked-files=normal", "--", "."], env=env,
                               capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return rev.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")
