"""Where a shipped model's graph spends its time: onnxruntime's own profiler on calls of one
batch size, the nodes' kernel time summed by kind of operation (products, exp / sqrt,
elementwise, gathers, other) and the largest single nodes, one thread.

    .venv/bin/python bench/runtime/graph_profile.py --model gp-sweep [--batch 512] [--calls 10]

The batch defaults to the predictor's chunk (``surrogate.runtime.predictor.CHUNK_ROWS``), the
rows one graph call sees when ``Predictor.predict`` answers a large batch. Features are random
in [0, 1] (the encoded range). A product's rate is printed beside its time: its FLOPs, counted
as ``bench/runtime/predict.py`` counts them (its ``graph_flops``), over its time. This is what
explains a ratio of ``bench/runtime/predict.py`` above the FLOP-bound: the bound counts
products only.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import tempfile

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import onnx
import onnxruntime as ort
from predict import graph_flops

from surrogate.runtime import find_model, load_model
from surrogate.runtime.card import read_model_file
from surrogate.runtime.predictor import CHUNK_ROWS

KINDS = {"product": ("Gemm", "MatMul", "FusedMatMul"), "exp / sqrt": ("Exp", "Sqrt", "Log", "Pow"),
         "gather": ("Gather", "GatherElements", "GatherND"),
         "elementwise": ("Mul", "Add", "Sub", "Div", "Neg", "Relu", "Clip", "Min", "Max", "Abs")}


def kind_of(op: str) -> str:
    """The kind of operation ``op`` (``"other"`` if none of :data:`KINDS`)."""
    return next((k for k, ops in KINDS.items() if op in ops), "other")


def profile(graph: bytes, batch: int, calls: int, dtype: type) -> list[dict]:
    """The profiler's node events of ``calls`` runs of ``graph`` on ``batch`` random encoded
    rows in ``dtype``, after a warm-up run whose events are left out."""
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = opts.inter_op_num_threads = 1
    opts.enable_profiling = True
    with tempfile.TemporaryDirectory() as tmp:
        opts.profile_file_prefix = os.path.join(tmp, "profile")
        session = ort.InferenceSession(graph, opts, providers=["CPUExecutionProvider"])
        (arg,) = session.get_inputs()
        x = np.random.default_rng(0).random((batch, arg.shape[1])).astype(dtype)
        for _ in range(calls + 1):
            session.run(None, {arg.name: x})
        with open(session.end_profiling()) as f:
            events = json.load(f)
    warm_up = min((e for e in events if e.get("name") == "model_run"), key=lambda e: e["ts"])
    after = warm_up["ts"] + warm_up["dur"]
    return [e for e in events if e.get("cat") == "Node" and e["ts"] >= after
            and e["name"].endswith("_kernel_time")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default="gp-sweep", help="a shipped model's name or directory")
    ap.add_argument("--batch", type=int, default=CHUNK_ROWS, help="rows a call (default: the "
                    f"predictor's chunk, {CHUNK_ROWS})")
    ap.add_argument("--calls", type=int, default=10, help="profiled calls (default 10)")
    ap.add_argument("--top", type=int, default=6, help="largest nodes listed (default 6)")
    args = ap.parse_args()
    path = find_model(args.model)
    card = load_model(path).card
    graph = read_model_file(path, card, card["graph"]["file"])
    dtype = np.float64 if card["graph"]["dtype"] == "float64" else np.float32
    events = profile(graph, args.batch, args.calls, dtype)
    width = onnx.load_from_string(graph).graph.input[0].type.tensor_type.shape.dim[1].dim_value
    flops_per_row = dict(graph_flops(graph, width)[1])
    by_kind, by_node = collections.Counter(), collections.Counter()
    flops = {}
    for e in events:
        name, op = e["name"][:-len("_kernel_time")], e["args"]["op_name"]
        by_kind[kind_of(op)] += e["dur"]
        by_node[f"{op} {name}"] += e["dur"]
        # a fused node keeps its first node's name before the "/" (node_matmul_1/...Fusion/)
        flops[f"{op} {name}"] = flops_per_row.get(name.split("/")[0], 0.0) * args.batch
    total = sum(by_kind.values())
    print(f"{path.name}: batch {args.batch}, {args.calls} calls, one thread; node kernel time "
          f"{total / args.calls / 1e3:.2f} ms a call")
    for kind, us in by_kind.most_common():
        print(f"  {kind:12s} {us / args.calls / 1e3:8.2f} ms  {100 * us / total:5.1f} %")
    print(" largest nodes:")
    for node, us in by_node.most_common(args.top):
        rate = (f", {flops[node] / (us / args.calls * 1e3):.1f} GFLOP/s"
                if flops.get(node) else "")
        print(f"  {node:50s} {us / args.calls / 1e3:8.2f} ms{rate}")


if __name__ == "__main__":
    main()
