"""Parameter spaces: a TOML file that says which scene fields vary, over which range, and how.

Layout (``datasets/spaces/default.toml`` is a commented example)::

    [space]
    name = "default"                 # required
    description = "..."
    sampler = "sobol"                # sobol | halton | lhs | random   (surrogate.sampling)
    seed = 2025                      # integer >= 0
    lhs_batch = 256                  # batch size of the extendable LHS / random designs
    base_scene = "scene.toml"        # optional scene file, relative to this file

    [base]                           # scene overrides (TOML-shaped, fem.scene schema),
    analysis.kind = "harmonic"       # merged over base_scene

    [[parameter]]
    name = "skin_E_kPa"              # column name in the dataset
    type = "continuous"              # continuous | integer | categorical | fixed
    path = "tissue.layer[0].E_kPa"   # dotted scene path with [i] list indices (or a list)
    low = 20.0                       # continuous / integer: low <= value <= high
    high = 120.0
    scale = "log"                    # continuous only: linear | log
    # categorical: choices = ["forward", "reverse"]; fixed: value = 1.0
    # map = "list_length"            # integer: truncate the list at `path` to `value` entries

    [[constraint]]
    name = "thin_layers"
    expr = "skin_thickness_mm + fat_thickness_mm <= 15"   # rejected points are skipped

Paths: a parameter writes its value at every path in ``path``. Tables or lists missing on the
way are first taken from the base scene's fully resolved defaults (so ``tissue.layer[1]...``
edits the default fat layer), otherwise created; lists grow as needed. Filled-in default
layers carry explicit E_kPa/density/nu, which override a layer's ``material``: to vary a
tissue layer's material, list the layers in ``[base]`` with ``material`` only.
``map = "list_length"`` mappings apply after all value mappings: ``n_rings`` with path
``unit.encapsulation`` keeps the first ``n_rings`` entries written by ``ring_1 .. ring_3``.

Constraints are expressions over parameter names with numbers, strings, ``+ - * / ** %``,
comparisons, ``and or not`` and the functions ``abs min max log log10 exp sqrt``. They are
parsed into a small interpreter (never ``eval``).

Checks at load time (:class:`SpaceError`, naming the field and the allowed range): the TOML
layout, every range and choice, unique names, the constraints' names, and the scene schema -
the space's centre point and a set of probe points are resolved into scenes with
``fem.scene.scene_from_dict``, a path unknown to the schema is reported with the parameter
that uses it, and a parameter that never changes the scene (its path is ignored or
overridden) is an error.
"""

from __future__ import annotations

import ast
import copy
import functools
import hashlib
import json
import math
import re
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from surrogate.sampling import LHS_BATCH_DEFAULT, SAMPLERS, unit_points

__all__ = [
    "PARAM_TYPES",
    "RESERVED_COLUMNS",
    "Constraint",
    "Parameter",
    "Space",
    "SpaceError",
    "load_space",
    "parse_path",
    "space_from_dict",
]

PARAM_TYPES = ("continuous", "integer", "categorical", "fixed")
SCALES = ("linear", "log")
MAPS = ("value", "list_length")
# Columns the store writes itself; parameters may not use these names.
RESERVED_COLUMNS = frozenset({
    "sample_id", "sample_index", "status", "error", "source", "wall_s", "dofs", "elements",
    "solver_version", "solver_hash", "scene_json", "warnings", "center_amplitude_um",
    "edge_amplitude_um", "normalized_edge", "profile_distance_mm", "profile_uz_um",
    "profile_magnitude_um",
    "history_t_s", "history_r_mm", "history_uz_um", "history_magnitude_um",
    "history_center_um", "history_edge_um",
})
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_SEGMENT_RE = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")
_PROBE_POINTS = 32  # points used to check that every parameter reaches the scene


