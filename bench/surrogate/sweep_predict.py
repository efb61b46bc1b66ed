"""Embedding cost of a sweep model (issue 20, item 6): ``Predictor.predict`` at batch 1 against
the raw onnxruntime call, and batch 10,000 against the FLOP-bound time, for the graph before
and after the factored decode, on the SAME members; and the factored basis's floor.

    .venv/bin/python bench/surrogate/sweep_predict.py --data SWEEP_DIR [--test-data TEST_DIR] \\
        [--options '{"max_epochs": 20, "loss": "coefficients"}'] [--test-fraction 0.2] \\
        [--before 266242a] [--models nn-default MODEL_DIR ...] [--rounds 15] [--batch 10000]

* One ensemble is fitted (``surrogate.sweep.nn.fit_sweep``, ``--options``; the timing does
  not depend on its accuracy, only on its sizes: 256 x 256 x 5 members and the basis by
  default) on the training designs of ``--data`` (the split ``hapticrom train`` makes, seed 0,
  ``--test-fraction``).
* "before": its graph exported by ``surrogate/sweep/export.py`` as of git revision
  ``--before`` (read with ``git show``; that decode gathers the whole (k, P * 6) basis with
  its zero blocks at two grid points per row, from the PODs' exact basis); "after": by the
  current code (the factored basis of ``surrogate/sweep/basis.py``). Each graph is checked
  against the numpy rebuild of its basis (``reference_log_outputs``) at every band frequency of
  held-out designs, then timed by ``bench/runtime/predict.py``'s :func:`bench_predictor`
  (one thread; FLOPs counted from the products the graph really does).
* ``--models``: shipped models (names under models/ or directories) timed the same way.
* The floor: |d ln| between the true magnitudes and those rebuilt from the true targets
  (``BandTargets.transform``), through the PODs' exact basis and through the factored one,
  at every band frequency of the held-out designs and of ``--test-data``.
"""

from __future__ import annotations

import argparse
import json
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import subprocess  # noqa: E402
import sys  # noqa: E402
import types  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
import torch  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # bench.runtime below
from bench.runtime.predict import bench, bench_predictor  # noqa: E402
from surrogate.runtime.encoding import encode  # noqa: E402
from surrogate.runtime.predictor import Predictor, make_session  # noqa: E402
from surrogate.sweep.basis import tail_error  # noqa: E402
from surrogate.sweep.export import (  # noqa: E402
    export_sweep_nn,
    member_targets,
    reference_log_outputs,
)
from surrogate.sweep.nn import fit_sweep  # noqa: E402
from surrogate.sweep.targets import (  # noqa: E402
    BandTargets,
    SweepData,
    load_sweep_datasets,
    log_magnitudes,
)
from surrogate.train import card_head, split  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
QUANTILES = (50, 95, 99, 100)


def module_at(revision: str, path: str, name: str) -> types.ModuleType:
    """The module ``path`` of the repository as of git ``revision``, imported as ``name``."""
    source = subprocess.run(["git", "-C", str(ROOT), "show", f"{revision}:{path}"],
                            check=True, capture_output=True, text=True).stdout
    module = types.ModuleType(name)
    module.__file__ = f"{revision}:{path}"
    sys.modules[name] = module
    exec(compile(source, module.__file__, "exec"), module.__dict__)
    return module


def exact_view(targets: BandTargets) -> Any:
    """``targets`` as the old decode reads them (``band_basis()``, ``shape_``), with the
    PODs' exact basis."""
    return types.SimpleNamespace(band_basis=lambda: targets.band_basis(exact=True),
                                 shape_=targets.shape_, n_modes=targets.n_modes)


def parity(predictor: Predictor, targets: Any, est: Any, data: SweepData,
           designs: np.ndarray) -> float:
    """Largest |d ln| (mean and std) of the graph against ``reference_log_outputs`` of
    ``targets`` at every band frequency of ``designs``."""
    n_f = data.band_hz.size
    codes = np.column_stack([np.repeat(data.codes[designs], n_f, axis=0),
                             np.tile(data.band_hz, designs.size)])
    X = encode(data.codes[designs], data.specs)
    y = member_targets(est, np.repeat(X, n_f, axis=0))
    ref = reference_log_outputs(targets, y, np.tile(np.arange(n_f), designs.size))
    got = predictor.session.run(["log_mean", "log_std"],
                                {"x": encode(codes, predictor.specs).astype(np.float32)})
    return float(max(np.abs(g - r).max() for g, r in zip(got, ref, strict=True)))


