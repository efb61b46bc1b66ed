"""Plain warnings about a trained model, read from its card: intervals left uncalibrated
because the rows were too few, held-out coverage of the 95 % interval far from 95 %, held-out
errors far from the project's accuracy targets.

One definition, shown in three places: at the end of ``hapticrom train``, in the card
(``warnings``, written when the card is sealed) and under the model's line in ``hapticrom
models list`` (recomputed from the card, so models written before the key existed are warned
about too). A card without steady-state metrics (the envelope model, ``rom``) gets none: its
metrics have targets of their own (docs/transient-model.md).

What "far" means:

* coverage: further from 95 % than three binomial standard deviations of the rows it was
  measured on, sqrt(0.95 * 0.05 / n), and than :data:`COVERAGE_SLACK` (3 points). On a
  calibrated model it is measured on the rows ``models calibrate-intervals`` kept apart (the
  card's ``coverage95_check.after``), else on the held-out rows of the card's metrics.
* errors: the centre amplitude's held-out median or p95 relative error above
  :data:`FAR_FACTOR` times its target (:data:`ACCURACY_TARGETS`, docs/accuracy.md).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from surrogate.intervals import AUTO_CALIBRATION_FRACTION, AUTO_CALIBRATION_ROWS, LEVEL

__all__ = ["ACCURACY_TARGETS", "COVERAGE_SLACK", "FAR_FACTOR", "MIN_HELD_OUT", "card_warnings"]

#: The project's accuracy targets of the centre amplitude, held-out relative error (the
#: surrogate's requirement, docs/accuracy.md: median below 1 %, p95 below 3 %)
ACCURACY_TARGETS = {"median_rel_err": 0.01, "p95_rel_err": 0.03}
#: An error is far from its target above this many times the target
FAR_FACTOR = 2.0
#: Coverage within this of 95 % is never called far, however many rows measured it
COVERAGE_SLACK = 0.03
#: Fewer held-out rows measure a 95 % coverage to no better than +-15 points (3 sigma)
MIN_HELD_OUT = 20


def card_warnings(card: Mapping[str, Any]) -> list[str]:
    """The warnings of a model's card, one sentence each (empty: nothing to say)."""
    metrics = card.get("metrics") or {}
    if "coverage95" not in metrics.get("center_amplitude_um", {}):
        return []  # not a steady-state card
    return [*_calibration(card), *_coverage(card), *_errors(metrics)]


def _calibration(card: Mapping[str, Any]) -> list[str]:
    if card.get("interval_calibration"):
        return []
    rows = int(card.get("training", {}).get("rows", 0))
    spare = round(AUTO_CALIBRATION_FRACTION * rows)
    if spare < AUTO_CALIBRATION_ROWS:
        return [f"95 % intervals not calibrated: too few rows ({rows} training rows, "
                f"{100 * AUTO_CALIBRATION_FRACTION:g} % of them is {spare}, fewer than the "
                f"{AUTO_CALIBRATION_ROWS} a 95 % quantile needs); the intervals are the raw "
                "model's, usually too narrow. Train on more rows, or give "
                "--calibration-fraction (at least 20 rows)"]
    return ["95 % intervals not calibrated (--calibration-fraction 0): `hapticrom models "
            "calibrate-intervals` calibrates them on the rows training held out"]


def _coverage(card: Mapping[str, Any]) -> list[str]:
    check = (card.get("interval_calibration") or {}).get("coverage95_check")
    if check:
        cover, n = check["after"], int(card["interval_calibration"]["rows"]["check"])
        where = "rows kept apart by calibrate-intervals"
    else:
        cover = {k: m["coverage95"] for k, m in card["metrics"].items() if "coverage95" in m}
        n, where = int(card.get("training", {}).get("held_out", 0)), "held-out rows"
    spread = 3 * math.sqrt(LEVEL * (1 - LEVEL) / max(n, 1))
    said = []
    if n < MIN_HELD_OUT:
        said.append(f"only {n} {where}: its held-out errors and coverage are rough (a 95 % "
                    f"coverage measured on them is uncertain by +-{100 * spread:.0f} points)")
    far = max(COVERAGE_SLACK, spread)
    off = {k: v for k, v in cover.items() if abs(v - LEVEL) > far}
    if off:
        said.append(f"95 % intervals cover {_list(off)} of {n} {where}: far from 95 % (more "
                    f"than {100 * far:.0f} points off)")
    return said


def _errors(metrics: Mapping[str, Any]) -> list[str]:
    centre = metrics["center_amplitude_um"]
    off = {k: centre[k] for k, target in ACCURACY_TARGETS.items()
           if k in centre and centre[k] > FAR_FACTOR * target}
    if not off:
        return []
    said = ", ".join(f"{k.split('_')[0]} {100 * v:.2g} % (target {100 * ACCURACY_TARGETS[k]:g} %)"
                     for k, v in off.items())
    return [f"held-out centre amplitude error {said}: more than {FAR_FACTOR:g} times the "
            "accuracy targets"]


def _list(cover: Mapping[str, float]) -> str:
    return ", ".join(f"{100 * v:.0f} % ({k})" for k, v in cover.items())