class SpaceError(ValueError):
    """Invalid parameter space. ``field`` names the offending entry, e.g.
    ``parameter[2] (skin_E_kPa).low``; the message names the allowed range or choices."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


# --------------------------------------------------------------------------- paths

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


def _format_path(tokens: Sequence[PathToken]) -> str:
    out = ""
    for tok in tokens:
        out += f"[{tok}]" if isinstance(tok, int) else (f".{tok}" if out else tok)
    return out


def _lookup(tree: Any, tokens: Sequence[PathToken]) -> tuple[bool, Any]:
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
        empty: Any = [] if isinstance(nxt, int) else {}
        found, default = _lookup(defaults, tokens[: depth + 1])
        fill = copy.deepcopy(default) if found and isinstance(default, type(empty)) else empty
        if isinstance(tok, int):
            if not isinstance(node, list):
                raise TypeError(f"{_format_path(tokens[:depth])} is not a list")
            node.extend([None] * (tok + 1 - len(node)))
            if node[tok] is None:
                node[tok] = fill
        else:
            if not isinstance(node, dict):
                raise TypeError(f"{_format_path(tokens[:depth])} is not a table")
            if tok not in node:
                node[tok] = fill
        node = node[tok]
        if not isinstance(node, list | dict):
            raise TypeError(f"{_format_path(tokens[: depth + 1])} is a value, not a table or "
                            f"list, so {where} cannot go below it")
    return node


def _set_path(tree: dict, defaults: Mapping, tokens: Sequence[PathToken], value: Any) -> None:
    where = _format_path(tokens)
    parent = _container(tree, defaults, tokens, where)
    last = tokens[-1]
    if isinstance(last, int):
        if not isinstance(parent, list):
            raise TypeError(f"{_format_path(tokens[:-1])} is not a list")
        parent.extend([None] * (last + 1 - len(parent)))
    elif not isinstance(parent, dict):
        raise TypeError(f"{_format_path(tokens[:-1])} is not a table")
    parent[last] = value


def _truncate_path(tree: dict, defaults: Mapping, tokens: Sequence[PathToken], n: int) -> None:
    parent = _container(tree, defaults, [*tokens, 0], _format_path(tokens))
    if not isinstance(parent, list):
        raise TypeError(f"{_format_path(tokens)} is not a list")
    if n > len(parent):
        raise IndexError(f"{_format_path(tokens)} has only {len(parent)} entries, cannot keep "
                         f"{n}; map parameters onto {_format_path(tokens)}[0..{n - 1}]")
    del parent[n:]


# --------------------------------------------------------------------------- parameters


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

    def from_unit(self, u: np.ndarray) -> np.ndarray:
        """Map unit-interval coordinates u in [0, 1) to parameter values (vectorised)."""
        u = np.clip(np.asarray(u, dtype=float), 0.0, np.nextafter(1.0, 0.0))
        if self.type == "continuous":
            lo, hi = float(self.low), float(self.high)  # type: ignore[arg-type]
            if self.scale == "log":
                return np.exp(math.log(lo) + u * (math.log(hi) - math.log(lo)))
            return lo + u * (hi - lo)
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


# --------------------------------------------------------------------------- constraints

_FUNCS = {"abs": np.abs, "min": np.minimum, "max": np.maximum, "log": np.log,
          "log10": np.log10, "exp": np.exp, "sqrt": np.sqrt}
_BINOPS = {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.divide,
           ast.Pow: np.power, ast.Mod: np.mod}
_CMPOPS = {ast.Lt: np.less, ast.LtE: np.less_equal, ast.Gt: np.greater,
           ast.GtE: np.greater_equal, ast.Eq: np.equal, ast.NotEq: np.not_equal}
_ALLOWED_NODES = (ast.Expression, ast.BoolOp, ast.BinOp, ast.UnaryOp, ast.Compare, ast.Name,
                  ast.Constant, ast.Call, ast.Load, ast.And, ast.Or, ast.Not, ast.USub, ast.UAdd,
                  *_BINOPS, *_CMPOPS)


@dataclass(frozen=True)
class Constraint:
    """A feasibility condition over parameter values; points where it is False are skipped."""

    name: str
    expr: str
    tree: ast.Expression = field(compare=False, repr=False)

    def evaluate(self, values: Mapping[str, np.ndarray]) -> np.ndarray:
        """Boolean mask over the rows of ``values`` (column name -> 1-D array)."""
        n = len(next(iter(values.values()))) if values else 0
        with np.errstate(all="ignore"):
            out = _eval_node(self.tree.body, values)
        return np.broadcast_to(np.asarray(out, dtype=bool), (n,)).copy()


def _compile_constraint(expr: str, names: Iterable[str], where: str) -> ast.Expression:
    try:
        tree = ast.parse(expr, mode="eval")
    except SyntaxError as err:
        raise SpaceError(where, f"{where}: cannot parse {expr!r}: {err.msg}") from None
    known = set(names)
    for node in ast.walk(tree):
        if not isinstance(node, _ALLOWED_NODES):
            raise SpaceError(where, f"{where}: {type(node).__name__} is not allowed in "
                             f"{expr!r}; use parameter names, numbers, strings, arithmetic, "
                             f"comparisons, and/or/not and {', '.join(_FUNCS)}")
        if isinstance(node, ast.Call) and not (
                isinstance(node.func, ast.Name) and node.func.id in _FUNCS and not node.keywords):
            raise SpaceError(where, f"{where}: only the functions {', '.join(_FUNCS)} may be "
                             f"called in {expr!r}")
        if isinstance(node, ast.Name) and node.id not in known and node.id not in _FUNCS:
            raise SpaceError(where, f"{where}: unknown name {node.id!r} in {expr!r}; "
                             f"parameters: {', '.join(sorted(known))}")
        if isinstance(node, ast.Constant) and not isinstance(node.value, int | float | str):
            raise SpaceError(where, f"{where}: constant {node.value!r} is not allowed")
    return tree


def _eval_node(node: ast.AST, env: Mapping[str, np.ndarray]) -> Any:
    if isinstance(node, ast.Constant):
        return node.value
    if isinstance(node, ast.Name):
        return env[node.id]
    if isinstance(node, ast.UnaryOp):
        val = _eval_node(node.operand, env)
        if isinstance(node.op, ast.Not):
            return np.logical_not(val)
        return np.negative(val) if isinstance(node.op, ast.USub) else val
    if isinstance(node, ast.BinOp):
        return _BINOPS[type(node.op)](_num(_eval_node(node.left, env)),
                                      _num(_eval_node(node.right, env)))
    if isinstance(node, ast.BoolOp):
        combine = np.logical_and if isinstance(node.op, ast.And) else np.logical_or
        out = _eval_node(node.values[0], env)
        for sub in node.values[1:]:
            out = combine(out, _eval_node(sub, env))
        return out
    if isinstance(node, ast.Compare):
        left, out = _eval_node(node.left, env), True
        for op, comp in zip(node.ops, node.comparators, strict=True):
            right = _eval_node(comp, env)
            out = np.logical_and(out, _CMPOPS[type(op)](left, right))
            left = right
        return out
    if isinstance(node, ast.Call):
        return _FUNCS[node.func.id](*(_num(_eval_node(a, env)) for a in node.args))  # type: ignore[attr-defined]
    raise TypeError(type(node).__name__)  # unreachable: nodes are checked at compile time


def _num(value: Any) -> Any:
    # Object arrays (fixed/categorical columns holding numbers) need a numeric dtype for ufuncs.
    if isinstance(value, np.ndarray) and value.dtype == object:
        return value.astype(float)
    return value


# --------------------------------------------------------------------------- the space


@dataclass(frozen=True)
class Space:
    """A validated parameter space. Build with :func:`load_space` or :func:`space_from_dict`.

    ``base`` is the scene override dict the parameters are written onto; ``defaults`` is its
    fully resolved scene (used to fill tables a path needs)."""

    name: str
    parameters: tuple[Parameter, ...]
    base: dict[str, Any]
    sampler: str = "sobol"
    seed: int = 0
    lhs_batch: int = LHS_BATCH_DEFAULT
    description: str = ""
    constraints: tuple[Constraint, ...] = ()

    @functools.cached_property
    def defaults(self) -> dict[str, Any]:
        """The base scene with every default filled in (``fem.scene``), or the default scene
        when the base alone is incomplete (parameters may supply what it lacks)."""
        return _resolved_defaults(self.base)

    @property
    def free(self) -> tuple[Parameter, ...]:
        """The sampled parameters, in declaration order (one hypercube dimension each)."""
        return tuple(p for p in self.parameters if p.free)

    @property
    def dim(self) -> int:
        """Number of sampled dimensions."""
        return len(self.free)

    @property
    def names(self) -> tuple[str, ...]:
        """All parameter names (dataset columns), in declaration order."""
        return tuple(p.name for p in self.parameters)

    def parameter(self, name: str) -> Parameter:
        """The parameter called ``name`` (KeyError naming the known ones otherwise)."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(f"unknown parameter {name!r}; known: {', '.join(self.names)}")

    # ---- sampling

    def values_from_unit(self, u: np.ndarray) -> dict[str, np.ndarray]:
        """Columns of parameter values for unit-hypercube rows ``u`` of shape (n, dim)."""
        u = np.atleast_2d(np.asarray(u, dtype=float))
        cols: dict[str, np.ndarray] = {}
        free = iter(range(u.shape[1]))
        for p in self.parameters:
            cols[p.name] = p.from_unit(u[:, next(free)] if p.free else np.zeros(len(u)))
        return cols

    def points(self, start: int, n: int) -> dict[str, np.ndarray]:
        """Parameter values of design points ``start .. start + n - 1`` (before constraints)."""
        u = unit_points(self.sampler, self.dim, self.seed, start, n, self.lhs_batch)
        return self.values_from_unit(u)

    def feasible(self, values: Mapping[str, np.ndarray]) -> np.ndarray:
        """Mask of rows that satisfy every constraint."""
        n = len(next(iter(values.values())))
        mask = np.ones(n, dtype=bool)
        for c in self.constraints:
            mask &= c.evaluate(values)
        return mask

    # ---- scenes

    def resolve(self, row: Mapping[str, Any]) -> dict[str, Any]:
        """Scene dict for one point (parameter name -> value); not yet validated.

        Raises :class:`SpaceError` naming the parameter whose path cannot be written."""
        scene = copy.deepcopy(self.base)
        ordered = sorted(self.parameters, key=lambda p: p.mapping == "list_length")
        for p in ordered:
            value = _plain(row[p.name])
            for path in p.paths:
                tokens = parse_path(path)
                try:
                    if p.mapping == "list_length":
                        _truncate_path(scene, self.defaults, tokens, int(value))
                    else:
                        _set_path(scene, self.defaults, tokens, value)
                except (TypeError, IndexError) as err:
                    raise SpaceError(f"parameter {p.name}.path",
                                     f"parameter {p.name!r} (path {path!r}): {err}") from None
        _check_no_holes(scene, self)
        return scene

    def scene(self, row: Mapping[str, Any]) -> Any:
        """Validated ``fem.scene.Scene`` for one point. A scene schema error is re-raised as
        :class:`SpaceError` naming the parameter whose path it concerns."""
        from fem.scene import SceneError, scene_from_dict

        resolved = self.resolve(row)
        try:
            return scene_from_dict(resolved)
        except SceneError as err:
            raise self._scene_error(err, row) from None

    def _scene_error(self, err: Any, row: Mapping[str, Any]) -> SpaceError:
        fld = getattr(err, "field", "") or ""
        for p in self.parameters:
            for path in p.paths:
                if fld == path or fld.startswith(path + ".") or fld.startswith(path + "[") \
                        or path.startswith(fld + ".") or path.startswith(fld + "["):
                    value = _plain(row[p.name])
                    return SpaceError(f"parameter {p.name}.path",
                                      f"parameter {p.name!r} = {value!r} (path {path!r}) "
                                      f"is not valid for the scene schema: {err}")
        return SpaceError("base", f"space {self.name!r}: the resolved scene is invalid at "
                          f"{fld or '?'}: {err}")

    def centre(self) -> dict[str, Any]:
        """The centre point of the space (u = 0.5 in every dimension), as a row."""
        cols = self.values_from_unit(np.full((1, self.dim), 0.5))
        return {k: _plain(v[0]) for k, v in cols.items()}

    # ---- serialisation

    def to_dict(self) -> dict[str, Any]:
        """Self-contained TOML-shaped dict (``base_scene`` already merged into ``base``)."""
        head: dict[str, Any] = {"name": self.name, "sampler": self.sampler, "seed": self.seed,
                                "lhs_batch": self.lhs_batch}
        if self.description:
            head["description"] = self.description
        d: dict[str, Any] = {"space": head, "base": copy.deepcopy(self.base),
                             "parameter": [p.to_dict() for p in self.parameters]}
        if self.constraints:
            d["constraint"] = [{"name": c.name, "expr": c.expr} for c in self.constraints]
        return d

    def space_hash(self) -> str:
        """sha256 of the canonical JSON of :meth:`to_dict`: equal spaces hash equally."""
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


