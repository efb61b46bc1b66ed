"""The harmonic operator of one mesh over a band of frequencies, as fixed matrices times scalar
functions of the frequency, and a solver for it at any one frequency.

On a fixed mesh the harmonic operator of one Fourier mode is

    A(omega) = K* - omega^2 M + P(omega) + S

outside the perfectly matched layer exactly: hysteretic stiffness K* = K(1 + i eta) (loss
factors do not depend on frequency), mass M, frequency-independent pogo-pin springs S. Inside
the layer the coordinate stretch s = 1 + (alpha0 - i beta0 / omega) xi^p (``fem.absorbers``)
makes the element matrices rational functions of the stretch at every Gauss point, so no
finite sum of fixed matrices represents them exactly. They are analytic in t = 1 / omega on the
band (their poles sit where the stretch vanishes, at a distance from the band), so Chebyshev
interpolation in t converges geometrically:

    P(omega) ~= sum_j l_j(1 / omega) Z_j,    Z_j = K_j - omega_j^2 M_j

with Z_j the layer's element matrices at the Chebyshev node t_j = 1 / omega_j and l_j the
Lagrange polynomials of the nodes (P is analytic in t on the band but for the pole of
omega^2 = 1 / t^2 at t = 0, so the convergence stays geometric). :data:`CHEBYSHEV_NODES` nodes
leave a relative error in P below 1e-6 on a band of ratio 2.5 (1.0e-6 measured at 7 nodes),
falling about 3x per node (tests/fem/test_sweep.py measures the decay).

Element-interior (Q9 centre) dofs are kept in the operator (the condensed operator is a rational
function of omega, not an affine one); the solver condenses them per element at its frequency,
which is exact for any right-hand side.

Every term is kept as element matrices with its element dofs, and applied or projected
element by element (dense batched products), which is faster here than complex sparse
products. All vectors live on the free dofs of one :class:`fem.assembly.DofMap` with the
element interiors free. SI units: N/m, kg, rad/s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from . import columns, elements, linalg
from .assembly import DofMap, assemble_blocks, assemble_vector, build_dofmap
from .problem import Problem
from .solve import boundary_dofmap, condense, interior_dofs, small_inverse

#: Chebyshev nodes in 1/omega that interpolate the PML's element matrices over a band.
CHEBYSHEV_NODES = 8


def chebyshev_points(lo: float, hi: float, n: int) -> NDArray:
    """``n`` Chebyshev points of the first kind on [lo, hi] (one point, the middle, if n = 1
    or lo == hi)."""
    if n == 1 or hi <= lo:
        return np.array([0.5 * (lo + hi)])
    k = np.arange(n)
    return 0.5 * (lo + hi) + 0.5 * (hi - lo) * np.cos((2 * k + 1) * np.pi / (2 * n))


def lagrange_weights(nodes: NDArray, x: float) -> tuple[NDArray, NDArray]:
    """Values l_j(x) and derivatives l_j'(x) of the Lagrange polynomials of ``nodes``."""
    n = nodes.size
    if n == 1:
        return np.ones(1), np.zeros(1)
    diff = x - nodes  # (n,)
    gaps = nodes[:, None] - nodes[None, :]
    np.fill_diagonal(gaps, 1.0)
    denom = gaps.prod(axis=1)
    factors = np.broadcast_to(diff, (n, n)).copy()
    np.fill_diagonal(factors, 1.0)  # row j: the factors (x - x_i), i != j
    values = factors.prod(axis=1) / denom
    if np.all(diff != 0.0):  # l_j'(x) = l_j(x) sum_{i != j} 1 / (x - x_i)
        inv = 1.0 / diff
        return values, values * (inv.sum() - inv)
    # at a node: sum over i != j of the product without factor i
    slopes = np.empty(n)
    for j in range(n):
        row = np.delete(factors[j], j)
        without = np.array([np.prod(np.delete(row, i)) for i in range(n - 1)])
        slopes[j] = without.sum() / denom[j]
    return values, slopes


