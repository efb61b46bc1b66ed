"""Structure counts of the source tree (issue 22): what growing the house costs.

    python bench/structure/count_structure.py            # the table
    python bench/structure/count_structure.py --list     # every hit, file:line
    python bench/structure/count_structure.py --root ../other-checkout

Counted over the project's packages (tests, bench, examples and embed are left out):

``kind switches``
    comparisons (``==``, ``!=``, ``in``), ``match`` cases and dict keys naming a surrogate kind
    (``"gp"``, ``"nn"``, ``"rom"``, ``"mlp"``, ``"lgbm"``) anywhere, or a device kind
    (``"sim"``, ``"log"``, ``"serial"``) in ``hardware/`` and ``hapticrom/`` (elsewhere
    ``"log"`` is a scale), outside the registries (``surrogate/kinds.py``,
    ``hardware/backends.py``, the output-choice study's learners); what is left validates a
    loaded card (tests/architecture/test_kind_switches.py lists each).
``function-level imports``
    ``import``/``from ... import`` statements inside a function body (invisible to an import
    graph read at module level; ``if TYPE_CHECKING:`` blocks are not counted).
``circles``
    strongly connected groups of two or more modules inside one package, following every
    import (module level, inside functions and under ``TYPE_CHECKING``: a circle hidden in a
    function is still a circle; ``from a import b`` where ``a.b`` is a module counts as
    ``a.b``; ``__init__`` re-exports are not followed, so a package face is not a circle).
``ValueError errors``
    exception classes deriving from ``ValueError`` directly rather than from
    ``fieldspec.FieldError`` (the one error base of bad input); ``--list`` marks those that
    set a ``.field`` of their own.
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("fieldspec", "figstyle", "motorlaw", "fem", "surrogate", "studies", "planner",
            "calibration", "hardware", "hapticrom")
SURROGATE_KINDS = frozenset({"gp", "nn", "rom", "mlp", "lgbm"})
DEVICE_KINDS = frozenset({"sim", "log", "serial"})
#: The registries: the surrogate kinds, the devices, and the output-choice study's learners
#: (its own peers, some named like a kind).
REGISTRIES = frozenset({"surrogate/kinds.py", "hardware/backends.py",
                        "studies/output_choice/learners.py"})

__all__ = ["circles", "counts", "function_imports", "kind_switches", "own_field_errors",
           "source_files"]


def source_files(root: Path = ROOT) -> list[Path]:
    """Every ``.py`` file of the project's packages (those present under ``root``), sorted."""
    return sorted(p for pkg in PACKAGES if (root / pkg).is_dir()
                  for p in (root / pkg).rglob("*.py"))


