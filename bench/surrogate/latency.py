"""Surrogate latency and throughput: ONNX NN vs torch eager vs scikit-learn GP, one run.

    .venv/bin/python bench/surrogate/latency.py [--data datasets/default] [--gp-rows 1000]

The floor of any in-process onnxruntime call on this machine is printed first: a graph of one
Add node, same session options (what a batch-1 latency cannot go below).

Builds, from the dataset, an NN ensemble of the default architecture (a few epochs: latency
does not depend on the weights) and a GP on ``--gp-rows`` rows, exports both, and prints
medians: batch-1 latency (one thread; the ONNX session made once; plain ``run`` and
IOBinding; the full ``Predictor.predict`` path with input validation), and large-batch
throughput of the ONNX NN against the machine's own dense matmul rate measured with numpy
on one thread in the same run (the net's FLOPs / that rate = the FLOP-bound time).
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np

from studies.accuracy.timing import matmul_rate, median_us, one_add_graph


def nn_flops_per_row(est) -> float:
    """Multiply-adds x 2 of the ensemble's layers plus the output map, per input row."""
    flops = sum(2.0 * w.shape[0] * w.shape[1] * w.shape[2] for w in est.weights_)
    return flops


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default="datasets/default")
    ap.add_argument("--gp-rows", type=int, default=1000)
    ap.add_argument("--batch", type=int, default=10000)
    args = ap.parse_args()

    import torch

    torch.set_num_threads(1)
    from surrogate.estimators.gp import GPSurrogateRegressor, export_gp
    from surrogate.estimators.nn import MLPEnsembleRegressor, export_nn
    from surrogate.pod import ProfileTargets
    from surrogate.runtime.encoding import encode
    from surrogate.runtime.predictor import Predictor, make_session
    from surrogate.train import edge_radius_rule, load_datasets

    data = load_datasets([args.data])
    X = encode(data.codes, data.specs)
    targets = ProfileTargets()
    T = targets.fit_transform(data.center_um, data.profile_um)
    B, b = targets.output_map()
    nn = MLPEnsembleRegressor(max_epochs=2).fit(X, T)  # the shipped architecture
    gp_t = ProfileTargets(n_modes=4)
    Tg = gp_t.fit_transform(data.center_um[:args.gp_rows], data.profile_um[:args.gp_rows])
    Bg, bg = gp_t.output_map()
    t0 = time.perf_counter()
    gp = GPSurrogateRegressor(max_train=args.gp_rows).fit(X[:args.gp_rows], Tg)
    gp_fit_s = time.perf_counter() - t0
    nn_sess = make_session(export_nn(nn, B, b, {}))
    gp_sess = make_session(export_gp(gp, Bg, bg, {}))
    card = {"inputs": [s.to_dict() for s in data.specs], "graph": {"dtype": "float32"},
            "profile_distance_mm": data.grid_mm.tolist(),
            "edge_radius": edge_radius_rule(data.codes, data.specs, data.edge_radius_mm)}
    pred = Predictor(card, nn_sess)

    x1 = X[:1].astype(np.float32)
    x1d = X[:1].copy()
    module = nn.to_module(B, b)
    xt = torch.as_tensor(x1)
    binding = nn_sess.io_binding()
    binding.bind_cpu_input("x", x1)
    for name in ("log_mean", "log_std"):
        binding.bind_output(name)

    def torch_eager():
        with torch.no_grad():
            module(xt)

    floor = make_session(one_add_graph(X.shape[1]))
    rows = [("onnxruntime floor (one Add node)",
             median_us(lambda: floor.run(None, {"x": x1}), 2000)),
            ("ONNX NN run()", median_us(lambda: nn_sess.run(None, {"x": x1}), 2000)),
            ("ONNX NN IOBinding", median_us(lambda: nn_sess.run_with_iobinding(binding), 2000)),
            ("Predictor.predict (validate+encode+run)",
             median_us(lambda: pred.predict(data.codes[:1]), 500)),
            ("torch eager", median_us(torch_eager, 500)),
            ("ONNX GP run() (mean+std)", median_us(lambda: gp_sess.run(None, {"x": x1d}), 200)),
            ("sklearn GP predict (mean)",
             median_us(lambda: [g.predict(x1d) for g in gp.gps_], 50)),
            ("sklearn GP predict (mean+std)", median_us(lambda: gp.predict(x1d, True), 50))]
    hidden = "x".join(str(h) for h in nn.hidden)
    print(f"batch-1 latency, one thread (NN {hidden} x {nn.n_members} members, "
          f"{X.shape[1]} features -> {B.shape[1]} outputs; GP {args.gp_rows} rows x "
          f"{len(gp.gps_)} targets, fit {gp_fit_s:.0f} s)")
    onnx_us = min(rows[1][1], rows[2][1])
    for name, us in rows:
        print(f"  {name:42s} {us:10.1f} us   {us / onnx_us:7.1f}x ONNX NN")
    print(f"  sklearn GP (mean+std) / ONNX NN: {rows[7][1] / onnx_us:.0f}x")

    xb = np.repeat(X, args.batch // len(X) + 1, axis=0)[:args.batch].astype(np.float32)
    t_onnx = median_us(lambda: nn_sess.run(None, {"x": xb}), 3) * 1e-6
    xbt = torch.as_tensor(xb)

    def torch_batch():
        with torch.no_grad():
            module(xbt)

    t_torch = median_us(torch_batch, 3) * 1e-6
    rate = matmul_rate()
    bound = nn_flops_per_row(nn) * args.batch / rate
    print(f"batch {args.batch}, one thread: numpy float32 matmul {rate / 1e9:.1f} GFLOP/s; "
          f"net {nn_flops_per_row(nn) / 1e3:.0f} kFLOP/row -> FLOP-bound {bound * 1e3:.1f} ms")
    print(f"  ONNX NN   {t_onnx * 1e3:8.1f} ms  {args.batch / t_onnx / 1e6:6.2f} M rows/s  "
          f"{t_onnx / bound:5.2f}x the FLOP-bound time")
    print(f"  torch     {t_torch * 1e3:8.1f} ms  {args.batch / t_torch / 1e6:6.2f} M rows/s  "
          f"{t_torch / bound:5.2f}x the FLOP-bound time")


if __name__ == "__main__":
    main()
