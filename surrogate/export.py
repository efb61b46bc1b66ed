"""ONNX export of the surrogates, one graph contract for all of them.

Every exported graph has one input ``x`` (batch, n_features) -- the encoded features of
:mod:`surrogate.runtime.encoding` -- and two outputs of shape (batch, 3 + m): ``log_mean``
and ``log_std``, the natural log of [center, edge, normalized edge, profile...] and its
predictive standard deviation (:func:`surrogate.pod.output_columns`). The linear output map
of :class:`surrogate.pod.ProfileTargets` and all scaling are inside the graph; the batch axis
is dynamic. Descriptive metadata (inputs, units, ranges, data hash, metrics) go into the
model's ``metadata_props`` as JSON strings.

* NN: ``torch.onnx.export`` (dynamo exporter), float32, a single file (no external data).
* GP: skl2onnx in float64 (float32 is unusable for a GP: the solve with K^-1 loses all
  digits) with ``return_std``; skl2onnx 1.20 cannot give per-target std for several targets,
  so the converted model is a twin with the target scales folded into ``alpha_``, whose std
  is the shared unit std s(x); the appended nodes scale it per output column.
"""

from __future__ import annotations

import copy
import io
import json
from collections.abc import Mapping
from typing import Any

import numpy as np
import onnx
from onnx import helper, numpy_helper

__all__ = ["MAX_IR_VERSION", "export_gp", "export_nn", "set_metadata"]

#: onnx >= 1.23 writes IR 14 by default; onnxruntime 1.31 reads at most 13.
MAX_IR_VERSION = 10
#: Opset of the GP graph (skl2onnx) -- read by every onnxruntime >= 1.14.
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


def _gp_twin(gp: Any) -> Any:
    """Copy of a fitted multi-target GaussianProcessRegressor whose target scale is 1 (folded
    into ``alpha_``): same mean, and its std is the unit std s(x) of the shared kernel."""
    twin = copy.deepcopy(gp)
    scale = np.atleast_1d(gp._y_train_std)
    twin.alpha_ = gp.alpha_ * scale[None, :] if gp.alpha_.ndim == 2 else gp.alpha_ * scale
    twin._y_train_std = np.array([1.0])
    return twin


def export_gp(estimator: Any, B: np.ndarray, b: np.ndarray,
              metadata: Mapping[str, Any]) -> bytes:
    """ONNX bytes (float64 input) of a fitted :class:`surrogate.gp.GPSurrogateRegressor`."""
    from skl2onnx import convert_sklearn
    from skl2onnx.common.data_types import DoubleTensorType
    from sklearn.gaussian_process import GaussianProcessRegressor

    if estimator.kernel != "rbf":
        raise ValueError(f"kernel = {estimator.kernel!r}: only 'rbf' exports to ONNX "
                         "(skl2onnx cannot convert a Matern kernel correctly)")
    gp = estimator.gp_
    d = estimator.n_features_in_
    # options: the default graph, never "cdist" (it hard-codes squared-Euclidean distances
    # and needs a com.microsoft operator).
    model = convert_sklearn(_gp_twin(gp), initial_types=[("x", DoubleTensorType([None, d]))],
                            options={GaussianProcessRegressor: {"return_std": True}},
                            target_opset=GP_OPSET)
    mean_name, std_name = (o.name for o in model.graph.output)
    scale = np.atleast_1d(gp._y_train_std).astype(float)
    B = np.asarray(B, dtype=float)
    if B.shape[0] != scale.size:
        raise ValueError(f"output map has {B.shape[0]} rows, the GP {scale.size} targets")
    # independent targets with one shared kernel: var_j = s^2 * sum_t (scale_t B_tj)^2
    col_std = np.sqrt((scale[:, None] ** 2 * B**2).sum(axis=0))[None, :]
    g = model.graph
    g.initializer.extend([numpy_helper.from_array(B, "out_B"),
                          numpy_helper.from_array(np.asarray(b, float)[None, :], "out_b"),
                          numpy_helper.from_array(col_std, "out_colstd"),
                          numpy_helper.from_array(np.array([1], np.int64), "axis1")])
    g.node.extend([helper.make_node("MatMul", [mean_name, "out_B"], ["lm0"]),
                   helper.make_node("Add", ["lm0", "out_b"], ["log_mean"]),
                   helper.make_node("Unsqueeze", [std_name, "axis1"], ["s1"]),
                   helper.make_node("Mul", ["s1", "out_colstd"], ["log_std"])])
    k = B.shape[1]
    del g.output[:]
    g.output.extend([helper.make_tensor_value_info(n, onnx.TensorProto.DOUBLE, [None, k])
                     for n in ("log_mean", "log_std")])
    return _finish(model, metadata)
