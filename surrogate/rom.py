"""Identify the transient envelope ROM of an ERM haptic unit with pysindy (SINDy with control).

Training data: transient datasets generated from ``datasets/spaces/transient.toml`` (rows with
``history_center_um`` / ``history_edge_um``: [u_r, u_z, u_theta] in um on the theta = 0
meridian, and the resolved scene with its voltage schedule and motor). Nothing here imports
the solver: it trains from stored rows only.

Model (see ``surrogate.runtime.rom`` for the run-time side, which this module shares the
motor-speed law and the feature definitions with):

- The envelope of a point is sqrt(sum_c |analytic(u_c)|^2) over the three displacement
  components (the Hilbert-transform amplitude): in steady running it equals the harmonic
  magnitude sqrt(|U_r|^2 + |U_z|^2 + |U_t|^2) of ``fem.results``.
- States x = (center, edge) envelope, um. Control: the motor speed ratio s = omega /
  omega_rated (omega from the drive voltage through the motor's first-order dynamics, known
  exactly) times design features. SINDy library: identity in x and in the forcing features
  ``s^p`` and ``s^p * d_j`` (p = 2..4; d = skin modulus on a log scale, fat thickness,
  orientation, attachment, orientation x attachment, each scaled to [-1, 1]), so that
  ``dx/dt = A x + B q(s, d)``: a linear, interpretable envelope filter whose steady level
  ``-A^-1 B q`` is the quasi-static harmonic response m e omega^2 |H(omega)|, expanded in s.
- Sparse regression: STLSQ on normalized columns, bagged over time samples
  (``EnsembleOptimizer``) for coefficient spreads; the median model is kept.

Stability: the identified A must have eigenvalues with negative real parts (checked here and
again at load time); with bounded forcing the envelope then stays bounded for any horizon.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import hashlib
import json
import math
import os
import platform
import shutil
import sys
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from surrogate.runtime.rom import (
    FORMAT,
    STATES,
    EnvelopeModel,
    MotorConstants,
    design_features,
    forcing_features,
    model_from_dict,
    motor_speed,
)

__all__ = ["Run", "envelope", "evaluate", "fit_envelope_model", "load_runs", "train"]

POWERS = (2, 3, 4)
DESIGN_SPEC: dict[str, Any] = {
    # ranges are replaced by the training space's own; choices order: -1, +1
    "design": [
        {"name": "skin_E_kPa", "low": 20.0, "high": 120.0, "scale": "log"},
        {"name": "fat_thickness_mm", "low": 3.0, "high": 20.0},
        {"name": "orientation", "choices": ["forward", "reverse"]},
        {"name": "attachment", "choices": ["glued", "pogo"]},
    ],
    "interactions": [["orientation", "attachment"]],
}
EDGE_TRIM_S = 3e-3  # the Hilbert envelope is least accurate within ~1 period of the record ends
HOLDOUT_EVERY = 4  # rows with sample_index % 4 == 3 are held out


@dataclass(frozen=True)
class Run:
    """One transient FE run: times (s), envelopes (nt, 2) in um (center, edge), drive voltage
    held from each time (V), design inputs (``EnvelopeModel.input_names``), sample index."""

    t: NDArray
    envelope: NDArray
    volts: NDArray
    design: dict[str, Any]
    sample_index: int
    on_time_s: float


def envelope(u: NDArray) -> NDArray:
    """Envelope sqrt(sum_c |analytic(u_c)|^2) of (3, nt) component histories.

    The record is extended by point reflection at both ends (continuous in value and slope:
    the run starts from rest) before the FFT-based Hilbert transform, which keeps the
    end artefacts within about a period."""
    from scipy.signal import hilbert

    u = np.asarray(u, dtype=float)
    head = -u[:, 1:][:, ::-1]
    tail = 2 * u[:, -1:] - u[:, :-1][:, ::-1]
    ext = np.concatenate([head, u, tail], axis=1)
    a = np.abs(hilbert(ext, axis=1))[:, head.shape[1]: head.shape[1] + u.shape[1]]
    return np.sqrt(np.sum(a**2, axis=0))


def _schedule_volts(t: NDArray, schedule_ms: Sequence[Sequence[float]]) -> NDArray:
    """Voltage held at each time (s) of a [[t_ms, V], ...] step schedule."""
    starts = np.array([s[0] for s in schedule_ms]) * 1e-3
    levels = np.array([s[1] for s in schedule_ms], dtype=float)
    return levels[np.searchsorted(starts, t + 1e-12, side="right") - 1]


def load_runs(paths: Sequence[str | Path]) -> tuple[list[Run], MotorConstants, list[str]]:
    """Successful transient unit runs of the datasets, their common motor law, and the
    sha256 of each dataset's manifest. Raises ValueError if a dataset holds no such run."""
    import pandas as pd

    runs: list[Run] = []
    motor: MotorConstants | None = None
    hashes = []
    for path in paths:
        manifest = Path(path) / "_manifest.json"
        if not manifest.is_file():
            raise ValueError(f"--data: {path} is not a dataset (no _manifest.json)")
        hashes.append(hashlib.sha256(manifest.read_bytes()).hexdigest())
        df = pd.read_parquet(path)
        if "history_center_um" not in df:
            raise ValueError(f"--data: {path} holds no center/edge histories (generate it "
                             "from a transient space of a unit)")
        df = df[(df["status"] == "ok") & df["history_center_um"].notna()]
        for row in df.itertuples(index=False):
            run, m = _run_from_row(row._asdict())
            if motor is not None and m != motor:
                raise ValueError(f"--data: sample {run.sample_index} of {path} has another "
                                 f"motor law ({m}) than the first ({motor})")
            motor = m
            runs.append(run)
    if motor is None:
        raise ValueError(f"--data: no successful transient unit run in {list(map(str, paths))}")
    return runs, motor, hashes


