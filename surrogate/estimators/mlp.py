"""A scikit-learn MLP baseline: one ``MLPRegressor`` on standardised inputs and targets.

The peer of the NN ensemble (:mod:`surrogate.estimators.nn`): the same targets (log center
amplitude and the POD coefficients of the log profile), one network instead of an ensemble, and
therefore no spread to estimate its own error from. Its ``log_std`` is the held-in residual RMS
of each target (homoscedastic: the same for every design), an honest but coarse error bar.

Exported with skl2onnx (the converter of ``StandardScaler`` and ``MLPRegressor`` is exact up
to float32 rounding); the target scaling and the output map of
:class:`surrogate.pod.ProfileTargets` are appended as ONNX nodes, so the graph has the one
contract of :mod:`surrogate.estimators.export` (input ``x`` float32; outputs ``log_mean``,
``log_std``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import onnx
from onnx import helper, numpy_helper
from skl2onnx import convert_sklearn
from skl2onnx.common.data_types import FloatTensorType
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.neural_network import MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.validation import check_is_fitted, validate_data

from surrogate.estimators.export import finish_model
from surrogate.estimators.params import check_choice, check_number, training_data
from surrogate.kind import SurrogateKind

__all__ = ["KIND", "MLPBaselineRegressor", "export_mlp"]

#: Opset of the exported graph (read by every onnxruntime >= 1.14).
OPSET = 18
ACTIVATIONS = ("relu", "tanh", "logistic")


class MLPBaselineRegressor(RegressorMixin, BaseEstimator):
    """scikit-learn ``MLPRegressor`` baseline with a constant (residual RMS) std.

    Parameters:
        hidden: hidden layer widths (one or more integers >= 1).
        activation: "relu", "tanh" or "logistic".
        alpha: L2 penalty, [0, 1].
        learning_rate: Adam step size, (0, 1].
        max_iter: training epochs at most, [1, 1e6].
        random_state: seed of the weights and of the shuffling.
    """

    def __init__(self, hidden: tuple[int, ...] = (64, 64), activation: str = "tanh",
                 alpha: float = 1e-4, learning_rate: float = 1e-3, max_iter: int = 2000,
                 random_state: int = 0) -> None:
        self.hidden = hidden
        self.activation = activation
        self.alpha = alpha
        self.learning_rate = learning_rate
        self.max_iter = max_iter
        self.random_state = random_state

    def _check_params(self) -> None:
        hidden = tuple(self.hidden) if isinstance(self.hidden, list | tuple) else ()
        if not hidden or not all(isinstance(h, int) and h >= 1 for h in hidden):
            raise ValueError(f"hidden = {self.hidden!r}: allowed one or more integer widths >= 1")
        check_choice("activation", self.activation, ACTIVATIONS)
        check_number("alpha", self.alpha, 0, 1)
        check_number("learning_rate", self.learning_rate, 0, 1, low_open=True)
        check_number("max_iter", self.max_iter, 1, 10**6, integer=True)
        check_number("random_state", self.random_state, 0, 2**32 - 1, integer=True)

    def fit(self, X: Any, y: Any) -> MLPBaselineRegressor:
        """Fit on features ``X`` (n, d) and targets ``y`` (n, t) or (n,)."""
        self._check_params()
        X, Y, self._y_1d = training_data(self, X, y)
        self.y_mean_ = Y.mean(axis=0)
        scale = Y.std(axis=0)
        self.y_scale_ = np.where(scale > 0, scale, 1.0)
        net = MLPRegressor(hidden_layer_sizes=tuple(self.hidden), activation=self.activation,
                           alpha=self.alpha, learning_rate_init=self.learning_rate,
                           max_iter=self.max_iter, random_state=self.random_state,
                           early_stopping=len(X) >= 50, n_iter_no_change=50, tol=1e-7)
        self.pipeline_ = Pipeline([("scale", StandardScaler()), ("mlp", net)])
        self.pipeline_.fit(X, (Y - self.y_mean_) / self.y_scale_)
        resid = self._mean(X) - Y
        self.residual_std_ = np.sqrt(np.mean(resid**2, axis=0))
        return self

    def _mean(self, X: np.ndarray) -> np.ndarray:
        raw = self.pipeline_.predict(X).reshape(len(X), -1)
        return raw * self.y_scale_ + self.y_mean_

    def predict(self, X: Any, return_std: bool = False) -> Any:
        """Mean of the targets (and their constant std with ``return_std``)."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=float, reset=False)
        mean = self._mean(X)
        std = np.broadcast_to(self.residual_std_, mean.shape).copy()
        if self._y_1d:
            mean, std = mean[:, 0], std[:, 0]
        return (mean, std) if return_std else mean


def export_mlp(estimator: MLPBaselineRegressor, B: np.ndarray, b: np.ndarray,
               metadata: Mapping[str, Any]) -> bytes:
    """ONNX bytes (float32 input) of a fitted :class:`MLPBaselineRegressor`: the skl2onnx
    graph of its pipeline, then ``log_mean = (raw * y_scale + y_mean) @ B + b`` folded into
    one MatMul and Add, and ``log_std = sqrt(residual_std^2 @ B^2)`` expanded to the batch."""
    check_is_fitted(estimator)
    d = estimator.n_features_in_
    model = convert_sklearn(estimator.pipeline_, initial_types=[("x", FloatTensorType([None, d]))],
                            target_opset=OPSET)
    raw = model.graph.output[0].name
    del model.graph.output[:]
    last = model.graph.node[-1]
    if last.op_type == "Reshape" and last.output[0] == raw:
        # skl2onnx 1.20's MLPRegressor converter ends with Reshape(-1, 1), which flattens a
        # multi-output network (3 rows of 2 targets come out as 6 x 1): take the (n, t)
        # result before it.
        raw = last.input[0]
        model.graph.node.remove(last)
    B = np.asarray(B, dtype=float)
    scale = estimator.y_scale_[:, None]
    consts = {"out_B": (scale * B).astype(np.float32),
              "out_b": (estimator.y_mean_ @ B + np.asarray(b, float))[None, :].astype(np.float32),
              "out_std": np.sqrt((estimator.residual_std_**2) @ B**2)[None, :]
              .astype(np.float32)}
    model.graph.initializer.extend(numpy_helper.from_array(v, n) for n, v in consts.items())
    model.graph.node.extend([
        helper.make_node("MatMul", [raw, "out_B"], ["lm0"]),
        helper.make_node("Add", ["lm0", "out_b"], ["log_mean"]),
        helper.make_node("Shape", ["log_mean"], ["mean_shape"]),
        helper.make_node("Expand", ["out_std", "mean_shape"], ["log_std"])])
    k = B.shape[1]
    model.graph.output.extend(
        [helper.make_tensor_value_info(n, onnx.TensorProto.FLOAT, [None, k])
         for n in ("log_mean", "log_std")])
    return finish_model(model, metadata)


KIND = SurrogateKind(
    name="mlp", summary="scikit-learn MLPRegressor baseline (harmonic amplitudes)",
    estimator=MLPBaselineRegressor, export=export_mlp, parity_tol=1e-4, dtype="float32",
    quick_options={"max_iter": 200})
