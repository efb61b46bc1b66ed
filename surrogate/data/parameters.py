"""One dimension of a parameter space: its type, range, scene paths and column type.

``[[parameter]]`` tables are read with the shared field-spec engine (:mod:`fieldspec`): the
keys a parameter may hold depend on its ``type`` (continuous: low, high, scale; integer: low,
high; categorical: choices; fixed: value), and every error names the parameter and the key.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fieldspec import REQUIRED, Context, Spec, read_fields, read_table
from surrogate.data.columns import COMPLEX_FIELDS, SWEEP_FIELDS
from surrogate.data.errors import SpaceError
from surrogate.data.scene_paths import parse_path

__all__ = ["MAPS", "PARAM_TYPES", "RESERVED_COLUMNS", "SCALES", "Parameter", "read_parameter",
           "round_significant"]

PARAM_TYPES = ("continuous", "integer", "categorical", "fixed")
SCALES = ("linear", "log")
MAPS = ("value", "list_length")
# Columns the store writes itself; parameters may not use these names.
RESERVED_COLUMNS = frozenset({
    "sample_id", "sample_index", "status", "error", "source", "wall_s", "dofs", "elements",
    "solver_version", "solver_hash", "scene_json", "warnings", "center_amplitude_um",
    "edge_amplitude_um", "normalized_edge", "edge_radius_mm", "profile_distance_mm",
    "profile_uz_um",
    "profile_magnitude_um",
    "history_t_s", "history_r_mm", "history_uz_um", "history_magnitude_um",
    "history_center_um", "history_edge_um",
}) | {f.name for f in COMPLEX_FIELDS + SWEEP_FIELDS}
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")



@dataclass(frozen=True)
class Parameter:
    """One dimension of the space (or a fixed value). Units are in the name (``_kPa``, ``_mm``).

    ``paths`` are dotted scene paths; ``mapping`` is "value" (write the value) or
    "list_length" (truncate the list at each path to ``value`` entries)."""

    name: str
    type: str
    paths: tuple[str, ...]
    mapping: str = "value"
    low: float | int | None = None
    high: float | int | None = None
    scale: str = "linear"
    choices: tuple[Any, ...] = ()
    value: Any = None
    description: str = ""

    @property
    def free(self) -> bool:
        """True when the parameter is a dimension of the sampled hypercube."""
        return self.type != "fixed"

    @property
    def column_type(self) -> str:
        """Arrow/pandas column type: "float64", "int64", "string" or "bool"."""
        if self.type == "continuous":
            return "float64"
        if self.type == "integer":
            return "int64"
        return _scalar_type(list(self.choices) if self.type == "categorical" else [self.value])

    def from_unit(self, u: np.ndarray, significant_digits: int = 0) -> np.ndarray:
        """Map unit-interval coordinates u in [0, 1) to parameter values (vectorised).

        Continuous values are rounded to ``significant_digits`` (0: not rounded) so that the
        same point gives the same value, and so the same scene hash, on every machine: the
        last bit of ``np.exp`` and of the sequence arithmetic differs between platforms and
        BLAS builds."""
        u = np.clip(np.asarray(u, dtype=float), 0.0, np.nextafter(1.0, 0.0))
        if self.type == "continuous":
            lo, hi = float(self.low), float(self.high)  # type: ignore[arg-type]
            if self.scale == "log":
                x = np.exp(math.log(lo) + u * (math.log(hi) - math.log(lo)))
            else:
                x = lo + u * (hi - lo)
            return np.clip(round_significant(x, significant_digits), lo, hi)
        if self.type == "integer":
            lo, hi = int(self.low), int(self.high)  # type: ignore[arg-type]
            return np.minimum(lo + np.floor(u * (hi - lo + 1)).astype(np.int64), hi)
        if self.type == "categorical":
            idx = np.minimum(np.floor(u * len(self.choices)).astype(np.int64),
                             len(self.choices) - 1)
            return np.asarray(self.choices, dtype=object)[idx]
        return np.full(u.shape, self.value, dtype=object)

    def allowed(self) -> str:
        """Human-readable allowed values, for error messages."""
        if self.type in ("continuous", "integer"):
            return f"{self.low} <= {self.name} <= {self.high}"
        if self.type == "categorical":
            return f"one of {', '.join(repr(c) for c in self.choices)}"
        return f"exactly {self.value!r}"

    def check_value(self, value: Any, where: str = "") -> Any:
        """Validate one externally given value (e.g. a CSV cell); return it converted to the
        column type. Raises :class:`SpaceError` naming the parameter and the allowed values."""
        label = where or self.name
        try:
            out = _convert(value, self.column_type)
        except (TypeError, ValueError):
            raise SpaceError(self.name, f"{label} = {value!r}: expected a {self.column_type} "
                             f"value, allowed {self.allowed()}") from None
        if self.type in ("continuous", "integer"):
            ok = self.low <= out <= self.high  # type: ignore[operator]
        elif self.type == "categorical":
            ok = out in self.choices
        else:
            ok = out == self.value
        if not ok:
            raise SpaceError(self.name, f"{label} = {value!r} is outside the space: "
                             f"allowed {self.allowed()}")
        return out

    def to_dict(self) -> dict[str, Any]:
        """TOML-shaped dict (inverse of the ``[[parameter]]`` reader)."""
        d: dict[str, Any] = {"name": self.name, "type": self.type}
        d["path"] = self.paths[0] if len(self.paths) == 1 else list(self.paths)
        if self.mapping != "value":
            d["map"] = self.mapping
        if self.type in ("continuous", "integer"):
            d["low"], d["high"] = self.low, self.high
        if self.type == "continuous":
            d["scale"] = self.scale
        if self.type == "categorical":
            d["choices"] = list(self.choices)
        if self.type == "fixed":
            d["value"] = self.value
        if self.description:
            d["description"] = self.description
        return d


def round_significant(x: np.ndarray, digits: int) -> np.ndarray:
    """``x`` rounded to ``digits`` significant decimal digits through its decimal text (exact
    and platform independent); ``digits = 0`` returns ``x`` unchanged."""
    if digits <= 0:
        return x
    return np.array([float(f"{v:.{digits}g}") for v in np.ravel(x)]).reshape(np.shape(x))


def _scalar_type(values: Sequence[Any]) -> str:
    if all(isinstance(v, bool) for v in values):
        return "bool"
    if all(isinstance(v, str) for v in values):
        return "string"
    if all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        return "int64"
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        return "float64"
    raise TypeError("mixed value types")


def _convert(value: Any, column_type: str) -> Any:
    if isinstance(value, np.generic):
        value = value.item()
    if column_type == "string":
        if not isinstance(value, str):
            raise TypeError
        return value
    if column_type == "bool":
        if isinstance(value, str) and value.strip().lower() in ("true", "false"):
            return value.strip().lower() == "true"
        if not isinstance(value, bool):
            raise TypeError
        return value
    if isinstance(value, bool):
        raise TypeError
    number = float(value)
    if not math.isfinite(number):
        raise ValueError
    if column_type == "int64":
        if number != int(number):
            raise ValueError
        return int(number)
    return number


# --------------------------------------------------------------------------- reading


def _read_name(value: Any, spec: Spec, path: str, ctx: Context) -> str:
    if not isinstance(value, str) or not _NAME_RE.match(value):
        raise ctx.error(path, f"{path} = {value!r}: a column name uses letters, digits and _ "
                        "and starts with a letter")
    if value in RESERVED_COLUMNS:
        raise ctx.error(path, f"{path} = {value!r} is reserved for a dataset column; reserved: "
                        f"{', '.join(sorted(RESERVED_COLUMNS))}")
    return value


def _read_paths(value: Any, spec: Spec, path: str, ctx: Context) -> tuple[str, ...]:
    paths = [value] if isinstance(value, str) else value
    if not isinstance(paths, list) or not paths or not all(isinstance(p, str) for p in paths):
        raise ctx.error(path, f"{path} = {value!r}: expected a scene path like "
                        "'tissue.layer[0].E_kPa' or a non-empty list of them")
    for item in paths:
        try:
            parse_path(item)
        except ValueError as err:
            raise ctx.error(path, f"{path}: {err}") from None
    return tuple(paths)


def _read_choices(value: Any, spec: Spec, path: str, ctx: Context) -> tuple[Any, ...]:
    if not isinstance(value, list) or len(value) < 2:
        raise ctx.error(path, f"{path} = {value!r}: need a list of at least 2 choices (use "
                        "type = 'fixed' for a constant)")
    if len(set(map(repr, value))) != len(value):
        raise ctx.error(path, f"{path} = {value!r}: duplicates")
    try:
        _scalar_type(value)
    except TypeError:
        raise ctx.error(path, f"{path} = {value!r}: all choices must be strings, or all "
                        "numbers, or all booleans") from None
    return tuple(value)


def _read_fixed(value: Any, spec: Spec, path: str, ctx: Context) -> Any:
    if not isinstance(value, str | int | float | bool):
        raise ctx.error(path, f"{path} = {value!r}: expected a string, number or boolean (put "
                        "lists and tables in [base])")
    if isinstance(value, float) and not math.isfinite(value):
        raise ctx.error(path, f"{path} = {value!r}: must be finite")
    return value


_HEAD = {
    "name": Spec(str, REQUIRED, reader=_read_name),
    "type": Spec(str, REQUIRED, choices=PARAM_TYPES),
}
_COMMON = {
    **_HEAD,
    "path": Spec(str, REQUIRED, reader=_read_paths),
    "map": Spec(str, "value", choices=MAPS),
    "description": Spec(str, ""),
}
# Keys by parameter type. ``high`` must exceed ``low`` (".low" names the sibling key).
_BY_TYPE: dict[str, dict[str, Spec]] = {
    "continuous": {"low": Spec(float, REQUIRED, "(-inf, inf)"),
                   "high": Spec(float, REQUIRED, "(.low, inf)"),
                   "scale": Spec(str, "linear", choices=SCALES)},
    "integer": {"low": Spec(int, REQUIRED, "(-inf, inf)"),
                "high": Spec(int, REQUIRED, "(.low, inf)")},
    "categorical": {"choices": Spec(list, REQUIRED, reader=_read_choices)},
    "fixed": {"value": Spec(object, REQUIRED, reader=_read_fixed)},
}


def read_parameter(raw: Any, i: int) -> Parameter:
    """The ``[[parameter]]`` table number ``i`` as a :class:`Parameter`."""
    ctx = Context(SpaceError)
    where = f"parameter[{i}]"
    if not isinstance(raw, dict):
        raise SpaceError(where, f"{where} must be a table, got {type(raw).__name__}")
    head = read_fields(raw, _HEAD, where, ctx)
    where = f"parameter[{i}] ({head['name']})"
    specs = {**_COMMON, **_BY_TYPE[head["type"]]}
    fields = read_table(raw, specs, where, ctx)
    fields["paths"] = fields.pop("path")
    fields["mapping"] = fields.pop("map")
    if fields.get("scale") == "log" and fields["low"] <= 0:
        raise SpaceError(f"{where}.low", f"{where}.low = {fields['low']!r}: a log scale needs "
                         "0 < low < high")
    param = Parameter(**fields)
    if param.mapping == "list_length" and param.column_type != "int64":
        raise SpaceError(f"{where}.map", f"{where}: map = 'list_length' needs integer values "
                         f"(type 'integer', or integer choices/value), got {param.column_type}")
    if param.mapping == "list_length" and param.type == "integer" and int(param.low) < 0:  # type: ignore[arg-type]
        raise SpaceError(f"{where}.low", f"{where}.low = {param.low}: a list length needs "
                         "low >= 0")
    return param