def _rel(path: Path, root: Path) -> str:
    return path.relative_to(root).as_posix()


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _strings(node: ast.AST) -> Iterator[str]:
    """String constants directly in ``node`` (a constant, or a tuple/list/set of them)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        yield node.value
    elif isinstance(node, ast.Tuple | ast.List | ast.Set):
        for elt in node.elts:
            if isinstance(elt, ast.Constant) and isinstance(elt.value, str):
                yield elt.value


def kind_switches(root: Path = ROOT) -> list[tuple[str, int, str]]:
    """(file, line, kind) of every branch on a surrogate or device kind name outside the
    registries."""
    hits = []
    for path in source_files(root):
        rel = _rel(path, root)
        if rel in REGISTRIES:
            continue
        names = SURROGATE_KINDS | (DEVICE_KINDS if rel.startswith(("hardware/", "hapticrom/"))
                                   else frozenset())
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            found: list[str] = []
            if isinstance(node, ast.Compare) and any(
                    isinstance(op, ast.Eq | ast.NotEq | ast.In | ast.NotIn) for op in node.ops):
                for side in [node.left, *node.comparators]:
                    found += [s for s in _strings(side) if s in names]
            elif isinstance(node, ast.Dict):
                found += [k.value for k in node.keys if isinstance(k, ast.Constant)
                          and isinstance(k.value, str) and k.value in names]
            elif isinstance(node, ast.match_case) and isinstance(node.pattern, ast.MatchValue):
                found += [s for s in _strings(node.pattern.value) if s in names]
            hits += [(rel, node.lineno if hasattr(node, "lineno") else 0, k) for k in found]
    return hits


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _function_imports(tree: ast.AST) -> Iterator[tuple[int, str, str]]:
    """(line, function, imported module) of every import inside a function body."""

    def visit(node: ast.AST, func: str | None) -> Iterator[tuple[int, str, str]]:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child):
                continue
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef):
                yield from visit(child, child.name if func is None else f"{func}.{child.name}")
                continue
            if func is not None and isinstance(child, ast.Import):
                for alias in child.names:
                    yield child.lineno, func, alias.name
            elif func is not None and isinstance(child, ast.ImportFrom):
                yield child.lineno, func, "." * child.level + (child.module or "")
            yield from visit(child, func)

    yield from visit(tree, None)


def function_imports(root: Path = ROOT) -> list[tuple[str, int, str, str]]:
    """(file, line, function, module) of every function-level import."""
    return [(_rel(p, root), line, func, mod) for p in source_files(root)
            for line, func, mod in _function_imports(ast.parse(p.read_text(encoding="utf-8")))]


def _resolve(module: str, level: int, here: str, is_pkg: bool) -> str:
    if not level:
        return module
    base = here.split(".") if is_pkg else here.split(".")[:-1]
    base = base[:len(base) - (level - 1)]
    return ".".join([*base, module] if module else base)


def _module_imports(path: Path, root: Path, known: set[str]) -> set[str]:
    """Project modules that ``path`` imports anywhere (module level, functions,
    ``TYPE_CHECKING``)."""
    here = _module_name(path, root)
    is_pkg = path.name == "__init__.py"
    out: set[str] = set()

    def visit(node: ast.AST) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.Import):
                out.update(a.name for a in child.names if a.name in known)
            elif isinstance(child, ast.ImportFrom):
                base = _resolve(child.module or "", child.level, here, is_pkg)
                for alias in child.names:
                    sub = f"{base}.{alias.name}"
                    if sub in known:
                        out.add(sub)
                    elif base in known:
                        out.add(base)
            else:
                visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8")))
    out.discard(here)
    return out


def circles(root: Path = ROOT) -> list[list[str]]:
    """Import circles (strongly connected groups of 2+ modules) inside one package, over every
    import; package faces (``__init__``) are left out of the graph."""
    files = {_module_name(p, root): p for p in source_files(root)}
    known = set(files)
    graph = {m: {t for t in _module_imports(p, root, known) if files[t].name != "__init__.py"
                 and t.split(".")[0] == m.split(".")[0]}
             for m, p in files.items() if p.name != "__init__.py"}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[list[str]] = []
    counter = [0]

    def strong(v: str) -> None:  # Tarjan, iterative enough for this tree's depth
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for v in sorted(graph):
        if v not in index:
            strong(v)
    return sorted(groups)


def own_field_errors(root: Path = ROOT) -> list[tuple[str, int, str, bool]]:
    """(file, line, class, sets its own ``.field``) of exception classes that derive from
    ``ValueError`` directly (``fieldspec.FieldError`` itself aside)."""
    hits = []
    for path in source_files(root):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if not isinstance(node, ast.ClassDef):
                continue
            bases = {b.id if isinstance(b, ast.Name) else getattr(b, "attr", "")
                     for b in node.bases}
            if "ValueError" not in bases or node.name == "FieldError":
                continue
            sets_field = any(isinstance(n, ast.Attribute) and n.attr == "field"
                             and isinstance(n.ctx, ast.Store) for n in ast.walk(node))
            hits.append((_rel(path, root), node.lineno, node.name, sets_field))
    return hits


def counts(root: Path = ROOT) -> dict[str, int]:
    """The four figures of issue 22."""
    return {"kind switches": len(kind_switches(root)),
            "function-level imports": len(function_imports(root)),
            "circles": len(circles(root)),
            "ValueError errors": len(own_field_errors(root))}


def main(argv: list[str] | None = None) -> int:
    """Print the table (``--list``: every hit too)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--list", action="store_true", help="print every hit, file:line")
    parser.add_argument("--root", type=Path, default=ROOT,
                        help="checkout to measure (default: this one)")
    args = parser.parse_args(argv)
    root = args.root.resolve()
    for name, value in counts(root).items():
        print(f"{name:24s} {value}")
    if args.list:
        print("\n# kind switches")
        for f, line, kind in kind_switches(root):
            print(f"{f}:{line} {kind}")
        print("\n# function-level imports")
        for f, line, func, mod in function_imports(root):
            print(f"{f}:{line} {func}: {mod}")
        print("\n# circles")
        for group in circles(root):
            print(" <-> ".join(group))
        print("\n# ValueError errors")
        for f, line, name, own in own_field_errors(root):
            print(f"{f}:{line} {name}" + (" (own .field)" if own else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