def stiffness_and_mass(problem: Problem, idx: NDArray, stretch) -> tuple[NDArray, NDArray]:
    """Element stiffness K* (hysteretic moduli) and mass M (ne, nd, nd) of elements ``idx``
    under ``stretch`` (None: none), formed as the harmonic solve forms them."""
    K = _formed(problem, idx, stretch, None)
    zero = np.zeros(problem.domain.mesh.n_elements)
    return K, _formed(problem, idx, stretch, 1.0, moduli=(zero, zero))


def dynamic_matrices(problem: Problem, idx: NDArray, stretch, omega: float) -> NDArray:
    """K* - omega^2 M (ne, nd, nd) of elements ``idx`` under ``stretch``, in one formation."""
    return _formed(problem, idx, stretch, -omega**2)


def _formed(problem: Problem, idx: NDArray, stretch, mass_factor: float | None,
            moduli: tuple[NDArray, NDArray] | None = None) -> NDArray:
    """sum of stiffness (``moduli``: shear and bulk per element, default the hysteretic
    ones) and ``mass_factor`` x mass (none if None) of elements ``idx``."""
    domain, mode = problem.domain, problem.mode
    mesh = domain.mesh
    if moduli is None:
        eta = domain.element_property("loss_factor")
        moduli = (domain.element_property("mu") * (1.0 + 1j * eta),
                  domain.element_property("kappa") * (1.0 + 1j * eta))
    mu, kappa = moduli
    rho = domain.element_property("density")
    nd = mesh.elements.shape[1] * elements.dofs_per_node(mode)
    out = np.empty((idx.size, nd, nd), dtype=complex)
    by_column = columns.column_path(mesh, stretch)[idx]
    col = idx[by_column]
    if col.size:
        coef = [mu[col], kappa[col]] + ([] if mass_factor is None else [mass_factor * rho[col]])
        out[by_column] = columns.column_matrices(mesh, col, stretch, mode,
                                                 np.column_stack(coef))
    rest = idx[~by_column]
    if rest.size:
        g = elements.gauss_data(mesh, stretch, subset=rest)
        Z = elements.stiffness(g, mode, mu[rest], kappa[rest])
        if mass_factor is not None:
            Z = Z + mass_factor * elements.mass(g, mode, rho[rest])
        out[~by_column] = Z
    return out


@dataclass(frozen=True)
class ElementGroup:
    """Element matrices (k, m, m) on element dofs (k, m), and the gather map from the free
    dofs: ``gather`` (k m, n_free) sparse, with the dof map's constraint coefficients."""

    dofs: NDArray
    matrices: NDArray
    gather: sp.csr_matrix

    @classmethod
    def build(cls, dm: DofMap, dofs: NDArray, matrices: NDArray) -> ElementGroup:
        rows = dm.master[dofs].ravel()
        keep = np.flatnonzero(rows >= 0)
        gather = sp.csr_matrix((dm.coef[dofs].ravel()[keep], (keep, rows[keep])),
                               shape=(rows.size, dm.n_free))
        return cls(dofs, matrices, gather)

    def local(self, X: NDArray) -> NDArray:
        """(k, m, c) element values of free-dof vectors X (n_free, c)."""
        return (self.gather @ X).reshape(*self.dofs.shape, X.shape[1])

    def apply(self, Z: NDArray, X: NDArray) -> NDArray:
        """sum_e T_e^T Z_e T_e X for element matrices Z (k, m, m): (n_free, c)."""
        Y = np.matmul(Z, self.local(X))
        return self.gather.T @ Y.reshape(-1, X.shape[1])

    def project(self, Z: NDArray, V: NDArray, Ve: NDArray | None = None) -> NDArray:
        """V^H (sum_e T_e^T Z_e T_e) V: (r, r)."""
        Ve = self.local(V) if Ve is None else Ve
        Y = np.matmul(Z, Ve)
        return Ve.reshape(-1, V.shape[1]).conj().T @ Y.reshape(-1, V.shape[1])


