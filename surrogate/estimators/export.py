"""ONNX export of the surrogates, one graph contract for all of them.

Every exported graph has one input ``x`` (batch, n_features) -- the encoded features of
:mod:`surrogate.runtime.encoding` -- and two outputs of shape (batch, 3 + m): ``log_mean``
and ``log_std``, the natural log of [center, edge, normalized edge, profile...] and its
predictive standard deviation (:func:`surrogate.pod.output_columns`). The linear output map
of :class:`surrogate.pod.ProfileTargets` and all scaling are inside the graph; the batch axis
is dynamic. Descriptive metadata (inputs, units, ranges, data hash, metrics) go into the
model's ``metadata_props`` as JSON strings.

* NN: ``torch.onnx.export`` (dynamo exporter), float32, a single file (no external data).
* GP: a float64 graph built node by node (float32 is unusable for a GP: the variance is a
  difference of nearly equal numbers), RBF or Matern 5/2; see :func:`export_gp` for why not
  skl2onnx.
"""

from __future__ import annotations

import io
import json
from collections.abc import Mapping
from typing import Any

import numpy as np
import onnx
from onnx import helper, numpy_helper
from scipy.linalg import solve_triangular
from sklearn.gaussian_process.kernels import RBF, Matern

__all__ = ["MAX_IR_VERSION", "export_gp", "export_module", "export_nn", "finish_model",
           "set_metadata"]

#: onnx >= 1.23 writes IR 14 by default; onnxruntime 1.31 reads at most 13.
MAX_IR_VERSION = 10
#: Opset of the GP graph -- read by every onnxruntime >= 1.14.
GP_OPSET = 18


def set_metadata(model: onnx.ModelProto, metadata: Mapping[str, Any]) -> onnx.ModelProto:
    """Write ``metadata`` into ``metadata_props`` (non-string values as JSON)."""
    del model.metadata_props[:]
    for key, value in metadata.items():
        text = value if isinstance(value, str) else json.dumps(value, sort_keys=True)
        model.metadata_props.add(key=key, value=text)
    return model


def finish_model(model: onnx.ModelProto, metadata: Mapping[str, Any]) -> bytes:
    """The serialised, checked graph: IR version capped for onnxruntime, metadata set."""
    model.ir_version = min(model.ir_version, MAX_IR_VERSION)
    set_metadata(model, metadata)
    onnx.checker.check_model(model)
    return model.SerializeToString()


def export_nn(estimator: Any, B: np.ndarray, b: np.ndarray,
              metadata: Mapping[str, Any]) -> bytes:
    """ONNX bytes of a fitted :class:`surrogate.estimators.nn.MLPEnsembleRegressor` (float32
    input)."""
    return export_module(estimator.to_module(B, b), estimator.n_features_in_, metadata)


def export_module(module: Any, n_features: int, metadata: Mapping[str, Any],
                  dtype: str = "float32") -> bytes:
    """ONNX bytes of a torch module ``x (batch, n_features) dtype -> (log_mean, log_std)``
    (the NN ensembles: :func:`export_nn`, the sweep models of :mod:`surrogate.sweep.export`;
    ``dtype`` "float64": the sweep GP of :mod:`surrogate.sweep.gp_export`)."""
    # Lazy: torch costs 3.9 s to import; the GP's paths (surrogate.refine) need none of it.
    import torch

    example = torch.zeros(2, n_features, dtype=getattr(torch, dtype))
    program = torch.onnx.export(module, (example,), dynamo=True, input_names=["x"],
                                output_names=["log_mean", "log_std"],
                                dynamic_shapes={"x": {0: "batch"}}, optimize=True,
                                verbose=False)
    buf = io.BytesIO()
    program.save(buf, external_data=False) if hasattr(program, "save") else None
    model = onnx.load_from_string(buf.getvalue())
    return finish_model(model, metadata)


