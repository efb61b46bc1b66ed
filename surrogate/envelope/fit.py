"""Fit the grey-box envelope model (``surrogate.runtime.rom``) on transient FE runs.

Training data: datasets generated from ``datasets/spaces/transient.toml`` (rows with
``history_center_um`` / ``history_edge_um``: [u_r, u_z, u_theta] in um on the theta = 0
meridian, the resolved scene with its voltage schedule and motor, and the design columns of
the harmonic model). Nothing here imports the solver: it fits from stored rows only.

What is fitted (everything else is known): per point (center, edge) the mode (log sigma, f_n)
and, with ``learn_gain``, a log gain g and its frequency slope on top of the harmonic model
(by default the ``envelope_harmonic`` model of :mod:`surrogate.runtime.defaults`:
``models/nn-sweep`` when installed, else ``models/nn-wide``, over the motor's whole speed
range; no gain: chosen by measurement, docs/transient-model.md), each affine in the harmonic
model's encoded design features (one map per attachment by default, ``group_by_attachment``):

1. FE envelopes: each displacement component is demodulated with the rotor angle phi (exact,
   :mod:`motorlaw`): z_c = analytic(u_c) e^{-i phi}; the point's envelope is
   sqrt(sum_c |z_c|^2), the harmonic magnitude in steady running.
2. Per run, a grid search over (sigma, f_n) with the gain in closed form (the envelope is
   linear in g), refined by least squares with the gain's frequency slope, gives per-run
   values; a ridge regression of them on the design features gives the starting weights.
3. The weights are refined jointly over all training runs by nonlinear least squares
   (scipy) on the envelope error relative to each run's FE peak.

With ``quasi_static_share`` (the shipped ``models/rom-default``) a share w of the steady
response passes through at once beside the mode (per run refined after the one-mode fit, then
mapped and refined jointly like the mode). The choice of correction (one rotating-frame mode vs
a plain first-order lag of the steady response, the share) was made by measurement, and so
was the fit itself: SINDy with control (pysindy) identifying what the one-mode model lacks
lost to it on the held-out runs (``bench/surrogate/envelope_sindy.py``); see
docs/transient-model.md.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

import motorlaw
from surrogate.envelope import card as rom_card
from surrogate.envelope.card import (
    COEFFICIENTS_FILE,
    HARMONIC_CARD_FILE,
    HARMONIC_GRAPH_FILE,
    HOLDOUT_EVERY,
)
from surrogate.envelope.metrics import evaluate
from surrogate.envelope.runs import Run, complex_envelopes, load_runs, run_from_row, schedule_volts
from surrogate.registry import check_model_out, write_model
from surrogate.runtime.card import read_card
from surrogate.runtime.defaults import default_model_path
from surrogate.runtime.encoding import n_features
from surrogate.runtime.predictor import load_predictor
from surrogate.runtime.rom import (
    FORMAT,
    MOTOR_INPUTS,
    PARAMS,
    POINTS,
    harmonic_grid,
    model_from_parts,
)
from surrogate.runtime.rom_modes import envelope_from_params, params_for
from surrogate.runtime.rom_steady import steady_from_params

# the runs' reading lives in surrogate.envelope.runs; re-exported here, where the fit's callers look
__all__ = ["Run", "complex_envelopes", "fit_weights", "load_runs", "run_from_row",
           "schedule_volts", "train"]

EDGE_TRIM_S = 3e-3  # the Hilbert transform is least accurate within ~1 period of the ends
SIGMA_GRID = np.geomspace(10.0, 800.0, 9)  # 1/s
FN_GRID = np.arange(20.0, 201.0, 10.0)  # Hz
RIDGE = 1e-2
# starts of the second mode about a run's one-mode fit (sigma, f_n): mode 1 sped up by
# FAST_FACTOR, mode 2 slower by SLOW_FACTOR at FN2_FACTOR f_n, mode 1's share w
FAST_FACTOR, SLOW_FACTOR, FN2_FACTOR = (1.0, 2.0), (0.15, 0.4), (0.7, 1.0)
SHARE_START = (0.5, 0.75, 0.95)
# quasi_static_share: mode 1 held this fast (a 0.2 ms lag: the force passed through at once);
# mode 2 starts at the run's one-mode fit with the quasi-static share w at QS_SHARE_START
QS_SIGMA, QS_FN, QS_SHARE_START = 5000.0, 50.0, 0.2
# per-run bounds of the parameters (PARAMS, then MODE2_PARAMS)
LOWER = (math.log(2.0), 5.0, -4.0, -4.0, math.log(2.0), 5.0, -3.0)
UPPER = (math.log(5000.0), 400.0, 4.0, 4.0, math.log(5000.0), 400.0, 3.0)


def _batch(runs: Sequence[Run], amp: dict[str, NDArray], point: int
           ) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
    """(t, omega (nb, nt), FE envelopes (nb, nt), harmonic amplitudes (nb, n_grid), fit mask)
    of runs sharing one time grid."""
    t = runs[0].t
    for r in runs:
        if r.t.shape != t.shape or not np.allclose(r.t, t):
            raise ValueError("--data: every run must share one time grid (time step and "
                             "duration of the transient space)")
    keep = (t >= t[0] + EDGE_TRIM_S) & (t <= t[-1] - EDGE_TRIM_S)
    return (t, np.stack([r.omega for r in runs]), np.stack([r.env[point] for r in runs]),
            amp[POINTS[point]], keep)


def _predict(t: NDArray, omega: NDArray, amp: NDArray, grid: NDArray, p: NDArray) -> NDArray:
    """Model envelopes (nb, nt) for parameter rows p (nb, 4) in ``PARAMS`` order (or (nb, 7)
    with the second mode's rows, :func:`surrogate.runtime.rom_modes.params_for`), harmonic
    amplitudes ``amp`` (nb, n_grid) on ``grid`` (Hz)."""
    return envelope_from_params(t, omega, steady_from_params(omega, grid, amp, p), p)


def _grid_start(t: NDArray, omega: NDArray, env: NDArray, amp: NDArray, grid: NDArray,
                keep: NDArray, n_free: int = 4) -> NDArray:
    """Per run (log sigma, f_n, log g, 0) of the best grid point, gain in closed form (held
    at 1 when ``n_free`` = 2: only the mode is free)."""
    nb = env.shape[0]
    best = np.full(nb, np.inf)
    out = np.zeros((nb, len(PARAMS)))
    for sigma in SIGMA_GRID:
        for fn in FN_GRID:
            p = np.tile([math.log(sigma), fn, 0.0, 0.0], (nb, 1))
            y = _predict(t, omega, amp, grid, p)
            yk, ek = y[:, keep], env[:, keep]
            g = np.maximum(np.sum(yk * ek, axis=1) / np.maximum(np.sum(yk * yk, axis=1),
                                                                  1e-30), 1e-6)
            g = g if n_free > 2 else np.ones(nb)
            err = np.sum((g[:, None] * yk - ek) ** 2, axis=1)
            better = err < best
            best[better] = err[better]
            p[:, 2] = np.log(g)
            out[better] = p[better]
    return out


def _second_mode_start(t: NDArray, omega: NDArray, env: NDArray, amp: NDArray, grid: NDArray,
                       keep: NDArray, one: NDArray) -> NDArray:
    """Per run the best two-mode start (nb, 7) about its one-mode fit ``one`` (nb, 4): the
    one mode kept or sped up (``FAST_FACTOR``), a slower second mode (``SLOW_FACTOR``,
    ``FN2_FACTOR``) and mode 1's share w (``SHARE_START``), every combination evaluated on
    the whole batch at once."""
    nb = env.shape[0]
    best = np.full(nb, np.inf)
    out = np.zeros((nb, len(params_for(2))))
    for fast in FAST_FACTOR:
        for slow in SLOW_FACTOR:
            for f2 in FN2_FACTOR:
                for share in SHARE_START:
                    p = np.column_stack([one[:, 0] + math.log(fast), one[:, 1:],
                                         one[:, 0] + math.log(slow), f2 * one[:, 1],
                                         np.full(nb, share)])
                    p = np.clip(p, LOWER, UPPER)
                    y = _predict(t, omega, amp, grid, p)
                    err = np.sum((y[:, keep] - env[:, keep]) ** 2, axis=1)
                    better = err < best
                    best[better] = err[better]
                    out[better] = p[better]
    return out


def _refine_runs(t: NDArray, omega: NDArray, env: NDArray, amp: NDArray, grid: NDArray,
                 keep: NDArray, start: NDArray, max_nfev: int, free: Sequence[int]) -> NDArray:
    """Per-run least-squares refinement of the start (nb, 4 or 7; every 4th sample) in its
    parameters ``free`` (column indices; the rest held)."""
    sub = keep & (np.arange(t.size) % 4 == 0)
    out = start.copy()
    free = list(free)
    n = start.shape[1]
    lo, hi = np.array(LOWER[:n])[free], np.array(UPPER[:n])[free]
    for i in range(env.shape[0]):
        scale = float(np.max(env[i]))

        def residual(x: NDArray, i: int = i, scale: float = scale) -> NDArray:
            p = start[i].copy()
            p[free] = x
            y = _predict(t, omega[i:i + 1], amp[i:i + 1], grid, p[None, :])[0]
            return ((y - env[i]) / scale)[sub]

        x0 = np.clip(start[i, free], lo, hi)
        out[i, free] = least_squares(residual, x0, bounds=(lo, hi), max_nfev=max_nfev).x
    return out


def fit_weights(runs: Sequence[Run], features: NDArray, amp: dict[str, NDArray],
                grid: NDArray, *, max_nfev: int = 40, intercepts: Sequence[int] = (-1,),
                learn_gain: bool = True, modes: int = 1, share: bool = False
                ) -> tuple[dict[str, NDArray], dict[str, Any]]:
    """Weights (point -> (n_params, nf + 1)) of ``params_for(modes)`` over ``features``
    (nb, nf + 1, intercept last; ``intercepts``: the intercept columns, one per group) from
    the harmonic amplitudes ``amp`` (point -> (nb, n_grid) on ``grid``, Hz), and a fit
    report: grid start, per-run refinement, ridge regression across runs, joint refinement.
    Without ``learn_gain`` the gain is 1 and its slope 0: the steady level is the harmonic
    model's. With ``modes`` = 2 the per-run one-mode fit starts the second mode
    (:func:`_second_mode_start`), refined per run before the ridge regression; with ``share``
    (and ``modes`` = 2) mode 1 is held at ``QS_SIGMA``, ``QS_FN`` (a quasi-static share w of
    the steady response) and mode 2, started at the one-mode fit, carries the dynamics."""
    params = params_for(modes)
    weights, report = {}, {}
    ridge = RIDGE * np.eye(features.shape[1])
    ridge[list(intercepts), list(intercepts)] = 0.0  # intercepts are not shrunk
    for j, point in enumerate(POINTS):
        t, omega, env, a, keep = _batch(runs, amp, j)
        free = [0, 1, 2, 3] if learn_gain else [0, 1]
        start = _refine_runs(t, omega, env, a, grid, keep,
                             _grid_start(t, omega, env, a, grid, keep, len(free)), max_nfev,
                             free)
        if modes == 2 and share:
            free = [k for k in free if k > 1] + [4, 5, 6]
            nb = start.shape[0]
            start = _refine_runs(t, omega, env, a, grid, keep, np.column_stack([
                np.full(nb, math.log(QS_SIGMA)), np.full(nb, QS_FN), start[:, 2:4],
                start[:, :2], np.full(nb, QS_SHARE_START)]), max_nfev, free)
        elif modes == 2:
            free += [4, 5, 6]
            start = _refine_runs(t, omega, env, a, grid, keep,
                                 _second_mode_start(t, omega, env, a, grid, keep, start),
                                 max_nfev, free)
        w0 = np.linalg.solve(features.T @ features + ridge, features.T @ start).T  # (np, nf+1)
        fixed = [k for k in range(len(params)) if k not in free]
        w0[fixed] = 0.0  # gain rows held: log g = 0, slope 0
        if share:  # the quasi-static mode 1: constant in every group
            w0[0, list(intercepts)], w0[1, list(intercepts)] = math.log(QS_SIGMA), QS_FN

        def full(w: NDArray, w0=w0, free=free) -> NDArray:
            out = w0.copy()
            out[free] = w.reshape(len(free), -1)
            return out

        scale = np.max(env, axis=1, keepdims=True)
        sub = keep & (np.arange(t.size) % 4 == 0)

        def residual(w: NDArray, t=t, omega=omega, a=a, env=env, scale=scale,
                     sub=sub) -> NDArray:
            y = _predict(t, omega, a, grid, features @ full(w).T)
            return ((y - env) / scale)[:, sub].ravel()

        r0 = residual(w0[free].ravel())

        def residual_runs(p: NDArray, t=t, omega=omega, a=a, env=env, scale=scale,
                          sub=sub) -> NDArray:
            return ((_predict(t, omega, a, grid, p) - env) / scale)[:, sub]

        sol = least_squares(residual, w0[free].ravel(), method="trf", x_scale="jac",
                            max_nfev=max_nfev, diff_step=1e-4)
        weights[point] = full(sol.x)
        per_run = np.sqrt(np.mean(residual_runs(start) ** 2))
        report[point] = {"per_run_optimum_rms": float(per_run),
                         "regression_start_rms": float(np.sqrt(np.mean(r0 ** 2))),
                         "refined_rms": float(np.sqrt(np.mean(sol.fun ** 2))),
                         "nfev": int(sol.nfev)}
    return weights, report


# --------------------------------------------------------------------------- training + card


def _feature_columns(harmonic: Any) -> list[int]:
    """Encoded feature columns of the harmonic model's inputs, frequency left out."""
    cols, at = [], 0
    for spec in harmonic.specs:
        width = n_features([spec])
        if spec.name != "frequency_hz":
            cols += list(range(at, at + width))
        at += width
    return cols


def train(data: Sequence[str | Path], out: str | Path, *, harmonic: str | Path | None =
          None, seed: int = 0, overwrite: bool = False,
          max_nfev: int = 40, equivalent_loss: bool = False,
          group_by_attachment: bool = True, learn_gain: bool = False,
          modes: int = 1, quasi_static_share: bool = False) -> dict[str, Any]:
    """Fit on the training rows of ``data`` (sample_index % 4 != 3), validate on the held-out
    rows, register ``out`` (card + coefficients + the harmonic model's card and graph, written
    atomically by :func:`surrogate.registry.write_model`); returns the card. ``max_nfev``
    bounds the least-squares evaluations of each refinement; ``seed`` is recorded (the fit is
    deterministic). ``equivalent_loss``: evaluate the harmonic model with the FE transient's
    damping, each loss factor eta as eta f / f_rated (see docs/transient-model.md).
    ``learn_gain``: fit a gain g exp(s (f - 130 Hz) / 50 Hz) on the harmonic model's level
    (off by default: the harmonic model's own level is the steady state). ``modes``: damped
    modes per point, 1 (default, chosen by measurement) or 2
    (:mod:`surrogate.runtime.rom_modes`). ``quasi_static_share``: one mode plus a share w of
    the steady response passed through at once (written as two modes, the first held at
    ``QS_SIGMA``; docs/transient-model.md)."""
    out = Path(out)
    check_model_out(out, overwrite)  # before the work: the output may not be replaced
    if isinstance(max_nfev, bool) or not isinstance(max_nfev, int) or not 1 <= max_nfev <= 1000:
        raise ValueError(f"max_nfev = {max_nfev!r}: allowed integers 1..1000")
    if not all(isinstance(x, bool) for x in (equivalent_loss, group_by_attachment, learn_gain)):
        raise ValueError("equivalent_loss, group_by_attachment, learn_gain: allowed true or "
                         "false")
    if type(modes) is not int or modes not in (1, 2):
        raise ValueError(f"modes = {modes!r}: allowed 1 or 2 (damped modes per point)")
    if not isinstance(quasi_static_share, bool) or (quasi_static_share and modes != 1):
        raise ValueError(f"quasi_static_share = {quasi_static_share!r}: allowed true (with "
                         "modes 1: it adds the quasi-static share) or false")
    modes = 2 if quasi_static_share else modes
    params = params_for(modes)
    if harmonic is None:  # nn-sweep when installed, else nn-wide
        harmonic = default_model_path("envelope_harmonic")
    hcard = read_card(harmonic)
    if hcard.get("kind") != "nn" or "frequency_hz" not in [i["name"] for i in hcard["inputs"]]:
        raise ValueError(f"harmonic: {harmonic} is not a harmonic NN model with frequency_hz")
    predictor = load_predictor(harmonic)
    design_names = [n for n in predictor.input_names if n != "frequency_hz"]
    runs, fixed, hashes = load_runs(data, design_names)
    train_runs = [r for r in runs if r.sample_index % HOLDOUT_EVERY != HOLDOUT_EVERY - 1]
    held = [r for r in runs if r.sample_index % HOLDOUT_EVERY == HOLDOUT_EVERY - 1]
    if len(train_runs) < 8 or not held:
        raise ValueError(f"--data: need at least 8 training and 1 held-out run, got "
                         f"{len(train_runs)} and {len(held)}")
    cols = _feature_columns(predictor)
    motor_ranges = {k: [min(r.design[k] for r in train_runs),
                        max(r.design[k] for r in train_runs)] for k in MOTOR_INPUTS}
    max_v = max(float(np.max(np.abs(r.volts))) for r in runs)
    provisional = {"format": FORMAT, "actuator": motorlaw.SpeedLaw.kind, "modes": modes,
                   "feature_columns": cols, "grid_hz": harmonic_grid(predictor).tolist(),
                   "motor": {**fixed, "max_voltage_V": max(max_v,
                                                           motorlaw.DEFAULTS["max_voltage_V"])},
                   "motor_ranges": motor_ranges,
                   "weights": {p: np.zeros((len(params), len(cols) + 1)).tolist()
                               for p in POINTS},
                   "clip": {k: [-1e6, 1e6] for k in params}}
    if quasi_static_share:
        provisional["quasi_static_share"] = {"sigma_1_s": QS_SIGMA, "fn_hz": QS_FN}
    if group_by_attachment:  # one affine map of the mode per attachment
        choices = next(s.choices for s in predictor.specs if s.name == "attachment")
        provisional["group_by"] = {"input": "attachment", "choices": list(choices)}
        provisional["weights"] = {p: np.zeros((len(params), (len(cols) + 1) * len(choices)))
                                  .tolist() for p in POINTS}
    if equivalent_loss:  # C = eta / omega_rated K in the FE transient (fem.transient_analysis)
        provisional["loss_reference_hz"] = fixed["rated_frequency_hz"]
    harmonic_dir = Path(harmonic)
    onnx = harmonic_dir / hcard["graph"]["file"]
    shell = model_from_parts(provisional, hcard, onnx)
    feats = np.stack([shell.features(r.design, extrapolate=True) for r in train_runs])
    amp: dict[str, list[NDArray]] = {p: [] for p in POINTS}
    for r in train_runs:
        for p, a in shell.steady_amplitudes(r.design, extrapolate=True).items():
            amp[p].append(a)
    n_groups = len(provisional.get("group_by", {"choices": [0]})["choices"])
    weights, report = fit_weights(train_runs, feats, {p: np.stack(v) for p, v in amp.items()},
                                  shell.grid_hz, max_nfev=max_nfev, intercepts=[
                                      (j + 1) * (len(cols) + 1) - 1 for j in range(n_groups)],
                                  learn_gain=learn_gain, modes=modes,
                                  share=quasi_static_share)
    rows = np.concatenate([feats @ w.T for w in weights.values()])
    clip = {name: [float(rows[:, i].min()), float(rows[:, i].max())]
            for i, name in enumerate(params)}
    coefficients = {**provisional, "weights": {p: w.tolist() for p, w in weights.items()},
                    "clip": clip, "fit": report}
    model = model_from_parts(coefficients, hcard, onnx)
    metrics = {"train": evaluate(model, train_runs)["summary"],
               "held_out": evaluate(model, held)}
    card = rom_card.card(model, coefficients, data, hashes, harmonic, hcard, len(train_runs),
                 len(held), seed, metrics)
    body = json.dumps(coefficients, indent=1, allow_nan=False) + "\n"
    write_model(out, card, {COEFFICIENTS_FILE: body.encode(),
                            HARMONIC_CARD_FILE: (json.dumps(hcard, indent=1) + "\n").encode(),
                            HARMONIC_GRAPH_FILE: onnx.read_bytes()}, overwrite=overwrite)
    return read_card(out)