@dataclass(frozen=True)
class TermGroup:
    """Terms of the affine form that share one element group, for projecting bases onto
    them: ``index`` (t,) the term numbers, ``real`` and ``imag`` (t, ne, m, m) the real and
    imaginary parts of their element matrices (``imag`` None when they are real)."""

    group: ElementGroup
    index: NDArray
    real: NDArray
    imag: NDArray | None

    @classmethod
    def of(cls, group: ElementGroup, index: list[int], matrices: NDArray) -> TermGroup:
        imag = np.ascontiguousarray(matrices.imag) if np.iscomplexobj(matrices) else None
        if imag is not None and not imag.any():
            imag = None
        return cls(group, np.asarray(index), np.ascontiguousarray(matrices.real), imag)


@dataclass(frozen=True)
class SweepOperator:
    """A(omega) on one mesh over a band: see the module docstring.

    Attributes:
        problem: the discretised scene (mesh sized for the band's highest frequency, absorbers
            for its lowest).
        dofmap: free dofs with element interiors free.
        inside, pml: element indices outside and inside the PML.
        stiffness, mass: the elements outside the PML (K*, M).
        springs: frequency-independent extra operators (pogo pins).
        layer: (q, n_pml, nd, nd) in ``layer.matrices``: Z_j of the PML at the nodes.
        nodes_t: (q,) Chebyshev nodes in 1/omega (s/rad).
        load: (n_free,) load vector at the problem's frequency (N).
    """

    problem: Problem
    dofmap: DofMap
    inside: NDArray
    pml: NDArray
    stiffness: ElementGroup
    mass: ElementGroup
    springs: tuple[ElementGroup, ...]
    layer: ElementGroup
    nodes_t: NDArray
    load: NDArray

    @classmethod
    def build(cls, problem: Problem, omega_lo: float, omega_hi: float,
              n_nodes: int = CHEBYSHEV_NODES) -> SweepOperator:
        """Form the element matrices once for the band [omega_lo, omega_hi] (rad/s)."""
        domain, mesh = problem.domain, problem.domain.mesh
        stretch = domain.stretch
        in_pml = (stretch.contains(mesh.cell_r0, mesh.cell_z0) if stretch is not None
                  else np.zeros(mesh.n_elements, dtype=bool))
        inside, pml = np.flatnonzero(~in_pml), np.flatnonzero(in_pml)
        dm = build_dofmap(mesh, problem.mode, domain.fixed(), (), domain.ties)
        edofs = dm.element_dofs
        K_in, M_in = stiffness_and_mass(problem, inside, None)
        nodes_t = chebyshev_points(1.0 / omega_hi, 1.0 / omega_lo, n_nodes if pml.size else 1)
        nd = K_in.shape[1]
        Z_pml = np.empty((nodes_t.size, pml.size, nd, nd), dtype=complex)
        for j, t in enumerate(nodes_t):
            if pml.size:
                Z_pml[j] = dynamic_matrices(problem, pml, replace(stretch, omega=1.0 / t),
                                            1.0 / t)
        layer = ElementGroup.build(dm, edofs[pml], Z_pml)
        springs = tuple(ElementGroup.build(dm, d, K) for _, d, K in problem.extra)
        return cls(problem, dm, inside, pml, ElementGroup.build(dm, edofs[inside], K_in),
                   ElementGroup.build(dm, edofs[inside], M_in), springs, layer, nodes_t,
                   assemble_vector(dm, problem.load))

    @property
    def n_terms(self) -> int:
        """Terms of the affine form: stiffness, mass, springs, one per PML node."""
        return 2 + len(self.springs) + (self.nodes_t.size if self.pml.size else 0)

    def coefficients(self, omega: float, derivative: bool = False) -> NDArray:
        """The scalar functions of the terms at ``omega`` (rad/s), or their derivatives in
        omega: 1, -omega^2, 1 per spring, l_j(1 / omega) per PML node."""
        layer = np.empty(0)
        if self.pml.size:
            values, slopes = lagrange_weights(self.nodes_t, 1.0 / omega)
            layer = -slopes / omega**2 if derivative else values
        head = [0.0, -2 * omega] if derivative else [1.0, -omega**2]
        springs = [0.0 if derivative else 1.0] * len(self.springs)
        return np.concatenate([head, springs, layer]).astype(complex)

    def _groups(self, c: NDArray) -> list[tuple[ElementGroup, NDArray]]:
        """(group, combined element matrices) for term coefficients ``c``."""
        out = [(self.stiffness, c[0] * self.stiffness.matrices + c[1] * self.mass.matrices)]
        out += [(g, c[2 + i] * g.matrices) for i, g in enumerate(self.springs)]
        if self.pml.size:
            out.append((self.layer, np.tensordot(c[2 + len(self.springs):],
                                                 self.layer.matrices, axes=1)))
        return out

    def combined(self, c: NDArray) -> list[tuple[ElementGroup, NDArray]]:
        """The operator sum_k c_k A_k as (element group, element matrices), for
        :meth:`apply` with the same coefficients many times."""
        return self._groups(c)

    def apply(self, c: NDArray | list, X: NDArray) -> NDArray:
        """(sum_k c_k A_k) X for term coefficients ``c`` (or their :meth:`combined` form);
        X (n_free,) or (n_free, k)."""
        groups = c if isinstance(c, list) else self._groups(c)
        X2 = X[:, None] if X.ndim == 1 else X
        out = sum(g.apply(Z, X2) for g, Z in groups)
        return out[:, 0] if X.ndim == 1 else out

    def project(self, V: NDArray) -> NDArray:
        """(n_terms, r, r): V^H A_k V for every term."""
        Vin = self.stiffness.local(V)
        out = [self.stiffness.project(self.stiffness.matrices, V, Vin),
               self.mass.project(self.mass.matrices, V, Vin)]
        out += [g.project(g.matrices, V) for g in self.springs]
        if self.pml.size:
            Vp = self.layer.local(V)
            out += [self.layer.project(Z, V, Vp) for Z in self.layer.matrices]
        return np.stack(out)

    def element_matrices(self, omega: float) -> NDArray:
        """(ne, nd, nd) element matrices of the continuum part of A(omega)."""
        c = self.coefficients(omega)
        n = self.problem.domain.mesh.n_elements
        Z = np.empty((n, *self.stiffness.matrices.shape[1:]), dtype=complex)
        Z[self.inside] = c[0] * self.stiffness.matrices + c[1] * self.mass.matrices
        if self.pml.size:
            Z[self.pml] = np.tensordot(c[2 + len(self.springs):], self.layer.matrices, axes=1)
        return Z

    @cached_property
    def _term_groups(self) -> tuple[TermGroup, ...]:
        ns = len(self.springs)
        stack = np.stack([self.stiffness.matrices, self.mass.matrices])
        out = [TermGroup.of(self.stiffness, [0, 1], stack)]
        out += [TermGroup.of(g, [2 + i], g.matrices[None]) for i, g in enumerate(self.springs)]
        if self.pml.size:
            out.append(TermGroup.of(self.layer, list(range(2 + ns, self.n_terms)),
                                    self.layer.matrices))
        return tuple(out)

    def term_groups(self) -> tuple[TermGroup, ...]:
        """The terms grouped by the elements they live on (stiffness and mass share one
        group), with the real and imaginary parts of their matrices (built on first use)."""
        return self._term_groups

    @cached_property
    def condensation(self) -> Condensation:
        """The frequency-independent maps of the condensed solvers (built on first use)."""
        return Condensation.build(self)

    def solver(self, omega: float) -> CondensedSolver:
        """A factorisation of A(omega), interiors condensed."""
        return CondensedSolver.build(self, omega)


