"""The output-choice study (studies.output_choice, bench/surrogate/output_choice.py): each output
choice decodes its own targets back to the band response (exactly when every POD mode is
kept), the per-output GP learns each target with its own kernel, and a run scores every
(learner, choice) with finite errors, zero for a perfect prediction."""

from __future__ import annotations

import numpy as np
import pytest

from studies.output_choice import learners, representations, run, table
from studies.output_choice.data import Sweeps, split
from studies.output_choice.poles import F_REF, PoleResidue, evaluate, vector_fit
from studies.output_choice.representations import Answers, ComplexBand, LnMagBand, Point
from studies.output_choice.study import FLOOR, score


def _sweeps(n: int, seed: int = 0, n_f: int = 12, n_p: int = 4) -> Sweeps:
    """Designs x in [0, 1]^3 with one damped resonance each (frequency, damping and level
    set by x) seen at the centre, the edge and along a decaying profile [um]."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 1, (n, 3))
    band = np.linspace(100.0, 250.0, n_f)
    f0 = 120.0 + 100.0 * x[:, :1]
    zeta = 0.05 + 0.1 * x[:, 1:2]
    h = 1e4 * (1 + x[:, 2:3]) / (f0**2 - band**2 + 2j * zeta * f0 * band)  # (n, n_f)
    comp = np.array([1.0, 0.3 + 0.2j, 0.1])
    center = h[..., None] * comp
    edge = 0.5 * h[..., None] * comp[::-1]
    decay = np.exp(-np.arange(n_p) / (2 + x[:, 2:3]))[:, None, :, None]
    profile = edge[:, :, None, :] * decay
    profile[:, :, 0] = edge
    return Sweeps(x, band, center, edge, profile, np.arange(n_p) * 2.0, "synthetic")


def test_complex_band_round_trip_is_exact_when_every_mode_is_kept():
    sw = _sweeps(30)
    codec = ComplexBand(modes=None, profile_modes=None)
    _, y = codec.training(sw, np.random.default_rng(0))
    c, e, p = codec.decode_complex(y, sw.band.size)
    scale = np.abs(sw.center).max()
    assert np.abs(c - sw.center).max() < 1e-10 * scale
    assert np.abs(e - sw.edge).max() < 1e-10 * scale
    assert np.abs(p - sw.profile).max() < 1e-10 * scale
    # the first target is ln of the band's RMS centre amplitude
    rms = np.sqrt(np.mean(np.sum(np.abs(sw.center) ** 2, axis=-1), axis=1))
    assert np.allclose(y[:, 0], np.log(rms))
    # truncated: fewer targets, no longer exact
    small = ComplexBand(modes=2, profile_modes=2)
    _, y2 = small.training(sw, np.random.default_rng(0))
    assert y2.shape[1] == 5 and np.abs(small.decode_complex(y2, 12)[0] - sw.center).max() > 0


@pytest.mark.parametrize("choice", [LnMagBand(None, None), Point(per_design=1, profile_modes=4)])
def test_magnitude_choices_decode_their_own_targets(choice):
    sw = _sweeps(25)
    x, y = choice.training(sw, np.random.default_rng(0))
    truth = Answers.of(sw)
    if isinstance(choice, Point):
        # one random band frequency per design: decode the rows back where they came from
        assert x.shape == (25, 4) and y.shape == (25, 2 + choice.pod_.basis_.shape[0])
        cols = np.rint(x[:, -1] * (sw.band.size - 1)).astype(int)
        assert np.allclose(np.exp(y[:, 0]), truth.center[np.arange(25), cols])
        assert choice.query(sw).shape == (25 * sw.band.size, 4)
        return
    got = choice.decode(y, sw)
    assert np.allclose(got.center, truth.center, rtol=1e-10)
    assert np.allclose(got.edge, truth.edge, rtol=1e-10)
    assert np.allclose(got.profile, truth.profile, rtol=1e-10)


def test_score_is_zero_for_the_truth_and_reads_the_field_scale():
    sw = _sweeps(10)
    truth = Answers.of(sw)
    s = score(truth, truth)
    assert all(v == 0 for v in s.values())
    off = Answers(truth.center * 1.1, truth.edge, truth.profile)
    s = score(off, truth)
    assert s["centre_median"] == pytest.approx(0.1) and s["edge_max"] == 0
    field = np.maximum(truth.center, truth.edge)
    assert s["max_field"] == pytest.approx(np.max(0.1 * truth.center / field))


def test_per_output_gp_learns_each_target_with_its_own_length_scales():
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 1, (80, 2))
    # one target varies fast along x0 only, the other slowly along x1 only
    y = np.column_stack([np.sin(6 * x[:, 0]), 0.5 * x[:, 1] ** 2])
    learner = learners.make("gp-each", 0, restarts=0)
    predict = learner.fit(x, y)
    q = rng.uniform(0, 1, (50, 2))
    want = np.column_stack([np.sin(6 * q[:, 0]), 0.5 * q[:, 1] ** 2])
    err = np.abs(predict(q) - want).max(axis=0)
    assert err[0] < 0.05 and err[1] < 0.01
    capped = learners.make("gp-each", 0, gp_rows=30)
    assert capped.rows(80) == 30 and learners.make("mlp", 0).rows(80) == 80
    with pytest.raises(ValueError, match="learner 'svm': allowed mlp, gp, gp-each, lgbm"):
        learners.make("svm", 0)


def test_run_scores_every_learner_and_choice_on_the_test_designs():
    train, test = split(_sweeps(60), 0.25, 0)
    assert len(train) == 45 and len(test) == 15
    made = [learners.make("gp-each", 0, restarts=0)]
    if learners.lightgbm_available():
        made.append(learners.make("lgbm", 0, trees=50))
    choices = [Point(1, 2), LnMagBand(6, 4), ComplexBand(6, 4)]
    records = run(train, test, made, choices, log=lambda _: None)
    assert [(r["learner"], r["choice"]) for r in records] == [
        (m, c.name) for m in [FLOOR] + [m.name for m in made] for c in choices]
    for r in records:
        assert all(np.isfinite(r[k]) and r[k] >= 0 for k in
                   ("centre_median", "edge_p99", "max_field", "profile_l2_median"))
    floor, gp_complex = records[:3], records[5]
    # magnitude@f has no basis for centre and edge: its floor there is exact
    assert floor[0]["centre_max"] < 1e-12 and floor[0]["edge_max"] < 1e-12
    assert gp_complex["targets"] == 1 + 6 + 4 and gp_complex["centre_median"] < 0.05
    text = table(records)
    assert text.count("\n") == len(records) + 1 and "| gp-each | complex band | 45 |" in text
    assert "| (projection) | magnitude@f x1 | 45 |" in text


def test_choices_and_learners_are_listed_by_their_command_line_names():
    assert set(representations.CHOICES) == {"point", "lnmag", "complex"}
    assert set(learners.LEARNERS) == {"mlp", "gp", "gp-each", "lgbm"}


def test_vector_fitting_recovers_the_poles_of_a_rational_response():
    f = np.linspace(100.0, 250.0, 40)
    s = 1j * f / F_REF
    rng = np.random.default_rng(0)
    p = np.array([-0.05 + 1.3j, -0.1 + 2.0j, -0.3 + 3.0j])
    r = rng.normal(size=(6, 3)) + 1j * rng.normal(size=(6, 3))
    h = evaluate(s, p, r, np.full(6, 0.3))
    got_p, got_r, got_d = vector_fit(f, h, 3)
    assert np.allclose(got_p, p, atol=1e-9) and np.allclose(got_d, 0.3, atol=1e-9)
    assert np.abs(evaluate(s, got_p, got_r, got_d) - h).max() < 1e-9 * np.abs(h).max()


def test_pole_residue_choice_decodes_its_own_targets():
    sw = _sweeps(6)  # one resonance per design: two poles fit it exactly
    choice = PoleResidue(2)
    _, y = choice.training(sw, np.random.default_rng(0))
    assert y.shape == (6, 1 + 2 * 2 + 2 * 6 * 2 + 2 * 6)
    got, truth = choice.decode(y, sw), Answers.of(sw)
    assert np.allclose(got.center, truth.center, rtol=1e-6)
    assert np.allclose(got.edge, truth.edge, rtol=1e-6) and got.profile is None


@pytest.mark.skipif(not learners.lightgbm_available(), reason="needs the bench extra")
def test_lightgbm_boosters_do_not_depend_on_the_workers_fitting_them():
    rng = np.random.default_rng(0)
    x = rng.random((60, 3))
    y = np.column_stack([np.sin(3 * x[:, 0]) + x[:, 1], x[:, 2] ** 2, x.sum(axis=1)])
    one = learners.lgbm(0, trees=20, workers=1)(x, y)
    two = learners.lgbm(0, trees=20, workers=2)(x, y)
    np.testing.assert_array_equal(one(x), two(x))
    assert learners.make("lgbm", 0, trees=20, workers=2).notes == {"trees": 20}
