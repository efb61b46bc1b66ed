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
- Envelope states x = (center, edge) in um, linear with the speed-dependent forcing
  ``dx/dt = A x + B q(s, d)``, s = omega / omega_rated, q the feature vector named in the
  coefficients file (powers of s times design features d; the unbalance force m e omega^2
  makes s^2 the leading term, higher powers carry the frequency dependence of the compliance).
  Each step is integrated exactly for a forcing linear in time between the samples (a
  first-order-hold exponential integrator), so any time step is stable.

Blow-up guard: the identified A must have eigenvalues with negative real parts (else
:class:`RomBlowUpError` at load), and a simulation whose state leaves the finite bound stored
with the model (a multiple of the largest trained envelope) stops with :class:`RomBlowUpError`
naming the time, instead of returning garbage.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "FORMAT",
    "EnvelopeModel",
    "MotorConstants",
    "RomBlowUpError",
    "RomInputError",
    "design_features",
    "forcing_features",
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
    target = motor.target_omega(volts)
    h = np.diff(t_s)
    omega = np.zeros(t_s.size)
    w = 0.0
    decay_up, decay_down = np.exp(-h / tau_up_s), np.exp(-h / tau_down_s)
    for k in range(h.size):  # a scalar recurrence: each step needs the previous speed
        tgt = target[k]
        decay = decay_up[k] if abs(tgt) > w else decay_down[k]
        w = max(tgt + (w - tgt) * decay, 0.0) if (w > 0.0 or tgt > 0.0) else 0.0
        omega[k + 1] = w
    return omega


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


def forcing_features(s: NDArray, d: Mapping[str, float], names: list[str]) -> NDArray:
    """(nt, len(names)) features ``s^p`` or ``s^p*NAME`` (NAME a design feature) at speed
    ratios ``s``."""
    cols = []
    for name in names:
        power, _, factor = name.partition("*")
        if not power.startswith("s^"):
            raise ValueError(f"forcing feature {name!r}: expected 's^P' or 's^P*NAME'")
        col = s ** int(power[2:])
        cols.append(col * d[factor] if factor else col)
    return np.column_stack(cols) if cols else np.zeros((s.size, 0))


# --------------------------------------------------------------------------- the model


def _expm(m: NDArray) -> NDArray:
    """Matrix exponential of a small matrix: scaling and squaring with an 18-term Taylor
    series (double precision for ||m|| / 2^j <= 0.5)."""
    norm = float(np.max(np.sum(np.abs(m), axis=1)))
    j = max(0, math.ceil(math.log2(norm / 0.5))) if norm > 0.5 else 0
    a = m / 2.0**j
    term = np.eye(m.shape[0])
    out = term.copy()
    for k in range(1, 19):
        term = term @ a / k
        out = out + term
    for _ in range(j):
        out = out @ out
    return out


