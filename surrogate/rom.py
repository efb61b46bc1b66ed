"""Identify the transient envelope ROM of an ERM haptic unit with pysindy (SINDy with control).

Training data: transient datasets generated from ``datasets/spaces/transient.toml`` (rows with
``history_center_um`` / ``history_edge_um``: [u_r, u_z, u_theta] in um on the theta = 0
meridian, and the resolved scene with its voltage schedule and motor). Nothing here imports
the solver: it trains from stored rows only.

Model (see ``surrogate.runtime.rom`` for the run-time side, which this module shares the
motor-speed law and the feature definitions with):

- Complex envelopes: each displacement component c of a point is demodulated with the
  rotor angle phi (known exactly from the motor law): z_c = analytic(u_c) e^{-i phi}, the
  analytic signal from the Hilbert transform. The point's envelope sqrt(sum_c |z_c|^2) is the
  harmonic magnitude sqrt(|U_r|^2 + |U_z|^2 + |U_t|^2) of ``fem.results`` in steady running.
- One damped mode per complex envelope, seen from the frame rotating with the force:
  ``dz/dt + omega J z = A(d) z + b(d) s^2`` with s = omega / omega_rated (the unbalance force
  m e omega^2) and A, b affine in the design features d (skin modulus on a log scale, fat
  thickness, orientation, attachment, orientation x attachment, each scaled to [-1, 1]). The
  frame term omega J z is known and moved to the left-hand side, so SINDy-with-control
  regresses the measured derivative on the identity library of (p, q) plus the control
  signals p d_j, q d_j, s^2, s^2 d_j (products of measured signals: the same regression).
- Sparse regression: STLSQ (normalized columns), bagged over time samples
  (``EnsembleOptimizer``) for the coefficients' spread; the median model is kept.

Stability: every A(d) + omega J over the trained design box and speeds must have eigenvalues
with negative real parts (checked at load, ``surrogate.runtime.rom.model_from_dict``).
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from surrogate.registry import check_model_out, package_versions, write_model
from surrogate.runtime.card import read_card
from surrogate.runtime.rom import (
    FORMAT,
    STATES,
    EnvelopeModel,
    MotorConstants,
    design_features,
    design_grid,
    model_from_dict,
    motor_speed,
)

__all__ = ["Run", "complex_envelopes", "evaluate", "fit_envelope_model", "load_runs", "train"]

DESIGN_SPEC: dict[str, Any] = {
    # ranges are replaced by the training data's own; choices order: -1, +1
    "design": [
        {"name": "skin_E_kPa", "low": 20.0, "high": 120.0, "scale": "log"},
        {"name": "fat_thickness_mm", "low": 3.0, "high": 20.0},
        {"name": "orientation", "choices": ["forward", "reverse"]},
        {"name": "attachment", "choices": ["glued", "pogo"]},
    ],
    "interactions": [["orientation", "attachment"]],
}
COMPONENTS = ("r", "z", "theta")
CONTINUOUS = tuple(d["name"] for d in DESIGN_SPEC["design"] if "choices" not in d)
EDGE_TRIM_S = 3e-3  # the Hilbert transform is least accurate within ~1 period of the ends
HOLDOUT_EVERY = 4  # rows with sample_index % 4 == 3 are held out
COEFFICIENTS_FILE = "coefficients.json"
MIN_COMPONENT = 1e-3  # a component below this fraction of its point's peak is not modelled


@dataclass(frozen=True)
class Run:
    """One transient FE run.

    Attributes:
        t: (nt,) times, s. volts: (nt,) drive held from each time, V.
        omega: (nt,) motor speed, rad/s (exact switch times).
        z: point -> (3, nt) complex envelopes (u_r, u_z, u_theta) in um.
        design: ``EnvelopeModel.input_names`` -> value. sample_index: dataset row index.
        on_time_s: first time the drive drops to <= 0 V (end of the drive phase), s.
    """

    t: NDArray
    volts: NDArray
    omega: NDArray
    z: dict[str, NDArray]
    design: dict[str, Any]
    sample_index: int
    on_time_s: float

    @property
    def envelope(self) -> NDArray:
        """(nt, 2) FE envelopes (center, edge), um."""
        return np.column_stack([np.sqrt(np.sum(np.abs(self.z[p]) ** 2, axis=0))
                                for p in ("center", "edge")])


def complex_envelopes(u: NDArray, phi: NDArray) -> NDArray:
    """Complex envelopes analytic(u_c) e^{-i phi} of (3, nt) component histories.

    Before the FFT-based Hilbert transform the record is extended at its start by odd
    reflection (continuous in value and slope: the run starts from rest) and at its end by
    zeros (a reflection there adds a spurious offset or a kink), which keeps the end
    artefacts within about a period."""
    from scipy.signal import hilbert

    u = np.asarray(u, dtype=float)
    head = -u[:, 1:][:, ::-1]
    tail = np.zeros((u.shape[0], u.shape[1] - 1))
    ext = np.concatenate([head, u, tail], axis=1)
    a = hilbert(ext, axis=1)[:, head.shape[1]: head.shape[1] + u.shape[1]]
    return a * np.exp(-1j * phi)


def _schedule_volts(t: NDArray, schedule_ms: Sequence[Sequence[float]]) -> NDArray:
    """Voltage held at each time (s) of a [[t_ms, V], ...] step schedule."""
    starts = np.array([s[0] for s in schedule_ms]) * 1e-3
    levels = np.array([s[1] for s in schedule_ms], dtype=float)
    return levels[np.searchsorted(starts, t + 1e-12, side="right") - 1]


def _speed_and_phase(t: NDArray, schedule_ms: Sequence[Sequence[float]], tau_up_s: float,
                     tau_down_s: float, motor: MotorConstants) -> tuple[NDArray, NDArray]:
    """Motor speed (rad/s) and rotor angle (rad) at times ``t``: the speed law on a 10x finer
    grid that holds the schedule's switch times exactly, the angle by the trapezoidal rule."""
    switches = np.array([s[0] for s in schedule_ms]) * 1e-3
    fine = np.union1d(np.linspace(t[0], t[-1], 10 * (t.size - 1) + 1),
                      switches[(switches > t[0]) & (switches < t[-1])])
    omega = motor_speed(fine, _schedule_volts(fine, schedule_ms), tau_up_s, tau_down_s, motor)
    phi = np.concatenate([[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * np.diff(fine))])
    return np.interp(t, fine, omega), np.interp(t, fine, phi)