def _gp_parts(gp: Any) -> dict[str, Any]:
    """Constants of a fitted ``amplitude * ARD(rbf|matern52) + white`` GaussianProcessRegressor."""
    k = gp.kernel_
    amp, core, noise = k.k1.k1.constant_value, k.k1.k2, k.k2.noise_level
    if isinstance(core, Matern) and core.nu == 2.5:
        name = "matern52"
    elif type(core) is RBF:
        name = "rbf"
    else:
        raise ValueError(f"kernel {core} cannot be exported (rbf or Matern nu=2.5 only)")
    ls = np.broadcast_to(np.asarray(core.length_scale, float), (gp.X_train_.shape[1],))
    L_inv = solve_triangular(gp.L_, np.eye(gp.L_.shape[0]), lower=True)
    scale = np.atleast_1d(gp._y_train_std).astype(float)
    alpha = gp.alpha_.reshape(len(gp.alpha_), -1) * scale[None, :1]
    return {"name": name, "amp": float(amp), "noise": float(noise), "ls": ls,
            "X": gp.X_train_ / ls, "alpha": alpha, "L_inv_T": L_inv.T,
            "y_mean": np.atleast_1d(gp._y_train_mean).astype(float), "y_scale": scale}


def _gp_nodes(p: dict[str, Any], t: int) -> tuple[list[Any], dict[str, np.ndarray]]:
    """Nodes and constants computing target ``t``'s mean ``m{t}`` and std ``s{t}`` (n, 1)."""
    def n(name: str) -> str:
        return f"{name}{t}"

    consts = {n("inv_ls"): 1.0 / p["ls"][None, :], n("Xt_T"): p["X"].T.copy(),
              n("Xt_sq"): (p["X"] ** 2).sum(axis=1)[None, :], n("amp"): np.array(p["amp"]),
              n("prior_var"): np.array(p["amp"] + p["noise"]), n("alpha"): p["alpha"],
              n("y_mean"): p["y_mean"][None, :], n("L_inv_T"): p["L_inv_T"]}
    nodes = [helper.make_node("Mul", ["x", n("inv_ls")], [n("xs")]),
             helper.make_node("Mul", [n("xs"), n("xs")], [n("xs2")]),
             helper.make_node("ReduceSum", [n("xs2"), "axis1"], [n("xsq")], keepdims=1),
             helper.make_node("MatMul", [n("xs"), n("Xt_T")], [n("cross")]),
             helper.make_node("Mul", [n("cross"), "minus2"], [n("cross2")]),
             helper.make_node("Add", [n("cross2"), n("xsq")], [n("d2a")]),
             helper.make_node("Add", [n("d2a"), n("Xt_sq")], [n("d2b")]),
             helper.make_node("Max", [n("d2b"), "zero"], [n("d2")])]
    if p["name"] == "rbf":
        nodes += [helper.make_node("Mul", [n("d2"), "minus_half"], [n("e")]),
                  helper.make_node("Exp", [n("e")], [n("kcore")])]
    else:  # Matern 5/2: (1 + r + r^2/3) exp(-r), r = sqrt(5) d
        nodes += [helper.make_node("Mul", [n("d2"), "five"], [n("r2")]),
                  helper.make_node("Sqrt", [n("r2")], [n("r")]),
                  helper.make_node("Mul", [n("r2"), "third"], [n("r2t")]),
                  helper.make_node("Add", [n("r"), n("r2t")], [n("poly0")]),
                  helper.make_node("Add", [n("poly0"), "one"], [n("poly")]),
                  helper.make_node("Neg", [n("r")], [n("nr")]),
                  helper.make_node("Exp", [n("nr")], [n("er")]),
                  helper.make_node("Mul", [n("poly"), n("er")], [n("kcore")])]
    nodes += [helper.make_node("Mul", [n("kcore"), n("amp")], [n("kstar")]),
              helper.make_node("MatMul", [n("kstar"), n("alpha")], [n("m0")]),
              helper.make_node("Add", [n("m0"), n("y_mean")], [n("m")]),
              helper.make_node("MatMul", [n("kstar"), n("L_inv_T")], [n("v")]),
              helper.make_node("Mul", [n("v"), n("v")], [n("v2")]),
              helper.make_node("ReduceSum", [n("v2"), "axis1"], [n("vsum")], keepdims=1),
              helper.make_node("Sub", [n("prior_var"), n("vsum")], [n("var0")]),
              helper.make_node("Max", [n("var0"), "zero"], [n("var")]),
              helper.make_node("Mul", [n("var"), n("y_var")], [n("vy")])]
    consts[n("y_var")] = np.array(p["y_scale"][0] ** 2)
    return nodes, consts


