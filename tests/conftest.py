"""Shared test fixtures. Tests live in folders mirroring the packages (``tests/fem``,
``tests/fieldspec``, ...) without ``__init__.py``; helpers shared within a folder are plain
modules beside the tests (``tests/fem/fem_cases.py``, ``tests/fem/analytic.py``)."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from pathlib import Path

# One BLAS / OpenMP / torch thread per pytest-xdist worker (make test: as many workers as
# cores). Set before numpy or torch is imported; subprocesses inherit it. Without it two workers
# each start a team of spinning threads per core: on the 2-core machine, one interval test took
# 388 s instead of 8 and the GP's scikit-learn checks 137 s instead of 7 (fresh-clone run).
if os.environ.get("PYTEST_XDIST_WORKER"):
    for _var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ.setdefault(_var, "1")
    if "numpy" in sys.modules:  # a plugin loaded it first: limit the pools it started
        from threadpoolctl import threadpool_limits

        threadpool_limits(1)

import pytest

REPO = Path(__file__).resolve().parents[1]

# pytest puts this folder on sys.path, where the test folders ``fem/`` and ``fieldspec/`` would
# be namespace packages shadowing the real ones when the package is installed in editable mode
# (its import hook runs after the path search). With the repository root on sys.path the real,
# regular packages are found first wherever pytest is started.
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


@pytest.fixture(autouse=True, scope="session")
def _run_from_repo_root() -> Iterator[None]:
    """Tests name example scenes relative to the repository root ("examples/forearm.toml"):
    run them from there wherever pytest was started."""
    previous = Path.cwd()
    os.chdir(REPO)
    try:
        yield
    finally:
        os.chdir(previous)


@pytest.fixture(scope="session")
def examples_dir() -> Path:
    """The directory of the commented example scenes."""
    return REPO / "examples"


@pytest.fixture(scope="session")
def sweep_dataset(tmp_path_factory) -> Path:
    """48 synthetic designs of the default sweep space, coarsened (tests/sweep_fixture.py)."""
    from sweep_fixture import make_dataset

    return make_dataset(tmp_path_factory.mktemp("sweep-data") / "default-sweep-coarse", 48)


@pytest.fixture(scope="session")
def sweep_model(sweep_dataset, tmp_path_factory) -> Path:
    """A small sweep NN on :func:`sweep_dataset` with the normal component, its profile to
    40 mm (a model directory named ``nn-sweep-fixture``)."""
    from sweep_fixture import train_model

    return train_model(sweep_dataset, tmp_path_factory.mktemp("sweep-models") / "nn-sweep-fixture")