def _plain(value: Any) -> Any:
    return value.item() if isinstance(value, np.generic) else value


def _check_no_holes(tree: Any, space: Space, where: str = "") -> None:
    """A list entry a parameter skipped (e.g. encapsulation[2] without [1]) is an error."""
    if isinstance(tree, dict):
        for k, v in tree.items():
            _check_no_holes(v, space, f"{where}.{k}" if where else k)
    elif isinstance(tree, list):
        for i, v in enumerate(tree):
            if v is None:
                raise SpaceError("parameter", f"space {space.name!r}: {where}[{i}] is never "
                                 "set: parameters must fill list entries from index 0 up")
            _check_no_holes(v, space, f"{where}[{i}]")


# --------------------------------------------------------------------------- reading

_SPACE_KEYS = ("name", "description", "sampler", "seed", "lhs_batch", "base_scene")
_PARAM_KEYS = ("name", "type", "path", "map", "low", "high", "scale", "choices", "value",
               "description")


def _table(raw: Any, where: str, allowed: Sequence[str]) -> Mapping[str, Any]:
    if not isinstance(raw, Mapping):
        raise SpaceError(where, f"{where} must be a table, got {type(raw).__name__}")
    for key in raw:
        if key not in allowed:
            raise SpaceError(f"{where}.{key}", f"unknown key {where}.{key}; allowed keys: "
                             f"{', '.join(allowed)}")
    return raw


