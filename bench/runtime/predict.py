"""What ``Predictor.predict`` costs beyond the graph: the raw onnxruntime call against the full
run-time path (validation, encoding, decoding), at batch 1 and batch 10,000, on shipped models.

    .venv/bin/python bench/runtime/predict.py [--models nn-default gp-default] [--rounds 15]
    .venv/bin/python bench/runtime/predict.py --models nn-default MODEL_DIR --chunk-rows 512,1024

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

FLOP-bound time at batch 10,000: the graph's FLOPs per row are counted from the shapes its
``MatMul`` and ``Gemm`` nodes really multiply (:func:`graph_flops`: the graph is run at batch
1 and 2 with every product's operands exposed; a product (..., n, k) @ (..., k, m) costs
2 * (batch dims) * n * k * m FLOPs, and the per-row count is the difference, so a gather of
one grid point of a table counts that point, not the table). The rate is numpy's on the
graph's dense matmuls, those with an initializer operand ``W`` (MatMul or Gemm, on either
side; W of shape (..., k, m) second: A of shape (..., 10000, k) times W; W (m, k) first: W
times B of shape (k, 10000)), in the graph's dtype and orientation, one thread, thread CPU time,
median of 5 (printed as GFLOP/s). The FLOP-bound time is the counted FLOPs at that rate: the
arithmetic the graph cannot avoid at the rate this machine achieves on dense products
(for a graph whose products are all dense, such as nn-default's, it is numpy's time for
exactly those matmuls). Everything else in the graph (gathers, activations, exp, reductions,
small batched products below the dense rate) is what the ratio above 1 pays for.
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
import onnx  # noqa: E402
from onnx import numpy_helper  # noqa: E402

from surrogate.runtime import find_model, load_model  # noqa: E402
from surrogate.runtime.card import read_model_file  # noqa: E402
from surrogate.runtime.defaults import default_model  # noqa: E402
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
    ``batch`` rows [s]). An initializer matmul is a ``MatMul`` or ``Gemm`` with a constant
    operand ``W``, on either side: the activation's rows times W (W second, or transposed by
    ``transB``), or W times the activation's columns (W first, as the GP's mean
    (alpha' @ K*')' is written); numpy times the same product in the same orientation."""
    model = onnx.load_from_string(graph)
    weights = {i.name: numpy_helper.to_array(i) for i in model.graph.initializer}
    flops, seconds = 0.0, 0.0
    rng = np.random.default_rng(0)
    for node in model.graph.node:
        product = _initializer_product(node, weights, batch, rng)
        if product is None:
            continue
        w, run = product
        flops += 2.0 * w.size
        run()
        times = []
        for _ in range(5):
            t0 = time.thread_time()
            run()
            times.append(time.thread_time() - t0)
        seconds += statistics.median(times)
    return flops, seconds


def _initializer_product(node: Any, weights: dict[str, np.ndarray], batch: int,
                         rng: np.random.Generator) -> tuple[np.ndarray, Callable[[], Any]] | None:
    """(W, numpy's product of ``batch`` random rows with W as ``node`` multiplies them), or
    None when ``node`` is not a MatMul / Gemm with a constant operand."""
    if node.op_type not in ("MatMul", "Gemm"):
        return None
    attrs = {t.name: t.i for t in node.attribute}
    if node.input[1] in weights:
        w = weights[node.input[1]]
        w = w.T if attrs.get("transB") else w
        a = rng.standard_normal((*w.shape[:-2], batch, w.shape[-2])).astype(w.dtype)
        return w, lambda: a @ w
    if node.input[0] in weights and weights[node.input[0]].ndim == 2:
        w = weights[node.input[0]]
        w = w.T if attrs.get("transA") else w
        b = rng.standard_normal((w.shape[1], batch)).astype(w.dtype)
        return w, lambda: w @ b
    return None


