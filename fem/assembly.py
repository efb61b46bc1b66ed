"""Degree-of-freedom maps, constraints and sparse assembly.

Constraints are eliminated at the element level: every full dof maps to a reduced dof with a
coefficient (+1, or -1 for the n = 1 axis tie U_t = -U_r) or to none (fixed, possibly at a
prescribed value). Element matrices are scattered straight into the reduced system, so no
transformation product T^T K T is ever formed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from .elements import dofs_per_node
from .mesh import Mesh

UR, UZ, UT = 0, 1, 2
COMPONENTS = {"ur": UR, "uz": UZ, "ut": UT}


@dataclass(frozen=True)
class DofMap:
    """Map from the full nodal dofs of one Fourier mode to the reduced (free) system.

    Attributes:
        mode: circumferential order n.
        dofs_per_node: 2 (n = 0) or 3.
        master: (n_full,) reduced index of each full dof, -1 if fixed.
        coef: (n_full,) coefficient multiplying the master value.
        prescribed: (n_full,) value of fixed dofs (m); zero for homogeneous constraints.
        element_dofs: (ne, nd) full dof indices of each element.
        n_free: size of the reduced system.
    """

    mode: int
    dofs_per_node: int
    master: NDArray
    coef: NDArray
    prescribed: NDArray
    element_dofs: NDArray
    n_free: int
    # ScatterMaps by element-dof array (see scatter_map); a `replace` starts an empty cache.
    _scatter: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def n_full(self) -> int:
        return self.master.size

    def expand(self, u_free: NDArray) -> NDArray:
        """Full nodal dof vector (n_full,) or (n_full, k) from a reduced solution."""
        u_free = np.asarray(u_free)
        shape = (self.n_full, *u_free.shape[1:])
        u = np.zeros(shape, dtype=np.result_type(u_free, self.prescribed))
        free = self.master >= 0
        coef = self.coef[free].reshape((-1,) + (1,) * (u_free.ndim - 1))
        u[free] = coef * u_free[self.master[free]]
        if u_free.ndim == 1:
            u[~free] = self.prescribed[~free]
        return u

    def nodal(self, u_full: NDArray) -> NDArray:
        """(n_nodes, 3) nodal (U_r, U_z, U_t) from a full dof vector (U_t = 0 for n = 0)."""
        vals = u_full.reshape(-1, self.dofs_per_node)
        out = np.zeros((vals.shape[0], 3), dtype=vals.dtype)
        out[:, : self.dofs_per_node] = vals
        return out


def axis_constraints(mode: int) -> tuple[list[int], bool]:
    """Conditions on r = 0 for a smooth field: (components fixed to zero, tie U_t = -U_r).

    n = 0: U_r = 0 (U_t absent). n = 1: U_z = 0 and U_r + U_t = 0 (a translation across the
    axis). n >= 2: everything zero.
    """
    if mode == 0:
        return [UR], False
    if mode == 1:
        return [UZ], True
    return [UR, UZ, UT], False


def build_dofmap(mesh: Mesh, mode: int,
                 fixed: Sequence[tuple[NDArray, int]] = (),
                 prescribed: Sequence[tuple[NDArray, int, NDArray]] = (),
                 ties: Sequence[tuple[NDArray, NDArray, int]] = ()) -> DofMap:
    """Number the free dofs of ``mode`` on ``mesh``.

    Args:
        fixed: (node indices, component) pairs held at zero.
        prescribed: (node indices, component, values in m) pairs held at given values.
        ties: (follower nodes, leader nodes, component): the follower's component equals the
            leader's (a frictionless contact passes the normal component only).
    """
    ndpn = dofs_per_node(mode)
    n_full = mesh.n_nodes * ndpn
    is_fixed = np.zeros(n_full, dtype=bool)
    values = np.zeros(n_full, dtype=complex)
    coef = np.ones(n_full)
    tie_to = np.arange(n_full)

    axis_nodes = mesh.nodes_where(lambda r, z: r <= 1e-12 * max(1.0, float(mesh.r_lines[-1])))
    axis_fixed, tie = axis_constraints(mode)
    for comp in axis_fixed:
        is_fixed[axis_nodes * ndpn + comp] = True
    for nodes, comp in fixed:
        if comp < ndpn:
            is_fixed[np.asarray(nodes) * ndpn + comp] = True
    for nodes, comp, vals in prescribed:
        if comp < ndpn:
            idx = np.asarray(nodes) * ndpn + comp
            is_fixed[idx] = True
            values[idx] = vals
    if tie:
        ut = axis_nodes * ndpn + UT
        ur = axis_nodes * ndpn + UR
        tie_to[ut] = ur
        coef[ut] = -1.0
    for followers, leaders, comp in ties:
        if comp < ndpn:
            tie_to[np.asarray(followers) * ndpn + comp] = np.asarray(leaders) * ndpn + comp
    is_fixed |= is_fixed[tie_to]  # a tied dof follows its partner

    primary = (~is_fixed) & (tie_to == np.arange(n_full))
    master = np.full(n_full, -1)
    master[primary] = np.arange(int(primary.sum()))
    master = np.where(is_fixed, -1, master[tie_to])
    if not np.iscomplexobj(values) or not np.any(values.imag):
        values = values.real
    nen = mesh.elements.shape[1]
    element_dofs = (mesh.elements[:, :, None] * ndpn + np.arange(ndpn)).reshape(-1, nen * ndpn)
    return DofMap(mode, ndpn, master, np.where(is_fixed, 0.0, coef), values, element_dofs,
                  int(primary.sum()))


@dataclass(frozen=True)
class ScatterMap:
    """Where every kept element-matrix entry lands in the CSR data of the reduced matrix.

    Built once per (dofmap, element-dof array) by one stable sort of the (row, col) keys, so
    assembling values is a gather and one segmented sum (``np.add.reduceat``) straight into the
    CSR data: no COO -> CSR conversion and no duplicate summing per assembly. Entries are summed
    in element order, as COO -> CSR does, so the result equals it to round-off.

    Attributes:
        gather: (m,) flat indices into Ke.reshape(-1) of the kept entries, sorted by (row, col).
        scale: (m,) product of the two dof coefficients of each gathered entry, or None when all
            are +1.
        starts: (nnz,) first gathered entry of each CSR entry.
        indptr, indices: CSR structure of the reduced matrix (sorted column indices).
        shape: (ne, nd, nd) element-matrix shape the map was built for.
    """

    gather: NDArray
    scale: NDArray | None
    starts: NDArray
    indptr: NDArray
    indices: NDArray
    shape: tuple[int, int, int]

    def assemble(self, Ke: NDArray, n: int) -> sp.csr_matrix:
        """The reduced (n, n) CSR matrix of element matrices ``Ke`` of shape ``self.shape``."""
        vals = np.ascontiguousarray(Ke).reshape(-1)[self.gather]
        if self.scale is not None:
            vals *= self.scale
        data = np.add.reduceat(vals, self.starts) if vals.size else vals
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(n, n))


def build_scatter_map(dm: DofMap, edofs: NDArray) -> ScatterMap:
    """Scatter map of element matrices on the full dofs ``edofs`` (ne, nd) into ``dm``'s
    reduced system (entries on fixed dofs dropped, tied dofs merged with their coefficient)."""
    rows = dm.master[edofs]
    ne, nd = rows.shape
    shape3 = (ne, nd, nd)
    R = np.broadcast_to(rows[:, :, None], shape3).reshape(-1)
    C = np.broadcast_to(rows[:, None, :], shape3).reshape(-1)
    kept = np.flatnonzero((R >= 0) & (C >= 0))
    n = dm.n_free
    key = R[kept].astype(np.int64) * n + C[kept]
    order = np.argsort(key, kind="stable")  # stable: duplicates keep element order
    gather = kept[order]
    key = key[order]
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]]) if key.size else key[:0]
    unique = key[starts]
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(unique // n, minlength=n), out=indptr[1:])
    index_dtype = np.int32 if max(n, unique.size) < 2**31 - 1 else np.int64
    coefs = dm.coef[edofs]
    scale = None
    if np.any(coefs != 1.0):
        scale = (coefs[:, :, None] * coefs[:, None, :]).reshape(-1)[gather]
    return ScatterMap(gather, scale, starts, indptr.astype(index_dtype),
                      (unique % n).astype(index_dtype), shape3)


def scatter_map(dm: DofMap, element_dofs: NDArray | None = None) -> ScatterMap:
    """The cached :class:`ScatterMap` of ``element_dofs`` (default: the mesh elements) on
    ``dm``; built on first use, so every later assembly on the same map (stiffness, mass and
    damping of a transient, repeated solves) reuses it."""
    edofs = dm.element_dofs if element_dofs is None else element_dofs
    hit = dm._scatter.get(id(edofs))
    if hit is not None and hit[0] is edofs:  # the stored array pins the id: no reuse by another
        return hit[1]
    smap = build_scatter_map(dm, edofs)
    dm._scatter[id(edofs)] = (edofs, smap)
    return smap


def assemble_matrix(dm: DofMap, Ke: NDArray, element_dofs: NDArray | None = None
                    ) -> sp.csr_matrix:
    """Scatter element matrices (ne, nd, nd) into the reduced sparse matrix (CSR, sorted
    indices, duplicates summed) through the dofmap's cached :func:`scatter_map`.

    ``element_dofs`` (ne, nd) defaults to the mesh elements; other element kinds (springs)
    pass their own full dof indices."""
    smap = scatter_map(dm, element_dofs)
    if Ke.shape != smap.shape:
        raise ValueError(f"element matrices of shape {Ke.shape} do not match the element dofs "
                         f"{smap.shape[:2]}: expected {smap.shape}")
    return smap.assemble(Ke, dm.n_free)


def assemble_matrix_coo(dm: DofMap, Ke: NDArray, element_dofs: NDArray | None = None
                        ) -> sp.csr_matrix:
    """Reference assembly through COO -> CSR (duplicate summing per call); the scatter map of
    :func:`assemble_matrix` must agree with it to round-off."""
    edofs = dm.element_dofs if element_dofs is None else element_dofs
    rows = dm.master[edofs]
    coefs = dm.coef[edofs]
    R = np.broadcast_to(rows[:, :, None], Ke.shape)
    C = np.broadcast_to(rows[:, None, :], Ke.shape)
    keep = (R >= 0) & (C >= 0)
    vals = (Ke * (coefs[:, :, None] * coefs[:, None, :]))[keep]
    A = sp.coo_matrix((vals, (R[keep], C[keep])), shape=(dm.n_free, dm.n_free))
    return A.tocsr()


def assemble_vector(dm: DofMap, f_full: NDArray) -> NDArray:
    """Reduce a full nodal load vector: f_red = T^T f."""
    free = dm.master >= 0
    dtype = np.result_type(f_full, float)
    out = np.zeros(dm.n_free, dtype=dtype)
    np.add.at(out, dm.master[free], dm.coef[free] * f_full[free])
    return out


def prescribed_load(dm: DofMap, Ke: NDArray) -> NDArray:
    """Reduced load equivalent of the prescribed values: -T^T K u_p (zero when none)."""
    up = dm.prescribed[dm.element_dofs]
    out = np.zeros(dm.n_free, dtype=np.result_type(Ke, up))
    if not np.any(up):
        return out
    fe = -np.einsum("eab,eb->ea", Ke, up)
    rows = dm.master[dm.element_dofs]
    keep = rows >= 0
    np.add.at(out, rows[keep], (dm.coef[dm.element_dofs] * fe)[keep])
    return out