def _need(raw: Mapping[str, Any], key: str, where: str, kinds: tuple[type, ...], what: str) -> Any:
    if key not in raw:
        raise SpaceError(f"{where}.{key}", f"{where}.{key} is missing: give {what}")
    value = raw[key]
    if (isinstance(value, bool) and bool not in kinds) or not isinstance(value, kinds):
        raise SpaceError(f"{where}.{key}", f"{where}.{key} = {value!r}: expected {what}")
    return value


def _read_parameter(raw: Any, i: int) -> Parameter:
    where = f"parameter[{i}]"
    raw = _table(raw, where, _PARAM_KEYS)
    name = _need(raw, "name", where, (str,), "a column name (letters, digits, _)")
    if not _NAME_RE.match(name):
        raise SpaceError(f"{where}.name", f"{where}.name = {name!r}: use letters, digits and _ "
                         "and start with a letter")
    if name in RESERVED_COLUMNS:
        raise SpaceError(f"{where}.name", f"{where}.name = {name!r} is reserved for a dataset "
                         f"column; reserved: {', '.join(sorted(RESERVED_COLUMNS))}")
    where = f"parameter[{i}] ({name})"
    ptype = _need(raw, "type", where, (str,), f"one of {', '.join(PARAM_TYPES)}")
    if ptype not in PARAM_TYPES:
        raise SpaceError(f"{where}.type", f"{where}.type = {ptype!r}: allowed "
                         f"{', '.join(PARAM_TYPES)}")
    paths = _read_paths(raw, where)
    mapping = raw.get("map", "value")
    if mapping not in MAPS:
        raise SpaceError(f"{where}.map", f"{where}.map = {mapping!r}: allowed {', '.join(MAPS)}")
    kw: dict[str, Any] = {"name": name, "type": ptype, "paths": paths, "mapping": mapping,
                          "description": str(raw.get("description", ""))}
    extra = {"continuous": ("low", "high", "scale"), "integer": ("low", "high"),
             "categorical": ("choices",), "fixed": ("value",)}[ptype]
    for key in ("low", "high", "scale", "choices", "value"):
        if key in raw and key not in extra:
            raise SpaceError(f"{where}.{key}", f"{where}.{key} does not apply to type "
                             f"{ptype!r}; its keys: {', '.join(extra)}")
    if ptype in ("continuous", "integer"):
        kw.update(_read_range(raw, where, ptype))
    elif ptype == "categorical":
        kw["choices"] = _read_choices(raw, where)
    else:
        kw["value"] = _read_fixed(raw, where)
    param = Parameter(**kw)
    if mapping == "list_length" and param.column_type != "int64":
        raise SpaceError(f"{where}.map", f"{where}: map = 'list_length' needs integer values "
                         f"(type 'integer', or integer choices/value), got {param.column_type}")
    if mapping == "list_length" and ptype == "integer" and int(param.low) < 0:  # type: ignore[arg-type]
        raise SpaceError(f"{where}.low", f"{where}.low = {param.low}: a list length needs "
                         "low >= 0")
    return param


