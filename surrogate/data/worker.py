"""The worker side of generation: one scene dict in, one row of output columns out.

Plain JSON strings cross the process (or Dask) boundary, so no solver object is ever pickled,
and every sample is computed from its scene alone. Output columns are read from the typed
attributes of :class:`fem.simulation.SimulationResult`, so a renamed result field fails loudly
instead of storing nulls.
"""

from __future__ import annotations

import functools
import json
import time
import traceback
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

import fem
from fem.results import magnitude
from fem.scene import scene_from_dict
from surrogate.data.columns import complex_columns, sweep_columns
from surrogate.data.provenance import solver_info

__all__ = ["edge_radius_mm", "outputs_from_result", "run_chunk", "run_sample",
           "worker_solver_hash"]


def run_sample(scene: Mapping[str, Any]) -> dict[str, Any]:
    """Solve one scene dict; return output columns plus status, error, wall_s [s], dofs.

    Never raises for a bad sample: the exception becomes ``status = "failed"`` with its text.
    The result depends on the scene only."""
    t0 = time.perf_counter()
    try:
        out = outputs_from_result(_solve(scene_from_dict(scene)))
        bad = _non_finite(out)
        out["status"], out["error"] = ("failed", f"NonFiniteResult: {bad}") if bad else ("ok",
                                                                                         None)
    except Exception as err:  # a failed sample is data, not a crash
        out = {"status": "failed", "error": _error_text(err)}
    out["wall_s"] = time.perf_counter() - t0
    return out


def _solve(scene: Any) -> Any:
    """``fem.simulate``: a :class:`fem.simulation.SimulationResult`, or a
    ``fem.sweep.SweepResult`` for a sweep scene (the reduced-order sweep over its band)."""
    return fem.simulate(scene)


def run_chunk(payload: str) -> str:
    """Worker entry point: JSON list of scene dicts in; JSON ``{"solver": hash, "rows":
    [output dicts]}`` out, ``solver`` being the fingerprint of the solver this worker runs.

    Plain strings cross the process boundary, so no solver object is ever pickled."""
    rows = [run_sample(scene) for scene in json.loads(payload)]
    return json.dumps({"solver": worker_solver_hash(), "rows": rows})


@functools.cache
def worker_solver_hash() -> str:
    """The fingerprint of the solver this process runs (computed once per process)."""
    return str(solver_info(git=False)["fingerprint"])


def outputs_from_result(res: Any) -> dict[str, Any]:
    """Dataset output columns (amplitudes in um, distances in mm) of a
    :class:`fem.simulation.SimulationResult` (with the complex amplitudes of a harmonic or
    static result) or of a sweep result (:func:`surrogate.data.columns.sweep_columns`)."""
    if np.ndim(getattr(res, "frequency_hz", 0)) == 1:  # a sweep: one row holds the band
        return sweep_columns(res)

    out: dict[str, Any] = {
        "center_amplitude_um": res.center_amplitude_um,
        "edge_amplitude_um": res.edge_amplitude_um,
        "normalized_edge": res.normalized_edge,
        "edge_radius_mm": res.edge_mm,
        "profile_distance_mm": res.profile_mm.tolist(),
        "profile_uz_um": (np.abs(res.profile[:, 1]) * 1e6).tolist(),
        "profile_magnitude_um": (magnitude(res.profile) * 1e6).tolist(),
        "dofs": int(res.meta["dofs"]),
        "elements": int(res.meta["elements"]),
        "warnings": "; ".join(str(w) for w in res.meta.get("warnings", [])) or None,
    }
    h = res.histories
    if h is None:  # the harmonic steady state's complex amplitudes (static: real)
        cols = complex_columns(np.asarray(res.center), np.asarray(res.edge),
                               np.asarray(res.profile))
        if res.edge_mm is None:  # a point force: no centre or edge of a unit
            cols = {k: (None if k.startswith(("center_", "edge_")) else v)
                    for k, v in cols.items()}
        out.update(cols)
    if h is not None:
        probes = h.radii[: res.r_mm.size]
        out["history_t_s"] = h.t.tolist()
        out["history_r_mm"] = (probes * 1e3).tolist()
        out["history_uz_um"] = (h.u[:, : probes.size, 1].T * 1e6).tolist()
        out["history_magnitude_um"] = (magnitude(h.u[:, : probes.size]).T * 1e6).tolist()
        if res.edge_mm is not None:  # a unit: histories hold the probes, the center, the edge
            for i, name in enumerate(("center", "edge")):
                out[f"history_{name}_um"] = (h.u[:, probes.size + i, :].T * 1e6).tolist()
    return out


def edge_radius_mm(scene_json: str) -> float | None:
    """The unit's outer radius [mm] of a stored row's scene (the solver's one definition), for
    rows written before datasets stored ``edge_radius_mm``; None for a scene without a unit."""
    unit = scene_from_dict(json.loads(scene_json)).unit
    return None if unit is None else float(unit.outer_radius_mm)


def _non_finite(out: Mapping[str, Any]) -> str:
    for key, value in out.items():
        if value is None or isinstance(value, str):
            continue
        flat = _flat(value)
        if flat.size and not np.all(np.isfinite(flat)):
            return f"{key} contains NaN or inf"
    return ""


def _flat(value: Any) -> np.ndarray:
    if isinstance(value, list) and value and isinstance(value[0], list):
        return np.concatenate([_flat(v) for v in value])
    return np.asarray(value, dtype=float).ravel()


def _error_text(err: BaseException) -> str:
    text = "".join(traceback.format_exception_only(type(err), err)).strip()
    tb = traceback.extract_tb(err.__traceback__)
    if tb:
        frame = tb[-1]
        text += f" (at {Path(frame.filename).name}:{frame.lineno} in {frame.name})"
    return text