def _product_flops(a: tuple[int, ...], b: tuple[int, ...], node: Any) -> float:
    """FLOPs of one ``MatMul`` (numpy broadcasting; 1-D operands as numpy treats them) or
    ``Gemm`` (2-D; ``transA`` / ``transB``) ``node`` of operand shapes ``a`` and ``b``."""
    if node.op_type == "Gemm":
        attrs = {t.name: t.i for t in node.attribute}
        n, k = a[::-1] if attrs.get("transA") else a
        m = b[0] if attrs.get("transB") else b[1]
        return 2.0 * n * k * m
    a2 = (1, *a) if len(a) == 1 else a
    b2 = (*b, 1) if len(b) == 1 else b
    batch = np.broadcast_shapes(a2[:-2], b2[:-2])
    return 2.0 * float(np.prod(batch)) * a2[-2] * a2[-1] * b2[-1]


def graph_flops(graph: bytes, n_features: int) -> tuple[float, list[tuple[str, float]]]:
    """(FLOPs per row of every ``MatMul`` / ``Gemm`` of the graph, per node (name, FLOPs per
    row)), from the operand shapes of a run at batch 1 and 2 (random features in [0, 1])."""
    import onnxruntime as ort

    model = onnx.load_from_string(graph)
    nodes = [n for n in model.graph.node if n.op_type in ("MatMul", "Gemm")]
    elem = model.graph.input[0].type.tensor_type.elem_type
    known = {o.name for o in model.graph.output}
    names = sorted({i for n in nodes for i in n.input[:2]} - known)
    weights = {i.name: tuple(i.dims) for i in model.graph.initializer}
    model.graph.output.extend(onnx.helper.make_tensor_value_info(i, elem, None)
                              for i in names if i not in weights)
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = opts.inter_op_num_threads = 1
    session = ort.InferenceSession(model.SerializeToString(), opts,
                                   providers=["CPUExecutionProvider"])
    wanted = [o.name for o in session.get_outputs()]
    dtype = np.float64 if elem == onnx.TensorProto.DOUBLE else np.float32
    per_batch = []
    for batch in (1, 2):
        x = np.random.default_rng(batch).uniform(size=(batch, n_features)).astype(dtype)
        shapes = {**weights, **dict(zip(wanted, (np.shape(v) for v in
                                                 session.run(wanted, {"x": x})), strict=True))}
        per_batch.append([_product_flops(shapes[n.input[0]], shapes[n.input[1]], n)
                          for n in nodes])
    per_node = [(n.name, two - one) for n, one, two in zip(nodes, *per_batch, strict=True)]
    return sum(f for _, f in per_node), per_node


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


def one_design(card: dict[str, Any]) -> dict[str, list[Any]]:
    """:data:`ONE` when the model takes its inputs, else one design of :func:`designs` (lists
    of one value, as an embedding app passes them)."""
    names = [d["name"] for d in card["inputs"]]
    if sorted(names) == sorted(ONE):
        return ONE
    return {k: [v[0].item()] for k, v in designs(card, 1, seed=1).items()}


