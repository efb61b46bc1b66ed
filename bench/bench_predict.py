"""What ``Predictor.predict`` costs beyond the graph: the raw onnxruntime call against the full
run-time path (validation, encoding, decoding), at batch 1 and batch 10,000, on shipped models.

    .venv/bin/python bench/bench_predict.py [--models nn-default gp-default] [--rounds 15]

For each model (one thread: the predictor's own session, OMP/BLAS threads set to 1):

* ``raw``: ``session.run(["log_mean", "log_std"], {"x": features})`` on features encoded
  beforehand -- the graph alone, through onnxruntime's public Python call;
* ``predict(dict)``: ``Predictor.predict`` of the same designs as a dict name -> values (one
  design: lists of one value, as an embedding app passes them; 10,000: numpy arrays,
  categoricals as choice strings, as the planner passes them), every check included (names,
  ranges, categories, integers, the edge-radius table) and every output decoded;
* ``predict(array)``: the same from the (n, d) float array of codes.

Timing: the candidates are interleaved in short blocks (``--rounds`` rounds; a block is 200
calls at batch 1, one call at batch 10,000), each block timed by the thread's CPU clock
(``time.thread_time``: on a shared machine another process's work is not counted) and by the
wall clock; the table gives medians over blocks, the ratios are medians of each round's
ratio (paired, so a slow round slows both).

FLOP-bound time at batch 10,000: the graph's FLOPs are counted from its initializers -- every
``MatMul`` whose second operand is an initializer ``W`` of shape (..., k, m) costs
2 * prod(W.shape) FLOPs per row -- and the FLOP-bound time is the time this machine's numpy
takes for exactly those matmuls (A of shape (..., 10000, k) in the graph's dtype, one
thread; thread CPU time, median of 5): the arithmetic the graph cannot avoid, at the rate
this machine achieves on those very shapes (printed as GFLOP/s). Everything else in the graph
(activations, exp, reductions) is what the ratio above 1 pays for.
"""

from __future__ import annotations

import argparse
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import statistics  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from surrogate.runtime import find_model, load_model  # noqa: E402
from surrogate.runtime.card import read_model_file  # noqa: E402
from surrogate.runtime.encoding import InputSpec  # noqa: E402

ONE = {"orientation": ["forward"], "attachment": ["glued"], "n_rings": [2],
       "ring_1_E_kPa": [95.0], "ring_2_E_kPa": [260.0], "ring_3_E_kPa": [95.0],
       "ring_density_kg_m3": [1070.0], "ring_nu": [0.47], "ring_loss_factor": [0.1],
       "skin_E_kPa": [49.0], "fat_thickness_mm": [14.0], "tissue_loss_factor": [0.3],
       "frequency_hz": [200.0]}


