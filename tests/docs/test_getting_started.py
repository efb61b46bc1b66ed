"""The getting-started chain (docs/getting-started.md) runs as written: simulate -> generate ->
train -> predict -> plan -> play, about three minutes on 2 cores, so in the slow tier. The
Python examples of README.md and of that page run when the site is built (docs/hooks/site.py,
``make docs``, part of ``make test``)."""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
PAGE = REPO / "docs" / "getting-started.md"


def shell_blocks(path: Path) -> list[str]:
    return re.findall(r"^```sh\n(.*?)^```", path.read_text(encoding="utf-8"), re.S | re.M)


@pytest.mark.slow
def test_the_getting_started_chain_runs_as_written(tmp_path):
    chain = next(b for b in shell_blocks(PAGE) if "$H train" in b)
    lines = chain.splitlines()
    assert lines[0] == "H=.venv/bin/hapticrom"
    script = "\n".join(["set -eu", f"H={shlex.quote(sys.executable)}' -m hapticrom.cli'",
                        "mkdir -p out", *lines[1:]])
    for name in ("examples", "datasets", "models"):  # read-only inputs; out/ is the test's own
        (tmp_path / name).symlink_to(REPO / name)
    run = subprocess.run(["bash", "-c", script], cwd=tmp_path, capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": str(REPO)}, timeout=1800)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    out = tmp_path / "out"
    card = json.loads((out / "lab-nn" / "card.json").read_text())
    assert card["training"]["held_out"] == 13 and card["warnings"]  # what the page says
    assert "warning: 95 % intervals not calibrated: too few rows" in run.stdout
    assert "torchvision" not in run.stderr and "FutureWarning" not in run.stderr
    assert json.loads((out / "plan.json").read_text())["model"].endswith("lab-nn")
    assert (out / "play").is_dir() and (out / "plan.png").stat().st_size > 0
