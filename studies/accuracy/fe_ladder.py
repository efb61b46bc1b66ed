"""The FE solver's own accuracy ladder: mesh level and element order against a converged
reference, and the transient steady state against the harmonic answer.

Level 1 is the default mesh (0.5 mm elements near the axis, 2 mm beyond; see
:class:`fem.scene.model.MeshSettings`); level f scales both sizes by f. Ladder scenes turn
``mesh.follow_wavelength`` off so the level alone sets the mesh; the row "default mesh" is the
scene exactly as the dataset solved it (wavelength-following on). The reference is quadratic
elements at :data:`REF_LEVEL` (``--quick``: :data:`REF_LEVEL_QUICK`).
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any

import numpy as np

from fem import SceneError, scene_from_dict, simulate
from fem.scene.model import Analysis, MeshSettings
from fem.scene.unit_model import Motor

from .designs import Design
from .metric import Answer, answer_from_result, errors, summary
from .timing import timed

__all__ = ["LEVELS", "LEVELS_QUICK", "REF_LEVEL", "REF_LEVEL_QUICK", "TRANSIENT", "fe_ladder",
           "reference_answers", "scene_at", "solve", "transient_answer", "transient_rows"]

#: Mesh levels of the ladder (x the default element sizes) and of the reference; the
#: reference is quadratic elements at a third of the default sizes (the forearm bench shows
#: the order-2 error falling below 1e-3 already at level 1, so level 1/3 is converged well
#: below the errors the ladder measures).
LEVELS = (2.0, 1.0, 0.5)
LEVELS_QUICK = (2.0, 1.0)
REF_LEVEL = 1.0 / 3.0
REF_LEVEL_QUICK = 0.5
#: Transient runs: step [ms], duration [ms], steady window at the end [ms] (>= one period at
#: the space's lowest frequency, 100 Hz), element order. Order 1 and a 0.2 ms step are the
#: discretisation of datasets/transient (datasets/README.md). The duration was measured: after
#: an instant start the response of the lightly damped unit still carries the start-up at 40 ms
#: (peaks 4-13 % above the harmonic answer on two designs, also with a 0.05 ms step), and is
#: within 0.5 % of it at 100 ms.
TRANSIENT = {"time_step_ms": 0.2, "duration_ms": 100.0, "window_ms": 10.0, "order": 1}


def scene_at(base: dict[str, Any], level: float | None, order: int) -> dict[str, Any]:
    """A copy of scene dict ``base`` at mesh ``level`` (None: the base mesh as is) and
    element ``order``."""
    d = copy.deepcopy(base)
    mesh = d.setdefault("mesh", {})
    mesh["order"] = order
    if level is not None:
        m = MeshSettings()
        mesh.update(near_size_mm=m.near_size_mm * level, far_size_mm=m.far_size_mm * level,
                    follow_wavelength=False)
    return d


def solve(scene: dict[str, Any], grid_mm: np.ndarray, repeat: int) -> tuple[Answer, float, int]:
    """(answer, median wall time [s] of the full solve, unknowns) of a harmonic scene dict."""
    sc = scene_from_dict(scene)
    res, t = timed(lambda: simulate(sc), repeat)
    return answer_from_result(res, grid_mm), t, int(res.meta["dofs"])


def reference_answers(designs: Sequence[Design], grid_mm: np.ndarray,
                      ref_level: float) -> tuple[list[Answer], list[int]]:
    """Converged answers (quadratic elements at ``ref_level``) of every design, and unknowns."""
    refs, dofs = [], []
    for des in designs:
        a, _, n = solve(scene_at(des.scene, ref_level, 2), grid_mm, 1)
        refs.append(a)
        dofs.append(n)
    return refs, dofs


def fe_ladder(designs: Sequence[Design], refs: Sequence[Answer], grid_mm: np.ndarray,
              levels: Sequence[float], repeat: int) -> list[dict[str, Any]]:
    """One row per (order, level) and the default mesh: median time per answer over the
    designs [s], median unknowns, and the error summary against ``refs``."""
    rows = []
    cases = [(o, lv) for o in (1, 2) for lv in levels] + [(2, None)]
    for order, level in cases:
        errs, times, dofs = [], [], []
        for des, ref in zip(designs, refs, strict=True):
            a, t, n = solve(scene_at(des.scene, level, order), grid_mm, repeat)
            errs.append(errors(a, ref))
            times.append(t)
            dofs.append(n)
        name = f"FE order {order}, level {level:g}" if level else "FE default mesh (as dataset)"
        rows.append({"method": name, "order": order, "level": level,
                     "dofs": int(np.median(dofs)), "seconds": float(np.median(times)),
                     **summary(errs)})
    return rows


def transient_answer(scene: dict[str, Any],
                     repeat: int = 1) -> tuple[Answer, float, int, float]:
    """Steady center and edge amplitudes of the scene's ERM run in time (motor at its rated
    voltage with the rated speed set to the design's frequency, instant spin-up), from the
    per-component peaks over the last :data:`TRANSIENT` window; (answer with an empty
    profile, median wall time [s], unknowns, unsettled = largest relative change of the
    center and edge peaks from the window before the last to the last)."""
    d = scene_at(scene, None, TRANSIENT["order"])
    f = float(d["analysis"].get("frequency_hz", 120.0))
    unit = d["unit"]
    motor = unit.setdefault("motor", {})
    motor["rated_frequency_hz"] = f

    volts = motor.get("rated_voltage_V", Motor.__dataclass_fields__["rated_voltage_V"].default)
    d["analysis"] = {"kind": "transient", "time_step_ms": TRANSIENT["time_step_ms"],
                     "duration_ms": TRANSIENT["duration_ms"], "rho_inf": Analysis().rho_inf,
                     "voltage_schedule": [[0.0, float(volts)]]}
    d.setdefault("effects", {})["spin_up"] = False
    sc = scene_from_dict(d)
    res, t = timed(lambda: simulate(sc), repeat)
    h = res.histories
    start = (TRANSIENT["duration_ms"] - TRANSIENT["window_ms"]) * 1e-3
    n_probe = res.r_mm.size
    window = TRANSIENT["window_ms"] * 1e-3

    def peaks(t0: float, t1: float) -> np.ndarray:
        sel = (h.t >= t0 - 1e-12) & (h.t < t1 - 1e-12)
        amp = np.abs(h.u[sel][:, n_probe:n_probe + 2]).max(axis=0) * 1e6  # (2, 3) um
        return np.linalg.norm(amp, axis=1)

    last, before = peaks(start, np.inf), peaks(start - window, start)
    unsettled = float(np.max(np.abs(last / before - 1.0)))
    return (Answer(np.asarray(last[0]), np.asarray(last[1]), np.zeros(0)), t,
            int(res.meta["dofs"]), unsettled)


def transient_rows(designs: Sequence[Design], refs: Sequence[Answer],
                   grid_mm: np.ndarray) -> list[dict[str, Any]]:
    """The transient steady state against the harmonic answer on the same mesh (order
    :data:`TRANSIENT`, default sizes) and against the reference; center and edge only (the
    profile of a transient run is a peak over the whole run, spin-up included). Designs the
    solver refuses to run in time (a bare unit on frictionless pins has nothing holding it
    sideways) are counted in ``refused``; no row at all when every design is refused."""
    same, total, times, h_times, dofs, unsettled, refused = [], [], [], [], [], [], 0
    for des, ref in zip(designs, refs, strict=True):
        try:
            a, t, n, u = transient_answer(des.scene)
        except (SceneError, ValueError):  # e.g. a bare unit on pins drifts away in time
            refused += 1
            continue
        h, th, _ = solve(scene_at(des.scene, None, TRANSIENT["order"]), grid_mm, 1)
        same.append(_scalar_errors(a, h))
        total.append(_scalar_errors(a, ref))
        times.append(t)
        h_times.append(th)
        dofs.append(n)
        unsettled.append(u)
    if not total:
        return []
    med = {k: float(np.median([e[k] for e in total])) for k in ("center", "edge", "worst")}
    mx = {k: float(np.max([e[k] for e in total])) for k in ("center", "edge", "worst")}
    vs = {k: float(np.max([e[k] for e in same])) for k in ("center", "edge")}
    return [{"method": f"FE transient steady state, order {TRANSIENT['order']}",
             "order": TRANSIENT["order"], "level": None, "dofs": int(np.median(dofs)),
             "seconds": float(np.median(times)),
             "harmonic_seconds": float(np.median(h_times)),
             **{f"{k}_median": v for k, v in med.items()},
             **{f"{k}_max": v for k, v in mx.items()},
             "profile_median": float("nan"), "profile_max": float("nan"),
             "vs_harmonic_center_max": vs["center"], "vs_harmonic_edge_max": vs["edge"],
             "designs": len(total), "refused": refused,
             "unsettled_max": float(np.max(unsettled))}]


def _scalar_errors(a: Answer, ref: Answer) -> dict[str, float]:
    c = float(abs(a.center_um / ref.center_um - 1))
    e = float(abs(a.edge_um / ref.edge_um - 1))
    return {"center": c, "edge": e, "worst": max(c, e)}
