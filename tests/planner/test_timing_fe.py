"""The plan's timing against FE transients driven by the planned schedules (slow: about a
minute of FE time steps per design on a quiet machine; `make test-slow`).

bench/bench_transient_rom.py runs the same comparison and prints it; docs/transient-model.md
quotes its numbers.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _bench():
    spec = importlib.util.spec_from_file_location("bench_transient_rom",
                                                  ROOT / "bench" / "bench_transient_rom.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow
@pytest.mark.parametrize("design", ["bare", "glued_rings", "pogo_3_rings"])
def test_plan_timing_matches_fe_driven_by_the_planned_schedule(design):
    res = _bench().compare(design, 130.0)
    keys = res["keys"]
    # the motor part is one law in both (motorlaw): kick and brake agree to the time grid
    for k in ("overdrive_ms", "brake_ms"):
        assert keys[k]["within"], (k, keys[k])
        assert abs(keys[k]["diff"]) <= 0.5, (k, keys[k])
    # the envelope part: within the tolerance issue 23 asks (1 ms or 5 %)
    for k in ("rise_ms", "decay_ms", "min_isi_ms"):
        assert keys[k]["within"], (k, keys[k])


@pytest.mark.slow
def test_beyond_the_motors_reach_the_plan_says_so():
    assert "at most 170 Hz" in _bench().beyond_reach(200.0)
