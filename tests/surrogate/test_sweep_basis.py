"""The factored band basis of sweep models (surrogate.sweep.basis): exact at full rank, within
its error bound at the chosen rank, and the same in the graph, in torch and in numpy."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from synthetic_sweep import make_sweep_dataset

from surrogate.sweep.basis import factor_block, tail_error
from surrogate.sweep.export import BandDecoder
from surrogate.sweep.targets import BandTargets, load_sweep_datasets


@pytest.fixture(scope="module")
def response(tmp_path_factory):
    data = load_sweep_datasets([make_sweep_dataset(tmp_path_factory.mktemp("s") / "d", 40)])
    return data.response


def _weighted(targets: BandTargets, T: np.ndarray, exact: bool) -> np.ndarray:
    """The weighted normalised components (n, n_f, P, 6) of targets ``T``."""
    _, z = targets.components(T, exact=exact)
    return z / targets.weights_[None, None, :, None]


def test_at_full_rank_the_factored_basis_is_the_pod_basis(response):
    rng = np.random.default_rng(0)
    n_f, k, L = 5, 7, 9
    modes, mean = rng.standard_normal((n_f, k, L)), rng.standard_normal((n_f, L))
    weights = rng.uniform(0.5, 2.0, L)
    coefficients = rng.standard_normal((30, k))
    fac = factor_block(modes, mean, coefficients - coefficients.mean(axis=0), weights,
                       ranks=(L,))
    np.testing.assert_allclose(fac.modes(), modes * weights, atol=1e-12)
    np.testing.assert_allclose(fac.means(), mean * weights, atol=1e-12)
    assert fac.rel_error == pytest.approx(0.0, abs=1e-7)
    t = BandTargets(centre_modes=6, profile_modes=8, spatial_tol=0.0)
    t.fit_transform(response)
    assert [f.ranks for f in t.factors] == [(12,), (30,)]
    for got, want in zip(t.band_basis(), t.band_basis(exact=True), strict=True):
        np.testing.assert_allclose(got, want, atol=1e-12)


def test_the_chosen_ranks_are_within_the_tolerance_and_cheaper_than_one_rank(response):
    tol = 1e-3
    t = BandTargets(centre_modes=6, profile_modes=8, spatial_tol=tol)
    T = t.fit_transform(response)
    profile = t.factors[1]
    assert 1 < profile.rank < 30                  # the synthetic profile is not full rank
    exact, factored = _weighted(t, T, True), _weighted(t, T, False)
    for j, loc in enumerate((slice(0, 2), slice(2, None))):
        err = np.linalg.norm(factored[:, :, loc] - exact[:, :, loc]) \
            / np.linalg.norm(exact[:, :, loc])
        assert err <= tol
        assert err == pytest.approx(t.factors[j].rel_error, rel=1e-3, abs=1e-6)
    # one rank for every mode, the smallest within tol, gathers at least as much per row
    one = int(np.argmax(tail_error(profile.spectrum) <= tol))
    assert profile.row_work() <= 8 * one
    assert t.to_dict()["spatial_rank"] == {"centre_edge": t.factors[0].rank,
                                           "profile": profile.rank}


def test_groups_of_modes_take_their_own_ranks_and_the_error_adds_up():
    rng = np.random.default_rng(1)
    n_f, k, L, n = 4, 40, 10, 200
    modes = rng.standard_normal((n_f, k, L))
    raw = rng.standard_normal((n, k))       # centred, orthogonal, decaying: as POD's are
    coefficients = np.linalg.qr(raw - raw.mean(axis=0))[0] * np.geomspace(1.0, 1e-2, k)
    fac = factor_block(modes, np.zeros((n_f, L)), coefficients, np.ones(L), ranks=(9, 5, 2),
                       merge=False)
    assert [(g.start, g.stop) for g in fac.groups] == [(0, 16), (16, 32), (32, 40)]
    assert fac.ranks == (9, 5, 2) and fac.rank == 9 and fac.row_work() == 16 * 9 + 16 * 5 + 8 * 2
    z = np.einsum("nk,fkl->nfl", coefficients, modes)
    zf = np.einsum("nk,fkl->nfl", coefficients, fac.modes())
    assert np.linalg.norm(zf - z) / np.linalg.norm(z) == pytest.approx(fac.rel_error, rel=1e-6)
    # merged where a group would save fewer than GROUP_OVERHEAD numbers per row
    merged = factor_block(modes, np.zeros((n_f, L)), coefficients, np.ones(L), ranks=(9, 5, 2))
    assert merged.groups == (slice(0, 40),) and merged.ranks == (9,)
    assert merged.rel_error <= fac.rel_error
    wide = factor_block(np.tile(modes, (1, 5, 1)), np.zeros((n_f, L)),
                        np.tile(coefficients, 5) / 5, np.ones(L), ranks=(9, 9, 9, 9, 1))
    assert wide.ranks == (9, 1) and wide.groups == (slice(0, 128), slice(128, 200))


def test_the_torch_decode_equals_the_numpy_basis_at_grid_points_and_between(response):
    t = BandTargets(centre_modes=6, profile_modes=8)
    T = t.fit_transform(response[:6])
    y = np.stack([T, T + 0.01])                   # two "members" (M, n, 1 + k)
    decoder = BandDecoder(t)
    _, z = t.components(y)                        # (M, n, n_f, P, 6)
    yt = torch.as_tensor(y, dtype=torch.float32)
    index = torch.tensor([0, 3, 15])
    np.testing.assert_allclose(decoder.at_grid(yt, index).numpy(), z[:, :, index.numpy()],
                               atol=2e-5)
    tf = torch.tensor([0.0, 4.0, 6.25, 14.5, 15.0, 15.0])   # one fractional index per row
    got = decoder.components(yt, tf).numpy()
    i0 = np.minimum(np.floor(tf.numpy()).astype(int), 14)
    w = (tf.numpy() - i0)[None, :, None, None]
    rows = np.arange(6)
    want = z[:, rows, i0] + w * (z[:, rows, i0 + 1] - z[:, rows, i0])
    np.testing.assert_allclose(got, want, atol=2e-5)


def test_spatial_ranks_out_of_range_are_refused():
    with pytest.raises(ValueError, match=r"spatial ranks \(0,\): need 1 ranks in 1..3"):
        factor_block(np.ones((2, 2, 3)), np.ones((2, 3)), np.ones((4, 2)), np.ones(3),
                     ranks=(0,))