def _read_paths(raw: Mapping[str, Any], where: str) -> tuple[str, ...]:
    value = _need(raw, "path", where, (str, list), "a scene path like 'tissue.layer[0].E_kPa' "
                  "or a list of them")
    paths = [value] if isinstance(value, str) else value
    if not paths:
        raise SpaceError(f"{where}.path", f"{where}.path is empty: give at least one path")
    for path in paths:
        try:
            parse_path(path)
        except ValueError as err:
            raise SpaceError(f"{where}.path", f"{where}.path: {err}") from None
    return tuple(paths)


def _read_range(raw: Mapping[str, Any], where: str, ptype: str) -> dict[str, Any]:
    kinds: tuple[type, ...] = (int,) if ptype == "integer" else (int, float)
    what = "an integer" if ptype == "integer" else "a number"
    low = _need(raw, "low", where, kinds, what)
    high = _need(raw, "high", where, kinds, what)
    for key, v in (("low", low), ("high", high)):
        if not math.isfinite(v):
            raise SpaceError(f"{where}.{key}", f"{where}.{key} = {v!r}: must be finite")
    if not low < high:
        raise SpaceError(f"{where}.low", f"{where}: empty range low = {low!r}, high = {high!r}; "
                         "need low < high (use type = 'fixed' for a constant)")
    out: dict[str, Any] = {"low": low, "high": high}
    if ptype == "continuous":
        out["low"], out["high"] = float(low), float(high)
        scale = raw.get("scale", "linear")
        if scale not in SCALES:
            raise SpaceError(f"{where}.scale", f"{where}.scale = {scale!r}: allowed "
                             f"{', '.join(SCALES)}")
        if scale == "log" and low <= 0:
            raise SpaceError(f"{where}.low", f"{where}.low = {low!r}: a log scale needs "
                             "0 < low < high")
        out["scale"] = scale
    return out


