"""Calibrate the intervals of a trained model on the rows its training held out
(``hapticrom models calibrate-intervals``; the method: :mod:`surrogate.intervals`)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from surrogate.card_warnings import card_warnings
from surrogate.intervals import calibrate, coverage, residuals
from surrogate.registry import manifest_sha256
from surrogate.runtime.card import replace_card, verify_model_dir
from surrogate.runtime.predictor import CALIBRATION_KEY, load_predictor
from surrogate.sweep.targets import load_sweep_datasets, pair_rows
from surrogate.train import load_datasets, split

__all__ = ["calibrate_model_dir"]


def calibrate_model_dir(path: str | Path, data: Sequence[str | Path] | None = None, *,
                        check_fraction: float = 0.5, seed: int = 0, write: bool = True
                        ) -> dict[str, Any]:
    """Calibrate a trained model's intervals on the rows its training held out (re-derived
    from the card's ``training`` seed and test fraction on its own datasets, whose manifests
    must match the card's, or at least its space and row count -- a manifest re-sealed since
    holds the same rows): a seeded ``1 - check_fraction`` of them compute the factors, the
    rest measure the coverage before and after. Writes the sealed card (unless ``write`` is
    False); returns the ``interval_calibration`` entry."""
    root = Path(path)
    card = verify_model_dir(root)
    training, sources = card.get("training", {}), card.get("training_data", [])
    if "seed" not in training or "test_fraction" not in training or not sources:
        raise ValueError(f"{root}: the card does not record its held-out rows (training.seed, "
                         "training.test_fraction, training_data)")
    if not 0 < check_fraction < 1:
        raise ValueError(f"--check-fraction {check_fraction}: must be in (0, 1)")
    paths = [Path(p) for p in (data or [s["path"] for s in sources])]
    if len(paths) != len(sources):
        raise ValueError(f"--data: {len(paths)} datasets, the card names {len(sources)}")
    raw = load_predictor(root, calibrated=False)
    extra = list(raw.extra_outputs)
    sweep = "representation" in card  # a sweep model: rows are designs, scored at every
    rows = (load_sweep_datasets(paths) if sweep  # band frequency (surrogate.sweep.train)
            else load_datasets(paths, outputs=extra))
    for p, s, now in zip(paths, sources, rows.sources, strict=True):
        if manifest_sha256(p) != s["manifest_sha256"] and (
                now["space_hash"] != s.get("space_hash") or now["rows"] != s.get("rows")):
            raise ValueError(f"--data {p}: not the data the model was trained on ({s['path']}: "
                             "its manifest, space and row count differ); the held-out rows "
                             "would not be those")
    tr, te = split(len(rows.codes), float(training["test_fraction"]), int(training["seed"]))
    if "rows" in training and tr.size != int(training["rows"]) + int(
            training.get("calibration_rows", 0)):
        raise ValueError(f"{root}: the split gives {tr.size} training rows, the card "
                         f"{training['rows']}; not the data the model was trained on")
    perm = np.random.default_rng(seed).permutation(te)
    n_check = round(check_fraction * perm.size)
    cal, check = np.sort(perm[n_check:]), np.sort(perm[:n_check])
    r_cal, r_check = (_residuals(raw, rows, which, extra, sweep) for which in (cal, check))
    # a sweep model's pairs are exchangeable only design by design (surrogate.intervals)
    entry = calibrate(r_cal, extra=extra,
                      group=np.repeat(cal, rows.band_hz.size) if sweep else None)
    entry["rows"] = {"from": "the rows training held out (training.seed, "
                     "training.test_fraction)", "seed": seed, "calibration": int(cal.size),
                     "check": int(check.size), "data": rows.sources}
    if sweep:
        entry["rows"]["pairs_per_design"] = int(rows.band_hz.size)  # every band frequency
    entry["coverage95_check"] = {"before": coverage(r_check, extra=extra),
                                 "after": coverage(r_check, entry["log_std_scale"], extra)}
    entry["command"] = "hapticrom models calibrate-intervals"
    if write:
        new = {**card, CALIBRATION_KEY: entry}
        replace_card(root, {**new, "warnings": card_warnings(new)})
    return entry


def _residuals(raw: Any, rows: Any, which: np.ndarray, extra: list[str], sweep: bool
               ) -> np.ndarray:
    """Normalised residuals of the rows ``which`` (of a sweep model: every band frequency of
    the designs ``which``)."""
    if sweep:
        codes, centre, profile, ext = pair_rows(rows, which, "profile_normal_um" in extra)
        return residuals(raw.predict(codes), centre, profile, ext)
    return residuals(raw.predict(rows.codes[which]), rows.center_um[which],
                     rows.profile_um[which], {name: rows.extra_um[name][which] for name in extra})
