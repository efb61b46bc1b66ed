"""Operators of one Fourier mode and the static, harmonic and modal solves.

Only the operators an analysis needs are built: a static solve assembles no mass, a harmonic
solve forms the dynamic element matrices K* - omega^2 M (+ i omega C) and assembles them once.
``OperatorLog`` records what was built so tests and the summary can prove it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from . import columns, elements, linalg
from .assembly import (
    DofMap,
    assemble_blocks,
    assemble_matrix,
    assemble_vector,
    build_dofmap,
    prescribed_load,
)
from .domain import Domain


@dataclass
class OperatorLog:
    """Names of the element operators built, in order (e.g. "stiffness[n=1]")."""

    built: list[str] = field(default_factory=list)

    def add(self, name: str, mode: int) -> None:
        self.built.append(f"{name}[n={mode}]")


def damping_layer_matrices(domain: Domain, g: elements.GaussData, mode: int,
                           density: NDArray) -> NDArray:
    """Element viscous matrices (N s/m) of the graded damping layer: c(r, z) rho N^T N."""
    rate = domain.damping.rate(g.r, g.z) * density[:, None]
    return elements.weighted_mass(g, mode, rate)


def dynamic_element_matrices(domain: Domain, mode: int, omega: float, log: OperatorLog,
                             volumetric: str = "bbar", stretch=None) -> NDArray:
    """K* - omega^2 M + i omega C per element: stiffness with hysteretic moduli E (1 + i eta),
    mass when omega > 0, the PML stretch and the damping layer when the domain has them.

    Elements are formed column by column (:mod:`fem.columns`), except those in a PML in z;
    elements outside the PML are formed in real arithmetic, complex factors enter only where an
    effect needs them.
    """
    mesh = domain.mesh
    mu, kappa = domain.element_property("mu"), domain.element_property("kappa")
    density = domain.element_property("density")
    eta = domain.element_property("loss_factor")
    hysteretic = bool(np.any(eta > 0))
    in_pml = (stretch.contains(mesh.cell_r0, mesh.cell_z0) if stretch is not None
              else np.zeros(mesh.n_elements, dtype=bool))
    damped = domain.damping is not None and omega > 0
    is_complex = hysteretic or damped or bool(in_pml.any())
    nd = mesh.elements.shape[1] * elements.dofs_per_node(mode)
    mu_star = mu * (1.0 + 1j * eta) if hysteretic else mu  # nu is real: E (1 + i eta) scales
    kappa_star = kappa * (1.0 + 1j * eta) if hysteretic else kappa  # mu and kappa alike
    by_column = columns.column_path(mesh, stretch)
    idx = np.flatnonzero(by_column)
    coef = np.column_stack([mu_star[idx], kappa_star[idx]]
                           + ([-omega**2 * density[idx]] if omega > 0 else []))
    Zc = columns.column_matrices(mesh, idx, stretch, mode, coef, volumetric)
    if idx.size == mesh.n_elements and (Zc.dtype == complex or not is_complex):
        Z = Zc
    else:
        Z = np.empty((mesh.n_elements, nd, nd), dtype=complex if is_complex else float)
        Z[idx] = Zc
    idx = np.flatnonzero(~by_column)  # elements in a PML in z: element by element
    if idx.size:
        g = elements.gauss_data(mesh, stretch, subset=idx)
        Ze = elements.stiffness(g, mode, mu_star[idx], kappa_star[idx], volumetric)
        if omega > 0:
            Ze = Ze - omega**2 * elements.mass(g, mode, density[idx])
        Z[idx] = Ze
    if damped:
        g = elements.gauss_data(mesh)
        Z += 1j * omega * damping_layer_matrices(domain, g, mode, density)
    log.add("stiffness", mode)
    if hysteretic:
        log.add("hysteretic damping", mode)
    if omega > 0:
        log.add("mass", mode)
    if damped:
        log.add("damping layer", mode)
    if in_pml.any():
        log.add("PML", mode)
    return Z


@dataclass(frozen=True)
class ModeSolution:
    """Solution of one Fourier mode: full nodal dofs and the map that numbers them."""

    mode: int
    dofmap: DofMap
    u_full: NDArray
    n_dofs: int  # unknowns of the discretisation, condensed interior dofs included

    def nodal(self) -> NDArray:
        """(n_nodes, 3) complex (U_r, U_z, U_t) in m."""
        return self.dofmap.nodal(self.u_full)


def interior_dofs(mode: int, order: int) -> NDArray:
    """Local dof indices of the element-interior node (the Q9 centre), empty for order 1."""
    if order < 2:
        return np.empty(0, dtype=int)
    ndpn = elements.dofs_per_node(mode)
    centre = 1 + (order + 1)  # local node (i, j) = (1, 1)
    return centre * ndpn + np.arange(ndpn)


def boundary_dofmap(domain: Domain, mode: int, prescribed=()) -> DofMap:
    """The dof map of the unknowns left after static condensation: the domain's constraints
    plus the element-interior (Q9 centre) dofs held out; ``element_dofs`` still lists every
    local dof."""
    mesh = domain.mesh
    fixed = domain.fixed()
    if interior_dofs(mode, mesh.order).size:
        centres = mesh.elements[:, 1 + (mesh.order + 1)]
        fixed += [(centres, c) for c in range(elements.dofs_per_node(mode))]
    return build_dofmap(mesh, mode, fixed, prescribed, domain.ties)


def condense(Ze: NDArray, inner: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Static condensation of element-interior dofs: Z_bb - Z_bc Z_cc^-1 Z_cb.

    The interior node touches one element, carries no load and no constraint, so eliminating it
    per element is exact and shrinks the global system by a quarter for Q9. ``inner`` is one
    contiguous block of local indices (a node's dofs, :func:`interior_dofs`); Z_cc (2 x 2 or
    3 x 3) is inverted by cofactors (:func:`small_inverse`), not by a batched LAPACK solve.

    Returns:
        (condensed matrices (ne, nb, nb), boundary local indices, recovery operator
        (ne, nc, nb) with u_c = R u_b).
    """
    lo, hi = int(inner[0]), int(inner[-1]) + 1
    if not np.array_equal(inner, np.arange(lo, hi)):
        raise ValueError(f"interior dofs {inner} are not one contiguous block")
    ne, nd, _ = Ze.shape
    outer = np.concatenate([np.arange(lo), np.arange(hi, nd)])
    flat = Ze.reshape(ne, nd * nd)

    def block(rows: NDArray, cols: NDArray) -> NDArray:
        # np.take on flat positions: one gather, much cheaper than 3D fancy indexing
        at = (rows[:, None] * nd + cols[None, :]).reshape(-1)
        return np.take(flat, at, axis=1).reshape(ne, rows.size, cols.size)

    recover = np.matmul(small_inverse(Ze[:, lo:hi, lo:hi]), block(inner, outer))
    np.negative(recover, out=recover)
    out = np.matmul(block(outer, inner), recover)
    out += block(outer, outer)
    return out, outer, recover


