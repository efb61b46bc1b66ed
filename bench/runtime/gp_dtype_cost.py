"""What the sweep GP's float64 graph costs at one design: its kernel against N fitted designs
and its mean (K* @ alpha, 177 targets) as one ONNX graph in float64 and in float32, timed
like bench/runtime/predict.py (one thread, thread CPU time, medians of interleaved rounds).

    .venv/bin/python bench/runtime/gp_dtype_cost.py [--designs 6500] [--rounds 15]

The graph is the kernel and mean of surrogate/sweep/gp_export.py (Matern 5/2 on 14 encoded
features, its squared distances by the |x|^2 - 2 x.X + |X|^2 expansion) on random inputs: the
arithmetic and shapes of the shipped graph's first part at the full dataset's size, not its
values, so it says which precision can answer within a time, not how accurate it would be.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import onnxruntime as ort
from onnx import TensorProto, helper, numpy_helper

FEATURES, TARGETS = 14, 177  # the default sweep space's encoded design features; 1 + 48 + 128


def kernel_mean_graph(n_designs: int, dtype: type) -> bytes:
    """ONNX bytes: x (batch, FEATURES) -> K* @ alpha (batch, TARGETS) in ``dtype``."""
    elem = TensorProto.DOUBLE if dtype == np.float64 else TensorProto.FLOAT
    rng = np.random.default_rng(0)
    consts = {"XT": rng.random((FEATURES, n_designs)), "Xsq": rng.random(n_designs),
              "alpha": rng.standard_normal((n_designs, TARGETS)), "two": np.array(2.0),
              "five": np.array(5.0), "c53": np.array(5.0 / 3.0), "one": np.array(1.0)}
    inits = [numpy_helper.from_array(v.astype(dtype), k) for k, v in consts.items()]
    steps = [("Mul", ["x", "x"], "xx"), ("ReduceSum", ["xx"], "xsq"), ("MatMul", ["x", "XT"], "xX"),
             ("Mul", ["xX", "two"], "xX2"), ("Sub", ["xsq", "xX2"], "a"),
             ("Add", ["a", "Xsq"], "d2r"), ("Relu", ["d2r"], "d2"), ("Mul", ["d2", "five"], "d5"),
             ("Sqrt", ["d5"], "r"), ("Mul", ["d2", "c53"], "q"), ("Add", ["r", "q"], "rq"),
             ("Add", ["rq", "one"], "p"), ("Neg", ["r"], "nr"), ("Exp", ["nr"], "e"),
             ("Mul", ["p", "e"], "k"), ("MatMul", ["k", "alpha"], "y")]
    nodes = [helper.make_node(op, ins, [out], **({"keepdims": 1} if op == "ReduceSum" else {}))
             for op, ins, out in steps]
    graph = helper.make_graph(nodes, "gp_kernel_mean",
                              [helper.make_tensor_value_info("x", elem, [None, FEATURES])],
                              [helper.make_tensor_value_info("y", elem, [None, TARGETS])], inits)
    return helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)]).SerializeToString()


def session(onnx_bytes: bytes) -> ort.InferenceSession:
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = opts.inter_op_num_threads = 1
    return ort.InferenceSession(onnx_bytes, opts, providers=["CPUExecutionProvider"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--designs", type=int, default=6500, help="fitted designs N (default 6500)")
    ap.add_argument("--rounds", type=int, default=15, help="interleaved rounds (default 15)")
    ap.add_argument("--calls", type=int, default=20, help="calls per round (default 20)")
    args = ap.parse_args()
    runs = {}
    for dtype in (np.float64, np.float32):
        s = session(kernel_mean_graph(args.designs, dtype))
        x = np.random.default_rng(1).random((1, FEATURES)).astype(dtype)
        s.run(None, {"x": x})  # warm-up
        runs[np.dtype(dtype).name] = (s, x, [])
    for _ in range(args.rounds):
        for s, x, times in runs.values():
            t0 = time.thread_time()
            for _ in range(args.calls):
                s.run(None, {"x": x})
            times.append((time.thread_time() - t0) / args.calls)
    for name, (_, _, times) in runs.items():
        print(f"N = {args.designs}, {name}: kernel + mean at batch 1, median "
              f"{1e3 * float(np.median(times)):.3f} ms (max {1e3 * max(times):.3f} ms)")


if __name__ == "__main__":
    main()
