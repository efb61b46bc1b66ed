"""A reduced-order model of one mesh's harmonic response over a band, built greedily from a few
factorisations, with an a-posteriori error estimate.

The reduced space is spanned by shift-and-invert Krylov vectors at a few expansion
frequencies omega_e: x_0 = A(omega_e)^-1 b, x_k = A(omega_e)^-1 A'(omega_e) x_(k-1), with A'
the derivative of the operator in omega (``fem.sweep_operator``). The response at every
frequency of the band is the Galerkin projection V^H A(omega) V y = V^H b, assembled from the
projected fixed matrices of :class:`fem.sweep_operator.SweepOperator` and their scalar
functions, so each frequency costs a dense r x r solve.

Error control: the estimate at a frequency is the difference between the outputs (centre, edge
and profile) of the model and of the model without the deepest Krylov vector of each expansion
point, relative to each output's size (the classical test of successive Pade-type
approximants), times :data:`ESTIMATE_SAFETY`: the difference estimates the error of the
smaller model, which bounds the final one from above only as long as the sequence converges
monotonically, and on the verification set the final error reached 1.7x the difference.
Expansion points are added where the estimate is largest until it is below the tolerance
everywhere on the band (or the budget of factorisations is spent, which the result reports).
The final model is also checked against the residual of the full operator at the frequency of
the largest estimate.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .sweep_operator import SweepOperator

#: Default tolerance of the estimated relative error of centre, edge and profile.
SWEEP_TOLERANCE = 1e-3
#: Krylov vectors added per expansion point.
KRYLOV_DEPTH = 8
#: The difference of successive models estimates the smaller one's error, which is not a strict
#: bound of the larger one's: on the verification designs the true error reached 1.7x the
#: difference, so the reported estimate (and the stopping test) is the difference times this.
ESTIMATE_SAFETY = 2.0
#: Most factorisations (expansion points) a sweep may spend.
MAX_EXPANSIONS = 16


@dataclass
class ReducedModel:
    """Projected operator terms, load and output map of one basis V (n_free, r).

    Attributes:
        basis: V with orthonormal columns (V^H V = I).
        reduced: (n_terms, r, r) V^H A_k V.
        load: (r,) V^H b.
        outputs: (n_out, 3, r) the output points' (U_r, U_z, U_t) of each basis vector.
        krylov: coordinates in V of each (normalised) Krylov vector, in the order built.
        deepest: whether each Krylov vector is the deepest of its expansion point's block.
    """

    basis: NDArray
    reduced: NDArray
    load: NDArray
    outputs: NDArray
    krylov: list[NDArray] = field(default_factory=list)
    deepest: list[bool] = field(default_factory=list)

    def evaluate(self, coefficients: NDArray, subspace: NDArray | None = None) -> NDArray:
        """Outputs (n_f, n_out, 3) at the frequencies whose term coefficients are the rows of
        ``coefficients`` (n_f, n_terms), in the whole basis or in the subspace spanned by the
        orthonormal coordinate columns ``subspace`` (r, s)."""
        if subspace is None:
            reduced, load, outputs = self.reduced, self.load, self.outputs
        else:
            Q = subspace
            reduced = np.einsum("ai,kab,bj->kij", Q.conj(), self.reduced, Q)
            load, outputs = Q.conj().T @ self.load, self.outputs @ Q
        A = np.tensordot(coefficients, reduced, axes=1)  # (n_f, s, s)
        y = np.linalg.solve(A, np.broadcast_to(load, (A.shape[0], load.size))[..., None])
        return np.einsum("ocr,fr->foc", outputs, y[..., 0])

    def without_deepest(self) -> NDArray:
        """Orthonormal coordinates (r, s) of the span of the Krylov vectors without the deepest
        one of every expansion point that has more than one."""
        r = self.basis.shape[1]
        keep = [np.pad(c, (0, r - c.size)) for c, last in zip(
            self.krylov, self.deepest, strict=True) if not last]
        Q, _ = np.linalg.qr(np.column_stack(keep))
        return Q


#: Components smaller than this share of their group's largest are judged against that floor.
ERROR_FLOOR = 0.01


def output_errors(approx: NDArray, ref: NDArray, groups: list[slice]) -> NDArray:
    """(n_f,) largest relative difference of any component of any output point, each
    relative to its own magnitude or, if smaller, to :data:`ERROR_FLOOR` of the largest
    magnitude in its group (centre, edge, profile) at that frequency. It bounds both the
    relative error of the magnitudes and the phase error (rad) of the components above the
    floor."""
    worst = np.zeros(approx.shape[0])
    for g in groups:
        diff = np.abs(approx[:, g] - ref[:, g]).reshape(approx.shape[0], -1)
        size = np.abs(ref[:, g]).reshape(ref.shape[0], -1)
        floor = ERROR_FLOOR * size.max(axis=1, keepdims=True)
        ratio = diff / np.maximum(np.maximum(size, floor), np.finfo(float).tiny)
        worst = np.maximum(worst, ratio.max(axis=1))
    return worst


@dataclass
class GreedyReport:
    """How the model was built: expansion frequencies (Hz), estimates after each, solves."""

    expansions_hz: list[float] = field(default_factory=list)
    estimates: list[float] = field(default_factory=list)
    factorisations: int = 0
    back_solves: int = 0
    residual: float = float("nan")
    residual_hz: float = float("nan")
    stages_s: dict[str, float] = field(default_factory=dict)


def _orthonormalise(V: NDArray, w: NDArray, drop: float = 1e-8) -> NDArray | None:
    """``w`` orthogonalised against the orthonormal columns of V (classical Gram-Schmidt
    twice) and normalised; None when it lies in span(V) to ``drop`` relative."""
    norm0 = np.linalg.norm(w)
    if norm0 == 0.0:
        return None
    w = w / norm0
    for _ in range(2):
        if V.shape[1]:
            w = w - V @ (V.conj().T @ w)
    norm = np.linalg.norm(w)
    return None if norm < drop else w / norm


def greedy_model(op: SweepOperator, omegas: NDArray, output_map: Callable[[NDArray], NDArray],
                 groups: list[slice], tolerance: float = SWEEP_TOLERANCE,
                 depth: int = KRYLOV_DEPTH, max_expansions: int = MAX_EXPANSIONS
                 ) -> tuple[ReducedModel, NDArray, NDArray, GreedyReport]:
    """Build the reduced model of ``op`` for the angular frequencies ``omegas`` (rad/s).

    Args:
        output_map: basis (n_free, k) -> outputs (n_out, 3, k).
        groups: slices of the output points compared as one (centre, edge, profile).

    Returns:
        (model, its outputs (n_f, n_out, 3) at ``omegas`` for the load ``op.load``, estimate
        (n_f,) of the relative output error, report).
    """
    coef = np.array([op.coefficients(w) for w in omegas])  # (n_f, n_terms)
    report = GreedyReport()
    V = np.empty((op.dofmap.n_free, 0), dtype=complex)
    krylov: list[NDArray] = []
    deepest: list[bool] = []
    used = np.zeros(omegas.size, dtype=bool)
    at = omegas.size // 2
    while True:
        used[at] = True
        V, new = _expand(op, float(omegas[at]), V, depth, report)
        krylov = [*krylov, *new]
        deepest = [*deepest, *([False] * (len(new) - 1) + [True] if len(new) > 1
                               else [False] * len(new))]
        t = time.perf_counter()
        model = ReducedModel(V, op.project(V), V.conj().T @ op.load, output_map(V), krylov,
                             deepest)
        t = _lap(report, "projection", t)
        full = model.evaluate(coef)
        estimate = ESTIMATE_SAFETY * output_errors(
            model.evaluate(coef, model.without_deepest()), full, groups)
        _lap(report, "evaluation", t)
        report.estimates.append(float(estimate.max()))
        # a point already expanded at is exact there; look elsewhere
        candidates = np.where(used, -1.0, estimate)
        if estimate.max() <= tolerance or report.factorisations >= max_expansions \
                or not new or candidates.max() < 0:
            break
        at = int(np.argmax(candidates))
    worst = int(np.argmax(estimate))
    report.residual = _residual(model, op, coef[worst])
    report.residual_hz = float(omegas[worst] / (2 * np.pi))
    return model, full, estimate, report


def _expand(op: SweepOperator, omega_e: float, V: NDArray, depth: int,
            report: GreedyReport) -> tuple[NDArray, list[NDArray]]:
    """Factorise A(omega_e) and add up to ``depth`` Krylov vectors to V: Arnoldi within the
    block (its span is this point's Krylov space); each vector then joins the global basis and
    its coordinates there are returned (for the estimate)."""
    t = time.perf_counter()
    solver = op.solver(omega_e)
    report.factorisations += 1
    report.expansions_hz.append(omega_e / (2 * np.pi))
    t = _lap(report, "factorisation", t)
    slope = op.combined(op.coefficients(omega_e, derivative=True))  # dA/domega
    block = np.empty((V.shape[0], 0), dtype=complex)
    coords: list[NDArray] = []
    w = solver.solve(op.load)
    for k in range(depth):
        qb = _orthonormalise(block, w)
        q = None if qb is None else _orthonormalise(V, qb)
        if q is None:
            break
        block = np.column_stack([block, qb])
        V = np.column_stack([V, q])
        coords.append(V.conj().T @ qb)
        report.back_solves += 1
        if k < depth - 1:
            w = solver.solve(op.apply(slope, qb))
    _lap(report, "basis", t)
    return V, coords


def _lap(report: GreedyReport, stage: str, t0: float) -> float:
    now = time.perf_counter()
    report.stages_s[stage] = report.stages_s.get(stage, 0.0) + now - t0
    return now


def _residual(model: ReducedModel, op: SweepOperator, coef: NDArray) -> float:
    """||A(omega) V y - b|| / ||b|| of the full operator at one frequency."""
    y = np.linalg.solve(np.tensordot(coef, model.reduced, axes=1), model.load)
    r = op.apply(coef, model.basis @ y) - op.load
    return float(np.linalg.norm(r) / np.linalg.norm(op.load))
