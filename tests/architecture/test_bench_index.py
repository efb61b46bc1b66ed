"""bench/README.md is the index of the benchmarks (issue 35): it names every script under
bench/, and names none that is gone."""

from __future__ import annotations

import re
from pathlib import Path

BENCH = Path(__file__).resolve().parents[2] / "bench"


def test_the_bench_index_names_every_script_and_no_other():
    scripts = {p.relative_to(BENCH).as_posix() for p in BENCH.rglob("*.py")}
    named = set(re.findall(r"^\| `([\w/]+\.py)`", (BENCH / "README.md").read_text(), re.M))
    assert scripts == named
