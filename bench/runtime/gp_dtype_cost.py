"""What the sweep GP's float64 graph costs at one design: its kernel against N fitted designs
and its mean (K* @ alpha, 177 targets) as one ONNX graph in float64 and in float32, timed
like bench/runtime/predict.py (one thread, thread CPU time, medians of interleaved rounds).

    .venv/bin/python bench/runtime/gp_dtype_cost.py [--designs 6500] [--rounds 15]
    .venv/bin/python bench/runtime/gp_dtype_cost.py --model models/gp-sweep

The float64 graph is timed as written (MatMul), with the product as Gemm with the constant
transposed (surrogate.estimators.export.double_matmuls_as_gemm), and as the export writes it:
alpha the left operand, (alpha' @ K*')'. The graph is the
kernel and mean of surrogate/sweep/gp_export.py (Matern 5/2 on 14 encoded features, its squared
distances by the |x|^2 - 2 x.X + |X|^2 expansion) on random inputs: the arithmetic and shapes of
the shipped graph's first part at the full dataset's size, not its values, so it says which
precision can answer within a time, not how accurate it would be. ``--model`` says that: it
reads a sweep GP's own constants from its graph (the fitted designs, length scales, alpha) and
prints how far the float32 kernel and mean land from the float64 ones in the targets (the POD
coefficients the decode turns into amplitudes), at random designs and near fitted ones, against
the targets' own spread.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import onnx
import onnxruntime as ort
from onnx import TensorProto, helper, numpy_helper

from surrogate.estimators.export import double_matmuls_as_gemm

FEATURES, TARGETS = 14, 177  # the default sweep space's encoded design features; 1 + 48 + 128


def kernel_mean_graph(n_designs: int, dtype: type, alpha_left: bool = False) -> bytes:
    """ONNX bytes: x (batch, FEATURES) -> K* @ alpha (batch, TARGETS) in ``dtype``
    (``alpha_left``: as (alpha' @ K*')', alpha the left operand, as the export writes it)."""
    elem = TensorProto.DOUBLE if dtype == np.float64 else TensorProto.FLOAT
    rng = np.random.default_rng(0)
    consts = {"XT": rng.random((FEATURES, n_designs)), "Xsq": rng.random(n_designs),
              "alpha": rng.standard_normal((n_designs, TARGETS)), "two": np.array(2.0),
              "five": np.array(5.0), "c53": np.array(5.0 / 3.0), "one": np.array(1.0)}
    if alpha_left:  # stored as the export stores it
        consts["alpha_T"] = consts.pop("alpha").T.copy()
    inits = [numpy_helper.from_array(v.astype(dtype), k) for k, v in consts.items()]
    steps = [("Mul", ["x", "x"], "xx"), ("ReduceSum", ["xx"], "xsq"), ("MatMul", ["x", "XT"], "xX"),
             ("Mul", ["xX", "two"], "xX2"), ("Sub", ["xsq", "xX2"], "a"),
             ("Add", ["a", "Xsq"], "d2r"), ("Relu", ["d2r"], "d2"), ("Mul", ["d2", "five"], "d5"),
             ("Sqrt", ["d5"], "r"), ("Mul", ["d2", "c53"], "q"), ("Add", ["r", "q"], "rq"),
             ("Add", ["rq", "one"], "p"), ("Neg", ["r"], "nr"), ("Exp", ["nr"], "e"),
             ("Mul", ["p", "e"], "k")]
    steps += ([("Transpose", ["k"], "kT"), ("MatMul", ["alpha_T", "kT"], "yT"),
               ("Transpose", ["yT"], "y")] if alpha_left else [("MatMul", ["k", "alpha"], "y")])
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


def float32_mean_error(model_dir: str, n: int = 2000) -> None:
    """Print |mean_float32 - mean_float64| of the sweep GP in ``model_dir`` (its targets, the
    scaled POD coefficients) at ``n`` uniform designs and ``n`` designs 0.01 from fitted ones."""
    graph = onnx.load(f"{model_dir}/model.onnx")
    c = {i.name: numpy_helper.to_array(i) for i in graph.graph.initializer}
    for name in ("alpha", "Xs_T"):  # stored transposed: name__T (the Gemm rewrite), name_T
        stored = [c[t] for t in (f"{name}__T", f"{name}_T") if t in c]   # (the export's alpha)
        if name not in c and stored:
            c[name] = stored[0].T
    alpha = c["alpha"]

    def mean(x: np.ndarray, dtype: type) -> tuple[np.ndarray, np.ndarray]:
        xs = (x.astype(dtype) - dtype(0.5)) * c["inv_ls"].astype(dtype)
        X_T, X_sq = c["Xs_T"].astype(dtype), c["Xs_sq"].astype(dtype)
        d2 = np.maximum((xs * xs).sum(1, keepdims=True) - dtype(2) * xs @ X_T + X_sq, 0)
        r = np.sqrt(dtype(5) * d2)
        k = dtype(c["amp"]) * (1 + r + dtype(5 / 3) * d2) * np.exp(-r)
        return k @ alpha.astype(dtype), np.abs(k) @ np.abs(alpha.astype(dtype))

    rng = np.random.default_rng(0)
    fitted = c["Xs_T"].T / c["inv_ls"] + 0.5
    d = fitted.shape[1]
    near = fitted[rng.integers(0, len(fitted), n)] + 0.01 * rng.standard_normal((n, d))
    print(f"{model_dir}: {len(fitted)} fitted designs, {alpha.shape[1]} targets, "
          f"max |alpha| {np.abs(alpha).max():.3g}")
    for name, x in (("uniform", rng.random((n, d))), ("near fitted", np.clip(near, 0, 1))):
        y64, terms = mean(x, np.float64)
        diff = np.abs(mean(x, np.float32)[0] - y64)
        spread = y64.std(axis=0)
        print(f"  {name}: |d target| median {np.median(diff):.2g}, p99 "
              f"{np.quantile(diff, 0.99):.2g}, max {diff.max():.2g}; relative to the "
              f"target's spread: max "
              f"{(diff / spread).max():.2g}; sum |k alpha| / |target| median "
              f"{np.median(terms / np.maximum(np.abs(y64), 1e-12)):.3g}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--designs", type=int, default=6500, help="fitted designs N (default 6500)")
    ap.add_argument("--rounds", type=int, default=15, help="interleaved rounds (default 15)")
    ap.add_argument("--calls", type=int, default=20, help="calls per round (default 20)")
    ap.add_argument("--model", help="a sweep GP's directory: its float32 mean's error instead")
    args = ap.parse_args()
    if args.model:
        float32_mean_error(args.model)
        return
    runs = {}
    for name, dtype, gemm, left in (
            ("float64 MatMul", np.float64, False, False),
            ("float64 Gemm (K* @ alpha)", np.float64, True, False),
            ("float64 alpha' @ K*' (as exported)", np.float64, True, True),
            ("float32", np.float32, False, False)):
        graph = kernel_mean_graph(args.designs, dtype, left)
        if gemm:
            graph = double_matmuls_as_gemm(onnx.load_from_string(graph)).SerializeToString()
        s = session(graph)
        x = np.random.default_rng(1).random((1, FEATURES)).astype(dtype)
        s.run(None, {"x": x})  # warm-up
        runs[name] = (s, x, [])
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
