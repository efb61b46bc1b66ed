"""Solving the cases: one scene dict in, the plain numbers the report needs out (:class:`Solved`),
on the shared process pool. Amplitudes in m inside, um in the derived properties."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import signal

from fem import simulate
from fem.scene import scene_from_dict, scene_hash
from surrogate.data.pool import process_map

from .cases import SCENES_DIR, Case, FollowUp, scene_dict
from .paper import LDV_BAND_HZ
from .solved import Solved, magnitude


def solve_scene(d: Mapping[str, Any]) -> Solved:
    """Build and solve one scene dict (worker side; plain data in and out)."""
    res = simulate(scene_from_dict(d))
    r_mm, surf = res.surface_curve()
    transient = None if res.histories is None else _transient_summary(res)
    if res.histories is not None:  # steady-looking values: the last two revolutions
        late = _late_peaks(res)
        centre, edge, axis, profile = late["centre"], late["edge"], late["axis"], late["profile"]
    else:
        centre, edge, profile = res.center, res.edge, res.profile
        axis = res.U[list(res.r_mm).index(0.0)] if 0.0 in res.r_mm else res.center * np.nan
    top = np.full(3, np.nan) if res.nodal is None else res.nodal[_top_of_axis(res.domain)]
    return Solved(float(res.edge_mm), centre, edge, axis, top, res.profile_mm, profile, r_mm, surf,
                  float(res.meta["wall_s"]), int(res.meta["dofs"]),
                  tuple(res.meta.get("warnings", ())), res.extras.get("preload"), transient)


def _top_of_axis(domain) -> int:
    """The highest mesh node on the axis: the motor's top face (nothing else reaches r = 0
    above the skin)."""
    nodes = domain.mesh.nodes
    on_axis = np.flatnonzero(np.abs(nodes[:, 0]) < 1e-12)
    return int(on_axis[np.argmin(nodes[on_axis, 1])])


def _late_peaks(res) -> dict[str, NDArray]:
    """Per-component peaks over the last two revolutions at each sampled point (m)."""
    h = res.histories
    a = h.amplitude(start=h.t[-1] - 2.0 / res.scene.unit.motor.rated_frequency_hz)
    n = res.r_mm.size
    axis = a[list(res.r_mm).index(0.0)] if 0.0 in res.r_mm else a[n] * np.nan
    return {"centre": a[n], "edge": a[n + 1], "axis": axis, "profile": a[n + 2:]}


def _transient_summary(res) -> dict:
    """Peaks over the whole run, over the last two revolutions, and over the last two
    revolutions after the paper's 40-200 Hz band-pass (um); the centre's mean displacement over
    the last revolution (a rigid drift); the centre and edge histories (um, every step)."""
    h = res.histories
    n = res.r_mm.size
    whole = h.amplitude()
    late = _late_peaks(res)
    revolution = 1.0 / res.scene.unit.motor.rated_frequency_hz
    sos = signal.butter(2, LDV_BAND_HZ, btype="bandpass", fs=1.0 / (h.t[1] - h.t[0]),
                        output="sos")
    band = signal.sosfiltfilt(sos, h.u[:, n:n + 2], axis=0)  # centre, edge
    in_late = h.t >= h.t[-1] - 2 * revolution
    band_peak = np.abs(band[in_late]).max(axis=0)
    drift = h.u[h.t >= h.t[-1] - revolution, n].mean(axis=0)
    return {
        "time_step_ms": float((h.t[1] - h.t[0]) * 1e3),
        "centre_band_um": float(magnitude(band_peak[0]) * 1e6),
        "edge_band_um": float(magnitude(band_peak[1]) * 1e6),
        "edge_z_band_um": float(band_peak[1, 1] * 1e6),
        "centre_drift_um": float(np.linalg.norm(drift) * 1e6),
        "centre_band_hist_um": (np.linalg.norm(band[:, 0], axis=-1) * 1e6).tolist(),
        "edge_band_hist_um": (np.linalg.norm(band[:, 1], axis=-1) * 1e6).tolist(),
        "duration_ms": float(h.t[-1] * 1e3),
        "centre_peak_um": float(magnitude(whole[n]) * 1e6),
        "edge_peak_um": float(magnitude(whole[n + 1]) * 1e6),
        "edge_z_peak_um": float(whole[n + 1, 1] * 1e6),
        "centre_late_um": float(magnitude(late["centre"]) * 1e6),
        "edge_late_um": float(magnitude(late["edge"]) * 1e6),
        "edge_z_late_um": float(late["edge"][1] * 1e6),
        "t_ms": (h.t * 1e3).tolist(),
        "centre_um": (np.linalg.norm(h.u[:, n], axis=-1) * 1e6).tolist(),
        "edge_um": (np.linalg.norm(h.u[:, n + 1], axis=-1) * 1e6).tolist(),
    }


def run_cases(cases: Mapping[str, Case], workers: int | None, scenes_dir: Path = SCENES_DIR,
              log: Callable[[str], None] = print,
              follow: FollowUp | None = None, progress: bool = True) -> dict[str, Solved]:
    """Solve every case once (names that are the same scene share one solve) with
    :func:`surrogate.data.pool.process_map` (``workers`` spawned processes, one BLAS thread
    each); transients (the longest) go first. Once the cases ``follow`` needs are solved,
    ``follow.make`` adds its cases as a second batch. Returns every named case, the follow-up's
    included. ``progress``: a bar with rate and ETA on stderr (when it is a terminal).
    Scripts must call this under ``if __name__ == "__main__":``."""
    if follow is not None and not set(follow.needs) <= set(cases):
        raise ValueError("follow-up needs cases that are not in the plan: "
                         + ", ".join(sorted(set(follow.needs) - set(cases))))
    key: dict[str, str] = {}  # name -> scene hash
    solved: dict[str, Solved] = {}

    def add(new: Mapping[str, Case]) -> dict[str, dict]:
        """Hash -> scene dict of the cases in ``new`` not yet known, in submission order."""
        todo: dict[str, dict] = {}
        for name in sorted(new, key=lambda n: (not new[n].transient, n)):
            if name in key:
                continue
            d = scene_dict(new[name], scenes_dir)
            key[name] = h = scene_hash(scene_from_dict(d))  # validates
            if h not in solved and h not in todo:
                todo[h] = d
        return todo

    def solve(todo: Mapping[str, dict], desc: str) -> None:
        results = process_map(solve_scene, list(todo.values()), workers=workers,
                              desc=desc if progress else None)
        solved.update(zip(todo, results, strict=True))

    solve(add(cases), "reproduce")
    if follow is not None:
        extra = add(follow.make({n: solved[key[n]] for n in follow.needs}))
        if extra:
            solve(extra, "reproduce, follow-up")
    log(f"  {len(solved)} distinct solves for {len(key)} named cases")
    return {name: solved[key[name]] for name in key}