@dataclass(frozen=True)
class Condensation:
    """How the uncondensed free dofs of a :class:`SweepOperator` map onto the unknowns left
    after static condensation; frequency-independent, built once per operator.

    Attributes:
        boundary: the condensed dof map (:func:`fem.solve.boundary_dofmap`).
        inner, outer: local indices of the element-interior and boundary dofs.
        to_full: (n_b,) free index in the uncondensed map of each boundary free dof.
        interior: (ne, nc) free index in the uncondensed map of each element's interior dofs.
        outer_group: the elements' boundary dofs on the condensed map (gather / scatter).
    """

    boundary: DofMap
    inner: NDArray
    outer: NDArray
    to_full: NDArray
    interior: NDArray
    outer_group: ElementGroup

    @classmethod
    def build(cls, op: SweepOperator) -> Condensation:
        problem = op.problem
        mesh, mode, full = problem.domain.mesh, problem.mode, op.dofmap
        inner = interior_dofs(mode, mesh.order)
        nd = full.element_dofs.shape[1]
        outer = np.setdiff1d(np.arange(nd), inner)
        boundary = boundary_dofmap(problem.domain, mode)
        masters = np.flatnonzero((boundary.master >= 0) & (boundary.coef == 1.0))
        to_full = np.empty(boundary.n_free, dtype=int)
        to_full[boundary.master[masters]] = full.master[masters]
        interior = full.master[full.element_dofs[:, inner]]
        outer_group = ElementGroup.build(boundary, full.element_dofs[:, outer], np.empty(0))
        return cls(boundary, inner, outer, to_full, interior, outer_group)


