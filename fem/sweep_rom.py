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

from .scene.model import Analysis
from .sweep_basis import GrowingBasis, galerkin_outputs, orthonormalised
from .sweep_operator import SweepOperator

#: Default tolerance of the estimated relative error of centre, edge and profile (the scene's).
SWEEP_TOLERANCE = Analysis.tolerance
#: Krylov vectors added per expansion point.
KRYLOV_DEPTH = 8
#: The difference of successive models estimates the smaller one's error, which is not a strict
#: bound of the larger one's: on the verification designs the true error reached 1.7x the
#: difference, so the reported estimate (and the stopping test) is the difference times this.
ESTIMATE_SAFETY = 2.0
#: Most factorisations (expansion points) a sweep may spend.
MAX_EXPANSIONS = 16


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


def greedy_model(op: SweepOperator, omegas: NDArray, output_map: Callable[[NDArray], NDArray],
                 groups: list[slice], tolerance: float = SWEEP_TOLERANCE,
                 depth: int = KRYLOV_DEPTH, max_expansions: int = MAX_EXPANSIONS
                 ) -> tuple[GrowingBasis, NDArray, NDArray, GreedyReport]:
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
    model = GrowingBasis(op, output_map, depth * 4)
    blocks: list[list[NDArray]] = []
    used = np.zeros(omegas.size, dtype=bool)
    at = omegas.size // 2
    while True:
        used[at] = True
        block = _expand(op, float(omegas[at]), model, depth, report)
        blocks.append(block)
        t = time.perf_counter()
        full = model.evaluate(coef)
        estimate = ESTIMATE_SAFETY * output_errors(
            _without_deepest(model, coef, blocks), full, groups)
        _lap(report, "evaluation", t)
        report.estimates.append(float(estimate.max()))
        # a point already expanded at is exact there; look elsewhere
        candidates = np.where(used, -1.0, estimate)
        if estimate.max() <= tolerance or report.factorisations >= max_expansions \
                or not block or candidates.max() < 0:
            break
        at = int(np.argmax(candidates))
    worst = int(np.argmax(estimate))
    report.residual = model.residual(coef[worst])
    report.residual_hz = float(omegas[worst] / (2 * np.pi))
    return model, full, estimate, report


def _factorise(op: SweepOperator, omega_e: float, report: GreedyReport):
    """A factorisation of A(omega_e) and the solution x = A^-1 b."""
    t = time.perf_counter()
    solver = op.solver(omega_e)
    report.factorisations += 1
    report.expansions_hz.append(omega_e / (2 * np.pi))
    t = _lap(report, "factorisation", t)
    x = solver.solve(op.load)
    report.back_solves += 1
    _lap(report, "basis", t)
    return solver, x


def _without_deepest(model: GrowingBasis, coef: NDArray,
                     blocks: list[list[NDArray]]) -> NDArray:
    """Outputs (n_f, n_out, 3) of the model on the span of its Krylov vectors without the
    deepest one of every block that has more than one; ``blocks`` holds the coordinates in
    the basis of each block's (block-orthonormal) Krylov vectors."""
    r = model.size
    keep = [np.pad(c, (0, r - c.size)) for b in blocks for c in (b[:-1] if len(b) > 1 else b)]
    Q, _ = np.linalg.qr(np.column_stack(keep))
    sub = np.einsum("ai,kab,bj->kij", Q.conj(), model.reduced, Q)
    return galerkin_outputs(sub, Q.conj().T @ model.load, model.outputs @ Q, coef)


def _expand(op: SweepOperator, omega_e: float, model: GrowingBasis, depth: int,
            report: GreedyReport) -> list[NDArray]:
    """Factorise A(omega_e) and append up to ``depth`` Krylov vectors x_0 = A^-1 b,
    x_k = A^-1 A' x_(k-1) (Arnoldi within the block) to the model, projected as one block.
    Returns the coordinates in the basis of the block's Krylov vectors (for the estimate)."""
    solver, w = _factorise(op, omega_e, report)
    t = time.perf_counter()
    slope = op.combined(op.coefficients(omega_e, derivative=True))  # dA/domega
    block: list[NDArray] = []  # the block's Krylov vectors, orthonormal among themselves
    new: list[NDArray] = []  # the same, orthogonalised against the basis
    for k in range(depth):
        qb = orthonormalised(w, [np.column_stack(block)] if block else [])
        q = None if qb is None else model.orthogonal_part(qb, new)
        if q is None:
            break
        block.append(qb)
        new.append(q)
        if k < depth - 1:
            w = solver.solve(op.apply(slope, qb))
            report.back_solves += 1
            t = _lap(report, "basis", t)
    model.append(new)
    _lap(report, "projection", t)
    V = model.basis
    coords = [(qb.conj() @ V).conj() for qb in block]
    return coords


def _lap(report: GreedyReport, stage: str, t0: float) -> float:
    now = time.perf_counter()
    report.stages_s[stage] = report.stages_s.get(stage, 0.0) + now - t0
    return now