def _run_from_row(row: Mapping[str, Any]) -> tuple[Run, MotorConstants]:
    scene = json.loads(row["scene_json"])
    m = scene["unit"]["motor"]
    schedule = scene["analysis"]["voltage_schedule"]
    motor = MotorConstants(float(m["rated_voltage_V"]), float(m["rated_frequency_hz"]),
                           float(m["start_voltage_V"]),
                           max(4.5, max(abs(v) for _, v in schedule)))
    t = np.asarray(row["history_t_s"], dtype=float)
    env = np.column_stack([envelope(np.stack(list(row[f"history_{p}_um"])))
                           for p in ("center", "edge")])
    design = {"skin_E_kPa": scene["tissue"]["layer"][0]["E_kPa"],
              "fat_thickness_mm": scene["tissue"]["layer"][1]["thickness_mm"],
              "orientation": scene["unit"]["orientation"],
              "attachment": scene["unit"]["attachment"],
              "tau_spinup_ms": float(m["tau_spinup_ms"]),
              "tau_spindown_ms": float(m["tau_spindown_ms"])}
    volts = _schedule_volts(t, schedule)
    off = [s[0] * 1e-3 for s in schedule if s[1] <= 0.0]
    return Run(t, env, volts, design, int(row["sample_index"]),
               off[0] if off else float(t[-1])), motor


# --------------------------------------------------------------------------- identification


def _spec_from_runs(runs: Sequence[Run]) -> dict[str, Any]:
    spec = json.loads(json.dumps(DESIGN_SPEC))
    for item in spec["design"]:
        if "choices" not in item:
            vals = [r.design[item["name"]] for r in runs]
            item["low"], item["high"] = float(min(vals)), float(max(vals))
    spec["motor_ranges"] = {k: [float(min(r.design[k] for r in runs)),
                                float(max(r.design[k] for r in runs))]
                            for k in ("tau_spinup_ms", "tau_spindown_ms")}
    return spec


def feature_names() -> list[str]:
    """Forcing features: s^p and s^p times each design feature (and interaction)."""
    design = [d["name"] for d in DESIGN_SPEC["design"]]
    design += [f"{a}*{b}" for a, b in DESIGN_SPEC["interactions"]]
    return [f"s^{p}" for p in POWERS] + [f"s^{p}*{d}" for p in POWERS for d in design]


def _forcing(run: Run, spec: Mapping[str, Any], motor: MotorConstants,
             names: list[str]) -> NDArray:
    omega = motor_speed(run.t, run.volts, run.design["tau_spinup_ms"] * 1e-3,
                        run.design["tau_spindown_ms"] * 1e-3, motor)
    return forcing_features(omega / motor.rated_omega, design_features(run.design, spec), names)


