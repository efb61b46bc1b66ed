"""Run-time transient ROM: the vibration envelope of an ERM haptic unit for any drive schedule.

numpy only (no fem, pysindy, scipy): ``load_envelope_model(path)`` reads the plain-JSON
coefficients that ``surrogate.rom`` identified from transient FE runs and integrates them.

Model (SI inside; um and ms only in names at the edges):

- Motor speed omega(t), rad/s, from the drive voltage with the ERM's first-order dynamics:
  target speed ``omega_T(V) = sign(V) k_v max(|V| - V_start, 0)`` (k_v from the rated voltage
  and frequency), ``d omega/dt = (omega_T - omega) / tau`` with ``tau = tau_spinup`` while
  ``|omega_T| > omega`` and ``tau_spindown`` otherwise, omega clamped at >= 0 (reverse drive
  brakes, never spins the motor backwards). The voltage is held constant between the given
  samples and every step is integrated exactly.
- Complex envelopes: every displacement component c of a point (u_r, u_theta at the center;
  u_r, u_z, u_theta at the edge) is u_c(t) = Re(z_c(t) e^{i phi(t)}), phi the rotor angle, and
  the point's envelope is sqrt(sum_c |z_c|^2) (in steady running the harmonic magnitude
  sqrt(|U_r|^2 + |U_z|^2 + |U_t|^2)). Each z_c = p + i q (um) follows one damped mode seen from
  the rotating frame of the force m e omega^2:
  ``dz/dt = (A(d) + omega(t) J) z + b(d) s^2``, J = [[0, 1], [-1, 0]] (the frame rotation,
  known exactly), s = omega / omega_rated, A(d) = A0 + sum_j d_j A_j and b(d) = b0 + sum_j d_j
  b_j affine in design features d (each about -1..1). The eigenvalues of A0 are the mode's
  damping (real part, 1/s) and natural frequency (imaginary part, rad/s).
  Each step is integrated exactly for omega and s^2 held at their step averages (an
  exponential integrator: any time step is stable).

Blow-up guard: at load, A(d) + omega J must have eigenvalues with negative real parts over a
grid of the trained design box and speeds (else :class:`RomBlowUpError`); ``simulate`` checks
the actual design the same way (a clean refusal for an extrapolated design that would be
unstable), and a state leaving the finite bound stored with the model (a multiple of the
largest trained envelope) stops with :class:`RomBlowUpError` naming the time.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fieldspec.documents import loads_json, read_json_file
from surrogate.runtime.card import CARD_NAME, ModelFileError, read_card, read_model_file
from surrogate.runtime.rom_checks import check_spec, finite

__all__ = [
    "FORMAT",
    "EnvelopeModel",
    "MotorConstants",
    "RomBlowUpError",
    "RomInputError",
    "design_features",
    "design_grid",
    "load_envelope_model",
    "motor_speed",
]

FORMAT = "hapticrom-envelope-rom/1"
STATES = ("center_envelope_um", "edge_envelope_um")


class RomBlowUpError(RuntimeError):
    """The envelope simulation diverged (or the model's linear part is unstable)."""


class RomInputError(ValueError):
    """Bad input to the ROM; ``field`` names the offending input."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(f"{field}: {message}")
        self.field = field


# --------------------------------------------------------------------------- motor speed


@dataclass(frozen=True)
class MotorConstants:
    """Steady-speed law of the ERM (the defaults of ``fem.motor.ERMMotor``: 120 rev/s at
    3.3 V, rotor stiction below 0.4 V, at most 4.5 V)."""

    rated_voltage_V: float = 3.3
    rated_frequency_hz: float = 120.0
    start_voltage_V: float = 0.4
    max_voltage_V: float = 4.5

    @property
    def rated_omega(self) -> float:
        """Rated speed, rad/s."""
        return 2.0 * math.pi * self.rated_frequency_hz

    def target_omega(self, volts: NDArray) -> NDArray:
        """Signed speed the motor is driven towards, rad/s (negative: braking)."""
        per_volt = self.rated_omega / (self.rated_voltage_V - self.start_voltage_V)
        return np.sign(volts) * per_volt * np.maximum(np.abs(volts) - self.start_voltage_V, 0.0)


def motor_speed(t_s: NDArray, volts: NDArray, tau_up_s: float, tau_down_s: float,
                motor: MotorConstants) -> NDArray:
    """Speed omega (rad/s) at the times ``t_s`` (s) for voltage ``volts[k]`` held on
    [t_k, t_k+1), from rest at t_0; each step exact (tau chosen at the step's start; a
    braking step that would cross zero stops at rest)."""
    h = np.diff(t_s)
    steps = zip(motor.target_omega(volts[:-1]).tolist(), np.exp(-h / tau_up_s).tolist(),
                np.exp(-h / tau_down_s).tolist(), strict=True)
    omega = [0.0]
    w = 0.0
    for tgt, decay_up, decay_down in steps:  # a scalar recurrence on Python floats
        decay = decay_up if abs(tgt) > w else decay_down
        w = max(tgt + (w - tgt) * decay, 0.0) if (w > 0.0 or tgt > 0.0) else 0.0
        omega.append(w)
    return np.array(omega)


# --------------------------------------------------------------------------- features


def design_features(design: Mapping[str, Any], spec: Mapping[str, Any]) -> dict[str, float]:
    """Named design features d (dimensionless, about -1..1) from a design mapping.

    ``spec["design"]`` lists each design input: continuous ``{"name", "low", "high",
    "scale"}`` map to [-1, 1] (on a log scale when ``scale == "log"``); categorical
    ``{"name", "choices": [a, b]}`` map to -1 / +1."""
    out: dict[str, float] = {}
    for item in spec["design"]:
        name = item["name"]
        if "choices" in item:
            a, b = item["choices"]
            out[name] = -1.0 if design[name] == a else 1.0
            continue
        lo, hi, v = float(item["low"]), float(item["high"]), float(design[name])
        if item.get("scale") == "log":
            lo, hi, v = math.log(lo), math.log(hi), math.log(v)
        out[name] = 2.0 * (v - lo) / (hi - lo) - 1.0
    for a, b in spec.get("interactions", []):
        out[f"{a}*{b}"] = out[a] * out[b]
    return out


# --------------------------------------------------------------------------- the model


_J = np.array([[0.0, 1.0], [-1.0, 0.0]])  # d/dt of (p, q) from the frame rotation, per rad/s


def _expm(m: NDArray) -> NDArray:
    """Matrix exponentials of a stack (..., n, n) of small matrices: scaling and squaring with
    a 12-term Taylor series (remainder below 0.25^13 / 13! ~ 2e-18 once ||m|| / 2^j <= 0.25)."""
    norm = float(np.max(np.sum(np.abs(m), axis=-1))) if m.size else 0.0
    j = max(0, math.ceil(math.log2(norm / 0.25))) if norm > 0.25 else 0
    a = m / 2.0**j
    term = np.broadcast_to(np.eye(m.shape[-1]), m.shape).copy()
    out = term.copy()
    for k in range(1, 13):
        term = term @ a / k
        out = out + term
    for _ in range(j):
        out = out @ out
    return out


@dataclass(frozen=True)
class Block:
    """One complex envelope z = p + i q (um) of displacement ``component`` at ``point``.

    A0 (2, 2) 1/s and b0 (2,) um/s, with per-design-feature increments A_d (nd, 2, 2) and
    b_d (nd, 2) in the order of ``EnvelopeModel.design_names``."""

    point: str
    component: str
    A0: NDArray
    A_d: NDArray
    b0: NDArray
    b_d: NDArray

    def matrices(self, d: NDArray) -> tuple[NDArray, NDArray]:
        """A(d) (..., 2, 2) and b(d) (..., 2) for design features d (..., nd)."""
        A = self.A0 + np.einsum("...j,jkl->...kl", d, self.A_d)
        return A, self.b0 + d @ self.b_d


@dataclass(frozen=True)
class EnvelopeModel:
    """Identified envelope ROM (see module docstring).

    Attributes:
        blocks: one complex envelope per (point, component).
        spec: design inputs (names, ranges, choices), interactions, motor-constant ranges.
        motor: the ERM's steady-speed law.
        bound_um: an envelope above this is a blow-up (um).
    """

    blocks: tuple[Block, ...]
    spec: dict[str, Any]
    motor: MotorConstants
    bound_um: float

    @property
    def design_names(self) -> list[str]:
        """Design features d, in the order of the A_d / b_d rows."""
        names = [item["name"] for item in self.spec["design"]]
        return names + [f"{a}*{b}" for a, b in self.spec.get("interactions", [])]

    @property
    def input_names(self) -> tuple[str, ...]:
        return (*(item["name"] for item in self.spec["design"]), "tau_spinup_ms",
                "tau_spindown_ms")

    @property
    def input_ranges(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for item in self.spec["design"]:
            out[item["name"]] = (tuple(item["choices"]) if "choices" in item
                                 else (float(item["low"]), float(item["high"])))
        out.update({k: tuple(v) for k, v in self.spec["motor_ranges"].items()})
        return out

    def features(self, design: Mapping[str, Any]) -> NDArray:
        """Design feature vector d of a (checked) design mapping."""
        d = design_features(design, self.spec)
        return np.array([d[name] for name in self.design_names])

    def max_growth_rate(self, d: NDArray) -> float:
        """Largest real part (1/s) of the eigenvalues of A(d) + omega J over the design
        features ``d`` (..., nd) and speeds 0..1.5 omega_rated: < 0 means every frozen
        state of the model decays."""
        omegas = np.linspace(0.0, 1.5 * self.motor.rated_omega, 31)
        worst = -math.inf
        for blk in self.blocks:
            A, _ = blk.matrices(d)
            M = A[..., None, :, :] + omegas[:, None, None] * _J
            worst = max(worst, float(np.max(np.linalg.eigvals(M).real)))
        return worst

    def simulate(self, t_s: Any, volts: Any, design: Mapping[str, Any], *,
                 extrapolate: bool = False) -> dict[str, NDArray]:
        """Envelopes (um) at the times ``t_s`` (s, increasing, starting from rest) for the
        drive ``volts`` (V, held from each time to the next) and the ``design`` mapping
        (``input_names``; motor time constants in ms). Returns ``center_envelope_um``,
        ``edge_envelope_um`` and ``speed_hz`` (rev/s). Raises :class:`RomInputError` for bad
        input (out of the trained range unless ``extrapolate``) and :class:`RomBlowUpError`
        for a design whose model is unstable or a state leaving ``bound_um``."""
        t, v = self._check_drive(t_s, volts)
        dsg = self._check_design(design, extrapolate)
        d = self.features(dsg)
        if extrapolate and self.max_growth_rate(d) >= 0.0:
            raise RomBlowUpError(f"the model is unstable for this (extrapolated) design "
                                 f"{dict(dsg)}: refusing to simulate")
        omega = motor_speed(t, v, dsg["tau_spinup_ms"] * 1e-3, dsg["tau_spindown_ms"] * 1e-3,
                            self.motor)
        z = self._integrate(t, omega, d)
        out: dict[str, NDArray] = {}
        for point, name in zip(("center", "edge"), STATES, strict=True):
            rows = [i for i, blk in enumerate(self.blocks) if blk.point == point]
            out[name] = np.sqrt(np.sum(z[:, rows, :] ** 2, axis=(1, 2)))
        out["speed_hz"] = omega / (2 * math.pi)
        return out

    def _integrate(self, t: NDArray, omega: NDArray, d: NDArray) -> NDArray:
        """(nt, n_blocks, 2) states from rest; omega and s^2 at their step averages."""
        h = np.diff(t)
        w = 0.5 * (omega[1:] + omega[:-1])
        s2 = 0.5 * ((omega[1:] / self.motor.rated_omega) ** 2
                    + (omega[:-1] / self.motor.rated_omega) ** 2)
        nb = len(self.blocks)
        aug = np.zeros((h.size, nb, 3, 3))
        for i, blk in enumerate(self.blocks):
            A, b = blk.matrices(d)
            aug[:, i, :2, :2] = (A[None] + w[:, None, None] * _J) * h[:, None, None]
            aug[:, i, :2, 2] = b[None] * (s2 * h)[:, None]
        e = _expm(aug)
        return _recurrence(e[..., :2, :2], e[..., :2, 2], t, self.bound_um)

    def _check_drive(self, t_s: Any, volts: Any) -> tuple[NDArray, NDArray]:
        t = np.asarray(t_s, dtype=float)
        v = np.asarray(volts, dtype=float)
        if t.ndim != 1 or t.size < 2:
            raise RomInputError("t_s", f"need a 1-D array of at least 2 times, got shape "
                                f"{t.shape}")
        if v.shape != t.shape:
            raise RomInputError("volts", f"shape {v.shape} must match t_s {t.shape}")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise RomInputError("t_s", "times must be finite and strictly increasing (s)")
        limit = self.motor.max_voltage_V
        if not np.all(np.isfinite(v)) or np.any(np.abs(v) > limit):
            raise RomInputError("volts", f"voltages must be finite and within [-{limit}, "
                                f"{limit}] V")
        return t, v

    def _check_design(self, design: Mapping[str, Any], extrapolate: bool) -> dict[str, Any]:
        if not isinstance(design, Mapping):
            raise RomInputError("design", f"need a mapping of {list(self.input_names)}")
        out: dict[str, Any] = {}
        for name, allowed in self.input_ranges.items():
            if name not in design:
                raise RomInputError(name, f"missing from design (inputs: "
                                    f"{list(self.input_names)})")
            value = design[name]
            if isinstance(allowed[0], str):
                if value not in allowed:
                    raise RomInputError(name, f"{value!r} is not one of {list(allowed)}")
                out[name] = value
                continue
            try:
                x = float(value)
            except (TypeError, ValueError):
                raise RomInputError(name, f"{value!r} is not a number") from None
            lo, hi = allowed
            if not math.isfinite(x) or (x <= 0 and name.startswith("tau")):
                raise RomInputError(name, f"{value!r} must be finite (and > 0 for a time "
                                    "constant)")
            if not extrapolate and not lo <= x <= hi:
                raise RomInputError(name, f"{x:g} is outside the trained range [{lo:g}, "
                                    f"{hi:g}] (pass extrapolate=True to accept)")
            out[name] = x
        unknown = sorted(set(design) - set(out))
        if unknown:
            raise RomInputError(unknown[0], f"unknown design input (inputs: "
                                f"{list(self.input_names)})")
        return out


def _recurrence(phi: NDArray, gamma: NDArray, t: NDArray, bound_um: float) -> NDArray:
    """x_{k+1} = phi_k x_k + gamma_k from x_0 = 0 for (nsteps, nb, 2, 2) phi and (nsteps, nb,
    2) gamma; (nt, nb, 2) states. Raises :class:`RomBlowUpError` at the first step whose state
    is not finite or exceeds ``bound_um``.

    The recurrence is sequential; on Python floats it runs much faster than numpy calls on
    2-vectors (the step matrices themselves are batched)."""
    nsteps, nb = gamma.shape[:2]
    coef = np.concatenate([phi.reshape(nsteps, nb, 4), gamma], axis=2).tolist()
    out = np.zeros((nsteps + 1, nb, 2))
    rows: list[list[float]] = []
    state = [[0.0, 0.0] for _ in range(nb)]
    for k in range(nsteps):
        step = coef[k]
        for i in range(nb):
            a, b, c, d, g0, g1 = step[i]
            p, q = state[i]
            state[i] = [a * p + b * q + g0, c * p + d * q + g1]
        flat = [v for pq in state for v in pq]
        if not (max(map(abs, flat)) <= bound_um and math.isfinite(sum(flat))):
            raise RomBlowUpError(f"envelope diverged at t = {t[k + 1]:.6g} s (beyond the "
                                 f"model's bound {bound_um:g} um)")
        rows.append(flat)
    if rows:
        out[1:] = np.asarray(rows).reshape(nsteps, nb, 2)
    return out


# --------------------------------------------------------------------------- loading


def model_from_dict(d: Mapping[str, Any]) -> EnvelopeModel:
    """An :class:`EnvelopeModel` from the coefficients JSON dict (``FORMAT``); raises
    ValueError for a malformed dict and :class:`RomBlowUpError` for an unstable model."""
    if d.get("format") != FORMAT:
        raise ValueError(f"format: expected {FORMAT!r}, got {d.get('format')!r}")
    spec = dict(d["spec"])
    check_spec(spec)
    nd = len(spec["design"]) + len(spec.get("interactions", []))
    blocks = []
    for i, blk in enumerate(d["blocks"]):
        arrays = [np.asarray(blk[k], dtype=float) for k in ("A0", "A_d", "b0", "b_d")]
        shapes = [(2, 2), (nd, 2, 2), (2,), (nd, 2)]
        for key, arr, shape in zip(("A0", "A_d", "b0", "b_d"), arrays, shapes, strict=True):
            if arr.shape != shape or not np.all(np.isfinite(arr)):
                raise ValueError(f"blocks[{i}].{key}: need finite values of shape {shape}, "
                                 f"got {arr.shape}")
        if blk["point"] not in ("center", "edge"):
            raise ValueError(f"blocks[{i}].point: {blk['point']!r} is not center or edge")
        blocks.append(Block(str(blk["point"]), str(blk["component"]), *arrays))
    motor = MotorConstants(**{k: finite(f"motor.{k}", v) for k, v in d["motor"].items()})
    if not 0 <= motor.start_voltage_V < motor.rated_voltage_V <= motor.max_voltage_V \
            or motor.rated_frequency_hz <= 0:
        raise ValueError(f"motor: need 0 <= start < rated <= max voltage and a positive "
                         f"rated frequency, got {d['motor']}")
    bound = finite("bound_um", d["bound_um"])
    if bound <= 0:
        raise ValueError(f"bound_um: need > 0, got {bound}")
    model = EnvelopeModel(tuple(blocks), spec, motor, bound)
    rate = model.max_growth_rate(design_grid(model))
    if rate >= 0.0:
        raise RomBlowUpError(f"the model's linear part is unstable: an eigenvalue of A(d) + "
                             f"omega J has real part {rate:.4g} 1/s >= 0 in the trained range")
    return model


def design_grid(model: EnvelopeModel) -> NDArray:
    """Design features over the trained box: continuous inputs at -1, 0, 1, every choice of
    the categorical ones; (n, nd)."""
    axes = [[-1.0, 1.0] if "choices" in item else [-1.0, 0.0, 1.0]
            for item in model.spec["design"]]
    names = [item["name"] for item in model.spec["design"]]
    grid = np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(axes), -1).T
    cols = [grid] + [grid[:, [names.index(a)]] * grid[:, [names.index(b)]]
                     for a, b in model.spec.get("interactions", [])]
    return np.concatenate(cols, axis=1)


def load_envelope_model(path: str | Path) -> EnvelopeModel:
    """Load a ROM from a ``models/NAME/`` directory (verified as a whole,
    :func:`surrogate.runtime.card.verify_model_dir`; its card names the coefficients file) or
    from a coefficients JSON file. A malformed file is a :class:`ModelFileError` naming it;
    an unstable model a :class:`RomBlowUpError`."""
    p = Path(path)
    if p.is_dir():
        card = read_card(p)
        if card.get("kind") != "rom":
            raise ModelFileError("kind", f"{p / CARD_NAME}: a {card.get('kind')!r} model, not "
                                 "a transient ROM")
        name = card["coefficients"]
        where = p / name
        text = read_model_file(p, card, name).decode("utf-8", errors="replace")
        data = loads_json(text, where, ModelFileError)
    else:
        where, name = p, p.name
        data = read_json_file(p, ModelFileError, "ROM coefficients file")
    if not isinstance(data, Mapping):
        raise ModelFileError(name, f"{where}: not a JSON object (check: coefficients)")
    try:
        return model_from_dict(data)
    except RomBlowUpError:
        raise
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as err:
        raise ModelFileError(name, f"{where}: malformed coefficients (check: coefficients; "
                             f"{type(err).__name__}: {err})") from None