def floor(targets: BandTargets, response: np.ndarray) -> dict[str, np.ndarray]:
    """|d ln u| [ln] quantiles (:data:`QUANTILES`) of centre, edge and profile between true
    magnitudes and those rebuilt from the true targets through the PODs' exact basis and
    through the factored one, and between the two rebuilds (the factorisation's own part)."""
    truth = log_magnitudes(response)                                 # (n, n_f, P)
    T = targets.transform(response)
    rebuilt = {}
    for exact in (True, False):
        ln_s, z = targets.components(T, exact=exact)
        rebuilt[exact] = log_magnitudes(z, ln_s[:, None])
    out = {}
    for label, err in (("POD basis vs truth (before)", rebuilt[True] - truth),
                       ("factored vs truth (after)", rebuilt[False] - truth),
                       ("factored vs POD basis", rebuilt[False] - rebuilt[True])):
        for part, cols in (("centre", slice(0, 1)), ("edge", slice(1, 2)),
                           ("profile", slice(1, None))):
            out[f"{label}, {part}"] = np.percentile(np.abs(err[..., cols]), QUANTILES)
    return out


def print_floor(title: str, table: dict[str, np.ndarray]) -> None:
    print(f"\n{title}: |d ln u| from the basis alone, median / p95 / p99 / max")
    for name, q in table.items():
        print(f"  {name:38s} " + " / ".join(f"{v:.2e}" for v in q))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", required=True, help="a sweep dataset")
    ap.add_argument("--test-data", help="another sweep dataset of the space (the floor)")
    ap.add_argument("--options", default='{"max_epochs": 20, "loss": "coefficients"}',
                    help="fit_sweep options (JSON)")
    ap.add_argument("--test-fraction", type=float, default=0.2,
                    help="designs held out of the fit (the split of hapticrom train)")
    ap.add_argument("--before", default="266242a", help="git revision of the old decode")
    ap.add_argument("--models", nargs="*", default=["nn-default"])
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--batch", type=int, default=10_000)
    args = ap.parse_args()
    torch.set_num_threads(1)
    data = load_sweep_datasets([args.data])
    tr, te = split(len(data.codes), args.test_fraction, 0)
    est, targets = fit_sweep(data, tr, options=json.loads(args.options))
    rep = targets.to_dict()
    print(f"{len(data.codes)} designs ({tr.size} fit, {te.size} held out); POD modes "
          f"{rep['pod_modes']}; spatial rank {rep['spatial_rank']} of (12, "
          f"{6 * (data.grid_mm.size - 1)}) values at tol {targets.spatial_tol:g}: relative "
          f"error {', '.join(f'{k} {v:.2e}' for k, v in rep['spatial_rel_error'].items())}")
    for name, fac in zip(("centre_edge", "profile"), targets.factors, strict=True):
        err = tail_error(fac.spectrum)
        ranks = {tol: int(np.argmax(err <= tol)) for tol in (1e-2, 3e-3, 1e-3, 3e-4, 1e-4)}
        print(f"  {name}: rank for relative error <= tol: "
              + ", ".join(f"{tol:g}: {s}" for tol, s in ranks.items()))
    old = module_at(args.before, "surrogate/sweep/export.py", "sweep_export_before")
    specs = data.all_specs
    card = {**card_head("nn", "float32", specs, data, ()), "files": {}}
    graphs = {f"sweep, before ({args.before}: whole basis gathered)":
              (old.export_sweep_nn(est, exact_view(targets), False, specs[-1].low,
                                   specs[-1].high, data.band_hz, {}), exact_view(targets)),
              "sweep, after (factored basis)":
              (export_sweep_nn(est, targets, False, specs[-1].low, specs[-1].high,
                               data.band_hz, {}), targets)}
    results = {}
    for label, (graph, basis) in graphs.items():
        p = Predictor(card, make_session(graph))
        ref = targets if basis is targets else types.SimpleNamespace(
            components=lambda y, t=targets: t.components(y, exact=True))
        print(f"\n{label}: export parity max |d ln| {parity(p, ref, est, data, te[:16]):.2e}")
        results[label] = bench_predictor(label, p, graph, args.rounds, args.batch)
    for name in args.models:
        results[name] = bench(name, args.rounds, args.batch)
    print(f"\nsummary (CPU time per call; batch {args.batch:,})")
    for label, r in results.items():
        print(f"  {label}: batch 1 predict(dict) {r['predict_1'] * 1e6:.0f} us = "
              f"{r['predict_1'] / r['raw_1']:.2f}x raw ({r['raw_1'] * 1e6:.0f} us); batch "
              f"{args.batch:,} raw {r['raw_b'] * 1e3:.0f} ms = {r['raw_b'] / r['bound_b']:.2f}x, "
              f"predict(dict) {r['predict_b'] * 1e3:.0f} ms = "
              f"{r['predict_b'] / r['bound_b']:.2f}x the FLOP-bound {r['bound_b'] * 1e3:.0f} ms "
              f"({r['flops_per_row'] / 1e6:.2f} MFLOP/row)")
    print_floor(f"floor, {te.size} held-out designs", floor(targets, data.response[te]))
    if args.test_data:
        test = load_sweep_datasets([args.test_data])
        print_floor(f"floor, {len(test.codes)} designs of {args.test_data}",
                    floor(targets, test.response))


if __name__ == "__main__":
    main()
