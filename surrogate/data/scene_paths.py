"""Dotted scene paths (``tissue.layer[0].E_kPa``): parse, read, write and truncate them in a
TOML-shaped scene dict.

A parameter space writes each design point's values into a copy of its base scene through
these paths. Tables or lists missing on the way are filled from the fully resolved base scene
(``defaults``), otherwise created, so ``tissue.layer[1].E_kPa`` edits the default fat layer.
Errors are plain ``ValueError`` / ``TypeError`` / ``IndexError``; the space turns them into a
:class:`~surrogate.data.errors.SpaceError` naming the parameter.
"""

from __future__ import annotations

import copy
import re
from collections.abc import Mapping, Sequence
from typing import Any

__all__ = ["PathToken", "deep_merge", "format_path", "lookup", "parse_path", "set_path",
           "truncate_path"]

_SEGMENT_RE = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")

PathToken = str | int


def parse_path(path: str) -> tuple[PathToken, ...]:
    """Split ``"tissue.layer[0].E_kPa"`` into ``("tissue", "layer", 0, "E_kPa")``.

    Raises ValueError for malformed paths (empty segments, bad names, bad indices)."""
    if not isinstance(path, str) or not path:
        raise ValueError(f"path must be a non-empty string like 'tissue.layer[0].E_kPa', "
                         f"got {path!r}")
    tokens: list[PathToken] = []
    for segment in path.split("."):
        m = _SEGMENT_RE.match(segment)
        if not m:
            raise ValueError(f"malformed path {path!r}: segment {segment!r} must be a name "
                             "optionally followed by [index] (e.g. layer[0])")
        tokens.append(m.group(1))
        tokens.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return tuple(tokens)


def format_path(tokens: Sequence[PathToken]) -> str:
    out = ""
    for tok in tokens:
        out += f"[{tok}]" if isinstance(tok, int) else (f".{tok}" if out else tok)
    return out


def lookup(tree: Any, tokens: Sequence[PathToken]) -> tuple[bool, Any]:
    node = tree
    for tok in tokens:
        if isinstance(tok, int):
            if not isinstance(node, list) or tok >= len(node):
                return False, None
        elif not isinstance(node, dict) or tok not in node:
            return False, None
        node = node[tok]
    return True, node


def _container(tree: dict, defaults: Mapping, tokens: Sequence[PathToken], where: str) -> Any:
    """Walk to the parent of the last token, filling missing tables/lists from ``defaults``
    (the resolved base scene) or creating them. Returns the parent container."""
    node: Any = tree
    for depth, tok in enumerate(tokens[:-1]):
        nxt = tokens[depth + 1]

        def fill(depth: int = depth, nxt: PathToken = nxt) -> Any:
            # built only when the container is missing: copying the defaults' subtree for every
            # path written was most of the time of planning a dataset
            empty: Any = [] if isinstance(nxt, int) else {}
            found, default = lookup(defaults, tokens[: depth + 1])
            return copy.deepcopy(default) if found and isinstance(default, type(empty)) else empty

        if isinstance(tok, int):
            if not isinstance(node, list):
                raise TypeError(f"{format_path(tokens[:depth])} is not a list")
            node.extend([None] * (tok + 1 - len(node)))
            if node[tok] is None:
                node[tok] = fill()
        else:
            if not isinstance(node, dict):
                raise TypeError(f"{format_path(tokens[:depth])} is not a table")
            if tok not in node:
                node[tok] = fill()
        node = node[tok]
        if not isinstance(node, list | dict):
            raise TypeError(f"{format_path(tokens[: depth + 1])} is a value, not a table or "
                            f"list, so {where} cannot go below it")
    return node


def set_path(tree: dict, defaults: Mapping, tokens: Sequence[PathToken], value: Any) -> None:
    where = format_path(tokens)
    parent = _container(tree, defaults, tokens, where)
    last = tokens[-1]
    if isinstance(last, int):
        if not isinstance(parent, list):
            raise TypeError(f"{format_path(tokens[:-1])} is not a list")
        parent.extend([None] * (last + 1 - len(parent)))
    elif not isinstance(parent, dict):
        raise TypeError(f"{format_path(tokens[:-1])} is not a table")
    parent[last] = value


def truncate_path(tree: dict, defaults: Mapping, tokens: Sequence[PathToken], n: int) -> None:
    parent = _container(tree, defaults, [*tokens, 0], format_path(tokens))
    if not isinstance(parent, list):
        raise TypeError(f"{format_path(tokens)} is not a list")
    if n > len(parent):
        raise IndexError(f"{format_path(tokens)} has only {len(parent)} entries, cannot keep "
                         f"{n}; map parameters onto {format_path(tokens)}[0..{n - 1}]")
    del parent[n:]

def deep_merge(under: Mapping[str, Any], over: Mapping[str, Any]) -> dict[str, Any]:
    out = copy.deepcopy(dict(under))
    for k, v in over.items():
        if isinstance(v, Mapping) and isinstance(out.get(k), Mapping):
            out[k] = deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out

