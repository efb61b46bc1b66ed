"""The full reproduction (slow tier): `hapticrom reproduce` gives the committed numbers."""

import json
import math
from pathlib import Path

import pytest

from hapticrom.cli import main

COMMITTED = Path(__file__).resolve().parents[2] / "reports" / "reproduce" / "results.json"
#: Solves are deterministic up to BLAS reduction order; the committed numbers carry 17 digits.
REL = 1e-6
#: Run bookkeeping (timings, pool size) and per-case solve times change from run to run.
VOLATILE = {"run", "wall_s"}


def _compare(a, b, path="", diffs=None):
    """Every number of ``a`` against ``b`` (same structure): the paths that differ."""
    diffs = [] if diffs is None else diffs
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), f"{path}: keys differ"
        for k in a:
            if k not in VOLATILE:
                _compare(a[k], b[k], f"{path}/{k}", diffs)
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{path}: lengths differ"
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _compare(x, y, f"{path}[{i}]", diffs)
    elif isinstance(a, float) and isinstance(b, float):
        if not math.isclose(a, b, rel_tol=REL, abs_tol=1e-12):
            diffs.append((path, a, b))
    elif a != b:
        diffs.append((path, a, b))
    return diffs


@pytest.mark.slow
def test_full_reproduction_gives_the_committed_numbers(tmp_path):
    if not COMMITTED.is_file():
        pytest.skip("not a checkout: no committed report")
    out = tmp_path / "report"
    assert main(["reproduce", "--out", str(out), "--workers", "2"]) == 0
    new = json.loads((out / "results.json").read_text())
    old = json.loads(COMMITTED.read_text())
    assert new["run"]["quick"] is False
    diffs = _compare(new, old)
    assert not diffs, diffs[:10]
