"""The plain warnings of a model card (issue 37 item 4): intervals too few rows to calibrate,
coverage far from 95 % for the rows that measured it, errors far from the accuracy targets;
in the card, at the end of ``hapticrom train`` and in ``hapticrom models list``."""

from __future__ import annotations

import copy
import json
import logging
import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from fieldspec import HapticromWarning
from hapticrom.cli import build_parser, main, quiet_libraries
from surrogate.card_warnings import ACCURACY_TARGETS, card_warnings

REPO = Path(__file__).resolve().parents[2]
GOOD = {"kind": "nn",
        "training": {"rows": 3277, "held_out": 819},
        "metrics": {"center_amplitude_um": {"median_rel_err": 0.008, "p95_rel_err": 0.025,
                                            "coverage95": 0.95},
                    "edge_amplitude_um": {"median_rel_err": 0.01, "coverage95": 0.96},
                    "profile_um": {"median_rel_l2": 0.01}},
        "interval_calibration": {"method": "split-conformal", "rows": {"calibration": 327}}}


def card(**changes) -> dict:
    c = copy.deepcopy(GOOD)
    for path, value in changes.items():
        *keys, last = path.split("__")
        node = c
        for k in keys:
            node = node[k]
        if value is None:
            del node[last]
        else:
            node[last] = value
    return c


def test_a_model_on_target_gets_no_warning():
    assert card_warnings(GOOD) == []
    assert card_warnings({"kind": "rom", "metrics": {"held_out": {}}}) == []  # not steady


def test_too_few_rows_to_calibrate_is_said_with_the_numbers():
    [w] = card_warnings(card(interval_calibration=None, training__rows=51))
    assert "not calibrated: too few rows (51 training rows, 10 % of them is 5, fewer than " \
           "the 100" in w
    [w] = card_warnings(card(interval_calibration=None))  # enough rows: calibration was off
    assert "--calibration-fraction 0" in w and "calibrate-intervals" in w


@pytest.mark.parametrize("coverage, held_out, far", [
    (0.915, 819, True),   # 3 sigma of 819 rows is 2.3 points: the 3-point floor decides
    (0.925, 819, False),
    (0.82, 819, True),
    (0.89, 100, False),   # 3 sigma of 100 rows is 6.5 points
    (0.88, 100, True),
    (0.88, 60, False),
    (0.80, 60, True),
    (1.00, 400, True),    # too wide is far too
])
def test_coverage_is_far_beyond_three_binomial_sigmas(coverage, held_out, far):
    ws = card_warnings(card(metrics__edge_amplitude_um__coverage95=coverage,
                            training__held_out=held_out))
    assert bool(ws) == far
    if far:
        assert ws == [f"95 % intervals cover {100 * coverage:.0f} % (edge_amplitude_um) of "
                      f"{held_out} held-out rows: far from 95 % (more than "
                      f"{max(3, 300 * (0.95 * 0.05 / held_out) ** 0.5):.0f} points off)"]


def test_a_calibrated_models_coverage_is_read_where_calibration_measured_it():
    c = card(metrics__center_amplitude_um__coverage95=0.82)  # the raw held-out coverage
    c["interval_calibration"]["rows"]["check"] = 410
    c["interval_calibration"]["coverage95_check"] = {
        "before": {"center_amplitude_um": 0.83}, "after": {"center_amplitude_um": 0.958}}
    assert card_warnings(c) == []
    c["interval_calibration"]["coverage95_check"]["after"]["center_amplitude_um"] = 0.90
    [w] = card_warnings(c)
    assert "90 % (center_amplitude_um) of 410 rows kept apart by calibrate-intervals" in w


def test_few_held_out_rows_are_called_rough_and_far_coverage_still_far():
    [rough, far] = card_warnings(card(training__held_out=13,
                                      metrics__center_amplitude_um__coverage95=0.31))
    assert rough == ("only 13 held-out rows: its held-out errors and coverage are rough (a 95 % "
                     "coverage measured on them is uncertain by +-18 points)")
    assert far == ("95 % intervals cover 31 % (center_amplitude_um) of 13 held-out rows: far "
                   "from 95 % (more than 18 points off)")
    assert card_warnings(card(training__held_out=13)) == [rough]


def test_errors_far_from_the_targets():
    median, p95 = ACCURACY_TARGETS["median_rel_err"], ACCURACY_TARGETS["p95_rel_err"]
    assert card_warnings(card(metrics__center_amplitude_um__median_rel_err=2 * median)) == []
    [w] = card_warnings(card(metrics__center_amplitude_um__median_rel_err=0.024,
                             metrics__center_amplitude_um__p95_rel_err=0.15))
    assert w == ("held-out centre amplitude error median 2.4 % (target 1 %), p95 15 % "
                 "(target 3 %): more than 2 times the accuracy targets")
    [w] = card_warnings(card(metrics__center_amplitude_um__p95_rel_err=2.01 * p95))
    assert "p95 6 % (target 3 %)" in w and "median" not in w


def test_the_card_and_models_list_carry_the_warnings(trained_models, tmp_path, capsys):
    path, returned = trained_models["gp"]
    sealed = json.loads((path / "card.json").read_text())
    assert sealed["warnings"] == card_warnings(returned) != []
    assert any("not calibrated: too few rows" in w for w in sealed["warnings"])
    root = tmp_path / "models"
    shutil.copytree(path, root / "lab")
    assert main(["models", "list", "--root", str(root)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("lab ")
    assert out[1:] == [f"  warning: {w}" for w in sealed["warnings"]]


def test_train_ends_with_the_warnings_and_no_library_notices(synthetic_dataset, tmp_path):
    """A lab's retraining as it sees it: torch's exporter notices (torchvision, ...) and
    deprecations stay off the terminal; the model's own warnings end the output."""
    out = tmp_path / "lab-nn"
    run = subprocess.run(
        [sys.executable, "-m", "hapticrom.cli", "train", "--data", str(synthetic_dataset),
         "--kind", "nn", "--out", str(out), "--modes", "3",
         "--options", '{"max_epochs": 30, "n_members": 1, "hidden": [8]}'],
        capture_output=True, text=True, cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO)},
        timeout=600)
    assert run.returncode == 0, run.stderr
    assert run.stderr == ""
    lines = run.stdout.splitlines()
    card = json.loads((out / "card.json").read_text())
    n = len(card["warnings"])
    assert n >= 1 and lines[-n - 1] == f"wrote {out}"
    assert lines[-n:] == [f"warning: {w}" for w in card["warnings"]]


def test_library_warnings_and_notices_only_with_verbose(caplog):
    log = logging.getLogger("some.library")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with quiet_libraries():
            warnings.warn("deprecated", FutureWarning, stacklevel=1)
            warnings.warn("stray files", HapticromWarning, stacklevel=1)
            log.warning("torchvision is not installed")
            log.error("an error is always shown")
        with quiet_libraries(False):
            warnings.warn("shown with --verbose", FutureWarning, stacklevel=1)
            log.warning("shown with --verbose")
    assert [str(w.message) for w in seen] == ["stray files", "shown with --verbose"]
    assert [r.getMessage() for r in caplog.records] == ["an error is always shown",
                                                        "shown with --verbose"]
    assert build_parser().parse_args(["train", "--verbose", "--data", "d", "--kind", "nn",
                                      "--out", "o"]).verbose
    assert build_parser().parse_args(["--verbose", "models", "list"]).verbose
    assert not build_parser().parse_args(["models", "list"]).verbose
