"""Input validation and feature encoding of a model's inputs (numpy only).

A model's inputs are described by :class:`InputSpec` records (stored in its ``card.json``):
continuous parameters (linear or log scale), integers and categoricals. Callers give design
points either as an (n, d) float array in input order (a categorical as the index of its
choice) or as a mapping ``name -> (n,)`` array (a categorical as its choice strings or
indices). :func:`parse_inputs` validates them (shape, NaN, unknown choices, the trained range)
and :func:`encode` turns them into the model's feature matrix:

* continuous: ``(v - low) / (high - low)``, on ``log v`` for log-scale parameters, so the
  trained range maps to [0, 1] whatever the unit;
* integer: the same linear map (ordinal: neighbouring counts are neighbours);
* categorical: one-hot (one column per choice; ``ordinal`` maps the choice index to [0, 1]).

An input may be *conditional*: ``used_when = (control, minimum)`` says it changes the design
only when the input ``control`` is at least ``minimum`` (the modulus of a second ring when
``n_rings >= 2``). Where it does not, its feature is set to 0, so rows that describe the same
physical design encode the same and the model is not asked to learn a dependence that is not
there.

The training side (``surrogate.features``) uses this same code, so training and run time
encode identically by construction.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fieldspec import FieldError
from surrogate.runtime.compiled import Plan, compile_specs, fast_codes

__all__ = ["InputSpec", "PredictorInputError", "compile_specs", "encode", "n_features",
           "parse_inputs"]

INPUT_TYPES = ("continuous", "integer", "categorical")
CATEGORICAL_ENCODINGS = ("onehot", "ordinal")


class PredictorInputError(FieldError):
    """Bad input to a predictor; ``.field`` names the offending input."""


@dataclass(frozen=True)
class InputSpec:
    """One model input. ``unit`` is the unit of the values callers pass (e.g. "kPa"), "" for
    dimensionless or categorical inputs; ``low``/``high`` bound the trained range."""

    name: str
    type: str
    low: float | None = None
    high: float | None = None
    scale: str = "linear"
    choices: tuple[str, ...] = ()
    unit: str = ""
    encoding: str = "onehot"
    description: str = ""
    used_when: tuple[str, float] | None = None

    def __post_init__(self) -> None:
        if self.type not in INPUT_TYPES:
            raise ValueError(f"input {self.name}: type {self.type!r} not in {INPUT_TYPES}")
        if self.type == "categorical":
            if len(self.choices) < 1:
                raise ValueError(f"input {self.name}: a categorical needs choices")
            if self.encoding not in CATEGORICAL_ENCODINGS:
                raise ValueError(f"input {self.name}: encoding {self.encoding!r} not in "
                                 f"{CATEGORICAL_ENCODINGS}")
        else:
            if self.low is None or self.high is None or not self.low < self.high:
                raise ValueError(f"input {self.name}: needs low < high, got "
                                 f"{self.low}, {self.high}")
            if self.scale not in ("linear", "log") or (self.scale == "log" and self.low <= 0):
                raise ValueError(f"input {self.name}: scale {self.scale!r} needs 'linear' or "
                                 "'log' with low > 0")

    @property
    def width(self) -> int:
        """Number of feature columns this input encodes to."""
        if self.type == "categorical" and self.encoding == "onehot":
            return len(self.choices)
        return 1

    @property
    def range(self) -> tuple[float, float]:
        """(low, high) for numeric inputs, (0, n_choices - 1) as indices for categoricals."""
        if self.type == "categorical":
            return (0.0, float(len(self.choices) - 1))
        return (float(self.low), float(self.high))  # type: ignore[arg-type]

    def allowed(self) -> str:
        """Human-readable allowed values, for error messages."""
        if self.type == "categorical":
            names = ", ".join(repr(c) for c in self.choices)
            return f"one of {names} (or its index 0..{len(self.choices) - 1})"
        unit = f" {self.unit}" if self.unit else ""
        return f"{self.low:g} <= {self.name} <= {self.high:g}{unit}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (inverse of :meth:`from_dict`)."""
        d: dict[str, Any] = {"name": self.name, "type": self.type, "unit": self.unit}
        if self.type == "categorical":
            d["choices"] = list(self.choices)
            d["encoding"] = self.encoding
        else:
            d.update(low=self.low, high=self.high, scale=self.scale)
        if self.description:
            d["description"] = self.description
        if self.used_when is not None:
            d["used_when"] = {"input": self.used_when[0], "at_least": self.used_when[1]}
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> InputSpec:
        """Spec from a card entry; raises ValueError on a malformed entry."""
        try:
            return cls(name=str(d["name"]), type=str(d["type"]), low=d.get("low"),
                       high=d.get("high"), scale=str(d.get("scale", "linear")),
                       choices=tuple(str(c) for c in d.get("choices", ())),
                       unit=str(d.get("unit", "")), encoding=str(d.get("encoding", "onehot")),
                       description=str(d.get("description", "")),
                       used_when=_used_when(d.get("used_when")))
        except KeyError as err:
            raise ValueError(f"input entry {dict(d)!r} lacks {err}") from None


