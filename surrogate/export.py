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

__all__ = ["MAX_IR_VERSION", "export_gp", "export_nn", "set_metadata"]

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


def _finish(model: onnx.ModelProto, metadata: Mapping[str, Any]) -> bytes:
    model.ir_version = min(model.ir_version, MAX_IR_VERSION)
    set_metadata(model, metadata)
    onnx.checker.check_model(model)
    return model.SerializeToString()


def export_nn(estimator: Any, B: np.ndarray, b: np.ndarray,
              metadata: Mapping[str, Any]) -> bytes:
    """ONNX bytes of a fitted :class:`surrogate.nn.MLPEnsembleRegressor` (float32 input)."""
    import torch

    module = estimator.to_module(B, b)
    example = torch.zeros(2, estimator.n_features_in_, dtype=torch.float32)
    program = torch.onnx.export(module, (example,), dynamo=True, input_names=["x"],
                                output_names=["log_mean", "log_std"],
                                dynamic_shapes={"x": {0: "batch"}}, optimize=True,
                                verbose=False)
    buf = io.BytesIO()
    program.save(buf, external_data=False) if hasattr(program, "save") else None
    model = onnx.load_from_string(buf.getvalue())
    return _finish(model, metadata)


def _gp_parts(gp: Any) -> dict[str, Any]:
    """Constants of a fitted ``amplitude * ARD(rbf|matern52) + white`` GaussianProcessRegressor."""
    from sklearn.gaussian_process.kernels import RBF, Matern

    k = gp.kernel_
    amp, core, noise = k.k1.k1.constant_value, k.k1.k2, k.k2.noise_level
    if isinstance(core, Matern) and core.nu == 2.5:
        name = "matern52"
    elif isinstance(core, RBF):
        name = "rbf"
    else:
        raise ValueError(f"kernel {core} cannot be exported (rbf or Matern nu=2.5 only)")
    ls = np.broadcast_to(np.asarray(core.length_scale, float), (gp.X_train_.shape[1],))
    L_inv = solve_triangular(gp.L_, np.eye(gp.L_.shape[0]), lower=True)
    scale = np.atleast_1d(gp._y_train_std).astype(float)
    alpha = gp.alpha_.reshape(len(gp.alpha_), -1) * scale[None, :]
    return {"name": name, "amp": float(amp), "noise": float(noise), "ls": ls,
            "X": gp.X_train_ / ls, "alpha": alpha, "L_inv_T": L_inv.T,
            "y_mean": np.atleast_1d(gp._y_train_mean).astype(float), "y_scale": scale}


