"""A small multi-output MLP ensemble (torch, CPU) with a scikit-learn interface.

``MLPEnsembleRegressor`` trains ``n_members`` independent tanh MLPs at once as one batched
network (weights of shape (members, in, out), so a step of the whole ensemble is a few
batched matrix products). Each member has its own seed, initialisation and random
train/validation split and stops early on its own validation loss (its best weights are
kept). The ensemble mean is the prediction, the spread between members the uncertainty (a
deep ensemble: it reflects model disagreement, not noise in the data). Inputs and targets are
standardised inside the model, so :meth:`to_module` gives a graph from raw features to
outputs, ready for ONNX export.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import torch
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from surrogate.estimators.export import export_module
from surrogate.estimators.params import check_number, training_data
from surrogate.kind import SurrogateKind

__all__ = ["KIND", "EnsembleModule", "MLPEnsembleRegressor", "export_nn"]

#: ``error(out, rows, training) -> (members, rows, q)`` squared errors of a training step
Error = Callable[[torch.Tensor, Any, bool], torch.Tensor]


class EnsembleModule(torch.nn.Module):
    """Batched ensemble of MLPs: x (n, f) -> (mean (n, k), std (n, k)) of ``y @ B + b``.

    Buffers hold the feature/target scaling and the linear output map, so the exported graph
    needs nothing outside it."""

    def __init__(self, weights: list[torch.Tensor], biases: list[torch.Tensor],
                 x_mean: np.ndarray, x_scale: np.ndarray, y_mean: np.ndarray,
                 y_scale: np.ndarray, B: np.ndarray, b: np.ndarray) -> None:
        super().__init__()
        self.weights = torch.nn.ParameterList([torch.nn.Parameter(w) for w in weights])
        self.biases = torch.nn.ParameterList([torch.nn.Parameter(v) for v in biases])
        f32 = torch.float32
        self.register_buffer("x_mean", torch.as_tensor(x_mean, dtype=f32))
        self.register_buffer("x_scale", torch.as_tensor(x_scale, dtype=f32))
        # output map folded with the target scaling: y_raw @ B + b
        Bs = (y_scale[:, None] * B)
        bs = y_mean @ B + b
        self.register_buffer("B", torch.as_tensor(Bs, dtype=f32))
        self.register_buffer("b", torch.as_tensor(bs, dtype=f32))

    def members(self, x: torch.Tensor) -> torch.Tensor:
        """Standardised outputs of every member, shape (members, n, targets)."""
        h = ((x - self.x_mean) / self.x_scale).unsqueeze(0)
        last = len(self.weights) - 1
        for i, (w, v) in enumerate(zip(self.weights, self.biases, strict=True)):
            h = torch.matmul(h, w) + v
            if i < last:
                h = torch.tanh(h)
        return h

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        out = torch.matmul(self.members(x), self.B) + self.b
        mean = out.mean(dim=0)
        std = ((out - mean) ** 2).mean(dim=0).sqrt()
        return mean, std


class MLPEnsembleRegressor(RegressorMixin, BaseEstimator):
    """Deep-ensemble MLP regressor (multi-output).

    Parameters:
        hidden: hidden layer widths.
        n_members: ensemble size (1 gives a plain MLP with zero std).
        max_epochs: epochs at most; patience: epochs without a validation improvement
            before a member stops (its best weights are kept).
        learning_rate, weight_decay, batch_size: AdamW settings (decoupled weight decay).
        val_fraction: share of rows each member holds out for early stopping (none when
            fewer than 20 rows).
        random_state: seed of everything random (torch and numpy), so a fit is reproducible.
    """

    def __init__(self, hidden: tuple[int, ...] = (64, 64), n_members: int = 5,
                 max_epochs: int = 1000, patience: int = 50, learning_rate: float = 1e-3,
                 weight_decay: float = 1e-4, batch_size: int = 64, val_fraction: float = 0.15,
                 random_state: int = 0) -> None:
        self.hidden = hidden
        self.n_members = n_members
        self.max_epochs = max_epochs
        self.patience = patience
        self.learning_rate = learning_rate
        self.weight_decay = weight_decay
        self.batch_size = batch_size
        self.val_fraction = val_fraction
        self.random_state = random_state

    def fit(self, X: Any, y: Any) -> MLPEnsembleRegressor:
        self._check_params()
        X, Y, self._y_1d = training_data(self, X, y)
        self.x_mean_, self.x_scale_ = _moments(X)
        self.y_mean_, self.y_scale_ = _moments(Y)
        Xs = torch.as_tensor((X - self.x_mean_) / self.x_scale_, dtype=torch.float32)
        Ys = torch.as_tensor((Y - self.y_mean_) / self.y_scale_, dtype=torch.float32)
        rng = np.random.default_rng(self.random_state)
        torch.manual_seed(self.random_state)
        train, val = _splits(len(X), self.n_members, self.val_fraction, rng)
        threads = torch.get_num_threads()
        torch.set_num_threads(1)  # small matrices: extra threads only contend for the cores
        try:
            self.weights_, self.biases_, self.best_epoch_ = _train(
                Xs, Ys, train, val, tuple(self.hidden), self.max_epochs, self.patience,
                self.learning_rate, self.weight_decay, self.batch_size)
        finally:
            torch.set_num_threads(threads)
        self.n_outputs_ = Y.shape[1]
        return self

    def refit(self, X: Any, error: Error, *, max_epochs: int, patience: int,
              learning_rate: float) -> MLPEnsembleRegressor:
        """Continue training the fitted members on ``error(y, rows, training)``: squared
        errors (members, rows, q) of their outputs ``y`` in target units (members, rows,
        targets) for the rows ``rows`` of ``X``; each member keeps the train/validation split
        of :meth:`fit` (same ``random_state``) and its best weights on its validation rows."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=float, reset=False)
        Xs = torch.as_tensor((X - self.x_mean_) / self.x_scale_, dtype=torch.float32)
        y_mean = torch.as_tensor(self.y_mean_, dtype=torch.float32)
        y_scale = torch.as_tensor(self.y_scale_, dtype=torch.float32)
        train, val = _splits(len(X), self.n_members, self.val_fraction,
                             np.random.default_rng(self.random_state))
        torch.manual_seed(self.random_state + 1)
        threads = torch.get_num_threads()
        torch.set_num_threads(1)
        try:
            self.weights_, self.biases_, self.refit_best_epoch_ = _train(
                Xs, torch.zeros(len(X), self.n_outputs_), train, val, tuple(self.hidden),
                max_epochs, patience, learning_rate, self.weight_decay, self.batch_size,
                error=lambda out, rows, training: error(out * y_scale + y_mean, rows,
                                                        training),
                init=(self.weights_, self.biases_))
        finally:
            torch.set_num_threads(threads)
        return self

    def _check_params(self) -> None:
        hidden = tuple(self.hidden)
        if not hidden or not all(isinstance(h, int) and h >= 1 for h in hidden):
            raise ValueError(f"hidden = {self.hidden!r}: allowed one or more integer widths >= 1")
        check_number("n_members", self.n_members, 1, 256, integer=True)
        check_number("max_epochs", self.max_epochs, 1, 10**6, integer=True)
        check_number("patience", self.patience, 1, 10**6, integer=True)
        check_number("learning_rate", self.learning_rate, 0, 1, low_open=True)
        check_number("weight_decay", self.weight_decay, 0, 1)
        check_number("batch_size", self.batch_size, 1, 10**7, integer=True)
        check_number("val_fraction", self.val_fraction, 0, 0.9)
        check_number("random_state", self.random_state, 0, 2**32 - 1, integer=True)

    def to_module(self, B: np.ndarray | None = None,
                  b: np.ndarray | None = None) -> EnsembleModule:
        """Torch module from raw features to (mean, std) of ``y @ B + b`` (identity map by
        default)."""
        check_is_fitted(self)
        k = self.n_outputs_
        B = np.eye(k) if B is None else np.asarray(B, dtype=float)
        b = np.zeros(B.shape[1]) if b is None else np.asarray(b, dtype=float)
        return EnsembleModule([w.clone() for w in self.weights_],
                              [v.clone() for v in self.biases_], self.x_mean_,
                              self.x_scale_, self.y_mean_, self.y_scale_, B, b).eval()

    def __sklearn_tags__(self) -> Any:
        tags = super().__sklearn_tags__()
        tags.target_tags.multi_output = True
        return tags

    def predict(self, X: Any, return_std: bool = False) -> Any:
        check_is_fitted(self)
        X = validate_data(self, X, dtype=float, reset=False)
        # in float64: float32 products round differently with the batch's size on some CPUs
        # (2 ulp), and a row's prediction must not depend on the rows beside it
        with torch.no_grad():
            mean, std = self.to_module().double()(torch.as_tensor(X, dtype=torch.float64))
        mean, std = mean.numpy(), std.numpy()
        if self._y_1d:
            mean, std = mean[:, 0], std[:, 0]
        return (mean, std) if return_std else mean


