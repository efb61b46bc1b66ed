"""Feasibility constraints of a parameter space: ``skin_thickness_mm + fat_thickness_mm <= 15``.

An expression over parameter names with numbers, strings, ``+ - * / ** %``, comparisons,
``and or not`` and the functions ``abs min max log log10 exp sqrt``. It is parsed with
:mod:`ast`, every node is checked against an allow-list, and a small interpreter evaluates it
vectorised over the design points (never ``eval``).
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fieldspec import Context, Spec, read_table
from surrogate.data.errors import SpaceError

__all__ = ["Constraint", "compile_constraint", "read_constraint"]

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


def compile_constraint(expr: str, names: Iterable[str], where: str) -> ast.Expression:
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


_CONSTRAINT_KEYS = {
    "name": Spec(str, None),
    "expr": Spec(str, missing_hint=" (an expression such as 'a + b <= 10')"),
}


def read_constraint(raw: Any, i: int, names: Sequence[str]) -> Constraint:
    """The ``[[constraint]]`` table number ``i`` over the parameter ``names``."""
    where = f"constraint[{i}]"
    fields = read_table(raw, _CONSTRAINT_KEYS, where, Context(SpaceError))
    name = fields["name"] or f"constraint{i}"
    expr = fields["expr"]
    return Constraint(name, expr, compile_constraint(expr, names, f"{where} ({name}).expr"))