def export_gp(estimator: Any, B: np.ndarray, b: np.ndarray,
              metadata: Mapping[str, Any]) -> bytes:
    """ONNX bytes (float64 input) of a fitted :class:`surrogate.gp.GPSurrogateRegressor`.

    The graph computes exactly what scikit-learn's ``predict(return_std=True)`` does::

        K* = amp * kernel(x / ls, X_train / ls)          (n, N)
        mean = K* @ alpha * y_scale + y_mean
        var  = amp + noise - || K* @ L^-T ||^2 per row   (L: Cholesky factor of K + noise I)

    It is built directly rather than with skl2onnx 1.20, whose GP converter crashes on a Matern
    kernel, and whose std uses an explicit K^-1 (var = k** - k* K^-1 k*), which cancels
    catastrophically once cond(K) is large (measured: |d ln std| of 0.036 on a smooth
    synthetic set where this graph agrees to 1e-10)."""
    p = _gp_parts(estimator.gp_)
    B = np.asarray(B, dtype=float)
    if B.shape[0] != p["y_scale"].size:
        raise ValueError(f"output map has {B.shape[0]} rows, the GP {p['y_scale'].size} targets")
    # independent targets sharing one kernel: var_j = s^2 * sum_t (scale_t B_tj)^2
    col_std = np.sqrt((p["y_scale"][:, None] ** 2 * B**2).sum(axis=0))[None, :]
    consts = {"inv_ls": 1.0 / p["ls"][None, :], "Xt_T": p["X"].T.copy(),
              "Xt_sq": (p["X"] ** 2).sum(axis=1)[None, :], "minus2": np.array(-2.0),
              "zero": np.array(0.0), "amp": np.array(p["amp"]),
              "prior_var": np.array(p["amp"] + p["noise"]), "alpha": p["alpha"],
              "y_mean": p["y_mean"][None, :], "L_inv_T": p["L_inv_T"], "out_B": B,
              "out_b": np.asarray(b, float)[None, :], "col_std": col_std,
              "axis1": np.array([1], np.int64)}
    nodes = [helper.make_node("Mul", ["x", "inv_ls"], ["xs"]),
             helper.make_node("Mul", ["xs", "xs"], ["xs2"]),
             helper.make_node("ReduceSum", ["xs2", "axis1"], ["xsq"], keepdims=1),
             helper.make_node("MatMul", ["xs", "Xt_T"], ["cross"]),
             helper.make_node("Mul", ["cross", "minus2"], ["cross2"]),
             helper.make_node("Add", ["cross2", "xsq"], ["d2a"]),
             helper.make_node("Add", ["d2a", "Xt_sq"], ["d2b"]),
             helper.make_node("Max", ["d2b", "zero"], ["d2"])]
    if p["name"] == "rbf":
        consts["minus_half"] = np.array(-0.5)
        nodes += [helper.make_node("Mul", ["d2", "minus_half"], ["e"]),
                  helper.make_node("Exp", ["e"], ["kcore"])]
    else:  # Matern 5/2: (1 + r + r^2/3) exp(-r), r = sqrt(5) d
        consts.update(five=np.array(5.0), third=np.array(1.0 / 3.0), one=np.array(1.0))
        nodes += [helper.make_node("Mul", ["d2", "five"], ["r2"]),
                  helper.make_node("Sqrt", ["r2"], ["r"]),
                  helper.make_node("Mul", ["r2", "third"], ["r2t"]),
                  helper.make_node("Add", ["r", "r2t"], ["poly0"]),
                  helper.make_node("Add", ["poly0", "one"], ["poly"]),
                  helper.make_node("Neg", ["r"], ["nr"]),
                  helper.make_node("Exp", ["nr"], ["er"]),
                  helper.make_node("Mul", ["poly", "er"], ["kcore"])]
    nodes += [helper.make_node("Mul", ["kcore", "amp"], ["kstar"]),
              helper.make_node("MatMul", ["kstar", "alpha"], ["m0"]),
              helper.make_node("Add", ["m0", "y_mean"], ["gp_mean"]),
              helper.make_node("MatMul", ["gp_mean", "out_B"], ["lm0"]),
              helper.make_node("Add", ["lm0", "out_b"], ["log_mean"]),
              helper.make_node("MatMul", ["kstar", "L_inv_T"], ["v"]),
              helper.make_node("Mul", ["v", "v"], ["v2"]),
              helper.make_node("ReduceSum", ["v2", "axis1"], ["vsum"], keepdims=1),
              helper.make_node("Sub", ["prior_var", "vsum"], ["var0"]),
              helper.make_node("Max", ["var0", "zero"], ["var"]),
              helper.make_node("Sqrt", ["var"], ["s"]),
              helper.make_node("Mul", ["s", "col_std"], ["log_std"])]
    k, d = B.shape[1], p["X"].shape[1]
    dbl = onnx.TensorProto.DOUBLE
    graph = helper.make_graph(
        nodes, "gp", [helper.make_tensor_value_info("x", dbl, [None, d])],
        [helper.make_tensor_value_info(n, dbl, [None, k]) for n in ("log_mean", "log_std")],
        initializer=[numpy_helper.from_array(np.asarray(v, dtype=np.int64 if n == "axis1"
                                                        else np.float64), n)
                     for n, v in consts.items()])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", GP_OPSET)],
                              producer_name="hapticrom")
    return _finish(model, metadata)