def _moments(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mean = A.mean(axis=0)
    scale = A.std(axis=0)
    return mean, np.where(scale > 1e-12, scale, 1.0)


def _splits(n: int, members: int, val_fraction: float,
            rng: np.random.Generator) -> tuple[torch.Tensor, torch.Tensor]:
    """(train, val) boolean masks of shape (members, n); an independent split per member."""
    n_val = round(val_fraction * n) if n >= 20 else 0
    train = np.ones((members, n), dtype=bool)
    for m in range(members):
        train[m, rng.permutation(n)[:n_val]] = False
    val = ~train if n_val else train.copy()
    return torch.as_tensor(train), torch.as_tensor(val)


def _forward(X: torch.Tensor, weights: list[torch.Tensor],
             biases: list[torch.Tensor]) -> torch.Tensor:
    h = X.unsqueeze(0)
    for i, (w, v) in enumerate(zip(weights, biases, strict=True)):
        h = torch.matmul(h, w) + v
        if i < len(weights) - 1:
            h = torch.tanh(h)
    return h


def _train(X: torch.Tensor, Y: torch.Tensor, train: torch.Tensor, val: torch.Tensor,
           hidden: tuple[int, ...], max_epochs: int, patience: int, lr: float,
           weight_decay: float, batch_size: int, error: Error | None = None,
           init: tuple[list[torch.Tensor], list[torch.Tensor]] | None = None
           ) -> tuple[list[torch.Tensor], list[torch.Tensor], list[int]]:
    """Mini-batch AdamW on all members at once (each member sees only its own training rows
    of a batch); per-member early stopping on the validation loss after each epoch.
    ``error(out, rows, training)``: the squared errors (members, rows, q) of the members'
    standardised outputs ``out`` for the rows ``rows`` (default: against ``Y``); ``init``:
    start from these (weights, biases) instead of a random initialisation."""
    members, n = train.shape
    if error is None:
        def error(out: torch.Tensor, rows: torch.Tensor | slice, training: bool) -> torch.Tensor:
            return (out - Y[rows].unsqueeze(0)) ** 2
    sizes = (X.shape[1], *hidden, Y.shape[1])
    weights, biases = [], []
    for fan_in, fan_out in itertools.pairwise(sizes):
        bound = np.sqrt(6.0 / (fan_in + fan_out))  # Glorot-uniform, suits tanh
        weights.append(((torch.rand(members, fan_in, fan_out) * 2 - 1) * bound)
                       .requires_grad_())
        biases.append(torch.zeros(members, 1, fan_out, requires_grad=True))
    if init is not None:
        weights = [w.detach().clone().requires_grad_() for w in init[0]]
        biases = [v.detach().clone().requires_grad_() for v in init[1]]
    params = weights + biases
    opt = torch.optim.AdamW(params, lr=lr, weight_decay=weight_decay)
    tmask = train.float().unsqueeze(-1)
    wva = val.float().unsqueeze(-1) / val.sum(dim=1).clamp(min=1).view(-1, 1, 1)
    best = torch.full((members,), float("inf"))
    best_epoch = torch.zeros(members, dtype=torch.long)
    kept = [p.detach().clone() for p in params]
    for epoch in range(max_epochs):
        for rows in torch.randperm(n).split(max(batch_size, 1)):
            m = tmask[:, rows]
            sq = error(_forward(X[rows], weights, biases), rows, True)
            loss = ((sq * m).sum(dim=(1, 2)) / m.sum(dim=(1, 2)).clamp(min=1)).sum()
            opt.zero_grad()
            loss.backward()
            opt.step()
        with torch.no_grad():
            sq = error(_forward(X, weights, biases), slice(None), False)
            val_loss = (sq * wva).sum(dim=(1, 2)) / sq.shape[2]
            better = val_loss < best
            best = torch.where(better, val_loss, best)
            best_epoch = torch.where(better, torch.full_like(best_epoch, epoch), best_epoch)
            for k, p in zip(kept, params, strict=True):
                k[better] = p.detach()[better]
            if int((epoch - best_epoch).min()) > patience:
                break
    return ([k.clone() for k in kept[:len(weights)]], [k.clone() for k in kept[len(weights):]],
            best_epoch.tolist())


def _in_memory(est: MLPEnsembleRegressor, B: np.ndarray,
               b: np.ndarray) -> Any:
    """The ensemble's torch module with the output map, float32 in, log outputs out."""
    module = est.to_module(B, b)

    def run(X: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return module(torch.as_tensor(X, dtype=torch.float32))[0].double().numpy()

    return run


def export_nn(estimator: Any, B: np.ndarray, b: np.ndarray,
              metadata: Mapping[str, Any]) -> bytes:
    """ONNX bytes of a fitted :class:`surrogate.estimators.nn.MLPEnsembleRegressor` (float32
    input)."""
    return export_module(estimator.to_module(B, b), estimator.n_features_in_, metadata)


#: float32 graph of the ensemble; its std is the members' spread, compared through the mean.
KIND = SurrogateKind(
    name="nn", summary="MLP ensemble in torch with the members' spread as std (harmonic "
    "amplitudes)", estimator=MLPEnsembleRegressor, export=export_nn, parity_tol=1e-4,
    dtype="float32", engine="torch", in_memory=_in_memory,
    quick_options={"max_epochs": 30, "n_members": 2})
