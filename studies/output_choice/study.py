"""Train every (learner, output choice) on the same training designs, score on the same test
designs, and render the table.

Errors, over every test design x band frequency: relative magnitude errors of the centre and
the edge, |predicted / FE - 1| (median, p95, p99, max); the largest error on the field's
scale, |predicted - FE| / max(FE centre, FE edge); and, when the choice predicts the profile,
the profile's relative L2 error over radius, ||predicted - FE|| / ||FE|| (median, p95).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .data import Sweeps
from .learners import Learner
from .representations import Answers, Choice

__all__ = ["run", "score", "table"]


def _stats(prefix: str, rel: np.ndarray) -> dict[str, float]:
    rel = rel.ravel()
    return {f"{prefix}_median": float(np.median(rel)),
            f"{prefix}_p95": float(np.percentile(rel, 95)),
            f"{prefix}_p99": float(np.percentile(rel, 99)),
            f"{prefix}_max": float(rel.max())}


def score(pred: Answers, true: Answers) -> dict[str, float | None]:
    """The error summary of ``pred`` against ``true`` (fractions, not %)."""
    field = np.maximum(true.center, true.edge)
    out: dict[str, float | None] = {}
    for name, p, t in (("centre", pred.center, true.center), ("edge", pred.edge, true.edge)):
        out.update(_stats(name, np.abs(p / t - 1.0)))
    out["max_field"] = float(max(np.max(np.abs(pred.center - true.center) / field),
                                 np.max(np.abs(pred.edge - true.edge) / field)))
    out["profile_l2_median"] = out["profile_l2_p95"] = None
    if pred.profile is not None and true.profile is not None:
        l2 = (np.linalg.norm(pred.profile - true.profile, axis=-1)
              / np.linalg.norm(true.profile, axis=-1))
        out["profile_l2_median"] = float(np.median(l2))
        out["profile_l2_p95"] = float(np.percentile(l2, 95))
    return out


#: The learner name of a choice's floor: its exact test targets decoded (POD truncation only).
FLOOR = "(projection)"


def floors(train: Sweeps, test: Sweeps, choices: Sequence[Choice], seed: int = 0
           ) -> list[dict[str, Any]]:
    """One record per choice: the error of decoding the test designs' exact targets in the
    bases fitted on ``train`` (what a perfect learner of that choice would reach)."""
    truth = Answers.of(test)
    out = []
    for choice in choices:
        x, y = choice.training(train, np.random.default_rng(seed))
        pred = choice.decode(choice.targets(test), test)
        out.append({"learner": FLOOR, "choice": choice.name, "train_rows": len(x),
                    "rows_available": len(x), "targets": int(y.shape[1]), "fit_s": 0.0,
                    "predict_s": 0.0, **score(pred, truth)})
    return out


def run(train: Sweeps, test: Sweeps, learners: Sequence[Learner], choices: Sequence[Choice],
        seed: int = 0, log: Callable[[str], None] = print) -> list[dict[str, Any]]:
    """One record per choice's floor (:func:`floors`) and per (learner, choice): names,
    training rows used, fit and predict time [s], and :func:`score` on ``test``."""
    truth = Answers.of(test)
    records = floors(train, test, choices, seed)
    for rec in records:
        log(row(rec))
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", module="sklearn")
        for learner in learners:
            for choice in choices:
                t0 = time.perf_counter()
                x, y = choice.training(train, np.random.default_rng(seed))
                model = learner.fit(x, y)
                fit_s = time.perf_counter() - t0
                t1 = time.perf_counter()
                pred = choice.decode(model(choice.query(test)), test)
                rec = {"learner": learner.name, "choice": choice.name,
                       "train_rows": learner.rows(len(x)), "rows_available": len(x),
                       "targets": int(y.shape[1]), "fit_s": fit_s,
                       "predict_s": time.perf_counter() - t1, **learner.notes,
                       **score(pred, truth)}
                records.append(rec)
                log(row(rec))
    return records


def _pct(v: float | None, digits: int) -> str:
    return "-" if v is None else f"{100 * v:.{digits}f}"


def _quad(r: dict[str, Any], name: str) -> str:
    return " / ".join(_pct(r[f"{name}_{k}"], d) for k, d in
                      (("median", 2), ("p95", 1), ("p99", 1), ("max", 0)))


HEADER = ("| learner | outputs | train rows | centre med / p95 / p99 / max % "
          "| edge med / p95 / p99 / max % | max err / field % | profile L2 median % | fit s |")


def row(r: dict[str, Any]) -> str:
    """One markdown table row of a record."""
    rows = f"{r['train_rows']}"
    if r["train_rows"] < r["rows_available"]:
        rows += f" of {r['rows_available']} (capped)"
    return (f"| {r['learner']} | {r['choice']} | {rows} | {_quad(r, 'centre')} "
            f"| {_quad(r, 'edge')} | {_pct(r['max_field'], 1)} "
            f"| {_pct(r['profile_l2_median'], 2)} | {r['fit_s']:.0f} |")


def table(records: Sequence[dict[str, Any]]) -> str:
    """The markdown table of ``records``."""
    sep = "|" + "---|" * (HEADER.count("|") - 1)
    return "\n".join([HEADER, sep, *(row(r) for r in records)])