def _read_choices(raw: Mapping[str, Any], where: str) -> tuple[Any, ...]:
    choices = _need(raw, "choices", where, (list,), "a list of at least 2 values")
    if len(choices) < 2:
        raise SpaceError(f"{where}.choices", f"{where}.choices = {choices!r}: need at least 2 "
                         "choices (use type = 'fixed' for a constant)")
    if len(set(map(repr, choices))) != len(choices):
        raise SpaceError(f"{where}.choices", f"{where}.choices = {choices!r}: duplicates")
    try:
        _scalar_type(choices)
    except TypeError:
        raise SpaceError(f"{where}.choices", f"{where}.choices = {choices!r}: all choices must "
                         "be strings, or all numbers, or all booleans") from None
    return tuple(choices)


def _read_fixed(raw: Mapping[str, Any], where: str) -> Any:
    value = _need(raw, "value", where, (str, int, float, bool), "a string, number or boolean "
                  "(put lists and tables in [base])")
    if isinstance(value, float) and not math.isfinite(value):
        raise SpaceError(f"{where}.value", f"{where}.value = {value!r}: must be finite")
    return value


def _read_constraint(raw: Any, i: int, names: Sequence[str]) -> Constraint:
    where = f"constraint[{i}]"
    raw = _table(raw, where, ("name", "expr"))
    expr = _need(raw, "expr", where, (str,), "an expression such as 'a + b <= 10'")
    name = str(raw.get("name", f"constraint{i}"))
    return Constraint(name, expr, _compile_constraint(expr, names, f"{where} ({name}).expr"))


