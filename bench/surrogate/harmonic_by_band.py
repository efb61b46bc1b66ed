"""Held-out errors of harmonic models across the motor's speed range, band by band.

    python bench/surrogate/harmonic_by_band.py --models models/nn-wide models/nn-default MLP_DIR

The rows are the held-out split that ``hapticrom train --data datasets/default
datasets/low-band`` makes (``surrogate.train.split``, seed 0, 20 %: the rows ``models/nn-wide``
never saw), scored by every model given on the same rows: centre and edge amplitude, median /
p95 / p99 / max relative error, per frequency band (20-50, 50-100, 100-250 Hz) and attachment.
The envelope model's steady part is such a model at the motor's instantaneous speed
(docs/transient-model.md). A model trained on other rows is scored on the same ones: for
``models/nn-default`` (trained on 80 % of ``datasets/default``, another split) the rows below
100 Hz are all new and outside its range (extrapolated), and about 80 % of those at
100-250 Hz are its own training rows, so its in-band figures here flatter it (its card's
held-out figures are the fair ones).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

BANDS_HZ = ((20.0, 50.0), (50.0, 100.0), (100.0, 250.0), (20.0, 250.0))
DATA = ("datasets/default", "datasets/low-band")


def held_out_rows(data: tuple[str, ...] = DATA, test_fraction: float = 0.2, seed: int = 0
                  ) -> tuple[Any, np.ndarray]:
    """(the training data, the held-out row indices of ``hapticrom train``)."""
    from surrogate.train import load_datasets, split

    d = load_datasets([str(ROOT / p) for p in data])
    return d, split(len(d.codes), test_fraction, seed)[1]


def scores(model: str, d: Any, test: np.ndarray) -> list[str]:
    """One line per band and attachment: median / p95 / p99 / max relative error, %."""
    from surrogate.runtime.predictor import load_predictor

    codes = d.codes[test]  # the predictor reads the datasets' input codes as they are
    pred = load_predictor(model).predict(codes, extrapolate=True)
    rel = {"centre": np.abs(pred["center_amplitude_um"] / d.center_um[test] - 1.0),
           "edge": np.abs(pred["profile_um"][:, 0] / d.profile_um[test, 0] - 1.0)}
    column = {s.name: j for j, s in enumerate(d.specs)}
    f = codes[:, column["frequency_hz"]]
    att = np.asarray(d.specs[column["attachment"]].choices)[
        codes[:, column["attachment"]].astype(int)]
    lines = []
    for lo, hi in BANDS_HZ:
        for group in ("glued", "pogo", "all"):
            rows = (f >= lo) & (f <= hi) & ((att == group) | (group == "all"))
            cells = [f"{p} " + " / ".join(f"{100 * q:.1f}" for q in
                                          np.percentile(e[rows], [50, 95, 99, 100]))
                     for p, e in rel.items()]
            lines.append(f"  {lo:3.0f}-{hi:3.0f} Hz {group:5s} ({rows.sum():4d} rows): "
                         + " | ".join(cells) + " %")
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", nargs="+", default=["models/nn-wide", "models/nn-default"],
                    help="harmonic model directories with a frequency_hz input")
    args = ap.parse_args(argv)
    data, test = held_out_rows()
    print("median / p95 / p99 / max relative error, centre | edge")
    for model in args.models:
        print(model)
        for line in scores(model, data, test):
            print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