def small_inverse(A: NDArray) -> NDArray:
    """Inverses of a stack of 1 x 1, 2 x 2 or 3 x 3 matrices (k, n, n) by cofactors (the
    adjugate over the determinant), vectorised over the stack; larger n by LAPACK."""
    n = A.shape[-1]
    if n == 1:
        return 1.0 / A
    if n == 2:
        adj = np.stack([A[:, 1, 1], -A[:, 0, 1], -A[:, 1, 0], A[:, 0, 0]], axis=1)
        det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
        return (adj / det[:, None]).reshape(-1, 2, 2)
    if n > 3:
        return np.linalg.inv(A)
    a, b, c = A[:, 0, 0], A[:, 0, 1], A[:, 0, 2]
    d, e, f = A[:, 1, 0], A[:, 1, 1], A[:, 1, 2]
    g, h, i = A[:, 2, 0], A[:, 2, 1], A[:, 2, 2]
    adj = np.stack([e * i - f * h, c * h - b * i, b * f - c * e,
                    f * g - d * i, a * i - c * g, c * d - a * f,
                    d * h - e * g, b * g - a * h, a * e - b * d], axis=1)
    det = a * adj[:, 0] + b * adj[:, 3] + c * adj[:, 6]
    return (adj / det[:, None]).reshape(-1, 3, 3)


