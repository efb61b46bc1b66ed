"""The graph rewrite of surrogate.estimators.export: float64 MatMul by a constant as Gemm."""

from __future__ import annotations

import numpy as np
import onnx
import onnxruntime as ort
from onnx import TensorProto, helper, numpy_helper

from surrogate.estimators.export import double_matmuls_as_gemm


def _graph(dtype: type, shared: bool) -> onnx.ModelProto:
    """x (n, 3) -> y = x @ W (n, 4), and z = x3 @ W (batch of matrices, rank 3) when
    ``shared`` (the constant then also feeds a node the rewrite must leave alone)."""
    elem = TensorProto.DOUBLE if dtype == np.float64 else TensorProto.FLOAT
    W = np.arange(12.0, dtype=dtype).reshape(3, 4) / 7.0
    nodes = [helper.make_node("MatMul", ["x", "W"], ["y"])]
    inputs = [helper.make_tensor_value_info("x", elem, [None, 3])]
    outputs = [helper.make_tensor_value_info("y", elem, [None, 4])]
    if shared:
        nodes.append(helper.make_node("MatMul", ["x3", "W"], ["z"]))
        inputs.append(helper.make_tensor_value_info("x3", elem, [2, None, 3]))
        outputs.append(helper.make_tensor_value_info("z", elem, [2, None, 4]))
    graph = helper.make_graph(nodes, "g", inputs, outputs, [numpy_helper.from_array(W, "W")])
    return helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)],
                             ir_version=9)


def _run(model: onnx.ModelProto, feeds: dict[str, np.ndarray]) -> list[np.ndarray]:
    session = ort.InferenceSession(model.SerializeToString(),
                                   providers=["CPUExecutionProvider"])
    return session.run(None, feeds)


def test_a_float64_matmul_by_a_constant_becomes_gemm_with_the_same_answer():
    rng = np.random.default_rng(0)
    feeds = {"x": rng.standard_normal((5, 3)), "x3": rng.standard_normal((2, 5, 3))}
    want = _run(_graph(np.float64, True), feeds)
    rewritten = double_matmuls_as_gemm(_graph(np.float64, True))
    onnx.checker.check_model(rewritten)
    assert [n.op_type for n in rewritten.graph.node] == ["Gemm", "MatMul"]  # rank 3 kept
    assert {i.name for i in rewritten.graph.initializer} == {"W", "W__T"}
    for got, ref in zip(_run(rewritten, feeds), want, strict=True):
        np.testing.assert_allclose(got, ref, rtol=1e-15, atol=1e-15)
    alone = double_matmuls_as_gemm(_graph(np.float64, False))
    assert [i.name for i in alone.graph.initializer] == ["W__T"]  # the untransposed copy dropped
    np.testing.assert_allclose(_run(alone, {"x": feeds["x"]})[0], want[0], rtol=1e-15)


def test_float32_graphs_are_left_alone():
    model = double_matmuls_as_gemm(_graph(np.float32, False))
    assert [n.op_type for n in model.graph.node] == ["MatMul"]
    assert [i.name for i in model.graph.initializer] == ["W"]