def _deep_merge(under: Mapping[str, Any], over: Mapping[str, Any]) -> dict[str, Any]:
    out = copy.deepcopy(dict(under))
    for k, v in over.items():
        if isinstance(v, Mapping) and isinstance(out.get(k), Mapping):
            out[k] = _deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def space_from_dict(d: Mapping[str, Any], base_dir: str | Path | None = None,
                    check_scenes: bool = True) -> Space:
    """Validate a TOML-shaped space dict and build a :class:`Space`.

    ``base_dir`` resolves a relative ``space.base_scene``. With ``check_scenes`` (default) the
    centre and probe points are resolved through ``fem.scene`` (see module docstring)."""
    d = _table(d, "<space file>", ("space", "base", "parameter", "constraint"))
    head = _table(d.get("space", {}), "space", _SPACE_KEYS)
    name = _need(head, "name", "space", (str,), "a name for the space")
    sampler = head.get("sampler", "sobol")
    if sampler not in SAMPLERS:
        raise SpaceError("space.sampler", f"space.sampler = {sampler!r}: allowed "
                         f"{', '.join(SAMPLERS)}")
    seed = head.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise SpaceError("space.seed", f"space.seed = {seed!r}: need an integer >= 0")
    lhs_batch = head.get("lhs_batch", LHS_BATCH_DEFAULT)
    if isinstance(lhs_batch, bool) or not isinstance(lhs_batch, int) or not 1 <= lhs_batch <= 2**20:
        raise SpaceError("space.lhs_batch", f"space.lhs_batch = {lhs_batch!r}: need an integer, "
                         "1 <= lhs_batch <= 1048576")
    base = _read_base(d, head, base_dir)
    raw_params = d.get("parameter", [])
    if not isinstance(raw_params, list) or not raw_params:
        raise SpaceError("parameter", "the space has no [[parameter]] entries: give at least one")
    params = tuple(_read_parameter(p, i) for i, p in enumerate(raw_params))
    _check_unique(params)
    if not any(p.free for p in params):
        raise SpaceError("parameter", "every parameter is fixed: give at least one continuous, "
                         "integer or categorical parameter")
    raw_cons = d.get("constraint", [])
    if not isinstance(raw_cons, list):
        raise SpaceError("constraint", "constraint must be an array of tables ([[constraint]])")
    names = [p.name for p in params]
    constraints = tuple(_read_constraint(c, i, names) for i, c in enumerate(raw_cons))
    space = Space(name=name, parameters=params, base=base, sampler=sampler, seed=seed,
                  lhs_batch=lhs_batch, description=str(head.get("description", "")),
                  constraints=constraints)
    if check_scenes:
        check_space(space)
    return space