def fit_envelope_model(runs: Sequence[Run], motor: MotorConstants, *, threshold: float = 0.02,
                       n_models: int = 20, seed: int = 0) -> tuple[dict[str, Any], Any]:
    """SINDy-with-control fit; returns the coefficients dict (``surrogate.runtime.rom``
    format) and the fitted ``pysindy.SINDy`` (for printing its equations)."""
    import pysindy as ps

    spec = _spec_from_runs(runs)
    names = feature_names()
    xs, us, ts = [], [], []
    for run in runs:
        keep = (run.t >= run.t[0] + EDGE_TRIM_S) & (run.t <= run.t[-1] - EDGE_TRIM_S)
        xs.append(run.envelope[keep])
        us.append(_forcing(run, spec, motor, names)[keep])
        ts.append(run.t[keep])
    np.random.seed(seed)  # EnsembleOptimizer bags with numpy's global generator
    opt = ps.EnsembleOptimizer(ps.STLSQ(threshold=threshold, normalize_columns=True),
                               bagging=True, n_models=n_models)
    model = ps.SINDy(optimizer=opt, feature_library=ps.IdentityLibrary(),
                     differentiation_method=ps.SmoothedFiniteDifference())
    model.fit(xs, t=ts, u=us, feature_names=["center", "edge", *names])
    coef = np.asarray(model.coefficients())
    spread = np.std(np.asarray(opt.coef_list), axis=0)
    peak = max(float(np.max(r.envelope)) for r in runs)
    coefficients = {
        "format": FORMAT,
        "states": list(STATES),
        "A": coef[:, :2].tolist(),
        "B": coef[:, 2:].tolist(),
        "A_std": spread[:, :2].tolist(),
        "B_std": spread[:, 2:].tolist(),
        "features": names,
        "spec": spec,
        "motor": {"rated_voltage_V": motor.rated_voltage_V,
                  "rated_frequency_hz": motor.rated_frequency_hz,
                  "start_voltage_V": motor.start_voltage_V,
                  "max_voltage_V": motor.max_voltage_V},
        # 100x the largest trained envelope: far above any physical response of the space
        "bound_um": 100.0 * peak,
    }
    return coefficients, model


# --------------------------------------------------------------------------- validation


def _crossing(t: NDArray, y: NDArray, level: float, start: float, rising: bool) -> float:
    """First time >= start at which y crosses ``level`` upwards (or downwards), s; nan if
    never."""
    sel = t >= start
    tt, yy = t[sel], y[sel]
    hit = np.flatnonzero(yy >= level if rising else yy <= level)
    return float(tt[hit[0]]) if hit.size else math.nan


def envelope_metrics(run: Run, pred: NDArray) -> dict[str, float]:
    """Rise time, steady level, decay time and relative RMS error of predicted against FE
    envelopes (columns center, edge), per point: ``{point}_{metric}``.

    rise: time to 90 % of the drive-phase peak (ms); steady: mean over the last 5 ms before
    switch-off (um); decay: time after switch-off to fall below 10 % of the switch-off level
    (ms); nrmse: rms difference over the record divided by the FE peak."""
    out: dict[str, float] = {}
    on = run.t < run.on_time_s
    last = (run.t >= run.on_time_s - 5e-3) & on
    for j, point in enumerate(("center", "edge")):
        fe, rom = run.envelope[:, j], pred[:, j]
        for tag, y in (("fe", fe), ("rom", rom)):
            peak = float(np.max(y[on]))
            level = float(np.mean(y[last]))
            out[f"{point}_rise_ms_{tag}"] = 1e3 * _crossing(run.t, y, 0.9 * peak, 0.0, True)
            out[f"{point}_steady_um_{tag}"] = level
            off = _crossing(run.t, y, 0.1 * level, run.on_time_s, False)
            out[f"{point}_decay_ms_{tag}"] = 1e3 * (off - run.on_time_s)
        out[f"{point}_nrmse"] = float(np.sqrt(np.mean((rom - fe) ** 2)) / np.max(fe))
    return out


def evaluate(model: EnvelopeModel, runs: Sequence[Run]) -> dict[str, Any]:
    """Per-run metrics and their summary (median / max absolute errors) on ``runs``."""
    rows = []
    for run in runs:
        sim = model.simulate(run.t, run.volts, run.design, extrapolate=True)
        pred = np.column_stack([sim[s] for s in STATES])
        rows.append({"sample_index": run.sample_index, **envelope_metrics(run, pred)})
    summary: dict[str, float] = {}
    for point in ("center", "edge"):
        steady = [abs(r[f"{point}_steady_um_rom"] / r[f"{point}_steady_um_fe"] - 1) for r in rows]
        rise = [abs(r[f"{point}_rise_ms_rom"] - r[f"{point}_rise_ms_fe"]) for r in rows]
        decay = [abs(r[f"{point}_decay_ms_rom"] - r[f"{point}_decay_ms_fe"]) for r in rows]
        nrmse = [r[f"{point}_nrmse"] for r in rows]
        for name, vals in (("steady_rel_err", steady), ("rise_abs_err_ms", rise),
                           ("decay_abs_err_ms", decay), ("nrmse", nrmse)):
            summary[f"{point}_{name}_median"] = float(np.nanmedian(vals))
            summary[f"{point}_{name}_max"] = float(np.nanmax(vals))
    return {"summary": summary, "runs": rows}


