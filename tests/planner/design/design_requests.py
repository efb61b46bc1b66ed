"""Paths of the design example the tests build their small requests from."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
EXAMPLE = ROOT / "examples" / "design-forearm.toml"


def example_dict() -> dict:
    """The forearm example's tables, reference scenes made absolute (a fresh copy)."""
    d = tomllib.loads(EXAMPLE.read_text())
    d["reference"]["scenes"] = [str(ROOT / "examples" / s) for s in d["reference"]["scenes"]]
    return copy.deepcopy(d)
