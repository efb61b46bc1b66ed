"""Tiny synthetic datasets with a known smooth answer, in the real dataset format."""

from __future__ import annotations

import json

import numpy as np

SPACE = {
    "space": {"name": "synthetic", "sampler": "sobol", "seed": 7},
    "base": {"load": {"kind": "unit"}, "analysis": {"kind": "harmonic"},
             "unit": {"encapsulation": ["ecoflex-00-10", "dragon-skin-30"]}},
    "parameter": [
        {"name": "orientation", "type": "categorical", "path": "unit.orientation",
         "choices": ["forward", "reverse"]},
        {"name": "n_rings", "type": "integer", "path": "unit.encapsulation",
         "map": "list_length", "low": 0, "high": 2},
        {"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
         "low": 20.0, "high": 120.0, "scale": "log"},
        {"name": "frequency_hz", "type": "continuous", "path": "analysis.frequency_hz",
         "low": 100.0, "high": 250.0},
    ],
}
GRID_MM = np.linspace(0.0, 20.0, 11)


def synthetic_amplitudes(orientation: np.ndarray, n_rings: np.ndarray, E_kPa: np.ndarray,
                         f_hz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A smooth known answer: (center (n,), profile (n, m)) in um."""
    rev = (orientation == "reverse").astype(float)
    center = 10.0 * (E_kPa / 50.0) ** -0.3 * (1 + 0.2 * rev) * np.exp(-0.1 * n_rings) \
        * (f_hz / 150.0) ** 0.5
    decay = 5.0 + n_rings[:, None] + 0.01 * f_hz[:, None]
    profile = 0.8 * center[:, None] * np.exp(-GRID_MM[None, :] / decay)
    return center, profile


def synthetic_normal(profile: np.ndarray, E_kPa: np.ndarray) -> np.ndarray:
    """A smooth known normal component |u_z| (n, m) [um] below the magnitude ``profile``."""
    return profile * (0.55 + 0.3 * np.cos(GRID_MM[None, :] / 6.0 + E_kPa[:, None] / 80.0))


def make_dataset(path, n: int, start: int = 0, reverse: bool = False, normal: bool = False):
    """Write a synthetic dataset of ``n`` Sobol points at ``path``; returns the path.
    ``reverse`` stores the rows last first, one part per row (as workers finishing out of
    order would); ``normal`` stores ``profile_uz_um`` (:func:`synthetic_normal`) too."""
    from surrogate.data.space import space_from_dict
    from surrogate.data.store import Store

    space = space_from_dict(SPACE)
    pts = space.points(start, n)
    center, profile = synthetic_amplitudes(pts["orientation"], pts["n_rings"].astype(float),
                                           pts["skin_E_kPa"], pts["frequency_hz"])
    uz = synthetic_normal(profile, pts["skin_E_kPa"])
    store = Store.create(path, space, profile_grid_mm=GRID_MM.tolist())
    rows = []
    for i in range(n):
        values = {k: (v[i].item() if hasattr(v[i], "item") else v[i]) for k, v in pts.items()}
        rows.append({"sample_id": f"s{start + i}", "sample_index": start + i, "status": "ok",
                     "source": "hapticrom-fem", "scene_json": json.dumps(space.resolve(values)),
                     **values, "center_amplitude_um": center[i],
                     "edge_amplitude_um": profile[i, 0],
                     "normalized_edge": profile[i, 0] / center[i],
                     "profile_distance_mm": GRID_MM.tolist(),
                     "profile_magnitude_um": profile[i].tolist(),
                     **({"profile_uz_um": uz[i].tolist()} if normal else {})})
    with store.lock():
        if reverse:
            for row in reversed(rows):
                store.write_part([row])
        else:
            store.write_part(rows)
    return path
