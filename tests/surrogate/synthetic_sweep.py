"""A tiny synthetic sweep dataset in the real format, with a response linear in frequency."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np

SPACE = {
    "space": {"name": "sweep-train", "seed": 5},
    "base": {"mesh": {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1,
                      "follow_wavelength": False},
             "output": {"profile_length_mm": 10.0, "profile_step_mm": 2.0}},
    "parameter": [
        {"name": "orientation", "type": "categorical", "path": "unit.orientation",
         "choices": ["forward", "reverse"]},
        {"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
         "low": 20.0, "high": 120.0, "scale": "log"},
        {"name": "fat_thickness_mm", "type": "continuous",
         "path": "tissue.layer[1].thickness_mm", "low": 3.0, "high": 15.0},
    ],
    "band": {"start": 100.0, "stop": 250.0, "step": 10.0},
}
BAND_HZ = np.round(100.0 + 10.0 * np.arange(16), 9)
GRID_MM = np.arange(0.0, 10.0 + 1e-9, 2.0)


def linear_sweep(orientation: str, E_kPa: float, fat_mm: float) -> SimpleNamespace:
    """The fields of fem.sweep.SweepResult [m] of a design: every complex component is linear
    in frequency, and smooth in the design (the unit's edge at 5.5 mm, reversed 6 mm)."""
    rev = orientation == "reverse"
    a, b = (E_kPa / 50.0) ** -0.3 * (1.2 if rev else 1.0), fat_mm / 10.0
    s = (BAND_HZ - 100.0) / 150.0
    c0 = a * np.array([1.0 + 0.5j, 0.3 - 0.2j, 0.1j])
    c1 = b * np.array([0.4 - 0.3j, -0.2 + 0.1j, 0.05 + 0.0j])
    centre = c0[None, :] + s[:, None] * c1[None, :]                       # (n_f, 3) um
    shape = 0.6 * np.exp(-GRID_MM / (4.0 + b)) * (1.0 + 0.1j * GRID_MM * a)  # (n_p,)
    profile = centre[:, None, :] * shape[None, :, None]
    return SimpleNamespace(frequency_hz=BAND_HZ, center=1e-6 * centre,
                           edge=1e-6 * profile[:, 0], profile_mm=GRID_MM,
                           profile=1e-6 * profile, edge_mm=6.0 if rev else 5.5, error_estimate=1e-4,
                           full_solves=2, meta={"dofs": 100, "elements": 40, "warnings": []})


def make_sweep_dataset(path: Path, n: int) -> Path:
    """A sweep dataset of ``n`` Sobol designs of :data:`SPACE`, written as generate writes."""
    from surrogate.data.provenance import solver_info
    from surrogate.data.space import space_from_dict
    from surrogate.data.store import Store, new_manifest
    from surrogate.data.worker import outputs_from_result

    space = space_from_dict(SPACE, check_scenes=False)
    manifest = {**new_manifest(space, solver_info(git=False)),
                "profile_grid_mm": GRID_MM.tolist()}
    store = Store.create(path, space, **manifest)
    pts = space.points(0, n)
    rows = []
    for i in range(n):
        values = {k: (v[i].item() if hasattr(v[i], "item") else v[i]) for k, v in pts.items()}
        res = linear_sweep(values["orientation"], values["skin_E_kPa"],
                           values["fat_thickness_mm"])
        rows.append({**outputs_from_result(res), **values, "status": "ok",
                     "sample_id": f"{i:064x}", "sample_index": i, "source": "hapticrom-fem",
                     "scene_json": json.dumps(space.resolve(values))})
    with store.lock():
        store.write_part(rows)
    return path