# --------------------------------------------------------------------------- training + card


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _versions() -> dict[str, str]:
    from importlib.metadata import PackageNotFoundError, version

    out = {"python": platform.python_version()}
    for pkg in ("numpy", "scipy", "pysindy", "scikit-learn", "hapticrom"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def train(data: Sequence[str | Path], out: str | Path, *, threshold: float = 0.02,
          seed: int = 0) -> dict[str, Any]:
    """Fit on the training rows of ``data`` (every sample with index % 4 != 3), validate on
    the held-out rows, write ``out`` (card.json + coefficients.json) atomically; returns the
    card."""
    out = Path(out)
    if out.exists() and any(out.iterdir()):
        raise ValueError(f"--out: {out} exists and is not empty")
    runs, motor, hashes = load_runs(data)
    train_runs = [r for r in runs if r.sample_index % HOLDOUT_EVERY != HOLDOUT_EVERY - 1]
    held = [r for r in runs if r.sample_index % HOLDOUT_EVERY == HOLDOUT_EVERY - 1]
    if len(train_runs) < 4 or not held:
        raise ValueError(f"--data: need at least 4 training and 1 held-out run, got "
                         f"{len(train_runs)} and {len(held)}")
    coefficients, _ = fit_envelope_model(train_runs, motor, threshold=threshold, seed=seed)
    model = model_from_dict(coefficients)  # raises RomBlowUpError if unstable
    eig = model.eigenvalues()
    metrics = {"train": evaluate(model, train_runs)["summary"],
               "held_out": evaluate(model, held), "eigenvalues_1_s":
               {"real": eig.real.tolist(), "imag": eig.imag.tolist()}}
    card = {
        "name": out.name,
        "kind": "rom",
        "predicts": {"center_envelope_um": "vibration envelope at the unit's center "
                     "(skin-side face on the axis), um",
                     "edge_envelope_um": "skin-surface vibration envelope at the unit's "
                     "outer radius, um"},
        "interface": "surrogate.runtime.rom.load_envelope_model(path).simulate(t_s, volts, "
                     "design)",
        "inputs": {
            "t_s": {"units": "s", "description": "increasing times, from rest at t_s[0]"},
            "volts": {"units": "V", "range": [-motor.max_voltage_V, motor.max_voltage_V],
                      "description": "drive voltage held from each time to the next"},
            **{name: ({"choices": list(rng)} if isinstance(rng[0], str) else
                      {"units": name.rsplit("_", 1)[-1], "range": list(rng)})
               for name, rng in model.input_ranges.items()},
        },
        "training_data": [{"path": str(p), "manifest_sha256": h}
                          for p, h in zip(data, hashes, strict=True)],
        "split": {"held_out": f"sample_index % {HOLDOUT_EVERY} == {HOLDOUT_EVERY - 1}",
                  "n_train": len(train_runs), "n_held_out": len(held)},
        "metrics": metrics,
        "created": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "versions": _versions(),
        "files": {"coefficients": "coefficients.json"},
    }
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        (tmp / "coefficients.json").write_text(json.dumps(coefficients, indent=1) + "\n")
        card["sha256"] = {"coefficients.json": _sha256(tmp / "coefficients.json")}
        (tmp / "card.json").write_text(json.dumps(card, indent=1) + "\n")
        if out.exists():
            out.rmdir()
        os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return card


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m surrogate.rom --data DATASET... --out models/NAME``."""
    p = argparse.ArgumentParser(prog="python -m surrogate.rom", description=__doc__.split(
        "\n")[0])
    p.add_argument("--data", nargs="+", required=True, help="transient dataset directories")
    p.add_argument("--out", required=True, help="model directory to create")
    p.add_argument("--threshold", type=float, default=0.02, help="STLSQ threshold")
    args = p.parse_args(argv)
    try:
        card = train(args.data, args.out, threshold=args.threshold)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(json.dumps(card["metrics"]["held_out"]["summary"], indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
