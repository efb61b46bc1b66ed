"""Static condensation of the element-interior dofs against a dense reference."""

from __future__ import annotations

import numpy as np
import pytest

from fem.solve import condense, interior_dofs, small_inverse


def _dense_condense(Ze, inner):
    """The textbook Schur complement, element by element, with LAPACK solves."""
    outer = np.setdiff1d(np.arange(Ze.shape[1]), inner)
    out, rec = [], []
    for Z in Ze:
        R = -np.linalg.solve(Z[np.ix_(inner, inner)], Z[np.ix_(inner, outer)])
        out.append(Z[np.ix_(outer, outer)] + Z[np.ix_(outer, inner)] @ R)
        rec.append(R)
    return np.array(out), outer, np.array(rec)


@pytest.mark.parametrize("mode", [0, 1, 2])
def test_condense_matches_dense_schur_complement(mode):
    inner = interior_dofs(mode, 2)
    nd = 9 * (2 if mode == 0 else 3)
    rng = np.random.default_rng(mode)
    A = rng.normal(size=(40, nd, nd)) + 1j * rng.normal(size=(40, nd, nd))
    Ze = A @ A.transpose(0, 2, 1) + nd * np.eye(nd)  # complex symmetric, like the operators
    got, outer, recover = condense(Ze, inner)
    want, want_outer, want_recover = _dense_condense(Ze, inner)
    assert np.array_equal(outer, want_outer)
    assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()
    assert np.abs(recover - want_recover).max() <= 1e-12 * np.abs(want_recover).max()
    # the recovered interior dofs make the interior rows of Z u vanish (no interior load)
    u_b = rng.normal(size=(40, outer.size))
    u = np.zeros((40, nd), dtype=complex)
    u[:, outer] = u_b
    u[:, inner] = np.einsum("ecb,eb->ec", recover, u_b)
    interior_rows = np.einsum("ecd,ed->ec", Ze[:, inner, :], u)
    assert np.abs(interior_rows).max() <= 1e-12 * np.abs(Ze).max() * np.abs(u).max()


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_small_inverse_matches_lapack(n):
    rng = np.random.default_rng(n)
    A = rng.normal(size=(50, n, n)) + 1j * rng.normal(size=(50, n, n)) + 3 * np.eye(n)
    assert np.abs(small_inverse(A) - np.linalg.inv(A)).max() <= 1e-12 * np.abs(
        np.linalg.inv(A)).max()


def test_condense_refuses_scattered_interior_dofs():
    with pytest.raises(ValueError, match="not one contiguous block"):
        condense(np.eye(6)[None] * np.ones((2, 1, 1)), np.array([1, 3]))
