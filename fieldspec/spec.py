"""Field specifications and the readers that resolve raw (TOML-shaped) tables against them.

A ``Spec`` declares one key of a table. Intervals use math notation, ``"(0, 1e9]"``; a bound
may be the dotted path of a field resolved earlier in the same :class:`Context`
(``"[0, unit.motor.height_mm]"``), so tables must be read in dependency order. Readers record
every resolved value in the context under its dotted path.
"""

from __future__ import annotations

import difflib
import numbers
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from fieldspec.errors import FieldError

__all__ = [
    "REQUIRED",
    "Context",
    "Spec",
    "allowed_text",
    "check_interval",
    "is_bool",
    "read_array",
    "read_fields",
    "read_number",
    "read_table",
    "read_value",
    "require_table",
    "unknown_key",
]


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()
"""Sentinel default: the key must be given (or supplied through ``defaults``)."""

_NUMBER_TOKEN = re.compile(r"[-+0-9.e]+")


class Context(dict[str, Any]):
    """Dotted path -> resolved value of every field read so far (interval bounds may refer to
    them), plus ``error``: the :class:`FieldError` subclass this input kind raises."""

    def __init__(self, error: type[FieldError] = FieldError) -> None:
        super().__init__()
        self.error = error


@dataclass(frozen=True)
class Spec:
    """One key of a table.

    Attributes:
        kind: ``float``, ``int``, ``str``, ``bool``, ``tuple`` (a non-empty list of floats,
            each in ``interval``), ``list`` (the same of integers) or any marker type handled
            by ``reader``.
        default: the value when the key is absent; :data:`REQUIRED` (must be given) or None
            (optional, no value).
        interval: allowed range in math notation, e.g. ``"[0, 0.5)"``; a bound may be the
            dotted path of an earlier field, or ``".key"`` for an earlier key of the same
            table (useful in arrays of tables).
        choices: the allowed values (enums).
        nonzero: zero is excluded from ``interval``.
        input_only: accepted in files but resolved into other keys, not stored.
        reader: custom reader ``(value, spec, path, ctx) -> value`` for ``kind`` markers.
        missing_hint: appended to the "is missing" message (e.g. another way to give it).
    """

    kind: type
    default: Any = REQUIRED
    interval: str = ""
    choices: tuple[Any, ...] = ()
    nonzero: bool = False
    input_only: bool = False
    reader: Callable[[Any, Spec, str, Context], Any] | None = None
    missing_hint: str = ""

    @property
    def relative(self) -> bool:
        """Whether a bound of ``interval`` names another field (so a default can violate it)."""
        return bool(self.interval) and any(
            _NUMBER_TOKEN.fullmatch(token.strip()) is None
            for token in self.interval[1:-1].split(","))


