"""Assembly through the cached scatter map equals a plain COO -> CSR sum, bit for bit across
calls whatever the cache holds."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from fem import assembly
from fem.assembly import UZ, assemble_matrix, build_dofmap, scatter_map
from fem.mesh import build_mesh


def _dofmap(mode: int):
    mesh = build_mesh(np.linspace(0.0, 1e-2, 5), np.linspace(0.0, 2e-2, 4),
                      np.zeros((3, 4), dtype=int), 2)
    base = mesh.nodes_where(lambda r, z: np.isclose(z, 2e-2))
    side = mesh.nodes_where(lambda r, z: np.isclose(r, 1e-2))
    ties = ((side[1:], side[:-1], UZ),)  # follower/leader pairs: coefficients and merged dofs
    return build_dofmap(mesh, mode, [(base, 0), (base, 1)], ties=ties)


def _coo_reference(dm, Ke):
    rows, coefs = dm.master[dm.element_dofs], dm.coef[dm.element_dofs]
    R = np.broadcast_to(rows[:, :, None], Ke.shape)
    C = np.broadcast_to(rows[:, None, :], Ke.shape)
    keep = (R >= 0) & (C >= 0)
    vals = (Ke * (coefs[:, :, None] * coefs[:, None, :]))[keep]
    return sp.coo_matrix((vals, (R[keep], C[keep])), shape=(dm.n_free, dm.n_free)).tocsr()


def test_cached_map_matches_coo_path():
    for mode in (0, 1, 2):
        dm = _dofmap(mode)
        rng = np.random.default_rng(mode)
        nd = dm.element_dofs.shape[1]
        Ke = rng.normal(size=(dm.element_dofs.shape[0], nd, nd)) * (1 + 0.5j)
        first = _coo_reference(dm, Ke)
        assembly._maps.clear()
        cold = assemble_matrix(dm, Ke)  # builds the map
        again = assemble_matrix(dm, Ke)  # through the cached map
        assert np.array_equal(cold.data, again.data)  # bit for bit, cache or not
        assert again.shape == first.shape == (dm.n_free, dm.n_free)
        assert np.abs((again - first).toarray()).max() <= 1e-14 * np.abs(first.data).max()
        # structure is canonical: sorted columns, no duplicates
        again_copy = again.copy()
        again_copy.sum_duplicates()
        assert again_copy.nnz == again.nnz
        assert np.all(np.diff(again.indices[again.indptr[0]:again.indptr[1]]) > 0)
        for _ in range(2):  # CSC: its own map
            csc = assemble_matrix(dm, Ke, fmt="csc")
            assert csc.format == "csc"
            assert np.abs((csc - first).toarray()).max() <= 1e-14 * np.abs(first.data).max()
        # the map is shared, the arrays of each matrix are not
        again.indices[:] = 0
        assert np.abs((assemble_matrix(dm, Ke) - first).toarray()).max() <= (
            1e-14 * np.abs(first.data).max())


def test_map_cache_is_bounded(monkeypatch):
    monkeypatch.setattr(assembly, "MAP_CACHE_SIZE", 2)
    monkeypatch.setattr(assembly, "_maps", type(assembly._maps)())
    for mode in (0, 1, 2):
        dm = _dofmap(mode)
        assert scatter_map(dm, dm.element_dofs) is scatter_map(dm, dm.element_dofs)
    assert len(assembly._maps) == 2  # the oldest (mode 0) was dropped
    dm0 = _dofmap(0)
    assert assembly._map_key(dm0, dm0.element_dofs) not in assembly._maps


def test_unknown_format_is_refused():
    dm = _dofmap(0)
    nd = dm.element_dofs.shape[1]
    with pytest.raises(ValueError, match="fmt = 'coo': allowed 'csr' or 'csc'"):
        assemble_matrix(dm, np.zeros((dm.element_dofs.shape[0], nd, nd)), fmt="coo")


def test_blocks_sum_on_a_pattern_that_keeps_zeros():
    """The continuum plus a spring block: the values equal the separate sum, and the pattern
    depends on the topology only (a spring of zero stiffness or element entries that happen to
    be zero leave it unchanged), which the factorisation's reuse of its analysis relies on."""
    from fem.assembly import assemble_blocks

    dm = _dofmap(1)
    rng = np.random.default_rng(7)
    nd = dm.element_dofs.shape[1]
    Ke = rng.normal(size=(dm.element_dofs.shape[0], nd, nd)) * (1 + 0.5j)
    # a spring between the z dofs of two nodes that share no element (a new pattern entry)
    first = next(d for d in dm.element_dofs[0] if dm.master[d] >= 0)
    last = next(d for d in dm.element_dofs[-1][::-1] if dm.master[d] >= 0)
    springs = np.array([[first, last]])
    Ks = np.array([[[2.0, -2.0], [-2.0, 2.0]]])
    A = assemble_blocks(dm, [(dm.element_dofs, Ke), (springs, Ks)], "csc")
    separate = assemble_matrix(dm, Ke, fmt="csc") + assemble_matrix(dm, Ks, springs, fmt="csc")
    assert np.abs((A - separate).toarray()).max() <= 1e-14 * np.abs(A.data).max()
    zeroed = Ke.copy()
    zeroed[0] = 0.0  # an element whose matrix is exactly zero
    B = assemble_blocks(dm, [(dm.element_dofs, zeroed), (springs, 0.0 * Ks)], "csc")
    assert np.array_equal(A.indptr, B.indptr) and np.array_equal(A.indices, B.indices)
    assert (B.data == 0).any()  # the zeros are stored, not dropped
    dropped = assemble_matrix(dm, zeroed, fmt="csc") + assemble_matrix(dm, 0.0 * Ks, springs,
                                                                        fmt="csc")
    assert dropped.nnz < B.nnz  # what a plain sum of matrices would have done
    with pytest.raises(ValueError, match="1 blocks of element matrices for a map of 2"):
        scatter_map(dm, [dm.element_dofs, springs], "csc").assemble([Ke])
