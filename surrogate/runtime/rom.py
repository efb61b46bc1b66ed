"""Run-time grey-box envelope model of an ERM haptic unit (numpy + onnxruntime only).

``load_envelope_model(path).simulate(t_s, volts, design)`` gives the vibration envelopes at the
unit's center and edge (um) for any drive schedule. The model is built from what is known and
learns only a small dynamic remainder (coefficients from ``surrogate.envelope.fit``):

1. **Motor speed** omega(t), rad/s, from the voltage schedule by the one ERM law of
   :mod:`motorlaw` (the solver's own), solved exactly for the voltage held between samples.
2. **Steady response at the instantaneous speed**: A(omega), um, the harmonic model (an NN
   with a ``frequency_hz`` input, shipped inside this model's directory as ``harmonic.onnx``
   with its card; ``models/rom-default`` carries ``models/nn-wide``, trained over the motor's
   whole speed range, 20-250 Hz) of that design at f = omega / 2 pi, times a design gain g
   (the harmonic model is trained on hysteretic damping, a finer mesh and a PML; the FE
   transients of ``datasets/transient`` stand in for the hysteretic loss with the causal band
   model of ``fem.viscoelastic``, its closest causal counterpart). The gain may vary over the
   harmonic model's band [f_low, f_high]: g exp(s (f - 130 Hz) / 50 Hz), f clamped into the
   band; g and s are learned only when the fit is asked to (``learn_gain``): in
   ``models/rom-default`` g = 1 and s = 0 (chosen by measurement, docs/transient-model.md),
   so its steady level is the harmonic model's. Below f_low (the first frequency of
   ``grid_hz``, the harmonic model's lowest trained frequency) the response is continued
   with the unbalance force m e omega^2 through the identified mode: A(omega) =
   A(omega_low) (omega / omega_low)^2 |i omega_low - lambda| / |i omega - lambda|
   (:mod:`surrogate.runtime.rom_steady`).
3. **Dynamic correction**: one damped mode lambda = -sigma + i 2 pi f_n per point (unit and
   tissue lag, the beat when the rotor passes the mode, the ring-down after switch-off), seen
   from the frame rotating with the force: ``dz/dt = (lambda - i omega) z + (i omega - lambda)
   A(omega)``, z(0) = 0, envelope |z|. In steady running z = A exactly; sigma > 0 by
   construction, so the model is stable for every schedule. Each step is integrated exactly
   with omega and A held at their step averages. Optionally (``coefficients.modes`` = 2) two
   modes per point, z = z_1 + z_2, mode 1 forced with a share w of the force and mode 2 with
   1 - w, so the steady state is still A (:mod:`surrogate.runtime.rom_modes`); the continuation
   below the band goes through mode 1. ``models/rom-default`` is such a model fitted with
   ``quasi_static_share`` (recorded in its coefficients): mode 1 held at sigma = 5,000 1/s
   passes its share w of A through at once and mode 2 carries the lag and the ring-down.

The mode (log sigma, f_n), log g and s (two modes: also log sigma_2, f_2, w) are affine in
the harmonic model's encoded design features (its own encoding, frequency column left out; with
``group_by`` in the coefficients one map per choice of that input, e.g. glued / pogo), fitted
on FE transients by nonlinear least squares (``surrogate.envelope.fit``: per-run grid search and
refinement, ridge regression on the features, joint refinement). Designs the FE
transient cannot run (a unit on pogo pins with no rings drifts away) are refused.

The model knows its actuator: ``coefficients.actuator`` (a ``motorlaw`` drive-law name; absent
in models trained before it was recorded, such as the shipped one: the coin ERM, ``"unit"``)
gives its drive law, which must be a speed law (no carrier: this model's form); a caller asks
:meth:`EnvelopeModel.check_actuator`, which refuses another actuator naming ``actuator``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fieldspec import FieldError
from fieldspec.documents import loads_json
from motorlaw import SpeedLaw, drive_law_class, held_speed_and_phase
from surrogate.runtime.card import CARD_NAME, ModelFileError, read_card, read_model_file
from surrogate.runtime.encoding import PredictorInputError, n_features
from surrogate.runtime.predictor import Predictor, make_session
from surrogate.runtime.rom_modes import PARAMS, envelope_from_params, mode_response, params_for
from surrogate.runtime.rom_steady import (
    continued_steady,
    gain_factor,
    harmonic_grid,
    steady_from_params,
    steady_response,
)

__all__ = ["FORMAT", "PARAMS", "POINTS", "STATES", "EnvelopeModel", "RomBlowUpError",
           "RomInputError", "continued_steady", "gain_factor", "harmonic_grid",
           "load_envelope_model", "mode_response", "model_from_parts", "motor_speed",
           "steady_response"]

FORMAT = "hapticrom-envelope-rom/2"
POINTS = ("center", "edge")
STATES = ("center_envelope_um", "edge_envelope_um")
MOTOR_INPUTS = ("tau_spinup_ms", "tau_spindown_ms")
LOSS_INPUTS = ("tissue_loss_factor", "ring_loss_factor")  # hysteretic loss factors


class RomBlowUpError(RuntimeError):
    """The envelope simulation left its finite bound (kept for callers; the mode is stable)."""


class RomInputError(FieldError):
    """Bad input to the envelope model; ``field`` names the offending input."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(field, f"{field}: {message}")