def unknown_key(path: str, key: str, allowed: Sequence[str], ctx: Context) -> FieldError:
    """The error for ``key`` not among ``allowed`` in table ``path`` (with a close-match hint)."""
    where = f"{path}.{key}" if path else key
    close = difflib.get_close_matches(key, list(allowed), n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    return ctx.error(where, f"unknown key {where!r}: {hint}allowed keys: {', '.join(allowed)}")


def require_table(raw: Any, path: str, allowed: Sequence[str], ctx: Context,
                  what: str = "the file") -> Mapping[str, Any]:
    """``raw`` as a mapping whose keys are all in ``allowed`` (else a FieldError naming the
    unknown key and listing the allowed ones). ``what`` names the top level (``path == ""``)."""
    if not isinstance(raw, Mapping):
        raise ctx.error(path, f"{path or what} must be a table, got {type(raw).__name__}")
    for key in raw:
        if key not in allowed:
            raise unknown_key(path, str(key), allowed, ctx)
    return raw


def _bound(token: str, ctx: Mapping[str, Any], path: str) -> tuple[float, str]:
    try:
        return float(token), token
    except ValueError:  # a dotted path to an earlier value; ".key" is a sibling of ``path``
        if token.startswith("."):
            token = _sibling(path, token)
        return ctx[token], f"{token} (= {ctx[token]:g})"


def _sibling(path: str, token: str) -> str:
    """``".key"`` as the dotted path of ``key`` in the table holding field ``path``
    (``box[1].inner_mm`` -> ``box[1].key``; list items ``box.radii_mm[2]`` -> ``box.key``)."""
    field = re.sub(r"(\[\d+\])+$", "", path)
    return field.rsplit(".", 1)[0] + token if "." in field else token[1:]


def allowed_text(spec: Spec, key: str, ctx: Mapping[str, Any], path: str = "") -> str:
    """The readable allowed range of ``spec`` for field ``path``, e.g. ``0 <= nu < 0.5``."""
    return _interval(spec, key, ctx, path)[2]


def _interval(spec: Spec, key: str, ctx: Mapping[str, Any],
              path: str) -> tuple[float, float, str]:
    lo_tok, hi_tok = (t.strip() for t in spec.interval[1:-1].split(","))
    (lo, lo_txt), (hi, hi_txt) = _bound(lo_tok, ctx, path), _bound(hi_tok, ctx, path)
    lo_op = "<" if spec.interval[0] == "(" else "<="
    hi_op = "<" if spec.interval[-1] == ")" else "<="
    text = f"{lo_txt} {lo_op} {key} {hi_op} {hi_txt}" + (", non-zero" if spec.nonzero else "")
    return lo, hi, text


def check_interval(value: float, spec: Spec, key: str, path: str, ctx: Context) -> None:
    """Raise ``ctx.error`` unless ``value`` lies in ``spec.interval`` (NaN never does)."""
    lo, hi, allowed = _interval(spec, key, ctx, path)
    lo_ok = lo < value if spec.interval[0] == "(" else lo <= value  # both False for NaN
    hi_ok = value < hi if spec.interval[-1] == ")" else value <= hi
    if not (lo_ok and hi_ok) or (spec.nonzero and value == 0):
        raise ctx.error(path, f"{path} = {value!r} is out of range: allowed {allowed}")


def is_bool(value: Any) -> bool:
    """Whether ``value`` is a boolean, numpy booleans (from parameter sweeps) included (checked
    without importing numpy)."""
    kind = type(value)
    return isinstance(value, bool) or (kind.__module__ == "numpy"
                                       and kind.__name__ in ("bool", "bool_"))


def read_number(value: Any, kind: type, path: str, ctx: Context) -> float | int:
    """``value`` as ``kind`` (float or int). numbers.Real/Integral also admit numpy scalars;
    booleans are refused."""
    abc = numbers.Integral if kind is int else numbers.Real
    if is_bool(value) or not isinstance(value, abc):
        what = "an integer" if kind is int else "a number (float or int)"
        extra = " (true/false is not a number)" if is_bool(value) else ""
        raise ctx.error(path, f"{path} = {value!r} has the wrong type: expected {what}, "
                        f"got {type(value).__name__}{extra}")
    try:
        return kind(value)
    except OverflowError:  # an integer too large for a float
        raise ctx.error(path, f"{path} = {value!r} is out of range: not a finite float") from None


def _read_list(value: Any, spec: Spec, key: str, path: str, ctx: Context) -> tuple[float, ...]:
    item_kind, noun = (int, "whole numbers") if spec.kind is list else (float, "numbers")
    if not isinstance(value, list | tuple) or not value:
        raise ctx.error(path, f"{path} = {value!r} has the wrong type: expected a "
                        f"non-empty list of {noun} ({allowed_text(spec, key, ctx, path)})")
    items = tuple(read_number(item, item_kind, f"{path}[{i}]", ctx)
                  for i, item in enumerate(value))
    for i, item in enumerate(items):
        check_interval(item, spec, key, f"{path}[{i}]", ctx)
    return items


def read_value(value: Any, spec: Spec, key: str, path: str, ctx: Context) -> Any:
    """Type-check, convert (int -> float) and range-check one value of field ``path``."""
    if spec.reader is not None:
        return spec.reader(value, spec, path, ctx)
    if spec.kind is str:
        if not isinstance(value, str):
            raise ctx.error(path, f"{path} = {value!r} has the wrong type: expected a string, "
                            f"got {type(value).__name__}")
        value = str(value)
    elif spec.kind is bool:
        if not is_bool(value):
            auto = " (leave the key out for auto)" if spec.default is None else ""
            raise ctx.error(path, f"{path} = {value!r} has the wrong type: expected true or "
                            f"false{auto}, got {type(value).__name__}")
        return bool(value)
    elif spec.kind is tuple or spec.kind is list:
        return _read_list(value, spec, key, path, ctx)
    else:
        value = read_number(value, spec.kind, path, ctx)
    if spec.choices and value not in spec.choices:
        choices = ", ".join(repr(c) for c in spec.choices)
        raise ctx.error(path, f"{path} = {value!r} is not allowed: choose one of {choices}")
    if spec.interval:
        check_interval(value, spec, key, path, ctx)
    return value


def read_fields(raw: Mapping[str, Any], specs: Mapping[str, Spec], path: str, ctx: Context,
                defaults: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Resolve every key of ``specs`` from ``raw`` (else ``defaults``, else the spec's default)
    and record it in ``ctx`` under ``path.key``. Unknown keys are not checked here (see
    :func:`read_table`). A default that violates a bound naming another field is reported as
    "(the default) is out of range"."""
    out: dict[str, Any] = {}
    for key, spec in specs.items():
        where = f"{path}.{key}" if path else key
        default = (defaults or {}).get(key, spec.default)
        if key in raw:
            out[key] = read_value(raw[key], spec, key, where, ctx)
        elif default is REQUIRED:
            raise ctx.error(where, f"{where} is missing: give {key}"
                            + (f" ({allowed_text(spec, key, ctx, where)})" if spec.interval else "")
                            + spec.missing_hint)
        else:
            out[key] = default
            if default is not None and spec.relative:
                try:
                    read_value(default, spec, key, where, ctx)
                except FieldError as err:
                    raise ctx.error(err.field, str(err).replace(
                        " is out of range", " (the default) is out of range")) from None
        ctx[where] = out[key]
    return out


def read_table(raw: Any, specs: Mapping[str, Spec], path: str, ctx: Context,
               extra_keys: Sequence[str] = (),
               defaults: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """:func:`read_fields` on a table that may hold only the keys of ``specs`` (plus
    ``extra_keys``, e.g. sub-tables the caller reads itself)."""
    table = require_table(raw, path, [*specs, *extra_keys], ctx)
    return read_fields(table, specs, path, ctx, defaults)


def read_array(raw: Any, path: str, ctx: Context,
               read_item: Callable[[Any, str, int], Any],
               count: tuple[int, int] = (0, 1 << 30), noun: str = "entries",
               expected: str = "an array of tables") -> list[Any]:
    """An array of tables (``[[path]]`` or an inline list): ``read_item(item, "path[i]", i)``
    for each item, with the number of items in ``count`` = (min, max). ``noun`` (plural) and
    ``expected`` word the errors."""
    if not isinstance(raw, list | tuple):
        raise ctx.error(path, f"{path} = {raw!r} has the wrong type: expected {expected}, "
                        f"got {type(raw).__name__}")
    lo, hi = count
    if not lo <= len(raw) <= hi:
        raise ctx.error(path, f"{path} has {len(raw)} {noun}: allowed {lo} <= number of "
                        f"{noun} <= {hi}")
    return [read_item(item, f"{path}[{i}]", i) for i, item in enumerate(raw)]
