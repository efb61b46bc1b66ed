"""Envelope metrics of the transient model against FE runs (numpy only).

Per run and point (center, edge), on the first burst of the schedule (drive from t = 0 until
the first step at <= 0 V, ``on_time_s``):

- ``steady``: mean envelope over the last 5 ms before switch-off, um; error relative to FE;
- ``rise``: 10-90 % rise time from rest, ms (first upward crossings of 10 % and 90 % of the
  run's own steady level, linearly interpolated);
- ``decay``: 90-10 % fall time after switch-off, ms (first crossing below 90 % of the steady
  level, last crossing above 10 % before the drive comes back on);
- ``nrmse``: rms envelope error over the record (ends trimmed by 3 ms) / FE peak;
- ``settled``: 1 when the FE envelope has settled before switch-off (over the last 10 ms it
  stays within +-2.5 % of its mean: peak-to-peak / mean < 5 %), else 0. Many runs have not:
  the low mode of a pogo unit still beats, or the speed still rises, so their "steady" level
  is a snapshot of a transient. The steady error is also summarised over settled runs only
  (``*_steady_rel_err_settled_*``).

Rise and decay errors are absolute (ms). A time that does not exist in the window (the
envelope never falls below 10 % before the next pulse) is NaN and counted in ``*_undefined``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["envelope_metrics", "evaluate", "fall_time", "first_crossing", "summarise"]

POINTS = ("center", "edge")
STATES = ("center_envelope_um", "edge_envelope_um")
STEADY_WINDOW_S = 5e-3
SETTLED_WINDOW_S, SETTLED_PTP = 10e-3, 0.05
TRIM_S = 3e-3


def first_crossing(t: NDArray, y: NDArray, level: float, *, rising: bool) -> float:
    """First time ``y`` reaches ``level`` upwards (or downwards), interpolated; nan if never."""
    hit = np.flatnonzero(y >= level if rising else y <= level)
    if not hit.size:
        return math.nan
    k = int(hit[0])
    if k == 0:
        return float(t[0])
    dy = float(y[k] - y[k - 1])
    frac = (level - float(y[k - 1])) / dy if dy else 1.0
    return float(t[k - 1] + frac * (t[k] - t[k - 1]))


def fall_time(t: NDArray, y: NDArray, high: float, low: float) -> float:
    """Time from the first crossing below ``high`` to the last crossing above ``low`` (the
    envelope stays below ``low`` after it), s; nan if it never settles below ``low``."""
    t_hi = first_crossing(t, y, high, rising=False)
    above = np.flatnonzero(y > low)
    if not above.size:
        return 0.0 if math.isnan(t_hi) else float(t[0]) - t_hi
    k = int(above[-1])
    if k == t.size - 1:
        return math.nan
    frac = (float(y[k]) - low) / float(y[k] - y[k + 1])
    t_lo = float(t[k] + frac * (t[k + 1] - t[k]))
    return t_lo - t_hi


def _next_on(t: NDArray, volts: NDArray, after: float) -> float:
    on = np.flatnonzero((t > after) & (volts > 0.0))
    return float(t[on[0]]) if on.size else float(t[-1])


def envelope_metrics(t: NDArray, volts: NDArray, on_time_s: float, fe: NDArray,
                     model: NDArray) -> dict[str, float]:
    """Metrics of one point: FE ``fe`` and model ``model`` envelopes (nt,) on ``t``."""
    out: dict[str, float] = {}
    drive = (t >= on_time_s - STEADY_WINDOW_S) & (t < on_time_s)
    back_on = _next_on(t, volts, on_time_s)
    window = (t >= on_time_s) & (t < back_on)
    for tag, y in (("fe", fe), ("model", model)):
        level = float(np.mean(y[drive]))
        up = t < on_time_s
        t10 = first_crossing(t[up], y[up], 0.1 * level, rising=True)
        t90 = first_crossing(t[up], y[up], 0.9 * level, rising=True)
        out[f"steady_um_{tag}"] = level
        out[f"rise_ms_{tag}"] = 1e3 * (t90 - t10)
        out[f"decay_ms_{tag}"] = 1e3 * fall_time(t[window], y[window], 0.9 * level,
                                                 0.1 * level)
    late = fe[(t >= on_time_s - SETTLED_WINDOW_S) & (t < on_time_s)]
    out["settled"] = float(np.ptp(late) / np.mean(late) < SETTLED_PTP) if late.size else 0.0
    keep = (t >= t[0] + TRIM_S) & (t <= t[-1] - TRIM_S)
    out["nrmse"] = float(np.sqrt(np.mean((model[keep] - fe[keep]) ** 2)) / np.max(fe[keep]))
    return out


def summarise(rows: Sequence[dict[str, Any]]) -> dict[str, float]:
    """Median and max of the errors over runs, per point."""
    summary: dict[str, float] = {}
    for p in POINTS:
        errs = {
            "steady_rel_err": [abs(r[f"{p}_steady_um_model"] / r[f"{p}_steady_um_fe"] - 1)
                               for r in rows],
            "rise_abs_err_ms": [abs(r[f"{p}_rise_ms_model"] - r[f"{p}_rise_ms_fe"])
                                for r in rows],
            "decay_abs_err_ms": [abs(r[f"{p}_decay_ms_model"] - r[f"{p}_decay_ms_fe"])
                                 for r in rows],
            "nrmse": [r[f"{p}_nrmse"] for r in rows],
            "steady_rel_err_settled": [
                abs(r[f"{p}_steady_um_model"] / r[f"{p}_steady_um_fe"] - 1)
                if r.get(f"{p}_settled") else math.nan for r in rows],
        }
        for name, vals in errs.items():
            arr = np.asarray(vals, dtype=float)
            ok = arr[np.isfinite(arr)]
            summary[f"{p}_{name}_median"] = float(np.median(ok)) if ok.size else math.nan
            summary[f"{p}_{name}_max"] = float(np.max(ok)) if ok.size else math.nan
            if ok.size < arr.size and name != "steady_rel_err_settled":
                summary[f"{p}_{name}_undefined"] = int(arr.size - ok.size)
        summary[f"{p}_settled_runs"] = int(sum(bool(r.get(f"{p}_settled")) for r in rows))
    return summary


def evaluate(model: Any, runs: Sequence[Any]) -> dict[str, Any]:
    """Per-run metrics of ``model`` (an ``EnvelopeModel``) on FE ``runs``
    (``surrogate.envelope.fit.Run``) and their summary."""
    rows = []
    for run in runs:
        sim = model.simulate(run.t, run.volts, run.design, extrapolate=True)
        row: dict[str, Any] = {"sample_index": run.sample_index}
        for j, (p, key) in enumerate(zip(POINTS, STATES, strict=True)):
            m = envelope_metrics(run.t, run.volts, run.on_time_s, run.env[j], sim[key])
            row.update({f"{p}_{k}": v for k, v in m.items()})
        rows.append(row)
    return {"summary": summarise(rows), "runs": rows}
