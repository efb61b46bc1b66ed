"""Shared test fixtures. Tests live in folders mirroring the packages (``tests/fem``,
``tests/fieldspec``, ...) without ``__init__.py``; helpers shared within a folder are plain
modules beside the tests (``tests/fem/fem_cases.py``, ``tests/fem/analytic.py``)."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


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
