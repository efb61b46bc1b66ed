"""Imports visible (issues 22 and 35): no import circle inside a package (package faces and
``TYPE_CHECKING`` imports included), and an import inside a function only where a measured
start-up cost or an optional dependency asks for it, each with its reason here and a comment
beside it. Counted by bench/structure/count_structure.py (every import, functions and
``TYPE_CHECKING`` included) and by grimp (import-linter's graph)."""

from __future__ import annotations

import grimp
import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from bench.structure.count_structure import PACKAGES, ROOT, circles, function_imports

#: Circles still standing, each with why: none (fem/scene went when a Scene's checks became a
#: hook the reader registers, fem.scene.model.SCENE_CHECKS; the actuators' when they named what
#: they read of a scene as interfaces, fem.actuators.base.SceneView, instead of importing it).
KNOWN_CIRCLES: dict[tuple[str, ...], str] = {}

#: Modules imported lazily anywhere, with the measured reason (numpy already loaded;
#: `python -c "import time, numpy; t = time.perf_counter(); import M; ..."`).
LAZY_MODULES = {
    "matplotlib": "1.9 s to import; only a figure needs it and most runs draw none",
    "PIL": "a figure's PNG palette: loaded with matplotlib",
    "cycler": "a figure's colour cycle: loaded with matplotlib",
    "torch": "3.9 s; only the NN kind needs it",
    "sklearn": "4.8 s; only training needs it",
    "scipy": "scipy.signal 0.55 s, scipy.optimize 0.32 s; planning imports no scipy at all "
             "(tests/planner/test_plan.py)",
    "serial": "pyserial, the `hardware` extra: present only where an array is driven",
    "cholespy": "optional sparse Cholesky backend, tried when installed",
    "threadpoolctl": "optional: limits BLAS threads when installed",
    "meshio": "optional VTU export",
    "emcee": "the `calibration` extra: only the sampler needs it",
    "distributed": "dask, the `datasets` extra: only the Dask backend needs it",
    "tqdm": "progress bars, drawn only on a terminal",
    "pysindy": "not a dependency: only the SINDy measurement (studies/envelope_sindy, "
               "bench/surrogate/envelope_sindy.py, which says how to install it) imports it",
    "lightgbm": "the `bench` extra: only fitting the LightGBM peer needs it "
                "(surrogate/estimators/lgbm.py, the output-choice study)",
    "optuna": "0.22 s, the `design` extra: only `search.optimiser = \"tpe\"` needs it",
    "cma": "2.3 s, the `design` extra: only `search.optimiser = \"cmaes\"` needs it",
}

#: (file, imported module) -> reason, for project modules imported inside a function.
LAZY_PLACES = {
    ("hapticrom/outputs.py", "surrogate.registry"):
        "loads onnxruntime: 0.16 s of the 0.4 s of `hapticrom --help`",
    ("surrogate/train.py", "surrogate.kinds"):
        "the registry loads torch and scikit-learn (5 s); load_datasets and "
        "evaluate (refine, the studies) need none of it",
    ("surrogate/data/pool.py", "fem.simulation"):
        "worker warm-up: imported in each worker process as it starts, not in the parent",
}

#: Every command's parser is built at start-up (`hapticrom --help`: 0.4 s); a command's own
#: library (fem, surrogate, planner, hardware, calibration, studies: 1.1 s without torch and
#: scikit-learn) is imported when it runs.
COMMANDS = "hapticrom/commands/"
PROJECT = ("fem", "surrogate", "planner", "hardware", "calibration", "studies")


def _allowed(path: str, module: str) -> bool:
    top = module.split(".")[0]
    if top in LAZY_MODULES or (path, module) in LAZY_PLACES:
        return True
    return path.startswith(COMMANDS) and top in PROJECT


def test_no_import_circle_inside_a_package():
    assert {tuple(c) for c in circles()} <= set(KNOWN_CIRCLES)


def test_fem_scene_has_no_circle_and_no_hidden_import():
    assert not [c for c in circles() if any(m.startswith("fem.scene") for m in c)]
    assert not [f for f in function_imports() if f[0].startswith("fem/scene/")]


def test_function_level_imports_are_only_where_a_reason_is_given():
    hidden = [f"{path}:{line} {func}: {module}" for path, line, func, module in function_imports()
              if not _allowed(path, module)]
    assert hidden == [], "\n".join(hidden)


def test_the_allow_list_has_no_stale_entries():
    used = {(path, module) for path, _, _, module in function_imports()}
    assert set(LAZY_PLACES) <= used


@pytest.mark.parametrize("package", PACKAGES)
def test_no_import_circle_in_the_package_graph(package):
    """Every import grimp sees (package faces, functions, ``TYPE_CHECKING``) forms no circle."""
    graph = grimp.build_graph(package, include_external_packages=False)
    names = sorted(graph.modules)
    index = {m: i for i, m in enumerate(names)}
    edges = [(index[a], index[b]) for a in names
             for b in graph.find_modules_directly_imported_by(a)]
    rows, cols = (np.array(x, dtype=int) for x in zip(*edges, strict=True)) if edges else ([], [])
    adjacency = csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(names), len(names)))
    _, label = connected_components(adjacency, directed=True, connection="strong")
    groups = [[names[i] for i in np.flatnonzero(label == k)] for k in np.unique(label)]
    assert [g for g in groups if len(g) > 1] == []


def test_every_function_level_import_says_why_beside_it():
    """A comment on the import, or above it in the same function."""
    silent = []
    for path, line, func, module in function_imports():
        lines = (ROOT / path).read_text(encoding="utf-8").splitlines()[:line]
        body = []
        for text in reversed(lines):
            body.append(text)
            if text.lstrip().startswith(("def ", "async def ")):
                break
        if not any("#" in text for text in body):
            silent.append(f"{path}:{line} {func}: {module}")
    assert silent == [], "\n".join(silent)
