"""Copy the parts of the source tree a distribution under packaging/ ships into its ``src/``.

Each ``packaging/<dist>/setup.py`` imports this (it sits beside them) and calls
:func:`stage` before ``setup()``: in a source checkout ``src/`` is rebuilt from the tree
(so a wheel always carries the current files); in an unpacked sdist, where there is no tree,
the ``src/`` the sdist carries is used as is.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterable
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "*.tmp")


def stage(dist_dir: Path, items: Iterable[tuple[str, str]]) -> Path:
    """Rebuild ``dist_dir/src`` from ``(source relative to the repo, target relative to
    src)`` pairs (files or directories) when the repository is present; return ``src``."""
    src = dist_dir / "src"
    items = list(items)
    if not all((REPO / a).exists() for a, _ in items):
        if not src.is_dir():
            raise SystemExit(f"{dist_dir}: neither the source tree nor a staged src/ found")
        return src  # building from an sdist: the staged copy is all there is
    shutil.rmtree(src, ignore_errors=True)
    shutil.rmtree(dist_dir / "build", ignore_errors=True)  # setuptools would reuse stale files
    for source, target in items:
        a, b = REPO / source, src / target
        b.parent.mkdir(parents=True, exist_ok=True)
        if a.is_dir():
            shutil.copytree(a, b, ignore=IGNORE, symlinks=False)
        else:
            shutil.copy2(a, b)
    return src