def designs(card: dict[str, Any], n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """n designs drawn inside the trained range, as the planner passes them (dict of arrays,
    categoricals as choice strings)."""
    rng = np.random.default_rng(seed)
    out: dict[str, np.ndarray] = {}
    for d in card["inputs"]:
        s = InputSpec.from_dict(d)
        if s.type == "categorical":
            out[s.name] = np.asarray(s.choices)[rng.integers(0, len(s.choices), n)]
        elif s.type == "integer":
            out[s.name] = rng.integers(int(s.low), int(s.high) + 1, n)
        elif s.scale == "log":
            out[s.name] = np.exp(rng.uniform(np.log(s.low), np.log(s.high), n))
        else:
            out[s.name] = rng.uniform(s.low, s.high, n)
    return out


def matmul_bound(graph: bytes, batch: int) -> tuple[float, float]:
    """(FLOPs per row of the graph's initializer matmuls, numpy's time for those matmuls at
    ``batch`` rows [s])."""
    import onnx
    from onnx import numpy_helper

    model = onnx.load_from_string(graph)
    weights = {i.name: numpy_helper.to_array(i) for i in model.graph.initializer}
    flops, seconds = 0.0, 0.0
    rng = np.random.default_rng(0)
    for node in model.graph.node:
        if node.op_type != "MatMul" or node.input[1] not in weights:
            continue
        w = weights[node.input[1]]
        a = rng.standard_normal((*w.shape[:-2], batch, w.shape[-2])).astype(w.dtype)
        flops += 2.0 * w.size
        a @ w
        times = []
        for _ in range(5):
            t0 = time.thread_time()
            a @ w
            times.append(time.thread_time() - t0)
        seconds += statistics.median(times)
    return flops, seconds


def interleaved(cands: dict[str, Callable[[], Any]], calls: int, rounds: int
                ) -> dict[str, list[tuple[float, float]]]:
    """Per candidate, per round: (thread CPU time, wall time) per call [s]."""
    for fn in cands.values():
        fn()  # warm-up
    out: dict[str, list[tuple[float, float]]] = {k: [] for k in cands}
    for _ in range(rounds):
        for name, fn in cands.items():
            c0, w0 = time.thread_time(), time.perf_counter()
            for _ in range(calls):
                fn()
            out[name].append(((time.thread_time() - c0) / calls,
                              (time.perf_counter() - w0) / calls))
    return out


def report(title: str, res: dict[str, list[tuple[float, float]]], unit: float,
           label: str) -> None:
    print(title)
    raw = res["raw"]
    for name, blocks in res.items():
        cpu = statistics.median(b[0] for b in blocks) / unit
        wall = statistics.median(b[1] for b in blocks) / unit
        ratio = statistics.median(b[0] / r[0] for b, r in zip(blocks, raw, strict=True))
        print(f"  {name:16s} {cpu:10.1f} {label} CPU  {wall:10.1f} {label} wall   "
              f"{ratio:5.2f}x raw")


def bench(name: str, rounds: int, batch: int) -> None:
    p = load_model(name)
    session, outs = p.session, ["log_mean", "log_std"]
    _, x1, _ = p.features(ONE)
    codes1 = p.features(ONE)[0].copy()
    heavy = p.card["graph"]["dtype"] == "float64"
    res1 = interleaved({"raw": lambda: session.run(outs, {"x": x1}),
                        "predict(dict)": lambda: p.predict(ONE),
                        "predict(array)": lambda: p.predict(codes1)},
                       calls=20 if heavy else 200, rounds=rounds)
    print(f"\n{name} ({p.card['graph']['dtype']} graph)")
    report(" batch 1 (one design), per call:", res1, 1e-6, "us")
    many = designs(p.card, batch)
    codes, xb, _ = p.features(many)
    codes = codes.copy()
    resb = interleaved({"raw": lambda: session.run(outs, {"x": xb}),
                        "predict(dict)": lambda: p.predict(many),
                        "predict(array)": lambda: p.predict(codes)},
                       calls=1, rounds=max(3, rounds // 3) if heavy else rounds)
    report(f" batch {batch:,}, per call:", resb, 1e-3, "ms")
    graph = read_model_file(find_model(name), p.card, p.card["graph"]["file"])
    flops, bound = matmul_bound(graph, batch)
    cpu = {k: statistics.median(b[0] for b in v) for k, v in resb.items()}
    print(f" FLOP-bound at batch {batch:,}: {flops / 1e3:.1f} kFLOP/row in the graph's "
          f"initializer matmuls; numpy does those matmuls in {bound * 1e3:.1f} ms "
          f"({flops * batch / bound / 1e9:.1f} GFLOP/s, one thread)")
    for k in cpu:
        print(f"  {k:16s} {cpu[k] / bound:5.2f}x the FLOP-bound time")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", nargs="+", default=["nn-default", "gp-default"])
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--batch", type=int, default=10_000)
    args = ap.parse_args()
    for name in args.models:
        bench(name, args.rounds, args.batch)


if __name__ == "__main__":
    main()
