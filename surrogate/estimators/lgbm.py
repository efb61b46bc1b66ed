"""A LightGBM peer: one gradient-boosted tree ensemble per target (issue 20's LightGBM peer).

The same targets as every steady-state kind (log center amplitude and the POD coefficients of
the log profile, :class:`surrogate.pod.ProfileTargets`), one LightGBM booster per target.
Trees have no spread to estimate their own error from: ``log_std`` is the RMS residual of each
target on a held-out tenth of the training rows (boosters refitted on that split first, then on
all rows), homoscedastic like the MLP baseline's (:mod:`surrogate.estimators.mlp`).

Exported as one ``ai.onnx.ml`` ``TreeEnsembleRegressor`` node (every booster's trees, each
tagged with its target) on float64 input with float64 thresholds and leaf values, so the graph
splits exactly where LightGBM does (the node's sum comes out as float32, opset 3 has no other
output type: parity about 1e-6 in log amplitude); then ``log_mean = raw @ B + b`` in float64
and the constant std, so the graph has the one contract of :mod:`surrogate.estimators.export`.
``lightgbm`` (the ``bench`` extra) is imported when a model is fitted, not when this module is:
the kind is registered either way and says what to install when it is used without it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from onnx import TensorProto, helper, numpy_helper
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from surrogate.estimators.export import finish_model
from surrogate.estimators.params import check_number, training_data
from surrogate.kind import SurrogateKind

__all__ = ["KIND", "LightGBMRegressor", "export_lgbm"]

#: Opsets of the exported graph: ai.onnx.ml 3 has the float64 (``*_as_tensor``) attributes.
OPSET, ML_OPSET = 18, 3
#: Fraction of the training rows held out to measure the residual std (and rows needed).
STD_FRACTION, STD_MIN_ROWS = 0.1, 20


def _lightgbm() -> Any:
    try:
        # optional (the `bench` extra): only the LightGBM peer needs it
        import lightgbm
    except ImportError as exc:
        raise ImportError("the lgbm kind needs the lightgbm package: pip install "
                          "'hapticrom[bench]' (or lightgbm>=4)") from exc
    return lightgbm


class LightGBMRegressor(RegressorMixin, BaseEstimator):
    """One LightGBM booster per target with a constant (held-out residual RMS) std.

    Parameters:
        n_estimators: trees per target, [1, 1e5].
        learning_rate: shrinkage, (0, 1].
        num_leaves: leaves per tree, [2, 4096].
        min_child_samples: rows per leaf at least, [1, 1e6].
        subsample: row fraction per tree (bagging every tree), (0, 1].
        random_state: seed of the bagging and of the held-out split.
    """

    def __init__(self, n_estimators: int = 3000, learning_rate: float = 0.02,
                 num_leaves: int = 15, min_child_samples: int = 5, subsample: float = 0.8,
                 random_state: int = 0) -> None:
        self.n_estimators = n_estimators
        self.learning_rate = learning_rate
        self.num_leaves = num_leaves
        self.min_child_samples = min_child_samples
        self.subsample = subsample
        self.random_state = random_state

    def _check_params(self) -> None:
        check_number("n_estimators", self.n_estimators, 1, 10**5, integer=True)
        check_number("learning_rate", self.learning_rate, 0, 1, low_open=True)
        check_number("num_leaves", self.num_leaves, 2, 4096, integer=True)
        check_number("min_child_samples", self.min_child_samples, 1, 10**6, integer=True)
        check_number("subsample", self.subsample, 0, 1, low_open=True)
        check_number("random_state", self.random_state, 0, 2**31 - 1, integer=True)

    def _boosters(self, X: np.ndarray, Y: np.ndarray) -> list[Any]:
        lgb = _lightgbm()
        params = dict(n_estimators=self.n_estimators, learning_rate=self.learning_rate,
                      num_leaves=self.num_leaves, min_child_samples=self.min_child_samples,
                      subsample=self.subsample, subsample_freq=1 if self.subsample < 1 else 0,
                      random_state=self.random_state, n_jobs=1, verbose=-1)
        return [lgb.LGBMRegressor(**params).fit(X, Y[:, j]) for j in range(Y.shape[1])]

    def fit(self, X: Any, y: Any) -> LightGBMRegressor:
        """Fit on features ``X`` (n, d) and targets ``y`` (n, t) or (n,)."""
        self._check_params()
        X, Y, self._y_1d = training_data(self, X, y)
        if len(X) >= STD_MIN_ROWS:
            order = np.random.default_rng(self.random_state).permutation(len(X))
            k = max(2, round(STD_FRACTION * len(X)))
            held, kept = order[:k], order[k:]
            first = self._boosters(X[kept], Y[kept])
            resid = np.column_stack([m.predict(X[held]) for m in first]) - Y[held]
        else:
            first = self._boosters(X, Y)
            resid = np.column_stack([m.predict(X) for m in first]) - Y
        self.residual_std_ = np.sqrt(np.mean(resid**2, axis=0))
        self.boosters_ = [m.booster_ for m in self._boosters(X, Y)]
        return self

    def _mean(self, X: np.ndarray) -> np.ndarray:
        return np.column_stack([b.predict(X) for b in self.boosters_])

    def predict(self, X: Any, return_std: bool = False) -> Any:
        """Mean of the targets (and their constant std with ``return_std``)."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=float, reset=False)
        mean = self._mean(X)
        std = np.broadcast_to(self.residual_std_, mean.shape).copy()
        if self._y_1d:
            mean, std = mean[:, 0], std[:, 0]
        return (mean, std) if return_std else mean


