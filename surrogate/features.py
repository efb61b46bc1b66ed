"""Model inputs from a dataset's parameter space (merged over datasets), the unit's edge radius of
each row, and the training-side feature encoder.

The inputs of a surrogate are the free parameters of the space its data was sampled from:
continuous ones keep their range and scale (log parameters are encoded on a log scale),
integers their bounds, categoricals their choices (one-hot by default, or ordinal). The
encoding itself lives in :mod:`surrogate.runtime.encoding` so the run time, which must not
import this package's training dependencies, encodes exactly as training did.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from surrogate.data.worker import edge_radius_mm
from surrogate.runtime.encoding import InputSpec, encode, n_features, parse_inputs

__all__ = ["SpaceEncoder", "codes_from_frame", "edge_radii_mm", "input_specs", "merge_specs",
           "unit_of", "used_when"]

#: Unit suffixes of parameter names (the project puts units in names: ``skin_E_kPa``).
_UNIT_SUFFIXES = {"_kPa": "kPa", "_Pa": "Pa", "_mm": "mm", "_um": "um", "_hz": "Hz",
                  "_Hz": "Hz", "_kg_m3": "kg/m^3", "_V": "V", "_g": "g", "_s": "s",
                  "_ms": "ms", "_deg": "deg"}


def unit_of(name: str) -> str:
    """The unit a parameter name carries in its suffix ("" when none)."""
    for suffix, unit in sorted(_UNIT_SUFFIXES.items(), key=lambda kv: -len(kv[0])):
        if name.endswith(suffix):
            return unit
    return ""


def _paths(p: Mapping[str, Any]) -> list[str]:
    return [p["path"]] if isinstance(p["path"], str) else list(p["path"])


def used_when(p: Mapping[str, Any], parameters: Sequence[Mapping[str, Any]]
              ) -> tuple[str, float] | None:
    """(control, minimum) when every path of ``p`` is inside entry ``[k]`` of a list whose
    length a ``map = "list_length"`` parameter sets: ``p`` changes the scene only when that
    parameter is at least ``k + 1`` (the smallest such ``k`` over its paths)."""
    lengths = {_paths(q)[0]: q["name"] for q in parameters
               if q.get("map") == "list_length" and q["type"] != "fixed"}
    found: list[tuple[str, int]] = []
    for path in _paths(p):
        hit = next(((name, int(path[len(lst) + 1:].split("]")[0]))
                    for lst, name in lengths.items() if path.startswith(lst + "[")), None)
        if hit is None:
            return None
        found.append(hit)
    if len({name for name, _ in found}) != 1:
        return None
    return (found[0][0], float(min(k for _, k in found) + 1))


def input_specs(parameters: Sequence[Mapping[str, Any]], *,
                categorical: str = "onehot") -> list[InputSpec]:
    """Input specs of the free parameters of a space, given as the manifest's
    ``space.parameter`` list (fixed parameters are not inputs), with the condition under
    which each one is used (:func:`used_when`)."""
    specs = []
    for p in parameters:
        kind = p["type"]
        if kind == "fixed":
            continue
        common = {"name": p["name"], "unit": unit_of(p["name"]),
                  "description": p.get("description", "")}
        if kind == "categorical":
            specs.append(InputSpec(type="categorical", choices=tuple(map(str, p["choices"])),
                                   encoding=categorical, **common))
        elif kind in ("continuous", "integer"):
            specs.append(InputSpec(type=kind, low=float(p["low"]), high=float(p["high"]),
                                   scale=p.get("scale", "linear"),
                                   used_when=used_when(p, parameters), **common))
        else:
            raise ValueError(f"parameter {p['name']}: unsupported type {kind!r}")
    return specs


def codes_from_frame(df: Any, specs: Sequence[InputSpec]) -> np.ndarray:
    """(n, d) float codes of a dataset frame's input columns (validated, no extrapolation)."""
    codes, _ = parse_inputs({s.name: df[s.name].to_numpy() for s in specs}, specs)
    return codes


class SpaceEncoder(TransformerMixin, BaseEstimator):
    """Encode (n, d) input codes to model features (scikit-learn transformer).

    Parameters: ``inputs``, a list of card-style input dicts (see ``InputSpec.to_dict``), or
    None to treat every column as already in [0, 1] (identity; for generic use)."""

    def __init__(self, inputs: list[dict[str, Any]] | None = None) -> None:
        self.inputs = inputs

    def _specs(self, d: int) -> list[InputSpec]:
        if self.inputs is None:
            return [InputSpec(name=f"x{j}", type="continuous", low=0.0, high=1.0)
                    for j in range(d)]
        return [InputSpec.from_dict(e) for e in self.inputs]

    def fit(self, X: Any, y: Any = None) -> SpaceEncoder:
        X = validate_data(self, X, dtype=float)
        specs = self._specs(X.shape[1])
        if len(specs) != X.shape[1]:
            raise ValueError(f"X has {X.shape[1]} columns, the inputs list {len(specs)}")
        self.specs_ = specs
        self.n_features_out_ = n_features(specs)
        return self

    def transform(self, X: Any) -> np.ndarray:
        check_is_fitted(self)
        X = validate_data(self, X, dtype=float, reset=False)
        codes, _ = parse_inputs(X, self.specs_, extrapolate=True) if self.inputs is None \
            else parse_inputs(X, self.specs_)
        return encode(codes, self.specs_)


def edge_radii_mm(df: Any) -> np.ndarray:
    """The unit's outer radius [mm] of every row: the dataset's column when it has one, else
    derived from the row's resolved scene by the solver's scene model."""
    stored = (df["edge_radius_mm"].to_numpy(dtype=float, copy=True)
              if "edge_radius_mm" in df.columns else np.full(len(df), np.nan))
    missing = np.isnan(stored)
    stored[missing] = [edge_radius_mm(s) for s in df.loc[missing, "scene_json"]]
    return stored


def merge_specs(a: list[InputSpec], b: list[InputSpec], where: str) -> list[InputSpec]:
    """The inputs of two datasets of one space: ``a`` with each continuous range widened to
    cover ``b``'s (``where``: the second dataset, named in the error when the inputs differ)."""
    if [(s.name, s.type, s.choices, s.scale, s.used_when) for s in a] != \
            [(s.name, s.type, s.choices, s.scale, s.used_when) for s in b]:
        raise ValueError(f"{where}: its space's inputs differ from the first dataset's "
                         f"({[s.name for s in b]} vs {[s.name for s in a]})")
    return [s if s.type == "categorical" else
            InputSpec(name=s.name, type=s.type, low=min(s.low, t.low), high=max(s.high, t.high),
                      scale=s.scale, unit=s.unit, description=s.description,
                      used_when=s.used_when)
            for s, t in zip(a, b, strict=True)]
