"""Fixtures of the embedding tests: sealed copies of the shipped models, random in-range
designs, and the JavaScript tools (node, the npm packages of embed/, chromium).

A test that needs node or chromium is skipped, saying what is missing, unless
HAPTICROM_REQUIRE_JS=1 (``make test`` sets it after installing them), which turns the skip into
a failure."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest
from embed_cases import EMBED, REPO, seal_copy  # noqa: F401  (re-exported to fixtures)
from sweep_fixture import GP_OPTIONS, train_model


@pytest.fixture(scope="session")
def sealed(tmp_path_factory) -> dict[str, Path]:
    """Sealed copies of nn-default, gp-default, nn-normal and the shipped sweep defaults."""
    dest = tmp_path_factory.mktemp("sealed")
    return {m: seal_copy(m, dest) for m in ("nn-default", "gp-default", "nn-normal", "nn-sweep",
                                            "gp-sweep")}


@pytest.fixture(scope="session")
def sweep_gp_model(sweep_dataset, tmp_path_factory) -> Path:
    """A small sweep GP on the synthetic sweep dataset, with the normal component."""
    return train_model(sweep_dataset, tmp_path_factory.mktemp("sweep-gp") / "gp-sweep-fixture",
                       kind="gp", options=GP_OPTIONS)


def _require(what: str) -> None:
    if os.environ.get("HAPTICROM_REQUIRE_JS") == "1":
        pytest.fail(f"{what} (HAPTICROM_REQUIRE_JS=1: `make test` installs it)")
    pytest.skip(what)


@pytest.fixture(scope="session")
def node() -> str:
    """The node executable, with embed/node_modules installed (`npm ci` in embed/)."""
    exe = shutil.which("node")
    if exe is None:
        _require("node is not installed")
    if not (EMBED / "node_modules" / "onnxruntime-node").is_dir():
        _require("embed/node_modules is missing: run `npm ci` in embed/")
    return exe


@pytest.fixture(scope="session")
def chromium(node) -> str:
    """Debian's chromium, and playwright-core in embed/node_modules."""
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        _require("chromium is not installed (apt-get install chromium)")
    if not (EMBED / "node_modules" / "playwright-core").is_dir():
        _require("embed/node_modules is missing: run `npm ci` in embed/")
    return exe