def _used_when(entry: Any) -> tuple[str, float] | None:
    if entry is None:
        return None
    return (str(entry["input"]), float(entry["at_least"]))


def n_features(specs: Sequence[InputSpec]) -> int:
    """Width of the encoded feature matrix."""
    return sum(s.width for s in specs)


def _column(spec: InputSpec, values: Any, n: int | None) -> np.ndarray:
    """One input's values as float codes (choice index for categoricals)."""
    arr = np.asarray(values)
    if arr.ndim != 1:
        raise PredictorInputError(spec.name, f"{spec.name}: expected a 1-D array of values, "
                                  f"got shape {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise PredictorInputError(spec.name, f"{spec.name}: {arr.shape[0]} values, expected {n}")
    if spec.type == "categorical" and arr.dtype.kind in "OUS":
        index = {c: i for i, c in enumerate(spec.choices)}
        try:
            return np.array([index[str(v)] for v in arr], dtype=float)
        except KeyError as err:
            raise PredictorInputError(spec.name, f"{spec.name} = {err.args[0]!r} is not "
                                      f"allowed: {spec.allowed()}") from None
    try:
        return arr.astype(float)
    except (TypeError, ValueError):
        raise PredictorInputError(spec.name, f"{spec.name}: values are not numbers; allowed "
                                  f"{spec.allowed()}") from None


def _as_codes(X: Any, specs: Sequence[InputSpec]) -> np.ndarray:
    names = [s.name for s in specs]
    if isinstance(X, Mapping):
        unknown = sorted(set(X) - set(names))
        if unknown:
            raise PredictorInputError(unknown[0], f"unknown input {unknown[0]!r}; inputs are "
                                      f"{', '.join(names)}")
        missing = [nm for nm in names if nm not in X]
        if missing:
            raise PredictorInputError(missing[0], f"missing input {missing[0]!r}; inputs are "
                                      f"{', '.join(names)}")
        n = len(np.atleast_1d(X[names[0]]))
        cols = [_column(s, np.atleast_1d(X[s.name]), n) for s in specs]
        return np.stack(cols, axis=1) if cols else np.zeros((n, 0))
    try:
        arr = np.asarray(X, dtype=float)
    except (TypeError, ValueError):
        raise PredictorInputError("X", "X must be an (n, d) float array or a mapping "
                                  "name -> values") from None
    if arr.ndim == 1 and arr.shape[0] == len(specs):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != len(specs):
        raise PredictorInputError("X", f"X has shape {arr.shape}; expected (n, {len(specs)}) "
                                  f"with columns {', '.join(names)}")
    return arr


def parse_inputs(X: Any, specs: Sequence[InputSpec], *, extrapolate: bool = False,
                 plan: Plan | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Validate design points; return (codes (n, d) float64, extrapolated (n,) bool).

    Raises :class:`PredictorInputError` naming the input for NaN/inf, an unknown choice, a
    non-integral integer or categorical index, and -- unless ``extrapolate`` -- a value outside
    the trained range. Categoricals and integers never extrapolate beyond their choices.

    The usual call (every value inside the trained range) is checked in a few array
    operations: inside [low, high] implies finite, and > 0 on a log scale (low > 0); only a
    batch that fails that test goes through the input-by-input checks that name the input."""
    plan = plan or compile_specs(specs)
    codes = fast_codes(X, plan)
    if codes is None:
        codes = _as_codes(X, specs)
    inside = (codes >= plan.lo) & (codes <= plan.hi)
    if inside.all():
        whole = codes[:, plan.integral_cols]
        if (whole == np.floor(whole)).all():
            return codes, np.zeros(codes.shape[0], dtype=bool)
    with np.errstate(invalid="ignore"):
        finite = np.isfinite(codes)
        whole = ~plan.integral | (codes == np.round(codes))
        outside_cell = ~inside
        bad_log = plan.positive & (codes <= 0)
    if finite.all() and whole.all() and not bad_log.any() and (
            not outside_cell.any() or (extrapolate and not outside_cell[:, plan.categorical]
                                       .any())):
        return codes, outside_cell.any(axis=1)
    _raise_first_error(codes, specs, extrapolate)
    raise AssertionError("unreachable: a bad cell was found but not explained")


def _raise_first_error(codes: np.ndarray, specs: Sequence[InputSpec], extrapolate: bool) -> None:
    """Raise the message for the first bad input (in input order)."""
    for j, spec in enumerate(specs):
        col = codes[:, j]
        bad = ~np.isfinite(col)
        if bad.any():
            i = int(np.argmax(bad))
            raise PredictorInputError(spec.name, f"{spec.name}: row {i} is {col[i]} "
                                      f"(not finite); allowed {spec.allowed()}")
        if spec.type in ("categorical", "integer"):
            frac = col != np.round(col)
            if frac.any():
                i = int(np.argmax(frac))
                raise PredictorInputError(spec.name, f"{spec.name}: row {i} = {col[i]:g} is "
                                          f"not an integer; allowed {spec.allowed()}")
        lo, hi = spec.range
        out = (col < lo) | (col > hi)
        if out.any() and (not extrapolate or spec.type == "categorical"):
            i = int(np.argmax(out))
            hint = "" if spec.type == "categorical" else " (pass extrapolate=True to allow)"
            raise PredictorInputError(spec.name, f"{spec.name}: row {i} = {col[i]:g} is outside "
                                      f"the trained range: {spec.allowed()}{hint}")
        if spec.type == "continuous" and spec.scale == "log" and (col <= 0).any():
            raise PredictorInputError(spec.name, f"{spec.name}: a log-scale input must be > 0")




def encode(codes: np.ndarray, specs: Sequence[InputSpec], *, plan: Plan | None = None,
           dtype: Any = float) -> np.ndarray:
    """Feature matrix (n, n_features(specs)) of validated codes (see module doc), computed in
    float64 and stored as ``dtype`` (the graph's input type)."""
    codes = np.asarray(codes, dtype=float)
    plan = plan or compile_specs(specs)
    raw = codes[:, plan.source]
    if plan.log_feats.size:
        raw[:, plan.log_feats] = np.log(raw[:, plan.log_feats])
    out = np.empty(raw.shape, dtype=dtype)
    np.divide(raw - plan.offset, plan.span, out=out, casting="same_kind")
    if plan.onehot_feats.size:
        out[:, plan.onehot_feats] = raw[:, plan.onehot_feats] == plan.onehot_codes
    if plan.gated_feats.size:
        unused = codes[:, plan.gate_cols] < plan.gate_min
        if unused.any():
            out[:, plan.gated_feats] = np.where(unused, 0.0, out[:, plan.gated_feats])
    return out