@dataclass(frozen=True)
class CondensedSolver:
    """Solves A(omega) x = f for any right-hand side on the uncondensed free dofs, with one
    factorisation of the operator condensed to the element boundaries (exact: each interior
    node belongs to one element)."""

    n_free: int
    maps: Condensation
    recover: NDArray  # (ne, nc, nb): u_c = Zcc^-1 f_c + recover u_b
    lift: NDArray  # (ne, nb, nc): Z_bc Zcc^-1, moves interior loads to the boundary
    inverse_cc: NDArray  # (ne, nc, nc)
    factor: linalg.Factorization

    @classmethod
    def build(cls, op: SweepOperator, omega: float) -> CondensedSolver:
        maps = op.condensation
        inner, outer = maps.inner, maps.outer
        Z = op.element_matrices(omega)
        if inner.size:
            Zb, _, recover = condense(Z, inner)
            block = slice(int(inner[0]), int(inner[-1]) + 1)
            inverse_cc = small_inverse(Z[:, block, block])
            lift = np.matmul(Z[:, outer][:, :, inner], inverse_cc)
        else:
            Zb = Z
            recover = lift = inverse_cc = np.empty((Z.shape[0], 0, 0))
        A = assemble_blocks(maps.boundary, [(maps.outer_group.dofs, Zb)]
                            + [(d, K) for _, d, K in op.problem.extra], "csc")
        return cls(op.dofmap.n_free, maps, recover, lift, inverse_cc, linalg.factorize(A))

    def solve(self, f: NDArray) -> NDArray:
        """x with A x = f; ``f`` and x (n_free,) or (n_free, k) on the uncondensed free dofs."""
        maps = self.maps
        f = np.asarray(f, dtype=complex)
        F = f[:, None] if f.ndim == 1 else f
        k = F.shape[1]
        Fb = F[maps.to_full]
        condensed = maps.inner.size > 0
        if condensed:
            Fc = F[maps.interior]  # (ne, nc, k)
            Fb = Fb - maps.outer_group.gather.T @ np.matmul(self.lift, Fc).reshape(-1, k)
        Ub = self.factor.solve(Fb).reshape(Fb.shape)
        X = np.zeros((self.n_free, k), dtype=complex)
        X[maps.to_full] = Ub
        if condensed:
            X[maps.interior] = (np.matmul(self.inverse_cc, Fc)
                                + np.matmul(self.recover, maps.outer_group.local(Ub)))
        return X[:, 0] if f.ndim == 1 else X
