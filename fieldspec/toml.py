"""A small TOML writer for the TOML-shaped dicts the readers resolve (tomllib only reads).

Values: str, bool, int, finite float (written with ``repr``, so they read back exactly),
lists and mappings (inline). Top-level mappings become ``[table]`` sections, nested mappings
``[table.key]`` and the keys named in ``arrays`` ``[[table.key]]`` arrays of tables.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fieldspec.documents import read_toml_file as _read_toml
from fieldspec.errors import FieldError

__all__ = ["dumps", "read_toml_file", "toml_value"]

_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f",
            "\r": "\\r"}
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def read_toml_file(path: str | Path, error: type[FieldError], what: str) -> dict[str, Any]:
    """The tables of a TOML file (a UTF-8 byte-order mark is accepted); an unreadable file,
    a syntax error or a file beyond the size and nesting limits of
    :mod:`fieldspec.documents` raises ``error`` with field ``"<file>"``, naming ``what``."""
    return _read_toml(path, error, what)


def toml_value(value: Any) -> str:
    """One value as TOML text (ValueError for a non-finite float, TypeError for other types)."""
    if isinstance(value, str):
        # TOML basic strings forbid raw control characters (U+0000-U+001F, U+007F).
        return '"' + re.sub(
            r'["\\\x00-\x1f\x7f]',
            lambda m: _ESCAPES.get(m.group(), f"\\u{ord(m.group()):04X}"), str(value)) + '"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"cannot write non-finite float {value!r}")
        return repr(value)  # shortest exact repr, always a valid TOML float ("1e-05", "2.0")
    if isinstance(value, int):
        return str(value)
    if isinstance(value, list | tuple):  # nested lists and inline tables recurse
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {type(value).__name__} to TOML")


def _key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else toml_value(key)


def _table(path: str, table: Mapping[str, Any], arrays: Mapping[str, str]) -> list[str]:
    """``[path]`` with its plain keys, then its sub-tables ``[path.key]`` and arrays of tables
    ``[[path.key]]`` (TOML needs the plain keys first)."""
    lines, after = [f"[{path}]"], []
    for key, value in table.items():
        if isinstance(value, Mapping):
            after += ["", *_table(f"{path}.{key}", value, arrays)]
        elif key == arrays.get(path):
            for item in value:
                after += ["", f"[[{path}.{key}]]"]
                after += [f"{k} = {toml_value(v)}" for k, v in item.items()]
        else:
            lines.append(f"{key} = {toml_value(value)}")
    return lines + after


def dumps(tables: Mapping[str, Mapping[str, Any]], arrays: Mapping[str, str] | None = None,
          header: str = "") -> str:
    """TOML text of ``tables`` (name -> table); ``arrays`` maps a table name to its key that
    holds an array of tables (``{"tissue": "layer"}`` -> ``[[tissue.layer]]``). ``header`` is
    written first as ``#`` comment lines."""
    lines = [f"# {line}" for line in header.splitlines()] + ([""] if header else [])
    for name, table in tables.items():
        lines += [*_table(name, table, arrays or {}), ""]
    return "\n".join(lines)
