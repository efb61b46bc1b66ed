"""Degree-of-freedom maps, constraints and sparse assembly.

Constraints are eliminated at the element level: every full dof maps to a reduced dof with a
coefficient (+1, or -1 for the n = 1 axis tie U_t = -U_r) or to none (fixed, possibly at a
prescribed value). Element matrices are scattered straight into the reduced system, so no
transformation product T^T K T is ever formed.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass

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


#: Scatter maps kept per process (each about 12 bytes per element-matrix entry: 9 MB for the
#: default forearm), least recently used dropped first.
MAP_CACHE_SIZE = 4

_maps: OrderedDict[bytes, ScatterMap] = OrderedDict()
_lock = threading.Lock()  # dask runs solves on threads of one process


@dataclass(frozen=True)
class ScatterMap:
    """Where every element-matrix entry lands in the CSR data of the reduced matrix.

    ``scatter`` holds one sparse matrix per block of element matrices (the continuum's, then
    e.g. the pogo pin springs'), (nnz, ne * nd * nd) each, with the constraint coefficient
    products (+-1) of the kept entries, so assembly is one sparse product per block: no COO
    sort and no duplicate summing per solve (default forearm: 9-12 ms against 35-39 ms for
    COO -> CSR; bench/fem/solver.py). Duplicates are summed in element order within a block,
    then the blocks are added. The pattern is the union of the blocks' structural patterns and
    keeps explicit zeros, so it depends on the topology only, never on the values (a sum of
    separately assembled matrices would drop entries that happen to be zero, and the sparse
    factorisation's analysis could then not be reused across samples).
    """

    shape: tuple[int, int]
    indptr: NDArray
    indices: NDArray
    scatter: tuple[sp.csr_matrix, ...]
    fmt: str = "csr"

    @classmethod
    def build(cls, dm: DofMap, edofs: NDArray | Sequence[NDArray],
              fmt: str = "csr") -> ScatterMap:
        """The map into CSR (``fmt = "csr"``) or CSC (``"csc"``) storage of one block of
        element dofs (ne, nd) or of several blocks."""
        blocks = [edofs] if isinstance(edofs, np.ndarray) else list(edofs)
        n = dm.n_free
        keys, positions, products, sizes = [], [], [], []
        offset = 0
        for block in blocks:
            rows, coefs = dm.master[block], dm.coef[block]
            major, minor = (rows[:, :, None], rows[:, None, :]) if fmt == "csr" else (
                rows[:, None, :], rows[:, :, None])
            valid = rows >= 0
            pos = np.flatnonzero((valid[:, :, None] & valid[:, None, :]).ravel())
            keys.append((major.astype(np.int64) * n + minor).ravel()[pos])
            products.append((coefs[:, :, None] * coefs[:, None, :]).ravel()[pos])
            positions.append(pos + offset)
            sizes.append(rows.shape[0] * rows.shape[1] ** 2)
            offset += sizes[-1]
        key = np.concatenate(keys)
        order = np.argsort(key, kind="stable")  # equal keys keep block and element order
        sorted_key = key[order]
        first = np.flatnonzero(np.concatenate([[True], sorted_key[1:] != sorted_key[:-1]]))
        unique = sorted_key[first]
        indptr = np.searchsorted(unique // n, np.arange(n + 1)).astype(np.int32)
        # row s of the scatter matrix lists, in element order, the entries summed into slot s
        scatter = sp.csr_matrix((np.concatenate(products)[order], np.concatenate(positions)[order],
                                 np.append(first, key.size)), shape=(unique.size, offset))
        bounds = np.cumsum([0, *sizes])
        parts = (scatter,) if len(blocks) == 1 else tuple(
            sp.csr_matrix(scatter[:, bounds[i]:bounds[i + 1]]) for i in range(len(blocks)))
        return cls((n, n), indptr, (unique % n).astype(np.int32), parts, fmt)

    def assemble(self, Ke: NDArray | Sequence[NDArray]) -> sp.csr_matrix | sp.csc_matrix:
        """The reduced matrix of element matrices (ne, nd, nd), one array per block."""
        mats = [Ke] if isinstance(Ke, np.ndarray) else list(Ke)
        if len(mats) != len(self.scatter):
            raise ValueError(f"{len(mats)} blocks of element matrices for a map of "
                             f"{len(self.scatter)}")
        data = self.scatter[0] @ mats[0].reshape(-1)
        for part, mat in zip(self.scatter[1:], mats[1:], strict=True):
            data = data + part @ mat.reshape(-1)
        kind = sp.csr_matrix if self.fmt == "csr" else sp.csc_matrix
        return kind((data, self.indices.copy(), self.indptr.copy()), shape=self.shape)


def _map_key(dm: DofMap, blocks: Sequence[NDArray], fmt: str = "csr") -> bytes:
    h = hashlib.blake2b(digest_size=16)
    h.update(fmt.encode())
    h.update(np.asarray([dm.n_free, len(blocks)]).tobytes())
    for a in (dm.master, dm.coef):
        h.update(np.ascontiguousarray(a).tobytes())
    for block in blocks:
        h.update(np.asarray(block.shape).tobytes())
        h.update(np.ascontiguousarray(block).tobytes())
    return h.digest()


def scatter_map(dm: DofMap, edofs: NDArray | Sequence[NDArray], fmt: str = "csr") -> ScatterMap:
    """The scatter map of this (dof map, element dofs) topology, one block or several, cached
    per process.

    Every assembly goes through a map, so the summation order and hence every bit of the
    result never depends on what was assembled before (the process pool and a threaded dask
    cluster give identical rows). Building one costs about 50 ms on the default forearm, 15 ms
    more than one COO -> CSR; each later assembly of the topology costs 9-12 ms."""
    blocks = [edofs] if isinstance(edofs, np.ndarray) else list(edofs)
    key = _map_key(dm, blocks, fmt)
    with _lock:
        if key in _maps:
            _maps.move_to_end(key)
            return _maps[key]
        built = _maps[key] = ScatterMap.build(dm, blocks, fmt)
        while len(_maps) > MAP_CACHE_SIZE:
            _maps.popitem(last=False)
        return built


def assemble_matrix(dm: DofMap, Ke: NDArray, element_dofs: NDArray | None = None,
                    fmt: str = "csr") -> sp.csr_matrix | sp.csc_matrix:
    """Scatter element matrices (ne, nd, nd) into the reduced sparse matrix.

    ``element_dofs`` (ne, nd) defaults to the mesh elements; other element kinds (springs)
    pass their own full dof indices. ``fmt`` "csr" or "csc" (what a factorisation takes, saving
    the conversion). Goes through the topology's cached :class:`ScatterMap`."""
    edofs = dm.element_dofs if element_dofs is None else element_dofs
    return assemble_blocks(dm, [(edofs, Ke)], fmt)


def assemble_blocks(dm: DofMap, blocks: Sequence[tuple[NDArray, NDArray]],
                    fmt: str = "csr") -> sp.csr_matrix | sp.csc_matrix:
    """The sum of several blocks of element matrices, each (element dofs (k, m), matrices
    (k, m, m)), on one pattern that keeps explicit zeros (see :class:`ScatterMap`)."""
    if fmt not in ("csr", "csc"):
        raise ValueError(f"fmt = {fmt!r}: allowed 'csr' or 'csc'")
    smap = scatter_map(dm, [edofs for edofs, _ in blocks], fmt)
    return smap.assemble([Ke for _, Ke in blocks])


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
