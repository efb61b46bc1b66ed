"""The one reader of the TOML and JSON documents the tool reads (scenes, spaces, layouts,
patterns, plans, model cards, dataset manifests), with limits on size and nesting.

A document larger than :data:`MAX_BYTES` (or the caller's limit), nested deeper than
:data:`MAX_DEPTH` tables/arrays, not UTF-8 or not valid TOML/JSON raises the caller's
:class:`~fieldspec.errors.FieldError` subclass with field ``"<file>"`` and a message naming
the file and the limit. No input reaches Python's recursion limit: the nesting is measured on
the text before it is parsed (TOML) and the parser's own recursion is caught (JSON).
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Any

from fieldspec.errors import FieldError

__all__ = ["MAX_BYTES", "MAX_DEPTH", "check_depth", "loads_json", "loads_toml",
           "read_json_file", "read_text_file", "read_toml_file"]

#: Largest document read [bytes] (the largest shipped model card is 14 kB, a dataset
#: manifest of 10,000 parts about 3 MB).
MAX_BYTES = 32 * 1024 * 1024
#: Deepest nesting of tables and arrays accepted (shipped documents use at most 6).
MAX_DEPTH = 32


def _where(where: str | Path) -> str:
    return str(where)


def read_text_file(path: str | Path, error: type[FieldError], what: str, *,
                   max_bytes: int = MAX_BYTES, syntax: str = "text") -> str:
    """The text of ``path`` (UTF-8, a byte-order mark accepted), refused when larger than
    ``max_bytes`` or not UTF-8; ``error`` with field ``"<file>"`` names ``what`` and the file."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            data = f.read(max_bytes + 1)
    except OSError as err:
        raise error("<file>", f"cannot read {what} {str(path)!r}: "
                    f"{err.strerror or err}") from None
    if len(data) > max_bytes:
        raise error("<file>", f"{path}: {what} larger than the limit of {max_bytes} bytes; "
                    "refusing to read it")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise error("<file>", f"{path}: invalid {syntax}: the {what} is not UTF-8 text "
                    f"(byte {err.start}: {err.reason})") from None


def check_depth(obj: Any, where: str | Path, error: type[FieldError], *,
                max_depth: int = MAX_DEPTH) -> None:
    """Raise ``error`` when ``obj`` nests dicts/lists deeper than ``max_depth`` (iterative:
    any depth is measured without recursion)."""
    stack: list[tuple[Any, int]] = [(obj, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict):
            children = list(item.values())
        elif isinstance(item, list | tuple):
            children = list(item)
        else:
            continue
        if depth > max_depth:
            raise error("<file>", f"{_where(where)}: nested deeper than the limit of "
                        f"{max_depth} tables/arrays")
        stack.extend((c, depth + 1) for c in children if isinstance(c, dict | list | tuple))


def _text_depth(text: str, opening: str, closing: str) -> int:
    """Deepest bracket nesting of ``text`` outside quoted strings (an upper bound for TOML,
    whose table headers ``[a]`` count one level)."""
    depth = best = 0
    quote = ""
    escaped = False
    for ch in text:
        if quote:
            if escaped:
                escaped = False
            elif ch == "\\" and quote == '"':
                escaped = True
            elif ch == quote:
                quote = ""
            continue
        if ch in "\"'":
            quote = ch
        elif ch == "\n":
            quote = ""
        elif ch in opening:
            depth += 1
            best = max(best, depth)
        elif ch in closing:
            depth = max(depth - 1, 0)
    return best


def loads_toml(text: str, where: str | Path, error: type[FieldError], *,
               max_depth: int = MAX_DEPTH) -> dict[str, Any]:
    """Parse TOML ``text`` (from ``where``, for messages) within the nesting limit."""
    if _text_depth(text, "[{", "]}") > max_depth + 1:
        raise error("<file>", f"{_where(where)}: nested deeper than the limit of {max_depth} "
                    "tables/arrays")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise error("<file>", f"{_where(where)}: invalid TOML: {err}") from None
    except RecursionError:
        raise error("<file>", f"{_where(where)}: nested deeper than the limit of {max_depth} "
                    "tables/arrays") from None
    check_depth(data, where, error, max_depth=max_depth)
    return data


def loads_json(text: str, where: str | Path, error: type[FieldError], *,
               max_depth: int = MAX_DEPTH) -> Any:
    """Parse JSON ``text`` (from ``where``, for messages) within the nesting limit; NaN and
    infinities are refused (they are not JSON)."""
    if _text_depth(text, "[{", "]}") > max_depth:
        raise error("<file>", f"{_where(where)}: nested deeper than the limit of {max_depth} "
                    "objects/arrays")

    def constant(name: str) -> Any:
        raise ValueError(f"{name} is not a JSON number")

    try:
        data = json.loads(text, parse_constant=constant)
    except RecursionError:
        raise error("<file>", f"{_where(where)}: nested deeper than the limit of {max_depth} "
                    "objects/arrays") from None
    except ValueError as err:  # JSONDecodeError is one
        raise error("<file>", f"{_where(where)}: invalid JSON: {err}") from None
    check_depth(data, where, error, max_depth=max_depth)
    return data


def read_toml_file(path: str | Path, error: type[FieldError], what: str, *,
                   max_bytes: int = MAX_BYTES) -> dict[str, Any]:
    """The tables of a TOML file within the size and nesting limits."""
    text = read_text_file(path, error, what, max_bytes=max_bytes, syntax="TOML")
    return loads_toml(text, path, error)


def read_json_file(path: str | Path, error: type[FieldError], what: str, *,
                   max_bytes: int = MAX_BYTES) -> Any:
    """The value of a JSON file within the size and nesting limits."""
    text = read_text_file(path, error, what, max_bytes=max_bytes, syntax="JSON")
    return loads_json(text, path, error)