@linalg.one_blas_thread()
def solve_mode(domain: Domain, mode: int, load_full: NDArray, omega: float = 0.0,
               log: OperatorLog | None = None, volumetric: str = "bbar",
               prescribed=(), extra=(), stages: dict[str, float] | None = None
               ) -> ModeSolution:
    """Static (omega = 0) or harmonic solve of one mode with one sparse LU factorisation.

    Args:
        load_full: full nodal load vector (N) of this mode; element-interior nodes unloaded.
        omega: angular frequency (rad/s); 0 for static.
        prescribed: (nodes, component, values) Dirichlet data, e.g. exact fields on a boundary.
        extra: (name, element dofs (k, m), matrices (k, m, m)) operators beyond the continuum,
            such as pogo pin springs, on dofs that are not element-interior.
        stages: if given, the wall time (s) of each stage is added under its name (the
            benchmark's stage table, bench/fem/solver.py).
    """
    log = log if log is not None else OperatorLog()
    t = time.perf_counter()
    mesh = domain.mesh
    stretch = domain.stretch if omega > 0 else None
    Ze = dynamic_element_matrices(domain, mode, omega, log, volumetric, stretch)
    t = _lap(stages, "element matrices", t)
    inner = interior_dofs(mode, mesh.order)
    dm = boundary_dofmap(domain, mode, prescribed)
    element_dofs = dm.element_dofs
    t = _lap(stages, "dof map", t)
    if inner.size:
        Ze, outer, recover = condense(Ze, inner)
        dm = replace(dm, element_dofs=element_dofs[:, outer])
    t = _lap(stages, "static condensation", t)
    # one pattern for the continuum and the extra operators, zeros kept: it depends on the
    # topology only, so the factorisation's analysis is reused across samples (fem.pardiso)
    A = assemble_blocks(dm, [(dm.element_dofs, Ze)] + [(e, K) for _, e, K in extra], "csc")
    for name, _, _ in extra:
        log.add(name, mode)
    rhs = assemble_vector(dm, load_full) + prescribed_load(dm, Ze)
    _lap(stages, "assembly", t)
    x = checked_solve(A, rhs, stages)
    t = time.perf_counter()
    u = dm.expand(x)
    if inner.size:
        u = u.astype(np.result_type(u, recover))
        u[element_dofs[:, inner]] = np.einsum("ecb,eb->ec", recover, u[dm.element_dofs])
    _lap(stages, "recovery", t)
    # unknowns of the discretisation: the global system plus the condensed interior dofs
    return ModeSolution(mode, dm, u, dm.n_free + mesh.n_elements * inner.size)


def _lap(stages: dict[str, float] | None, name: str, t0: float) -> float:
    """Add the time since ``t0`` (s) to ``stages[name]`` (when recording); the time now."""
    now = time.perf_counter()
    if stages is not None:
        stages[name] = stages.get(name, 0.0) + now - t0
    return now


#: Largest relative residual ||A x - b|| / ||b|| a direct solve may leave.
RESIDUAL_TOLERANCE = 1e-6


def checked_solve(A: sp.spmatrix, b: NDArray,
                  stages: dict[str, float] | None = None) -> NDArray:
    """Solve A x = b with one factorisation; raise if the answer is not finite or does not
    satisfy the system (a singular operator: an unrestrained body, a mechanism)."""
    t = time.perf_counter()
    lu = linalg.factorize(A)
    t = _lap(stages, "factor", t)
    x = lu.solve(b.astype(np.result_type(A.dtype, b.dtype)))
    t = _lap(stages, "solve", t)
    norm_b = np.linalg.norm(b)
    residual = np.linalg.norm(A @ x - b) / norm_b if norm_b > 0 else np.linalg.norm(x)
    if not np.all(np.isfinite(x)) or residual > RESIDUAL_TOLERANCE:
        raise FloatingPointError(
            f"the system is singular or ill-posed (relative residual {residual:.1e}): a part of "
            "the model is not restrained; check boundary conditions and effects")
    _lap(stages, "residual", t)
    return x


def natural_modes(domain: Domain, mode: int, k: int = 6,
                  sigma_hz: float = 0.0) -> tuple[NDArray, NDArray]:
    """Natural frequencies (Hz, ascending) and full-dof mode shapes (n_full, k) of ``mode``."""
    dm = build_dofmap(domain.mesh, mode, domain.fixed(), ties=domain.ties)
    g = elements.gauss_data(domain.mesh)
    mu, kappa = domain.element_property("mu"), domain.element_property("kappa")
    K = assemble_matrix(dm, elements.stiffness(g, mode, mu, kappa))
    M = assemble_matrix(dm, elements.mass(g, mode, domain.element_property("density")))
    sigma = (2 * np.pi * sigma_hz) ** 2
    vals, vecs = spla.eigsh(K, k=k, M=M, sigma=sigma, which="LM")
    order = np.argsort(vals)
    freqs = np.sqrt(np.abs(vals[order])) / (2 * np.pi)
    return freqs, dm.expand(vecs[:, order])
