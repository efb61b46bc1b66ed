"""Active learning against Sobol order on a sweep dataset, retrospectively (no new FE solve).

Both arms draw from the already solved designs of one sweep dataset, in its design-sequence
(Sobol) order:

* start set: the first ``start`` designs; pool: every design after them;
* Sobol arm: the first ``start + add`` designs (what ``hapticrom generate --n`` would have run);
* active arm: the start set plus the ``add`` pool designs where the model trained on the start
  set disagrees most with itself (:func:`surrogate.refine.band_disagreement`: its raw log std
  of the centre and the edge, averaged over the band), spread out by a minimum distance in the
  encoded features (:func:`surrogate.refine.select_batch`, what ``hapticrom refine`` runs).

Every model is the sweep pipeline of ``hapticrom train`` (:func:`surrogate.sweep.train.
train_sweep` on the arm's designs, the same kind, options, split fraction and seed in every
arm) and is scored by the card's ``test_set`` on every design of the test datasets. The Sobol
arm (and, when asked, the active arm) is trained again with other seeds (the split and the
estimator's random state) to show the run-to-run spread. Each model is written under
``out_dir`` and reused when it is there, so an interrupted run resumes.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from surrogate.refine import band_disagreement, select_batch
from surrogate.runtime.encoding import encode
from surrogate.runtime.predictor import load_predictor
from surrogate.sweep.targets import SweepData, load_sweep_datasets, pair_rows
from surrogate.sweep.train import train_sweep

__all__ = ["METRICS", "attachment_table", "by_attachment", "pick_active", "row", "run", "table"]

#: (label, card output, metric) of a table row, in order
METRICS = (("centre median", "center_amplitude_um", "median_rel_err"),
           ("centre p95", "center_amplitude_um", "p95_rel_err"),
           ("centre p99", "center_amplitude_um", "p99_rel_err"),
           ("centre max", "center_amplitude_um", "max_rel_err"),
           ("edge median", "edge_amplitude_um", "median_rel_err"),
           ("edge p95", "edge_amplitude_um", "p95_rel_err"),
           ("edge p99", "edge_amplitude_um", "p99_rel_err"),
           ("edge max", "edge_amplitude_um", "max_rel_err"),
           ("max / field", None, "max_abs_err_over_field"),
           ("profile L2 median", "profile_um", "median_rel_l2"),
           ("profile L2 p95", "profile_um", "p95_rel_l2"))


def row(metrics: dict[str, Any]) -> dict[str, float]:
    """A card's ``test_set.metrics`` (or ``metrics``) as the table's numbers (fractions);
    max / field: the larger of the centre's and the edge's."""
    out = {}
    for label, name, key in METRICS:
        if name is None:
            out[label] = max(metrics["center_amplitude_um"][key],
                             metrics["edge_amplitude_um"][key])
        else:
            out[label] = float(metrics[name][key])
    return out


def pick_active(model: str | Path, codes: np.ndarray, specs: Sequence[Any],
                band_hz: np.ndarray, pool: np.ndarray, k: int,
                min_distance: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(``k`` designs of ``pool`` (row positions of ``codes``), every pool design's score):
    the pool designs where the model directory ``model`` disagrees most with itself, spread
    out by ``min_distance`` in the encoded design features (default: select_batch's)."""
    predictor = load_predictor(model, calibrated=False)
    score = band_disagreement(predictor, codes[pool], band_hz)
    X = encode(codes[pool], list(specs))
    chosen = select_batch(score, X, k, min_distance)
    return pool[chosen], score


def _train(name: str, out_dir: Path, data: str | Path, test: Sequence[str | Path],
           designs: np.ndarray, seed: int, kind: str, options: dict[str, Any],
           test_fraction: float, log: Callable[[str], None]) -> dict[str, Any]:
    out = out_dir / name
    if (out / "card.json").exists():
        log(f"{name}: reusing {out}")
        return json.loads((out / "card.json").read_text())
    log(f"{name}: training {kind} on {designs.size} designs (seed {seed})")
    return train_sweep([data], kind, out, test_fraction=test_fraction, seed=seed,
                       options=dict(options), calibration_fraction=0, test_data=list(test),
                       designs=designs)