def _tree_nodes(tree: Mapping[str, Any], tid: int, target: int, a: dict[str, list[Any]]
                ) -> None:
    """Append one LightGBM tree (``dump_model`` form) to the TreeEnsembleRegressor lists."""
    ids: dict[int, int] = {}
    stack = [tree]
    order = []
    while stack:  # number the nodes depth first, root 0
        node = stack.pop()
        ids[id(node)] = len(order)
        order.append(node)
        if "leaf_value" not in node:
            stack += [node["right_child"], node["left_child"]]
    for node in order:
        a["nodes_treeids"].append(tid)
        a["nodes_nodeids"].append(ids[id(node)])
        if "leaf_value" in node:
            a["nodes_modes"].append("LEAF")
            a["nodes_featureids"].append(0)
            a["nodes_values"].append(0.0)
            a["nodes_truenodeids"].append(0)
            a["nodes_falsenodeids"].append(0)
            a["target_treeids"].append(tid)
            a["target_nodeids"].append(ids[id(node)])
            a["target_ids"].append(target)
            a["target_weights"].append(float(node["leaf_value"]))
            continue
        if node.get("decision_type") != "<=" or node.get("missing_type") not in ("None", None):
            raise ValueError(f"LightGBM split {node.get('decision_type')!r} with missing type "
                             f"{node.get('missing_type')!r}: only '<=' splits without missing "
                             "values export")
        a["nodes_modes"].append("BRANCH_LEQ")
        a["nodes_featureids"].append(int(node["split_feature"]))
        a["nodes_values"].append(float(node["threshold"]))
        a["nodes_truenodeids"].append(ids[id(node["left_child"])])
        a["nodes_falsenodeids"].append(ids[id(node["right_child"])])


def export_lgbm(estimator: LightGBMRegressor, B: np.ndarray, b: np.ndarray,
                metadata: Mapping[str, Any]) -> bytes:
    """ONNX bytes (float64 input) of a fitted :class:`LightGBMRegressor`:
    ``log_mean = trees(x) @ B + b``, ``log_std = sqrt(residual_std^2 @ B^2)`` for every row."""
    check_is_fitted(estimator)
    a: dict[str, list[Any]] = {k: [] for k in (
        "nodes_treeids", "nodes_nodeids", "nodes_modes", "nodes_featureids", "nodes_values",
        "nodes_truenodeids", "nodes_falsenodeids", "target_treeids", "target_nodeids",
        "target_ids", "target_weights")}
    tid = 0
    for target, booster in enumerate(estimator.boosters_):
        for info in booster.dump_model()["tree_info"]:
            _tree_nodes(info["tree_structure"], tid, target, a)
            tid += 1
    t = len(estimator.boosters_)
    values = numpy_helper.from_array(np.asarray(a.pop("nodes_values"), float), "v")
    weights = numpy_helper.from_array(np.asarray(a.pop("target_weights"), float), "w")
    trees = helper.make_node(
        "TreeEnsembleRegressor", ["x"], ["raw"], domain="ai.onnx.ml", n_targets=t,
        aggregate_function="SUM", post_transform="NONE", nodes_values_as_tensor=values,
        target_weights_as_tensor=weights,
        nodes_missing_value_tracks_true=[0] * len(a["nodes_treeids"]), **a)
    B = np.asarray(B, dtype=float)
    consts = {"out_B": B, "out_b": np.asarray(b, float)[None, :],
              "out_std": np.sqrt((estimator.residual_std_**2) @ B**2)[None, :]}
    k, d = B.shape[1], estimator.n_features_in_
    graph = helper.make_graph(
        [trees, helper.make_node("Cast", ["raw"], ["raw64"], to=TensorProto.DOUBLE),
         helper.make_node("MatMul", ["raw64", "out_B"], ["lm0"]),
         helper.make_node("Add", ["lm0", "out_b"], ["log_mean"]),
         helper.make_node("Shape", ["log_mean"], ["mean_shape"]),
         helper.make_node("Expand", ["out_std", "mean_shape"], ["log_std"])],
        "lgbm", [helper.make_tensor_value_info("x", TensorProto.DOUBLE, [None, d])],
        [helper.make_tensor_value_info(n, TensorProto.DOUBLE, [None, k])
         for n in ("log_mean", "log_std")],
        [numpy_helper.from_array(v, n) for n, v in consts.items()])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", OPSET),
                                                    helper.make_opsetid("ai.onnx.ml", ML_OPSET)])
    return finish_model(model, metadata)


def _card_extras(est: LightGBMRegressor) -> dict[str, Any]:
    return {"lgbm_trees_per_target": int(est.n_estimators),
            "lgbm_targets": len(est.boosters_)}


KIND = SurrogateKind(
    name="lgbm", summary="LightGBM peer, one booster per target (harmonic amplitudes)",
    estimator=LightGBMRegressor, export=export_lgbm, parity_tol=1e-5, dtype="float64",
    engine="lightgbm", card_extras=_card_extras,
    quick_options={"n_estimators": 200, "learning_rate": 0.05})