def bench_predictor(label: str, p: Any, graph: bytes, rounds: int, batch: int
                    ) -> dict[str, float]:
    """Time predictor ``p`` (its graph's bytes ``graph``) at batch 1 and ``batch``, print the
    tables, and return the medians: raw and predict(dict) CPU times per call at batch 1 [s]
    and at ``batch`` [s], the FLOP-bound time [s] and the FLOPs per row."""
    one = one_design(p.card)
    session, outs = p.session, ["log_mean", "log_std"]
    codes1, x1, _ = p.features(one)
    codes1 = codes1.copy()
    heavy = p.card["graph"]["dtype"] == "float64"
    res1 = interleaved({"raw": lambda: session.run(outs, {"x": x1}),
                        "predict(dict)": lambda: p.predict(one),
                        "predict(array)": lambda: p.predict(codes1)},
                       calls=20 if heavy else 200, rounds=rounds)
    print(f"\n{label} ({p.card['graph']['dtype']} graph, {len(graph) / 1e6:.1f} MB)")
    report(" batch 1 (one design), per call:", res1, 1e-6, "us")
    many = designs(p.card, batch)
    codes, xb, _ = p.features(many)
    codes = codes.copy()
    resb = interleaved({"raw": lambda: session.run(outs, {"x": xb}),
                        "predict(dict)": lambda: p.predict(many),
                        "predict(array)": lambda: p.predict(codes)},
                       calls=1, rounds=max(3, rounds // 3) if heavy else rounds)
    report(f" batch {batch:,}, per call:", resb, 1e-3, "ms")
    dense, dense_s = matmul_bound(graph, batch)
    flops, per_node = graph_flops(graph, x1.shape[1])
    rate = dense * batch / dense_s
    bound = flops * batch / rate
    largest = sorted(per_node, key=lambda v: -v[1])[:3]
    print(f" FLOPs per row (every MatMul/Gemm, as run): {flops / 1e3:.1f} k (2 x prod(W) over "
          f"the initializer matmuls W: {dense / 1e3:.1f} k; largest products: "
          f"{', '.join(f'{n} {f / 1e3:.1f} k' for n, f in largest)})")
    print(f" FLOP-bound at batch {batch:,}: {bound * 1e3:.1f} ms (numpy: "
          f"{rate / 1e9:.1f} GFLOP/s on the graph's dense matmuls, one thread)")
    cpu = {k: statistics.median(b[0] for b in v) for k, v in resb.items()}
    for k in cpu:
        print(f"  {k:16s} {cpu[k] / bound:5.2f}x the FLOP-bound time")
    return {"raw_1": statistics.median(b[0] for b in res1["raw"]),
            "predict_1": statistics.median(b[0] for b in res1["predict(dict)"]),
            "raw_b": cpu["raw"], "predict_b": cpu["predict(dict)"], "bound_b": bound,
            "flops_per_row": flops}


def bench(name: str, rounds: int, batch: int) -> dict[str, float]:
    """:func:`bench_predictor` of a shipped model (a name under models/ or a directory)."""
    p = load_model(name)
    graph = read_model_file(find_model(name), p.card, p.card["graph"]["file"])
    return bench_predictor(name, p, graph, rounds, batch)


def chunk_rows(name: str, sizes: list[int], rounds: int, batch: int) -> None:
    """``Predictor.predict`` of ``batch`` designs (dict) with each chunk size
    (``surrogate.runtime.predictor.CHUNK_ROWS``), interleaved: medians of thread CPU time."""
    import surrogate.runtime.predictor as predictor_module

    p = load_model(name)
    many = designs(p.card, batch)
    default = predictor_module.CHUNK_ROWS
    times: dict[int, list[float]] = {n: [] for n in sizes}
    try:
        for _ in range(rounds):
            for n in sizes:
                predictor_module.CHUNK_ROWS = n
                t0 = time.thread_time()
                p.predict(many)
                times[n].append(time.thread_time() - t0)
    finally:
        predictor_module.CHUNK_ROWS = default
    print(f"\n{name}: predict(dict) of {batch:,} designs by chunk rows: "
          + ", ".join(f"{n}: {statistics.median(v) * 1e3:.0f} ms" for n, v in times.items()))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", nargs="+", default=None,
                    help="model names or directories (default: the shipped network and GP, "
                    "surrogate.runtime.defaults: nn-sweep / gp-sweep when installed)")
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--batch", type=int, default=10_000)
    ap.add_argument("--chunk-rows", help="instead: time predict at --batch with these "
                    "CHUNK_ROWS values, e.g. 256,512,1024")
    args = ap.parse_args()
    if args.models is None:
        args.models = [default_model("harmonic"), default_model("gaussian_process")]
    for name in args.models:
        if args.chunk_rows:
            chunk_rows(name, [int(v) for v in args.chunk_rows.split(",")], args.rounds,
                       args.batch)
        else:
            bench(name, args.rounds, args.batch)


if __name__ == "__main__":
    main()