def _read_base(d: Mapping[str, Any], head: Mapping[str, Any],
               base_dir: str | Path | None) -> dict[str, Any]:
    base = d.get("base", {})
    if not isinstance(base, Mapping):
        raise SpaceError("base", f"base must be a table of scene overrides, got "
                         f"{type(base).__name__}")
    if "base_scene" not in head:
        return copy.deepcopy(dict(base))
    path = Path(head["base_scene"])
    if not path.is_absolute():
        path = Path(base_dir or ".") / path
    try:
        scene = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise SpaceError("space.base_scene", f"space.base_scene = {str(path)!r}: cannot read "
                         f"it: {err}") from None
    return _deep_merge(scene, base)


def _check_unique(params: Sequence[Parameter]) -> None:
    seen: dict[str, int] = {}
    written: dict[str, str] = {}
    for i, p in enumerate(params):
        if p.name in seen:
            raise SpaceError(f"parameter[{i}].name", f"parameter[{i}].name = {p.name!r} is "
                             f"already used by parameter[{seen[p.name]}]")
        seen[p.name] = i
        for path in p.paths:
            key = f"{p.mapping}:{_format_path(parse_path(path))}"
            if key in written:
                raise SpaceError(f"parameter[{i}].path", f"parameter {p.name!r}: path {path!r} "
                                 f"is also written by parameter {written[key]!r}")
            written[key] = p.name


def _resolved_defaults(base: Mapping[str, Any]) -> dict[str, Any]:
    from fem.scene import SceneError, scene_from_dict, scene_to_dict

    # The base alone may be incomplete (a parameter supplies the rest): then fill missing
    # tables from the schema's own defaults.
    for scene in (base, {}):
        try:
            return scene_to_dict(scene_from_dict(scene))
        except SceneError:
            continue
    return {}


def check_space(space: Space) -> None:
    """Resolve the centre and probe points into scenes (raising :class:`SpaceError` for paths
    the schema rejects), check the constraints admit points, and check that every free
    parameter changes the scene somewhere."""
    from fem.scene import scene_hash

    centre = space.centre()
    space.scene(centre)
    probe = space.points(0, _PROBE_POINTS)
    mask = space.feasible(probe)
    if not mask.any():
        cons = ", ".join(f"{c.name}: {c.expr}" for c in space.constraints)
        raise SpaceError("constraint", f"the constraints reject all of the first "
                         f"{_PROBE_POINTS} design points ({cons}); widen them or the ranges")
    rows = [{k: _plain(v[i]) for k, v in probe.items()} for i in np.flatnonzero(mask)]
    hashes = [scene_hash(space.scene(row)) for row in rows]
    for p in space.free:
        alt = p.from_unit(np.array([0.0, 0.999]))
        if not any(_changes(space, row, h, p, alt, scene_hash) for row, h in zip(rows, hashes,
                                                                                   strict=True)):
            raise SpaceError(f"parameter {p.name}.path",
                             f"parameter {p.name!r} (path {', '.join(p.paths)}) never changes the "
                             "resolved scene in the probe points: its list entry is always "
                             "truncated away, or the field is overwritten")


def _changes(space: Space, row: Mapping[str, Any], h: str, p: Parameter, alt: np.ndarray,
             scene_hash: Any) -> bool:
    for value in alt:
        if value == row[p.name]:
            continue
        if scene_hash(space.scene({**row, p.name: value})) != h:
            return True
    return False


def load_space(path: str | Path, check_scenes: bool = True) -> Space:
    """Read a space TOML file (see module docstring). Raises :class:`SpaceError`."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise SpaceError("<file>", f"cannot read space file {str(path)!r}: {err}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SpaceError("<file>", f"{path}: invalid TOML: {err}") from None
    return space_from_dict(data, base_dir=path.parent, check_scenes=check_scenes)