def motor_speed(t_s: NDArray, volts: NDArray, tau_up_s: float, tau_down_s: float,
                motor: SpeedLaw) -> NDArray:
    """Speed omega (rad/s) at the times ``t_s`` (s) for voltage ``volts[k]`` held on
    [t_k, t_k+1), from rest at t_0: the one ERM law (:mod:`motorlaw`, exact) with these time
    constants."""
    law = replace(motor, tau_spinup_s=tau_up_s, tau_spindown_s=tau_down_s)
    return held_speed_and_phase(law, t_s, volts)[0]


@dataclass(frozen=True)
class EnvelopeModel:
    """The grey-box envelope model (see the module docstring).

    Attributes:
        harmonic: the harmonic predictor (steady amplitudes at a design and frequency).
        weights: point -> (len(params), n_features + 1) rows for log sigma, f_n, log g and
            the gain's frequency slope, with two modes then log sigma_2, f_2 and w (last
            column: intercept), over the harmonic model's encoded design features.
        motor: the actuator's drive law, a speed law (time constants are design inputs).
        motor_ranges: trained ranges of the motor time constants, ms.
        grid_hz: frequencies (Hz) the harmonic model is evaluated at, over its trained band.
        clip: parameter -> (low, high), the trained spread of each mode parameter.
        meta: the coefficients' remaining keys (format, provenance).
    """

    harmonic: Predictor
    weights: dict[str, NDArray]
    motor: SpeedLaw
    motor_ranges: dict[str, tuple[float, float]]
    grid_hz: NDArray
    clip: dict[str, tuple[float, float]]
    meta: dict[str, Any]

    @property
    def modes(self) -> int:
        """Modes per point (``coefficients.modes``; 1 in models that do not record it)."""
        return int(self.meta.get("modes", 1))

    @property
    def params(self) -> tuple[str, ...]:
        """The names of the weight rows (:func:`surrogate.runtime.rom_modes.params_for`)."""
        return params_for(self.modes)

    @property
    def actuator(self) -> str:
        """The actuator kind the model was trained for (``coefficients.actuator``; a model
        that does not record it was trained on the coin ERM, ``"unit"``)."""
        return str(self.meta.get("actuator", type(self.motor).kind))

    def check_actuator(self, kind: str) -> None:
        """Refuse an actuator the model was not trained for (:class:`RomInputError` naming
        ``actuator``): its dynamics are the trained actuator's, not another's."""
        if str(kind) != self.actuator:
            raise RomInputError("actuator", f"{str(kind)!r}: this envelope model was trained "
                                f"for the actuator {self.actuator!r} "
                                f"({type(self.motor).title}) only; its drive dynamics are not "
                                "another actuator's")

    @property
    def design_names(self) -> tuple[str, ...]:
        """The harmonic model's design inputs (its frequency left out)."""
        return tuple(n for n in self.harmonic.input_names if n != "frequency_hz")

    @property
    def input_names(self) -> tuple[str, ...]:
        return (*self.design_names, *MOTOR_INPUTS)

    @property
    def input_ranges(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for spec in self.harmonic.specs:
            if spec.name != "frequency_hz":
                out[spec.name] = (spec.choices if spec.type == "categorical"
                                  else (float(spec.low), float(spec.high)))
        out.update({k: tuple(v) for k, v in self.motor_ranges.items()})
        return out

    def features(self, design: Mapping[str, Any], *, extrapolate: bool = False) -> NDArray:
        """Encoded design features (n_features + 1,) with the intercept last; with
        ``group_by`` one such block per choice of that input, zero except the design's."""
        X = {k: [design[k]] for k in self.design_names}
        X["frequency_hz"] = [float(self.grid_hz[0])]
        try:
            _, feats, _ = self.harmonic.features(X, extrapolate=extrapolate)
        except PredictorInputError as err:
            raise RomInputError(err.field, str(err)) from None
        keep = np.asarray(self.meta["feature_columns"], dtype=int)
        x = np.append(feats[0, keep].astype(float), 1.0)
        group = self.meta.get("group_by")
        if group is None:
            return x
        # one affine map per choice of a categorical input (e.g. glued / pogo units)
        return np.kron([design[group["input"]] == c for c in group["choices"]], x)

    def parameter_rows(self, design: Mapping[str, Any], *,
                       extrapolate: bool = False) -> dict[str, NDArray]:
        """point -> the design's parameters (len(params),) in ``params`` order, each clipped
        to its trained spread."""
        x = self.features(design, extrapolate=extrapolate)
        lo, hi = (np.array([self.clip[n][i] for n in self.params]) for i in (0, 1))
        return {point: np.clip(self.weights[point] @ x, lo, hi) for point in POINTS}

    def parameters(self, design: Mapping[str, Any], *,
                   extrapolate: bool = False) -> dict[str, dict[str, float]]:
        """point -> {sigma_1_s, fn_hz, gain, gain_slope} of a design (with two modes also
        sigma2_1_s, fn2_hz and weight, mode 1's share of the force)."""
        out = {}
        for point, row in self.parameter_rows(design, extrapolate=extrapolate).items():
            raw = dict(zip(self.params, map(float, row), strict=True))
            out[point] = {"sigma_1_s": math.exp(raw["log_sigma"]), "fn_hz": raw["fn_hz"],
                          "gain": math.exp(raw["log_gain"]), "gain_slope": raw["gain_slope"]}
            if self.modes == 2:
                out[point].update(sigma2_1_s=math.exp(raw["log_sigma2"]),
                                  fn2_hz=raw["fn2_hz"], weight=raw["weight"])
        return out

    def steady_amplitudes(self, design: Mapping[str, Any], *,
                          extrapolate: bool = False) -> dict[str, NDArray]:
        """Harmonic amplitudes (um) of the design on ``grid_hz``, per point."""
        n = self.grid_hz.size
        X = {k: [design[k]] * n for k in self.design_names}
        X["frequency_hz"] = self.grid_hz
        ref = self.meta.get("loss_reference_hz")
        if ref is not None:  # the FE transient's damping: loss factor eta f / f_ref at f
            for name in LOSS_INPUTS:
                X[name] = float(design[name]) * self.grid_hz / float(ref)
        out = self.harmonic.predict(X, extrapolate=extrapolate or ref is not None)
        return {p: out[f"{p}_amplitude_um"] for p in POINTS}

    def steady_levels(self, omega: Any, design: Mapping[str, Any], *,
                      extrapolate: bool = False) -> dict[str, NDArray]:
        """point -> the model's steady envelope (um) at the speeds ``omega`` (rad/s, any
        shape (n,)): what the envelope tends to while the speed is held (the gain, 1 unless
        learned, times the harmonic response, continued below its band;
        :func:`steady_response`)."""
        rows = self.parameter_rows(design, extrapolate=extrapolate)
        return self._steady(np.atleast_1d(np.asarray(omega, dtype=float)), rows, design,
                            extrapolate)

    def _steady(self, omega: NDArray, rows: Mapping[str, NDArray], design: Mapping[str, Any],
                extrapolate: bool) -> dict[str, NDArray]:
        """point -> steady envelope (um) at ``omega`` for the design's parameter ``rows``."""
        amp = self.steady_amplitudes(design, extrapolate=extrapolate)
        return {p: steady_from_params(omega, self.grid_hz, amp[p][None, :], row[None])[0]
                for p, row in rows.items()}

    def simulate(self, t_s: Any, volts: Any, design: Mapping[str, Any], *,
                 extrapolate: bool = False) -> dict[str, NDArray]:
        """Envelopes (um) at the times ``t_s`` (s, increasing, from rest) for the drive
        ``volts`` (V, held from each time to the next) and the ``design`` mapping
        (``input_names``; motor time constants in ms). Returns ``center_envelope_um``,
        ``edge_envelope_um`` and ``speed_hz`` (rev/s). Raises :class:`RomInputError` naming the
        input for bad input (outside the trained range unless ``extrapolate``)."""
        t, v = self._check_drive(t_s, volts)
        dsg = self._check_design(design, extrapolate)
        omega = motor_speed(t, v, dsg["tau_spinup_ms"] * 1e-3, dsg["tau_spindown_ms"] * 1e-3,
                            self.motor)
        rows = self.parameter_rows(dsg, extrapolate=extrapolate)
        steady = self._steady(omega, rows, dsg, extrapolate)
        out: dict[str, NDArray] = {}
        for point, name in zip(POINTS, STATES, strict=True):
            env = envelope_from_params(t, omega, steady[point][None, :], rows[point][None])[0]
            if not np.all(np.isfinite(env)):
                raise RomBlowUpError("the envelope is not finite (corrupt coefficients?)")
            out[name] = env
        out["speed_hz"] = omega / (2 * math.pi)
        return out

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
        missing = [k for k in self.input_names if k not in design]
        if missing:
            raise RomInputError(missing[0], f"missing from design (inputs: "
                                f"{list(self.input_names)})")
        unknown = sorted(set(design) - set(self.input_names))
        if unknown:
            raise RomInputError(unknown[0], f"unknown design input (inputs: "
                                f"{list(self.input_names)})")
        out = dict(design)
        for name in MOTOR_INPUTS:
            lo, hi = self.motor_ranges[name]
            try:
                x = float(design[name])
            except (TypeError, ValueError):
                raise RomInputError(name, f"{design[name]!r} is not a number") from None
            if not math.isfinite(x) or x <= 0:
                raise RomInputError(name, f"{x!r} must be finite and > 0 ms")
            if not extrapolate and not lo <= x <= hi:
                raise RomInputError(name, f"{x:g} is outside the trained range [{lo:g}, "
                                    f"{hi:g}] ms (pass extrapolate=True to accept)")
            out[name] = x
        if design["attachment"] == "pogo" and float(design["n_rings"]) == 0:
            raise RomInputError("n_rings", "0 with attachment 'pogo': a unit on frictionless "
                                "pogo pins with no ring has no transient (nothing holds it "
                                "sideways; the FE solver refuses it); allowed n_rings 1..3")
        return out


def model_from_parts(coefficients: Mapping[str, Any], harmonic_card: dict[str, Any],
                     onnx: bytes | str | Path) -> EnvelopeModel:
    """An :class:`EnvelopeModel` from its coefficients dict, the harmonic model's card and its
    ONNX graph; raises ValueError naming the key for malformed coefficients."""
    if coefficients.get("format") != FORMAT:
        raise ValueError(f"format: expected {FORMAT!r}, got {coefficients.get('format')!r}")
    harmonic = Predictor(harmonic_card, make_session(onnx))
    group = coefficients.get("group_by")
    if group is not None and (not isinstance(group, Mapping) or group.get("input") not in
                              harmonic.input_names or not group.get("choices")):
        raise ValueError("group_by: need {input: a categorical design input, choices: [...]}")
    n = (len(coefficients["feature_columns"]) + 1) * (1 if group is None
                                                      else len(group["choices"]))
    modes = coefficients.get("modes", 1)  # absent in one-mode models trained before it
    params = params_for(modes)  # ValueError naming modes
    weights = {}
    for point in POINTS:
        w = np.asarray(coefficients["weights"][point], dtype=float)
        if w.shape != (len(params), n) or not np.all(np.isfinite(w)):
            raise ValueError(f"weights.{point}: need finite values of shape "
                             f"{(len(params), n)}, got {w.shape}")
        weights[point] = w
    clip = {k: (float(lo), float(hi)) for k, (lo, hi) in coefficients["clip"].items()}
    if set(clip) != set(params):
        raise ValueError(f"clip: need bounds for {list(params)}")
    grid = np.asarray(coefficients["grid_hz"], dtype=float)
    band = harmonic_grid(harmonic)
    if (grid.ndim != 1 or grid.size < 2 or not math.isclose(grid[0], band[0])
            or grid[-1] > band[-1] + 1e-9 or np.any(np.diff(grid) <= 0)):
        raise ValueError(f"grid_hz: need increasing frequencies from the harmonic model's "
                         f"lowest trained frequency {band[0]:g} Hz to at most {band[-1]:g} Hz")
    ranges = coefficients["motor_ranges"]
    if not isinstance(ranges, Mapping) or set(ranges) != set(MOTOR_INPUTS) or not all(
            len(ranges[k]) == 2 and all(np.isfinite(np.asarray(ranges[k], dtype=float)))
            and float(ranges[k][0]) < float(ranges[k][1]) for k in MOTOR_INPUTS):
        raise ValueError(f"motor_ranges: need finite [low, high] for exactly "
                         f"{list(MOTOR_INPUTS)}")
    columns = np.asarray(coefficients["feature_columns"])
    width = n_features(harmonic.specs)  # the harmonic model's encoded inputs
    if columns.ndim != 1 or columns.dtype.kind not in "iu" or np.unique(columns).size != \
            columns.size or (columns.size and not 0 <= columns.min() <= columns.max() < width):
        raise ValueError(f"feature_columns: need distinct integers in [0, {width})")
    meta = {k: v for k, v in coefficients.items() if k not in ("weights", "clip", "motor")}
    return EnvelopeModel(harmonic, weights, _speed_law(coefficients),
                         {k: (float(a), float(b))
                          for k, (a, b) in coefficients["motor_ranges"].items()},
                         grid, clip, meta)


def _speed_law(coefficients: Mapping[str, Any]) -> SpeedLaw:
    """The drive law of the actuator the coefficients name (``actuator``, default the coin
    ERM ``"unit"``); this model's form (the harmonic response at the instantaneous speed, the
    force continued as m e omega^2) needs a law whose drive sets the frequency (no carrier)."""
    kind = coefficients.get("actuator", SpeedLaw.kind)
    law = drive_law_class(kind)  # ValueError naming the actuators that have a law
    if law.carrier or not issubclass(law, SpeedLaw):
        raise ValueError(f"actuator: {kind!r} ({law.title}) is driven with a carrier; this "
                         f"envelope model's form follows a speed law ({FORMAT})")
    return law.from_params(coefficients["motor"])


def load_envelope_model(path: str | Path) -> EnvelopeModel:
    """Load the model directory ``models/NAME/``, verified as a whole
    (:func:`surrogate.runtime.card.read_card`): its card names the coefficients, the harmonic
    model's card and its ONNX graph, all inside the directory, each read through its digest. A
    malformed file is a :class:`ModelFileError` naming it and the check."""
    p = Path(path)
    card = read_card(p)
    if card.get("kind") != "rom":
        raise ModelFileError("kind", f"{p / CARD_NAME}: a {card.get('kind')!r} model, not a "
                             "transient ROM")
    try:
        names = {"coefficients": card["coefficients"],
                 "harmonic card": card["harmonic"]["card"],
                 "harmonic graph": card["harmonic"]["graph"]}
    except (KeyError, TypeError) as err:
        raise ModelFileError("coefficients", f"{p / CARD_NAME}: the card names no "
                             f"{err} file (check: files)") from None
    data = {}
    for role, name in names.items():
        raw = read_model_file(p, card, name)
        data[role] = raw if role == "harmonic graph" else loads_json(
            raw.decode("utf-8", errors="replace"), p / name, ModelFileError)
    try:
        return model_from_parts(data["coefficients"], data["harmonic card"],
                                data["harmonic graph"])
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as err:
        raise ModelFileError(names["coefficients"], f"{p / names['coefficients']}: malformed "
                             f"coefficients (check: coefficients; {type(err).__name__}: "
                             f"{err})") from None