def run(data: str | Path, test_data: Sequence[str | Path], out_dir: str | Path, *,
        start: int = 1024, add: int = 512, kind: str = "nn", seeds: Sequence[int] = (0, 1),
        active_seeds: Sequence[int] = (0,), options: dict[str, Any] | None = None,
        test_fraction: float = 0.1, min_distance: float | None = None,
        log: Callable[[str], None] = print) -> dict[str, Any]:
    """The study on sweep dataset ``data`` scored on ``test_data``; returns its record (also
    written to ``out_dir/record.json``): per model its designs, seed and test-set numbers,
    and what the active arm picked."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    options = dict(options or {})
    sweep = load_sweep_datasets([data])
    n = len(sweep.codes)
    if not 0 < start < start + add <= n:
        raise ValueError(f"start = {start}, add = {add}: need 0 < start and start + add <= "
                         f"{n} (the dataset's ok designs)")
    first = np.arange(start)
    pool = np.arange(start, n)
    record: dict[str, Any] = {"data": str(data), "test_data": [str(t) for t in test_data],
                              "designs": n, "start": start, "add": add, "kind": kind,
                              "options": options, "test_fraction": test_fraction,
                              "models": {}}
    card = _train("start", out_dir, data, test_data, first, seeds[0], kind, options,
                  test_fraction, log)
    record["models"]["start"] = {"designs": start, "seed": seeds[0],
                                 "test": row(card["test_set"]["metrics"])}
    tests = load_sweep_datasets(list(test_data))
    grouped = "attachment" in [s.name for s in tests.specs]
    if grouped:
        record["models"]["start"]["by_attachment"] = by_attachment(out_dir / "start", tests)
    picks_file = out_dir / "active_picks.json"
    if picks_file.exists():
        saved = json.loads(picks_file.read_text())
        chosen, score = np.asarray(saved["picked"]), np.asarray(saved["pool_score"])
    else:
        log(f"scoring {pool.size} pool designs by the start model's disagreement")
        chosen, score = pick_active(out_dir / "start", sweep.codes, sweep.specs,
                                    sweep.band_hz, pool, add, min_distance)
        picks_file.write_text(json.dumps({"picked": chosen.tolist(),
                                          "pool_score": score.tolist()}))
    picked_score = score[np.searchsorted(pool, chosen)]
    next_sobol = np.arange(start, start + add)
    record["selection"] = {
        "pool": int(pool.size),
        "score_mean": {"pool": float(score.mean()), "picked": float(picked_score.mean()),
                       "next_sobol": float(score[next_sobol - start].mean())},
        "picked_positions": {"min": int(chosen.min()), "median": float(np.median(chosen)),
                             "max": int(chosen.max())},
        "composition": {arm: _composition(sweep, idx) for arm, idx in
                        (("picked", chosen), ("next_sobol", next_sobol), ("pool", pool))}}
    arms = {"sobol": np.arange(start + add), "active": np.sort(np.concatenate([first, chosen]))}
    # interleaved (sobol, active) per seed, so that a cut-short run has both arms' first seed
    jobs = []
    for i in range(max(len(seeds), len(active_seeds))):
        jobs += [("sobol", seeds[i])] if i < len(seeds) else []
        jobs += [("active", active_seeds[i])] if i < len(active_seeds) else []
    for arm, seed in jobs:
        name = f"{arm}-seed{seed}"
        card = _train(name, out_dir, data, test_data, arms[arm], seed, kind, options,
                      test_fraction, log)
        record["models"][name] = {"designs": int(arms[arm].size), "seed": seed,
                                  "fitted": card["training"]["rows"],
                                  "test": row(card["test_set"]["metrics"]),
                                  "held_out": row(card["metrics"])}
        if grouped:
            record["models"][name]["by_attachment"] = by_attachment(out_dir / name, tests)
        (out_dir / "record.json").write_text(json.dumps(record, indent=1))
    return record


def by_attachment(model: str | Path, test: SweepData) -> dict[str, dict[str, float]]:
    """The model's centre and edge median and p95 relative errors on the test designs of
    each attachment (glued, pogo), every band frequency (fractions)."""
    predictor = load_predictor(model)
    names = [s.name for s in test.specs]
    spec = test.specs[names.index("attachment")]
    att = np.asarray(spec.choices)[test.codes[:, names.index("attachment")].astype(int)]
    out = {}
    for choice in spec.choices:
        designs = np.flatnonzero(att == choice)
        codes, centre, profile, _ = pair_rows(test, designs)
        pred = predictor.predict(codes)
        entry = {"designs": int(designs.size)}
        for label, got, y in (("centre", pred["center_amplitude_um"], centre),
                              ("edge", pred["edge_amplitude_um"], profile[:, 0])):
            rel = np.abs(got / y - 1.0)
            entry[f"{label} median"] = float(np.median(rel))
            entry[f"{label} p95"] = float(np.percentile(rel, 95))
        out[str(choice)] = entry
    return out


def _composition(sweep: Any, idx: np.ndarray) -> dict[str, float]:
    """Shares of the designs ``idx`` by attachment and ring count (the hard region: pogo units
    with several rings)."""
    names = [s.name for s in sweep.specs]
    out: dict[str, float] = {}
    if "attachment" in names:
        spec = sweep.specs[names.index("attachment")]
        att = np.asarray(spec.choices)[sweep.codes[idx, names.index("attachment")].astype(int)]
        out["pogo"] = float(np.mean(att == "pogo"))
    if "n_rings" in names:
        rings = sweep.codes[idx, names.index("n_rings")]
        for r in np.unique(sweep.codes[:, names.index("n_rings")]):
            out[f"rings_{int(r)}"] = float(np.mean(rings == r))
    return out


def table(record: dict[str, Any]) -> str:
    """The record's test-set numbers as a markdown table (errors in %), with the spread of the
    repeated arms (largest minus smallest) under them."""
    labels = [m[0] for m in METRICS]
    lines = ["| model | designs | " + " | ".join(labels) + " |",
             "|---|---|" + "---|" * len(labels)]
    models = record["models"]
    for name, m in models.items():
        lines.append(f"| {name} | {m['designs']} | "
                     + " | ".join(_pct(m["test"][k]) for k in labels) + " |")
    for arm in ("sobol", "active"):
        runs = [m["test"] for name, m in models.items() if name.startswith(arm + "-")]
        if len(runs) > 1:
            lines.append(f"| {arm}: spread over {len(runs)} seeds | | " + " | ".join(
                _pct(max(r[k] for r in runs) - min(r[k] for r in runs)) for k in labels) + " |")
    return "\n".join(lines)


def attachment_table(record: dict[str, Any]) -> str:
    """Centre and edge median / p95 [%] of each model on the test designs of each attachment
    (empty when the record has none)."""
    models = {n: m["by_attachment"] for n, m in record["models"].items() if "by_attachment" in m}
    if not models:
        return ""
    groups = list(next(iter(models.values())))
    lines = ["| model | " + " | ".join(f"{g} ({models[next(iter(models))][g]['designs']} "
                                       "designs): centre / edge median / p95 %" for g in groups)
             + " |", "|---|" + "---|" * len(groups)]
    for name, by in models.items():
        lines.append(f"| {name} | " + " | ".join(
            f"{_pct(by[g]['centre median'])} / {_pct(by[g]['centre p95'])}, "
            f"{_pct(by[g]['edge median'])} / {_pct(by[g]['edge p95'])}" for g in groups) + " |")
    return "\n".join(lines)


def _pct(v: float) -> str:
    p = 100.0 * v
    return f"{p:,.0f}" if p >= 100 else f"{p:.1f}" if p >= 10 else f"{p:.2f}"
