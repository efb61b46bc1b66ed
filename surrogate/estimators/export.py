"""ONNX export of the surrogates, one graph contract for all of them.

Every exported graph has one input ``x`` (batch, n_features) -- the encoded features of
:mod:`surrogate.runtime.encoding` -- and two outputs of shape (batch, 3 + m): ``log_mean``
and ``log_std``, the natural log of [center, edge, normalized edge, profile...] and its
predictive standard deviation (:func:`surrogate.pod.output_columns`). The linear output map
of :class:`surrogate.pod.ProfileTargets` and all scaling are inside the graph; the batch axis
is dynamic. Descriptive metadata (inputs, units, ranges, data hash, metrics) go into the
model's ``metadata_props`` as JSON strings.

Each kind writes its graph beside its estimator (:mod:`surrogate.estimators`) and finishes it
here (:func:`finish_model`); a torch module is exported by :func:`export_module`
(``torch.onnx.export``, dynamo exporter, a single file without external data): the NN
ensembles in float32, the sweep GP of :mod:`surrogate.sweep.gp_export` in float64.
"""

from __future__ import annotations

import io
import json
from collections.abc import Mapping
from typing import Any

import onnx
from onnx import helper, numpy_helper

__all__ = ["MAX_IR_VERSION", "double_matmuls_as_gemm", "export_module", "finish_model",
           "set_metadata"]

#: onnx >= 1.23 writes IR 14 by default; onnxruntime 1.31 reads at most 13.
MAX_IR_VERSION = 10


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


def export_module(module: Any, n_features: int, metadata: Mapping[str, Any],
                  dtype: str = "float32") -> bytes:
    """ONNX bytes of a torch module ``x (batch, n_features) dtype -> (log_mean, log_std)``
    (the NN ensembles: :func:`surrogate.estimators.nn.export_nn`, the sweep models of
    :mod:`surrogate.sweep.export`; ``dtype`` "float64": the sweep GP of
    :mod:`surrogate.sweep.gp_export`)."""
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
    return finish_model(double_matmuls_as_gemm(model), metadata)


def double_matmuls_as_gemm(model: onnx.ModelProto) -> onnx.ModelProto:
    """``model`` with every float64 MatMul of a 2-D activation by a 2-D constant rewritten as
    Gemm with the constant stored transposed (``transB = 1``): the same products, but
    onnxruntime runs float64 MatMul through a slower path than float64 Gemm (at one design the
    sweep GP's kernel and K* @ alpha over 6,636 designs took 1.7x as long,
    ``bench/runtime/gp_dtype_cost.py``; float32 MatMul is fast and is left alone).
    A node whose activation's rank is not known from shape inference is left alone too."""
    inferred = onnx.shape_inference.infer_shapes(model)
    rank = {v.name: len(v.type.tensor_type.shape.dim)
            for v in [*inferred.graph.value_info, *inferred.graph.input]
            if v.type.tensor_type.HasField("shape")}
    consts = {i.name: i for i in model.graph.initializer}
    nodes, used_plain = [], set()
    for node in model.graph.node:
        b = consts.get(node.input[1]) if node.op_type == "MatMul" else None
        if (b is None or b.data_type != onnx.TensorProto.DOUBLE or len(b.dims) != 2
                or rank.get(node.input[0]) != 2):
            nodes.append(node)
            used_plain.update(node.input)
            continue
        name = f"{b.name}__T"
        if name not in consts:
            consts[name] = numpy_helper.from_array(numpy_helper.to_array(b).T.copy(), name)
            model.graph.initializer.append(consts[name])
        nodes.append(helper.make_node("Gemm", [node.input[0], name], list(node.output),
                                      name=node.name, transB=1))
    del model.graph.node[:]
    model.graph.node.extend(nodes)
    # a constant only the rewritten nodes read is kept once, transposed
    kept = [i for i in model.graph.initializer
            if not (i.name + "__T" in consts and i.name not in used_plain)]
    del model.graph.initializer[:]
    model.graph.initializer.extend(kept)
    return model