@dataclass(frozen=True)
class EnvelopeModel:
    """Identified envelope ROM (see module docstring).

    Attributes:
        A: (2, 2) state matrix, 1/s. B: (2, m) forcing matrix, um/s per feature.
        features: the m forcing-feature names (``s^2``, ``s^2*skin_E_kPa``, ...).
        spec: design inputs (names, ranges, choices) and interactions.
        motor: the ERM's steady-speed law.
        bound_um: an envelope above this is a blow-up (um).
        input_ranges: trained range of every design input and of the voltage.
    """

    A: NDArray
    B: NDArray
    features: list[str]
    spec: dict[str, Any]
    motor: MotorConstants
    bound_um: float

    @property
    def input_names(self) -> tuple[str, ...]:
        return tuple(item["name"] for item in self.spec["design"]) + ("tau_spinup_ms",
                                                                       "tau_spindown_ms")

    @property
    def input_ranges(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for item in self.spec["design"]:
            out[item["name"]] = (tuple(item["choices"]) if "choices" in item
                                 else (float(item["low"]), float(item["high"])))
        out.update({k: tuple(v) for k, v in self.spec["motor_ranges"].items()})
        return out

    def eigenvalues(self) -> NDArray:
        """Eigenvalues of A, 1/s."""
        return np.linalg.eigvals(self.A)

    def simulate(self, t_s: Any, volts: Any, design: Mapping[str, Any], *,
                 extrapolate: bool = False) -> dict[str, NDArray]:
        """Envelopes (um) at the times ``t_s`` (s, increasing, starting from rest) for the
        drive ``volts`` (V, held from each time to the next) and the ``design`` mapping
        (``input_names``; motor time constants in ms). Returns ``center_envelope_um``,
        ``edge_envelope_um`` and ``speed_hz`` (rev/s). Raises :class:`RomInputError` for bad
        input (out of the trained range unless ``extrapolate``) and :class:`RomBlowUpError`
        if the state leaves ``bound_um``."""
        t, v = self._check_drive(t_s, volts)
        dsg = self._check_design(design, extrapolate)
        omega = motor_speed(t, v, dsg["tau_spinup_ms"] * 1e-3, dsg["tau_spindown_ms"] * 1e-3,
                            self.motor)
        q = forcing_features(omega / self.motor.rated_omega, design_features(dsg, self.spec),
                             self.features)
        x = self._integrate(t, q @ self.B.T)
        x = np.maximum(x, 0.0)  # an envelope is a magnitude: clip linear undershoot near rest
        return {STATES[0]: x[:, 0], STATES[1]: x[:, 1], "speed_hz": omega / (2 * math.pi)}

    def _integrate(self, t: NDArray, g: NDArray) -> NDArray:
        """x' = A x + g(t), g linear between samples, x(t_0) = 0; exact per step."""
        n = self.A.shape[0]
        x = np.zeros((t.size, n))
        h = np.diff(t)
        cache: dict[float, tuple[NDArray, NDArray, NDArray]] = {}
        for k in range(h.size):  # the recurrence is sequential; step matrices are cached
            key = round(float(h[k]), 15)
            if key not in cache:
                cache[key] = self._step_matrices(h[k])
            phi, g0, g1 = cache[key]
            x[k + 1] = phi @ x[k] + g0 @ g[k] + g1 @ g[k + 1]
            if not np.all(np.isfinite(x[k + 1])) or np.max(np.abs(x[k + 1])) > self.bound_um:
                raise RomBlowUpError(f"envelope diverged at t = {t[k + 1]:.6g} s (state "
                                     f"{x[k + 1].tolist()} um beyond the model's bound "
                                     f"{self.bound_um:g} um)")
        return x

    def _step_matrices(self, h: float) -> tuple[NDArray, NDArray, NDArray]:
        # Augmented exponential [[A, I, 0], [0, 0, I/h], [0, 0, 0]] * h gives, for a forcing
        # g0 + (g1 - g0) s / h, x(h) = Phi x0 + G1 g0 + G2 (g1 - g0) (first-order hold).
        n = self.A.shape[0]
        m = np.zeros((3 * n, 3 * n))
        m[:n, :n] = self.A * h
        m[:n, n:2 * n] = np.eye(n) * h
        m[n:2 * n, 2 * n:] = np.eye(n)
        e = _expm(m)
        phi, g1, g2 = e[:n, :n], e[:n, n:2 * n], e[:n, 2 * n:]
        return phi, g1 - g2, g2

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


# --------------------------------------------------------------------------- loading


def model_from_dict(d: Mapping[str, Any]) -> EnvelopeModel:
    """An :class:`EnvelopeModel` from the coefficients JSON dict (``FORMAT``)."""
    if d.get("format") != FORMAT:
        raise ValueError(f"format: expected {FORMAT!r}, got {d.get('format')!r}")
    A = np.asarray(d["A"], dtype=float)
    B = np.asarray(d["B"], dtype=float)
    feats = list(d["features"])
    if A.shape != (2, 2) or B.shape != (2, len(feats)):
        raise ValueError(f"A must be 2x2 and B 2x{len(feats)}, got {A.shape} and {B.shape}")
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B))):
        raise ValueError("A and B must be finite")
    model = EnvelopeModel(A, B, feats, dict(d["spec"]), MotorConstants(**d["motor"]),
                          float(d["bound_um"]))
    eig = model.eigenvalues()
    if np.any(eig.real >= 0.0):
        raise RomBlowUpError(f"the model's linear part is unstable: eigenvalues of A "
                             f"{eig.tolist()} 1/s (need negative real parts)")
    return model


def load_envelope_model(path: str | Path) -> EnvelopeModel:
    """Load a ROM from a ``models/NAME/`` directory (``card.json`` naming the coefficients
    file; the sha256 of every file listed in the card is verified) or a coefficients JSON."""
    p = Path(path)
    if p.is_dir():
        card = json.loads((p / "card.json").read_text())
        for name, digest in card["sha256"].items():
            actual = hashlib.sha256((p / name).read_bytes()).hexdigest()
            if actual != digest:
                raise ValueError(f"sha256: {p / name} does not match card.json (expected "
                                 f"{digest[:12]}, got {actual[:12]}): the file was altered")
        p = p / card["files"]["coefficients"]
    return model_from_dict(json.loads(p.read_text()))
