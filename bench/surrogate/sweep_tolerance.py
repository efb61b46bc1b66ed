"""Which sweep tolerance training data needs: the same network trained on the same designs
solved at two (or more) tolerances, scored on the same test designs, beside the run-to-run
spread of the training itself.

    python bench/surrogate/sweep_tolerance.py --data TIGHT_DIR LOOSE_DIR --test-data TEST_DIR \
        --n 256 --seeds 0 1 2

Each ``--data`` directory holds the same design sequence (the same space and seed, its
``[band] tolerance`` aside); the first ``--n`` designs solved in every one of them are used,
so the sets differ only by the solver's tolerance. For every set and seed the sweep NN of
``hapticrom train --kind nn`` is trained (its defaults, ``--options`` to change them) and
scored through the run-time predictor at every band frequency of every test design: median
and p95 relative error of the centre and edge amplitudes, median relative L2 error of the
profile. Also printed: the data's own difference between the sets (the looser solve against
the tighter, relative to each quantity's band maximum). The looser tolerance is good enough
when its errors differ from the tighter's by no more than the spread over seeds.
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from surrogate.data.store import Store
from surrogate.runtime.predictor import load_predictor
from surrogate.sweep.targets import load_sweep_datasets
from surrogate.sweep.train import sweep_metrics, train_sweep

METRICS = (("center_amplitude_um", "median_rel_err"), ("center_amplitude_um", "p95_rel_err"),
           ("edge_amplitude_um", "median_rel_err"), ("edge_amplitude_um", "p95_rel_err"),
           ("profile_um", "median_rel_l2"))


def _common_designs(dirs: list[Path], n: int) -> list[str]:
    """Sample ids of the first ``n`` sample indices solved (ok) in every directory."""
    solved = []
    for d in dirs:
        df = Store.open(d).read(columns=["sample_index", "status"])
        solved.append(set(df.loc[df["status"] == "ok", "sample_index"]))
    common = sorted(set.intersection(*solved))[:n]
    if len(common) < n:
        raise SystemExit(f"only {len(common)} designs are solved in every --data directory "
                         f"(asked for {n})")
    return common


def _subset(src: Path, indices: list[int], out: Path) -> Path:
    """The rows of ``indices`` of dataset ``src`` as a new dataset at ``out``."""
    store = Store.open(src)
    table = store.read_table()
    keep = np.isin(table.column("sample_index").to_numpy(), indices)
    copy = {k: v for k, v in store.manifest.items()
            if k in ("sampling", "solver", "solver_history", "mesh", "analysis_kind",
                     "profile_grid_mm", "band")}
    subset = Store.create(out, store.space, **copy)
    with subset.lock():
        subset.write_part(table.filter(keep))
    return out


def _data_difference(dirs: list[Path], indices: list[int]) -> dict[str, float]:
    """Largest and median difference of each looser set from the first, per design and
    quantity relative to the quantity's band maximum (centre, profile incl. the edge)."""
    def arrays(d: Path) -> dict[str, np.ndarray]:
        df = Store.open(d).read()
        df = df[df["sample_index"].isin(indices)].sort_values("sample_index")
        out = {}
        for where in ("center", "profile"):
            parts = [np.stack(df[f"sweep_{where}_u{c}_{p}_um"]).astype(float)
                     for c in "rzt" for p in ("re", "im")]
            out[where] = np.stack(parts, axis=-1)  # (designs, n_f or n_f n_p, 6)
        return out

    ref = arrays(dirs[0])
    report = {}
    for d in dirs[1:]:
        got = arrays(d)
        for where, a in ref.items():
            scale = np.sqrt((a ** 2).sum(-1)).max(axis=1, keepdims=True)  # band maximum
            diff = np.sqrt(((got[where] - a) ** 2).sum(-1)) / scale
            report[f"{d.name} {where}: max"] = float(diff.max())
            report[f"{d.name} {where}: median of design maxima"] = float(
                np.median(diff.max(axis=1)))
    return report


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, nargs="+", required=True,
                    help="the same designs at decreasing tolerance... first is the reference")
    ap.add_argument("--test-data", type=Path, required=True)
    ap.add_argument("--n", type=int, default=256)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--options", default=None, help="JSON options of the NN")
    args = ap.parse_args()
    options = json.loads(args.options) if args.options else None
    indices = _common_designs(args.data, args.n)
    test = load_sweep_datasets([args.test_data])
    print(f"{len(indices)} designs in every set; test: {len(test.codes)} designs of "
          f"{args.test_data}")
    for name, value in _data_difference(args.data, indices).items():
        print(f"  data difference {name}: {value:.2e}")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for d in args.data:
            tol = json.loads((d / "_manifest.json").read_text())["band"].get("tolerance",
                                                                            1e-3)
            subset = _subset(d, indices, Path(tmp) / f"{d.name}-data")
            for seed in args.seeds:
                out = Path(tmp) / f"{d.name}-{seed}"
                train_sweep([subset], "nn", out, seed=seed, options=options)
                m = sweep_metrics(load_predictor(out), test, np.arange(len(test.codes)), ())
                rows.append({"tolerance": tol, "seed": seed,
                             **{f"{q} {k}": m[q][k] for q, k in METRICS}})
                print(rows[-1], flush=True)
    df = pd.DataFrame(rows)
    cols = [c for c in df.columns if c not in ("tolerance", "seed")]
    print("\n| tolerance | " + " | ".join(cols) + " |")
    print("|---" * (len(cols) + 1) + "|")
    for tol, g in df.groupby("tolerance", sort=False):
        cells = [f"{g[c].mean() * 100:.2f} ± {statistics.pstdev(g[c]) * 100:.2f} %"
                 for c in cols]
        print(f"| {tol:g} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
