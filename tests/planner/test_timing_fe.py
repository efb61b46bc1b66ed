"""The plan's timing against FE transients driven by the planned schedules (slow: six FE
transients of up to 0.62 s per design, 0.5-1.5 min each on the loaded 2-core machine;
`make test-slow`).

bench/planner/transient_rom.py runs the same comparison and prints it; docs/transient-model.md
quotes its numbers. Criterion (issue 23): within 1 ms or 5 %. Overdrive and brake come from the
one motor law in both and must agree; the envelope times that the model misses by more than the
criterion at the last measurement are strict expected failures, so that a model that starts
meeting them makes these tests fail until the marks are removed.
"""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FREQUENCY_HZ = 130.0
# (design, key) outside 1 ms / 5 % in the last bench run (docs/transient-model.md)
MEASURED_OUTSIDE = {("bare", "rise_ms"), ("bare", "decay_ms"), ("bare", "min_isi_ms"),
                    ("glued_rings", "min_isi_ms"),
                    ("pogo_3_rings", "rise_ms"), ("pogo_3_rings", "decay_ms"),
                    ("pogo_3_rings", "min_isi_ms")}


@functools.cache
def _bench():
    spec = importlib.util.spec_from_file_location("transient_rom",
                                                  ROOT / "bench" / "planner" / "transient_rom.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@functools.cache
def _compare(design: str) -> dict:
    return _bench().compare(design, FREQUENCY_HZ)


def _cases():
    for design in ("bare", "glued_rings", "pogo_3_rings"):
        for key in ("rise_ms", "decay_ms", "overdrive_ms", "brake_ms", "min_isi_ms"):
            marks = [pytest.mark.slow]
            if (design, key) in MEASURED_OUTSIDE:
                marks.append(pytest.mark.xfail(strict=True, reason="measured gap of the "
                                               "envelope model, docs/transient-model.md"))
            yield pytest.param(design, key, marks=marks, id=f"{design}-{key}")


@pytest.mark.parametrize(("design", "key"), list(_cases()))
def test_plan_timing_matches_fe_driven_by_the_planned_schedule(design, key):
    row = _compare(design)["keys"][key]
    assert row["within"], row
    if key in ("overdrive_ms", "brake_ms"):  # one law in both: equal to the time grid
        assert abs(row["diff"]) <= 0.5, row


@pytest.mark.slow
def test_beyond_the_motors_reach_the_plan_says_so():
    assert "needs 5.233 V" in _bench().beyond_reach(200.0)
    assert "at most 169.65 Hz" in _bench().beyond_reach(200.0)