def export_gp(estimator: Any, B: np.ndarray, b: np.ndarray,
              metadata: Mapping[str, Any]) -> bytes:
    """ONNX bytes (float64 input) of a fitted :class:`surrogate.estimators.gp.GPSurrogateRegressor`.

    Per target, the graph computes exactly what scikit-learn's ``predict(return_std=True)``
    does::

        K* = amp * kernel(x / ls, X_train / ls)          (n, N)
        mean = K* @ alpha * y_scale + y_mean
        var  = (amp + noise - || K* @ L^-T ||^2) y_scale^2   (L: Cholesky of K + noise I)

    then the output map: log_mean = mean @ B + b, log_std^2 = var @ B^2 (independent targets).
    It is built directly rather than with skl2onnx 1.20, whose GP converter crashes on a
    Matern kernel, and whose std uses an explicit K^-1 (var = k** - k* K^-1 k*), which cancels
    catastrophically once cond(K) is large (measured: |d ln std| of 0.036 on a smooth
    synthetic set where this graph agrees to 1e-10)."""
    parts = [_gp_parts(gp) for gp in estimator.gps_]
    B = np.asarray(B, dtype=float)
    if B.shape[0] != len(parts):
        raise ValueError(f"output map has {B.shape[0]} rows, the GP {len(parts)} targets")
    consts: dict[str, np.ndarray] = {
        "minus2": np.array(-2.0), "zero": np.array(0.0), "minus_half": np.array(-0.5),
        "five": np.array(5.0), "third": np.array(1.0 / 3.0), "one": np.array(1.0),
        "out_B": B, "out_B2": B**2, "out_b": np.asarray(b, float)[None, :],
        "axis1": np.array([1], np.int64)}
    nodes = []
    for t, p in enumerate(parts):
        more, c = _gp_nodes(p, t)
        nodes += more
        consts.update(c)
    T = len(parts)
    used = {name for node in nodes for name in node.input} | {"out_B", "out_B2", "out_b"}
    consts = {n: v for n, v in consts.items() if n in used}
    nodes += [helper.make_node("Concat", [f"m{t}" for t in range(T)], ["gp_mean"], axis=1),
              helper.make_node("Concat", [f"vy{t}" for t in range(T)], ["gp_var"], axis=1),
              helper.make_node("MatMul", ["gp_mean", "out_B"], ["lm0"]),
              helper.make_node("Add", ["lm0", "out_b"], ["log_mean"]),
              helper.make_node("MatMul", ["gp_var", "out_B2"], ["lv"]),
              helper.make_node("Sqrt", ["lv"], ["log_std"])]
    k, d = B.shape[1], parts[0]["X"].shape[1]
    dbl = onnx.TensorProto.DOUBLE
    graph = helper.make_graph(
        nodes, "gp", [helper.make_tensor_value_info("x", dbl, [None, d])],
        [helper.make_tensor_value_info(n, dbl, [None, k]) for n in ("log_mean", "log_std")],
        initializer=[numpy_helper.from_array(np.asarray(v, dtype=np.int64 if n == "axis1"
                                                        else np.float64), n)
                     for n, v in consts.items()])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", GP_OPSET)],
                              producer_name="hapticrom")
    return finish_model(model, metadata)
