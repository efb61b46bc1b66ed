"""Gaussian-process regression on encoded design features (scikit-learn).

``GPSurrogateRegressor`` wraps :class:`sklearn.gaussian_process.GaussianProcessRegressor`
with the kernel this project uses: an amplitude times an ARD kernel (one length scale per
feature; features are already scaled to [0, 1] from the space's ranges, log parameters on a
log scale) plus white noise (the FE data is not a smooth function at the resolution it is
sampled: the fitted noise level is part of the honest predictive std). Targets are normalised
(``normalize_y``); each target gets its own GP (own length scales and noise: a shared
kernel over targets as different as a center amplitude and a high POD coefficient collapses
to the shortest length scales and a large noise, measured on the shipped data).

GP fitting is O(n^3) in time and O(n^2) in memory: above ``max_train`` rows a random subset
(seeded) is used, and the subset size is recorded as ``n_train_``.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np
import onnx
from onnx import helper, numpy_helper
from scipy.linalg import solve_triangular
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, Kernel, Matern, WhiteKernel
from sklearn.utils.validation import check_is_fitted, validate_data

from surrogate.estimators.export import finish_model
from surrogate.estimators.params import check_choice, check_number
from surrogate.kind import SurrogateKind

__all__ = ["KERNELS", "KIND", "POD_MODES", "GPSurrogateRegressor", "export_gp"]

#: Kernels offered; both export to ONNX (surrogate.estimators.export) with a parity test each.
KERNELS = ("rbf", "matern52")
#: Length scales on features scaled to [0, 1]: below 0.05 a feature would vary faster than
#: any affordable sample spacing resolves (a GP then degenerates to white noise); above 1e3
#: the feature is irrelevant.
LENGTH_SCALE_BOUNDS = (5e-2, 1e3)


def ard_kernel(name: str, d: int, noise: float, noise_bounds: tuple[float, float]) -> Kernel:
    """amplitude * ARD(name) + white noise, for ``d`` features scaled to [0, 1]."""
    amplitude = ConstantKernel(1.0, (1e-2, 1e2))
    scales = np.ones(max(d, 1))
    if name == "rbf":
        core: Kernel = RBF(scales, LENGTH_SCALE_BOUNDS)
    elif name == "matern52":
        core = Matern(scales, LENGTH_SCALE_BOUNDS, nu=2.5)
    else:
        raise ValueError(f"kernel = {name!r}: allowed {', '.join(KERNELS)}")
    return amplitude * core + WhiteKernel(noise, noise_bounds)


class GPSurrogateRegressor(RegressorMixin, BaseEstimator):
    """ARD Gaussian processes with predictive std (one per target).

    Parameters:
        kernel: "rbf" or "matern52" (see ``KERNELS``).
        noise: initial white-noise variance (of normalised targets); noise_bounds its bounds.
        n_restarts_optimizer: extra random starts of the hyperparameter search.
        max_train: rows used at most (a seeded random subset above it).
        random_state: seed of the subset and the restarts.
    """

    def __init__(self, kernel: str = "rbf", noise: float = 1e-2,
                 noise_bounds: tuple[float, float] = (1e-5, 1.0),
                 n_restarts_optimizer: int = 0, max_train: int = 1000,
                 random_state: int = 0) -> None:
        self.kernel = kernel
        self.noise = noise
        self.noise_bounds = noise_bounds
        self.n_restarts_optimizer = n_restarts_optimizer
        self.max_train = max_train
        self.random_state = random_state

    def fit(self, X: Any, y: Any) -> GPSurrogateRegressor:
        self._check_params()
        X, y = validate_data(self, X, y, dtype=float, multi_output=True, y_numeric=True)
        rng = np.random.default_rng(self.random_state)
        if len(X) > self.max_train:
            keep = np.sort(rng.choice(len(X), self.max_train, replace=False))
            X, y = X[keep], y[keep]
        Y = y.reshape(len(y), -1)
        self.gps_ = []
        for t in range(Y.shape[1]):
            gp = GaussianProcessRegressor(
                ard_kernel(self.kernel, X.shape[1], self.noise, self.noise_bounds),
                normalize_y=True, n_restarts_optimizer=self.n_restarts_optimizer,
                random_state=int(rng.integers(2**31)))
            with warnings.catch_warnings():  # a length scale at its bound means "irrelevant"
                warnings.simplefilter("ignore", ConvergenceWarning)
                gp.fit(X, Y[:, t])
            self.gps_.append(gp)
        self._y_1d = y.ndim == 1
        self.n_train_ = len(X)
        return self

    def _check_params(self) -> None:
        check_choice("kernel", self.kernel, KERNELS)
        check_number("noise", self.noise, 0, 1e3, low_open=True)
        low, high = self.noise_bounds
        if not 0 < low <= self.noise <= high:
            raise ValueError(f"noise_bounds = {self.noise_bounds!r}: allowed 0 < low <= "
                             f"noise ({self.noise:g}) <= high")
        check_number("n_restarts_optimizer", self.n_restarts_optimizer, 0, 100, integer=True)
        check_number("max_train", self.max_train, 2, 20000, integer=True)
        check_number("random_state", self.random_state, 0, 2**32 - 1, integer=True)

    def __sklearn_tags__(self) -> Any:
        tags = super().__sklearn_tags__()
        tags.target_tags.multi_output = True
        return tags

    def predict(self, X: Any, return_std: bool = False) -> Any:
        check_is_fitted(self)
        X = validate_data(self, X, dtype=float, reset=False)
        parts = [gp.predict(X, return_std=True) for gp in self.gps_]
        mean = np.column_stack([m for m, _ in parts])
        std = np.column_stack([s for _, s in parts])
        if self._y_1d:
            mean, std = mean[:, 0], std[:, 0]
        return (mean, std) if return_std else mean

    def kernels(self) -> list[str]:
        """The fitted kernel of every target, as text."""
        check_is_fitted(self)
        return [str(gp.kernel_) for gp in self.gps_]


#: POD modes a GP learns by default (one GP each; the ONNX graph holds an N x N matrix per
#: target, so each mode costs N^2 doubles of model size).
POD_MODES = 4


def _card_extras(est: GPSurrogateRegressor) -> dict[str, Any]:
    return {"gp_kernels": est.kernels(), "gp_rows_used": int(est.n_train_)}


#: Opset of the GP graph -- read by every onnxruntime >= 1.14.
GP_OPSET = 18


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


#: float64 graph: the GP std, a difference of nearly equal numbers near the data, agrees with
#: scikit-learn to about 1e-5 in log amplitude (the tolerance leaves a margin of 10).
KIND = SurrogateKind(
    name="gp", summary="Gaussian processes with predictive std (harmonic amplitudes)",
    estimator=GPSurrogateRegressor, export=export_gp, parity_tol=1e-4, dtype="float64",
    std_parity=True, pod_modes=POD_MODES, card_extras=_card_extras, row_cap=500)