def load_runs(paths: Sequence[str | Path]) -> tuple[list[Run], MotorConstants, list[str]]:
    """Successful transient unit runs of the datasets, their common motor law, and the
    sha256 of each dataset's manifest. Raises ValueError if a dataset holds no such run."""
    from surrogate.data.store import Store

    runs: list[Run] = []
    motor: MotorConstants | None = None
    hashes = []
    for path in paths:
        manifest = Path(path) / "_manifest.json"
        if not manifest.is_file():
            raise ValueError(f"--data: {path} is not a dataset (no _manifest.json)")
        hashes.append(hashlib.sha256(manifest.read_bytes()).hexdigest())
        df = Store.open(path).read()  # the manifest's parts, checked against their digests
        if "history_center_um" not in df:
            raise ValueError(f"--data: {path} holds no center/edge histories (generate it "
                             "from a transient space of a unit)")
        df = df[(df["status"] == "ok") & df["history_center_um"].notna()]
        for row in df.to_dict("records"):
            run, m = _run_from_row(row)
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
                           max(4.5, max(abs(v) for _, v in schedule)))  # as fem.time_domain
    t = np.asarray(row["history_t_s"], dtype=float)
    design = {"skin_E_kPa": float(scene["tissue"]["layer"][0]["E_kPa"]),
              "fat_thickness_mm": float(scene["tissue"]["layer"][1]["thickness_mm"]),
              "orientation": scene["unit"]["orientation"],
              "attachment": scene["unit"]["attachment"],
              "tau_spinup_ms": float(m["tau_spinup_ms"]),
              "tau_spindown_ms": float(m["tau_spindown_ms"])}
    omega, phi = _speed_and_phase(t, schedule, design["tau_spinup_ms"] * 1e-3,
                                  design["tau_spindown_ms"] * 1e-3, motor)
    z = {p: complex_envelopes(np.stack([np.asarray(c, dtype=float)
                                        for c in row[f"history_{p}_um"]]), phi)
         for p in ("center", "edge")}
    off = [s[0] * 1e-3 for s in schedule if s[1] <= 0.0]
    return Run(t, _schedule_volts(t, schedule), omega, z, design, int(row["sample_index"]),
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


def _design_names(spec: Mapping[str, Any]) -> list[str]:
    return ([item["name"] for item in spec["design"]]
            + [f"{a}*{b}" for a, b in spec.get("interactions", [])])


def _block_rows(run: Run, point: str, c: int, d: NDArray, rated_omega: float
                ) -> tuple[NDArray, NDArray]:
    """Library rows and targets of one complex envelope, ends trimmed: real parts stacked
    over imaginary parts, so that every term has one complex coefficient (see
    :func:`_complex_library`)."""
    z = run.z[point][c]
    target = np.gradient(z, run.t) + 1j * run.omega * z  # dz/dt + omega J z
    s2 = (run.omega / rated_omega) ** 2 + 0j
    keep = (run.t >= run.t[0] + EDGE_TRIM_S) & (run.t <= run.t[-1] - EDGE_TRIM_S)
    terms = np.column_stack([z, z[:, None] * d, s2, s2[:, None] * d])[keep]
    return _complex_library(terms), np.concatenate([target[keep].real, target[keep].imag])


def _complex_library(terms: NDArray) -> NDArray:
    """Real regression matrix of complex terms f_k with complex coefficients c_k:
    Re(sum c f) = sum Re c Re f - Im c Im f, Im(sum c f) = sum Re c Im f + Im c Re f; columns
    (Re c_0, Im c_0, Re c_1, ...)."""
    top = np.stack([terms.real, -terms.imag], axis=-1).reshape(terms.shape[0], -1)
    bottom = np.stack([terms.imag, terms.real], axis=-1).reshape(terms.shape[0], -1)
    return np.concatenate([top, bottom])


def _real_block(c: NDArray) -> NDArray:
    """The real 2x2 matrix of multiplication by the complex number c on (p, q)."""
    return np.array([[c.real, -c.imag], [c.imag, c.real]])


def _modelled_components(runs: Sequence[Run]) -> list[tuple[str, int]]:
    out = []
    for point in ("center", "edge"):
        peak = np.array([np.max(np.abs(r.z[point]), axis=1) for r in runs]).max(axis=0)
        out += [(point, c) for c in range(3) if peak[c] > MIN_COMPONENT * peak.max()]
    return out


def fit_envelope_model(runs: Sequence[Run], motor: MotorConstants, *, threshold: float = 1e-3,
                       n_models: int = 20, seed: int = 0) -> tuple[dict[str, Any], list[str]]:
    """Sparse identification of every complex envelope; returns the coefficients dict
    (``surrogate.runtime.rom`` format) and the identified equations as text.

    The library (z, z d_j, s^2, s^2 d_j with one complex coefficient each; z d_j purely
    imaginary for continuous d_j): a single damped mode whose natural frequency and forcing
    vary with the design. One complex coefficient per term is a linear constraint between
    the real and imaginary equations, which ``pysindy.SINDy`` cannot impose without cvxpy
    (``ConstrainedSR3``); so the real regression matrix is built here and pysindy's STLSQ,
    bagged by ``EnsembleOptimizer``, solves it (``threshold`` applies to the normalized
    columns)."""
    import pysindy as ps

    spec = _spec_from_runs(runs)
    names = _design_names(spec)
    nd = len(names)
    terms = ["z"] + [f"z*{n}" for n in names] + ["s^2"] + [f"s^2*{n}" for n in names]
    d_of = {r.sample_index: np.array([design_features(r.design, spec)[n] for n in names])
            for r in runs}
    blocks, equations = [], []
    for point, c in _modelled_components(runs):
        rows = [_block_rows(r, point, c, d_of[r.sample_index], motor.rated_omega) for r in runs]
        theta = np.concatenate([th for th, _ in rows])
        y = np.concatenate([yy for _, yy in rows])
        # Continuous design inputs shift the mode's frequency (Im) but not its damping (Re):
        # a damping affine in them turns negative at corners of the box that the data do not
        # reach. The categorical inputs (every combination is trained) may change both. With
        # Re lambda(d) < 0 the model is contractive for any speed history.
        free = np.ones(theta.shape[1], dtype=bool)
        free[[2 + 2 * j for j, n in enumerate(names) if n in CONTINUOUS]] = False
        np.random.seed(seed)  # noqa: NPY002 - EnsembleOptimizer bags with the global generator
        opt = ps.EnsembleOptimizer(ps.STLSQ(threshold=threshold, normalize_columns=True),
                                   bagging=True, n_models=n_models)
        opt.fit(theta[:, free], y[:, None])
        coef = np.zeros(theta.shape[1])
        coef[free] = np.asarray(opt.coef_)[0]
        cc = coef[0::2] + 1j * coef[1::2]  # complex coefficient of each term
        spread = np.std(np.asarray(opt.coef_list)[:, 0], axis=0)
        spread = float(np.linalg.norm(spread) / np.linalg.norm(coef))
        blocks.append({
            "point": point, "component": COMPONENTS[c],
            "A0": _real_block(cc[0]).tolist(),
            "A_d": [_real_block(x).tolist() for x in cc[1: 1 + nd]],
            "b0": [cc[1 + nd].real, cc[1 + nd].imag],
            "b_d": [[x.real, x.imag] for x in cc[2 + nd:]],
            "mode": {"damping_1_s": float(-cc[0].real),
                     "frequency_hz": float(cc[0].imag / (2 * math.pi))},
            "relative_spread": spread,
            "terms_kept": int(np.count_nonzero(cc)), "terms": len(terms),
        })
        eq = " + ".join(f"({x.real:.4g}{x.imag:+.4g}i) {n}" for x, n in zip(cc, terms,
                                                                           strict=True) if x)
        equations.append(f"{point} u_{COMPONENTS[c]}: dz/dt + i omega z = {eq}")
    peak = max(float(np.max(r.envelope)) for r in runs)
    coefficients = {
        "format": FORMAT,
        "states": list(STATES),
        "design_features": names,
        "blocks": blocks,
        "spec": spec,
        "motor": {"rated_voltage_V": motor.rated_voltage_V,
                  "rated_frequency_hz": motor.rated_frequency_hz,
                  "start_voltage_V": motor.start_voltage_V,
                  "max_voltage_V": motor.max_voltage_V},
        # 100x the largest trained envelope: far above any physical response of the space
        "bound_um": 100.0 * peak,
    }
    return coefficients, equations


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


def _finite(obj: Any) -> Any:
    """``obj`` with every non-finite float (an undefined metric, e.g. an envelope that never
    decays within the record) replaced by None, so that the card is strict JSON."""
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def train(data: Sequence[str | Path], out: str | Path, *, threshold: float = 1e-3,
          seed: int = 0, overwrite: bool = False) -> dict[str, Any]:
    """Fit on the training rows of ``data`` (every sample with index % 4 != 3), validate on
    the held-out rows, register ``out`` (card.json + coefficients.json, written atomically
    by :func:`surrogate.registry.write_model`); returns the card."""
    out = Path(out)
    check_model_out(out, overwrite)  # before the work: the output may not be replaced
    if not 0 < threshold < 1:
        raise ValueError(f"threshold = {threshold!r}: allowed (0, 1)")
    runs, motor, hashes = load_runs(data)
    train_runs = [r for r in runs if r.sample_index % HOLDOUT_EVERY != HOLDOUT_EVERY - 1]
    held = [r for r in runs if r.sample_index % HOLDOUT_EVERY == HOLDOUT_EVERY - 1]
    if len(train_runs) < 4 or not held:
        raise ValueError(f"--data: need at least 4 training and 1 held-out run, got "
                         f"{len(train_runs)} and {len(held)}")
    coefficients, equations = fit_envelope_model(train_runs, motor, threshold=threshold,
                                                  seed=seed)
    model = model_from_dict(coefficients)  # raises RomBlowUpError if unstable
    metrics = {"train": evaluate(model, train_runs)["summary"],
               "held_out": evaluate(model, held),
               "stability": {
                   "max_real_eigenvalue_1_s": model.max_growth_rate(design_grid(model)),
                   "checked": "A(d) + omega J over the trained design box (continuous inputs "
                              "at -1, 0, 1; every categorical choice) and omega 0..1.5 rated",
                   "modes": {f"{b['point']}_{b['component']}": b["mode"]
                             for b in coefficients["blocks"]}},
               "equations": equations}
    card = {
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
        "coefficients": COEFFICIENTS_FILE,
        "training_data": [{"path": str(p), "manifest_sha256": h}
                          for p, h in zip(data, hashes, strict=True)],
        "split": {"held_out": f"sample_index % {HOLDOUT_EVERY} == {HOLDOUT_EVERY - 1}",
                  "n_train": len(train_runs), "n_held_out": len(held)},
        "training": {"threshold": threshold, "seed": seed},
        "metrics": _finite(metrics),
        "versions": package_versions(),
    }
    body = json.dumps(coefficients, indent=1, allow_nan=False) + "\n"
    write_model(out, card, {COEFFICIENTS_FILE: body.encode()}, overwrite=overwrite)
    return read_card(out)
