"""Calibrated 95 % intervals: split-conformal scaling of a model's predictive log-std.

A surrogate's ``log_std`` (the spread of a deep ensemble, a GP's posterior std) is a shape,
not a calibrated width: the shipped NN's exp(mu +- 1.96 sigma) covered 82-86 % of its held-out
rows. On calibration rows the model never fitted, the normalised residual

    r = |ln y - mu| / sigma

is computed for every output column of a group -- ``center`` (column 0), ``edge`` (the edge
amplitude and the normalized edge, columns 1-2) and ``profile`` (columns 3+, pooled over
rows and radii) -- and the group's factor is f = r_(k) / 1.959964 with r_(k) the
k = ceil((n + 1) 0.95)-th smallest of its n residuals (split conformal: exp(mu +- 1.96 f sigma)
then covers at least 95 % of exchangeable new rows, marginally). The card stores it as

    "interval_calibration": {"method": "split-conformal", "level": 0.95,
                             "log_std_scale": [f for each log output column],
                             "groups": {name: {"columns": [...], "factor": f, "rows": n}}, ...}

and the run-time predictor multiplies its ``log_std`` column k by ``log_std_scale[k]`` (a card
without the key: 1). :func:`calibrate` computes it from a model's raw predictions;
:func:`calibrate_model_dir` (``hapticrom models calibrate-intervals``) does it for a trained
model on held-out rows of its own data that it never saw, and re-seals the card.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from surrogate.registry import manifest_sha256
from surrogate.runtime.card import CARD_NAME, seal_card, verify_model_dir
from surrogate.runtime.predictor import CALIBRATION_KEY, load_predictor

__all__ = ["GROUPS", "LEVEL", "Z95", "calibrate", "calibrate_model_dir", "coverage",
           "residuals"]

LEVEL = 0.95
Z95 = 1.959964
#: Output groups sharing one factor: name -> (first column, stop column or None = to the end)
GROUPS: dict[str, tuple[int, int | None]] = {"center": (0, 1), "edge": (1, 3),
                                             "profile": (3, None)}


def residuals(pred: dict[str, np.ndarray], center_um: np.ndarray,
              profile_um: np.ndarray) -> np.ndarray:
    """(n, K) normalised residuals |ln y - mu| / sigma of every log output column, from a
    predictor's outputs (``pred``, raw log-std) and the true center and profile [um]."""
    truth = np.column_stack([np.log(center_um), np.log(profile_um[:, 0]),
                             np.log(profile_um[:, 0] / center_um), np.log(profile_um)])
    mu = np.column_stack([np.log(pred["center_amplitude_um"]),
                          np.log(pred["edge_amplitude_um"]), np.log(pred["normalized_edge"]),
                          np.log(pred["profile_um"])])
    sigma = np.column_stack([pred["center_amplitude_um_log_std"],
                             pred["edge_amplitude_um_log_std"],
                             pred["normalized_edge_log_std"], pred["profile_um_log_std"]])
    return np.abs(truth - mu) / np.maximum(sigma, 1e-300)


def _columns(group: str, k: int) -> list[int]:
    a, b = GROUPS[group]
    return list(range(a, k if b is None else b))


def calibrate(r: np.ndarray, level: float = LEVEL) -> dict[str, Any]:
    """The ``interval_calibration`` entry for residuals ``r`` (n, K) of calibration rows."""
    n, k = r.shape
    if n < 20:
        raise ValueError(f"{n} calibration rows: at least 20 are needed for a 95 % factor")
    scale = np.ones(k)
    groups = {}
    for name in GROUPS:
        cols = _columns(name, k)
        pooled = np.sort(r[:, cols].ravel())
        rank = min(math.ceil((pooled.size + 1) * level), pooled.size)
        factor = float(pooled[rank - 1] / Z95)
        scale[cols] = factor
        groups[name] = {"columns": cols, "factor": factor, "rows": int(n)}
    return {"method": "split-conformal", "level": level, "z": Z95,
            "log_std_scale": scale.tolist(), "groups": groups}


def coverage(r: np.ndarray, scale: Sequence[float] | np.ndarray | None = None
             ) -> dict[str, float]:
    """Share of residuals inside the 95 % interval (with the per-column ``scale``, or raw),
    per output: center, edge, normalized_edge and the profile pooled."""
    s = np.ones(r.shape[1]) if scale is None else np.asarray(scale, dtype=float)
    inside = r <= Z95 * s[None, :]
    return {"center_amplitude_um": float(inside[:, 0].mean()),
            "edge_amplitude_um": float(inside[:, 1].mean()),
            "normalized_edge": float(inside[:, 2].mean()),
            "profile_um": float(inside[:, 3:].mean())}


def calibrate_model_dir(path: str | Path, data: Sequence[str | Path] | None = None, *,
                        check_fraction: float = 0.5, seed: int = 0, write: bool = True
                        ) -> dict[str, Any]:
    """Calibrate a trained model's intervals on the rows its training held out (re-derived
    from the card's ``training`` seed and test fraction on its own datasets, whose manifests
    must match the card's, or at least its space and row count -- a manifest re-sealed since
    holds the same rows): a seeded ``1 - check_fraction`` of them compute the factors, the
    rest measure the coverage before and after. Writes the sealed card (unless ``write`` is
    False); returns the ``interval_calibration`` entry."""
    from surrogate.train import load_datasets, split  # the dataset layer: not for run time

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
    rows = load_datasets(paths)
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
    raw = load_predictor(root, calibrated=False)
    r_cal = residuals(raw.predict(rows.codes[cal]), rows.center_um[cal], rows.profile_um[cal])
    r_check = residuals(raw.predict(rows.codes[check]), rows.center_um[check],
                        rows.profile_um[check])
    entry = calibrate(r_cal)
    entry["rows"] = {"from": "the rows training held out (training.seed, "
                     "training.test_fraction)", "seed": seed, "calibration": int(cal.size),
                     "check": int(check.size), "data": rows.sources}
    entry["coverage95_check"] = {"before": coverage(r_check),
                                 "after": coverage(r_check, entry["log_std_scale"])}
    entry["command"] = "hapticrom models calibrate-intervals"
    if write:
        _write_card(root, {**card, CALIBRATION_KEY: entry})
    return entry


def _write_card(root: Path, card: dict[str, Any]) -> None:
    """Replace ``card.json`` atomically with the sealed ``card`` (the files are unchanged)."""
    tmp = root.parent / f".{root.name}.{CARD_NAME}.tmp"
    tmp.write_text(json.dumps(seal_card(card), indent=1) + "\n")
    os.replace(tmp, root / CARD_NAME)
    verify_model_dir(root)
