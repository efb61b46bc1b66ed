"""A small sweep model on the inputs of ``datasets/spaces/default-sweep.toml`` (shared by the
tests of the model's consumers: planner, calibration, the envelope model, the defaults).

The dataset is synthetic, in the real format (no FE: the fixture must be fast and the CPU is
shared): the default sweep space coarsened to a 10 Hz band and a 4 mm profile grid (0-40 mm),
each design's complex response a damped resonance over the band whose surface profile decays
with distance and turns with a shear wave, smooth in every input. It serves contracts (inputs,
band, a 40 mm profile, the normal component), not accuracy.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
SPACE_FILE = REPO / "datasets" / "spaces" / "default-sweep.toml"
BAND = {"start": 100.0, "stop": 250.0, "step": 10.0}
PROFILE_STEP_MM = 4.0
#: a small network: 16 x 16, three members, a few stage-2 epochs (seconds to train)
OPTIONS = {"hidden": (16, 16), "n_members": 3, "max_epochs": 60, "centre_modes": 6,
           "refit_epochs": 4, "refit_patience": 2}


def coarse_space_dict(seed: int | None = None) -> dict[str, Any]:
    """The default sweep space with a coarser band and profile grid (same inputs, 40 mm), at
    its own Sobol seed unless ``seed`` is given."""
    d = tomllib.loads(SPACE_FILE.read_text())
    d["space"]["name"] = "default-sweep-coarse"
    if seed is not None:
        d["space"]["seed"] = seed
    d["band"] = {**BAND}
    d["base"]["output"]["profile_step_mm"] = PROFILE_STEP_MM
    return d


def response(values: dict[str, Any], band_hz: np.ndarray, grid_mm: np.ndarray,
             edge_mm: float) -> SimpleNamespace:
    """The fields of ``fem.sweep.SweepResult`` [m] of one design (see the module docstring)."""
    stiff = (values["skin_E_kPa"] / 50.0) ** 0.5 * (1.0 + 0.1 * values["n_rings"])
    fn_hz = 150.0 * stiff ** 0.3 * (1.1 if values["attachment"] == "pogo" else 1.0)
    eta = values["tissue_loss_factor"]
    f = band_hz / fn_hz
    a = (2.0 if values["orientation"] == "reverse" else 1.5) / (1.0 - f**2 + 1j * eta)
    centre = a[:, None] * np.array([0.3, 1.0, 0.05j])[None, :]          # (n_f, 3) um
    decay_mm = 6.0 + 0.4 * values["fat_thickness_mm"]
    k_per_mm = 2 * np.pi * band_hz / (5000.0 * stiff)                     # shear wave ~5 m/s
    shape = (0.6 * np.exp(-grid_mm[None, :] / decay_mm) / np.sqrt(1.0 + grid_mm[None, :] / edge_mm)
             * np.exp(-1j * k_per_mm[:, None] * grid_mm[None, :]))        # (n_f, n_p)
    profile = centre[:, None, :] * shape[:, :, None]
    return SimpleNamespace(frequency_hz=band_hz, center=1e-6 * centre, edge=1e-6 * profile[:, 0],
                           profile_mm=grid_mm, profile=1e-6 * profile, edge_mm=edge_mm,
                           error_estimate=1e-4, full_solves=2,
                           meta={"dofs": 100, "elements": 40, "warnings": []})


def make_dataset(path: Path, n: int, seed: int | None = None,
                 band: dict[str, float] | None = None) -> Path:
    """``n`` Sobol designs of the coarse space (``seed``: another Sobol seed; ``band``: another
    band), written as ``hapticrom generate`` writes."""
    from surrogate.data.provenance import solver_info
    from surrogate.data.space import space_from_dict
    from surrogate.data.store import Store, new_manifest
    from surrogate.data.worker import edge_radius_mm, outputs_from_result

    d = coarse_space_dict(seed)
    d["band"] = {**d["band"], **(band or {})}
    space = space_from_dict(d, check_scenes=False)
    b = d["band"]
    band_hz = np.round(np.arange(b["start"], b["stop"] + 1e-9, b["step"]), 9)
    grid_mm = np.arange(0.0, 40.0 + 1e-9, PROFILE_STEP_MM)
    manifest = {**new_manifest(space, solver_info(git=False)), "profile_grid_mm": grid_mm.tolist()}
    store = Store.create(path, space, **manifest)
    pts = space.points(0, n)
    rows = []
    for i in range(n):
        values = {k: (v[i].item() if hasattr(v[i], "item") else v[i]) for k, v in pts.items()}
        scene_json = json.dumps(space.resolve(values))
        res = response(values, band_hz, grid_mm, edge_radius_mm(scene_json))
        rows.append({**outputs_from_result(res), **values, "status": "ok",
                     "sample_id": f"{i:064x}", "sample_index": i, "source": "hapticrom-fem",
                     "scene_json": scene_json})
    with store.lock():
        store.write_part(rows)
    return path


#: the GP's options: 20 inducing designs of the ~38 fitted, so the variance's DTC factor has
#: the low-rank part it has on the shipped GP
GP_OPTIONS = {"centre_modes": 6, "inducing": 20}


def train_model(data: Path, out: Path, *, normal: bool = True, kind: str = "nn",
                options: dict[str, Any] | None = None) -> Path:
    """A small sweep model of ``kind`` with ``options`` (default: the network of
    :data:`OPTIONS`) on ``data`` at ``out`` (with the normal component when ``normal``)."""
    from surrogate.sweep.train import train_sweep

    outputs = ("profile_um", "profile_normal_um") if normal else ("profile_um",)
    train_sweep([data], kind, out, n_modes=8, options=dict(options or OPTIONS), outputs=outputs)
    return out
