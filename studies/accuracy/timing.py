"""Wall-clock helpers shared by the study and the bench scripts: medians, never means."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from onnx import TensorProto, helper

__all__ = ["matmul_rate", "median_us", "one_add_graph", "timed"]


def median_us(fn: Callable[[], Any], n: int, repeat: int = 5) -> float:
    """Median over ``repeat`` blocks of the mean time of ``n`` calls [us] (one warm-up call)."""
    fn()
    blocks = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        blocks.append((time.perf_counter() - t0) / n * 1e6)
    return float(np.median(blocks))


def timed(fn: Callable[[], Any], repeat: int) -> tuple[Any, float]:
    """(last result, median wall time [s]) of ``repeat`` calls of ``fn``."""
    times, out = [], None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times)


def one_add_graph(n_features: int) -> bytes:
    """ONNX bytes of y = x + x on a float32 (batch, n_features) input: the floor of any
    onnxruntime call on this machine."""
    io = [helper.make_tensor_value_info(n, TensorProto.FLOAT, [None, n_features])
          for n in ("x", "y")]
    graph = helper.make_graph([helper.make_node("Add", ["x", "x"], ["y"])], "floor", [io[0]],
                              [io[1]])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)])
    model.ir_version = 10
    return model.SerializeToString()


def matmul_rate(dtype: Any = np.float32, n: int = 512) -> float:
    """Dense matmul rate of this machine on the current thread setting [FLOP/s] (median)."""
    a = np.random.default_rng(0).random((n, n)).astype(dtype)
    t = median_us(lambda: a @ a, 5) * 1e-6
    return 2.0 * n**3 / t
