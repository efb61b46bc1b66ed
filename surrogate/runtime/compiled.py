"""A model's input specs compiled once into arrays and lookup tables (numpy only), so that the
run-time predictor checks and encodes a call in a few array operations -- or, for one design,
in a few Python scalar operations -- instead of one Python step per input.

:func:`compile_specs` builds the :class:`Plan` (cached per spec tuple). Two fast paths read
it, both returning None for anything they do not handle so that the caller falls back to the
full parser of :mod:`surrogate.runtime.encoding`, which explains every refusal; a refusal
therefore reads the same whichever path saw the input first:

* :func:`fast_codes`: the codes (n, d) of a dict of equal-length lists or 1-D arrays
  (categoricals as choice strings, looked up in tables built once) or of an (n, d) float64
  array, in one ``np.array`` call;
* :func:`row_codes` and :func:`encode_row`: one design's codes and features as Python floats
  (at batch 1 an array operation costs about a microsecond, a scalar one a few tens of
  nanoseconds), with exactly the arithmetic of ``encoding.encode`` (float64; the logs by
  numpy's own ``log``, which differs from ``math.log`` in the last bit on some inputs).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Plan", "compile_specs", "encode_row", "fast_codes", "row_codes"]


@dataclass(frozen=True, eq=False)
class Plan:
    """The specs as arrays (batch path) and tuples of Python numbers (one-design path)."""

    names: tuple[str, ...]
    name_set: frozenset[str]
    lookups: tuple[tuple[int, dict[str, int]], ...]  # (column, choice -> index) of categoricals
    lo: np.ndarray  # (d,) range of each input's code
    hi: np.ndarray
    integral: np.ndarray  # (d,) bool: categorical or integer
    integral_cols: np.ndarray  # their columns
    positive: np.ndarray  # (d,) bool: log scale, must be > 0
    categorical: np.ndarray  # (d,) bool: never extrapolated
    source: np.ndarray  # (F,) input column of each feature
    offset: np.ndarray  # (F,) feature = (code' - offset) / span: exactly 0 and 1 at the ends
    span: np.ndarray
    log_feats: np.ndarray  # features on the log of their code
    onehot_feats: np.ndarray  # one-hot features ...
    onehot_codes: np.ndarray  # ... and the category index each stands for
    gated_feats: np.ndarray  # features of conditional inputs ...
    gate_cols: np.ndarray  # ... the column of their controlling input ...
    gate_min: np.ndarray  # ... and its minimum
    row_inputs: tuple[tuple[str, dict[str, int] | None, float, float, bool], ...]  # name,
    # choice table (categoricals), low, high, integral
    row_logs: tuple[int, ...]  # columns of the log-scale inputs
    row_feats: tuple[tuple[bool, int, float, float, int, float], ...]  # see encode_row


def _ints(values: Sequence[int]) -> np.ndarray:
    return np.array(values, dtype=np.intp)


@functools.lru_cache(maxsize=64)
def _compile(specs: tuple[Any, ...]) -> Plan:
    index = {s.name: j for j, s in enumerate(specs)}
    src, offset, span, logf, ohf, ohk, gf, gcol, gmin = [], [], [], [], [], [], [], [], []
    row_feats = []
    for j, spec in enumerate(specs):
        if spec.type == "categorical" and spec.encoding == "onehot":
            for c in range(len(spec.choices)):
                ohf.append(len(src)), ohk.append(c)
                row_feats.append((True, j, float(c), 1.0, -1, 0.0))
                src.append(j), offset.append(0.0), span.append(1.0)
            continue
        if spec.type == "categorical":  # ordinal code scaled to [0, 1]
            a, b = 0.0, float(max(len(spec.choices) - 1, 1))
        else:
            a, b = float(spec.low), float(spec.high)  # type: ignore[arg-type]
            if spec.scale == "log":
                a, b = float(np.log(a)), float(np.log(b))
        gate, minimum = -1, 0.0
        if spec.used_when is not None:
            gate, minimum = index[spec.used_when[0]], float(spec.used_when[1])
            gf.append(len(src)), gcol.append(gate), gmin.append(minimum)
        # one-design path: the log of input j is found at len(specs) + its rank among the logs
        at = j
        if spec.type == "continuous" and spec.scale == "log":
            at = len(specs) + sum(s.type == "continuous" and s.scale == "log"
                                  for s in specs[:j])
            logf.append(len(src))
        row_feats.append((False, at, a, b - a, gate, minimum))
        src.append(j), offset.append(a), span.append(b - a)
    integral = [s.type in ("categorical", "integer") for s in specs]
    return Plan(
        names=tuple(s.name for s in specs), name_set=frozenset(s.name for s in specs),
        lookups=tuple((j, {c: i for i, c in enumerate(s.choices)}) for j, s in enumerate(specs)
                      if s.type == "categorical"),
        lo=np.array([s.range[0] for s in specs], dtype=float),
        hi=np.array([s.range[1] for s in specs], dtype=float),
        integral=np.array(integral, dtype=bool),
        integral_cols=_ints([j for j, w in enumerate(integral) if w]),
        positive=np.array([s.type == "continuous" and s.scale == "log" for s in specs],
                          dtype=bool),
        categorical=np.array([s.type == "categorical" for s in specs], dtype=bool),
        source=_ints(src), offset=np.array(offset, dtype=float), span=np.array(span, dtype=float),
        log_feats=_ints(logf), onehot_feats=_ints(ohf), onehot_codes=np.array(ohk, dtype=float),
        gated_feats=_ints(gf), gate_cols=_ints(gcol), gate_min=np.array(gmin, dtype=float),
        row_inputs=tuple((s.name, {c: i for i, c in enumerate(s.choices)}
                          if s.type == "categorical" else None, float(s.range[0]),
                          float(s.range[1]), w) for s, w in zip(specs, integral, strict=True)),
        row_logs=tuple(j for j, s in enumerate(specs)
                       if s.type == "continuous" and s.scale == "log"),
        row_feats=tuple(row_feats))


def compile_specs(specs: Sequence[Any]) -> Plan:
    """The compiled form of ``specs`` (``encoding.InputSpec`` records; built once per distinct
    spec tuple)."""
    return _compile(tuple(specs))


def _choice_indices(values: Any, index: dict[str, int]) -> Any:
    """A categorical's values given as choice strings -> their indices, other values as they
    are (numbers: indices); None when they need the full parser (an unknown choice, an
    unusual container)."""
    kind = type(values)
    try:
        if kind is str:
            return [index[values]]
        if kind is list or kind is tuple:
            return [index[v] for v in values] if values and type(values[0]) is str else values
        if kind is np.ndarray:
            if values.dtype.kind == "U" and values.size > 64:  # one comparison per choice
                codes = np.full(values.shape, -1.0)
                for choice, i in index.items():
                    codes[values == choice] = i
                return codes if values.ndim == 1 and codes.min() >= 0 else None
            if values.dtype.kind == "U":
                return [index[v] for v in values.tolist()]
            return values if values.dtype.kind in "iufb" else None
    except (KeyError, TypeError):
        return None
    return None


def fast_codes(X: Any, plan: Plan) -> np.ndarray | None:
    """The codes (n, d) float64 of a dict of every input (equal-length lists or 1-D arrays,
    categoricals as choice strings or indices) or of an (n, d) float64 array; None for
    anything else (scalars, text for a number, ragged columns, an unknown choice...)."""
    if type(X) is np.ndarray:
        return X if X.ndim == 2 and X.shape[1] == plan.lo.size and X.dtype == float else None
    if type(X) is not dict or X.keys() != plan.name_set:
        return None
    cols = [X[name] for name in plan.names]
    for j, index in plan.lookups:
        cols[j] = _choice_indices(cols[j], index)
        if cols[j] is None:
            return None
    try:
        arr = np.array(cols)
    except (TypeError, ValueError):  # ragged columns
        return None
    if arr.ndim != 2 or arr.dtype.kind not in "iufb":  # text, None, nested: the full parser
        return None
    return (arr if arr.dtype == float else arr.astype(float)).T


def row_codes(X: Any, plan: Plan) -> list[float] | None:
    """One design inside the trained range, as its codes (Python floats), from a dict of
    every input with one value each (a list, tuple or 1-D array of one int, float or choice
    string) or from a (1, d) float64 array; None for anything else, including a value outside
    the trained range or a fractional count (the full parser then names it)."""
    if type(X) is np.ndarray:
        if X.shape != (1, plan.lo.size) or X.dtype != float:
            return None
        row = X[0].tolist()
        for c, (_, _, lo, hi, integral) in zip(row, plan.row_inputs):  # noqa: B905
            if not lo <= c <= hi or (integral and not c.is_integer()):
                return None
        return row
    if type(X) is not dict or X.keys() != plan.name_set:
        return None
    row = []
    for name, index, lo, hi, integral in plan.row_inputs:
        v = X[name]
        kind = type(v)
        if (kind is list or kind is tuple) and len(v) == 1:
            x = v[0]
        elif kind is np.ndarray and v.shape == (1,):
            x = v.item()
        else:
            return None
        kind = type(x)
        if kind is float:
            if not lo <= x <= hi or (integral and not x.is_integer()):
                return None
            row.append(x)
        elif kind is int and lo <= x <= hi:
            row.append(float(x))
        elif index is not None and kind is str and x in index:
            row.append(float(index[x]))
        else:
            return None
    return row


def encode_row(row: list[float], plan: Plan) -> list[float]:
    """The features of one design given as its codes from :func:`row_codes` (checked), with
    the arithmetic of ``encoding.encode``."""
    x = row + np.log([row[j] for j in plan.row_logs]).tolist() if plan.row_logs else row
    return [(1.0 if x[j] == a else 0.0) if onehot else
            0.0 if gate >= 0 and x[gate] < minimum else (x[j] - a) / b
            for onehot, j, a, b, gate, minimum in plan.row_feats]
