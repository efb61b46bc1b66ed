"""The frequency sweep: scene band, the operator's affine form, the condensed solver, and the
reduced-order model against one direct solve per frequency on the same mesh.

Fast cases here; every example scene and 40 designs of the default space at 1 Hz steps in
test_sweep_slow.py (``make test-slow``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from sweep_cases import MAGNITUDE_TOL, PHASE_TOL, ROOT, as_sweep, example

from fem import results, simulate
from fem.scene import SceneError, load_scene, scene_from_dict, scene_to_dict
from fem.solve import OperatorLog, solve_mode
from fem.sweep import SweepResult, direct_sweep, setup, sweep, sweep_errors
from fem.sweep_operator import (
    chebyshev_points,
    lagrange_weights,
    stiffness_and_mass,
)
from fem.sweep_output import extrema, sweep_document

BAND = {"start": 100, "stop": 250, "step": 1}


def unit_scene(**analysis) -> dict:
    return {"load": {"kind": "unit"}, "unit": {},
            "analysis": {"kind": "sweep", "frequency_hz": BAND} | analysis}


# ---------------------------------------------------------------- the scene's band


def test_band_table_and_list_give_the_same_scene_and_round_trip():
    by_table = scene_from_dict(unit_scene())
    assert by_table.analysis.frequencies_hz == tuple(float(f) for f in range(100, 251))
    assert by_table.analysis.frequency_hz == 250.0  # the mesh is sized for the highest
    by_list = scene_from_dict(unit_scene(frequency_hz=list(range(100, 251))))
    assert by_list == by_table
    assert scene_from_dict(scene_to_dict(by_table)) == by_table


@pytest.mark.parametrize("analysis, field, text", [
    ({"frequency_hz": 150.0}, "analysis.frequency_hz", "a sweep needs a band"),
    ({"kind": "harmonic"}, "analysis.frequency_hz", "only with analysis.kind = 'sweep'"),
    ({"frequency_hz": {"start": 200, "stop": 100, "step": 1}}, "analysis.frequency_hz.stop",
     "allowed stop > start"),
    ({"frequency_hz": {"start": 100, "stop": 250, "step": 0}}, "analysis.frequency_hz.step",
     "allowed 0 < step <= 1e5"),
    ({"frequency_hz": {"start": 100, "stop": 250, "step": 1e-6}},
     "analysis.frequency_hz.step", "at most 100000"),
    ({"frequency_hz": {"start": 100, "stop": 250}}, "analysis.frequency_hz.step", "missing"),
    ({"frequency_hz": {"start": 100, "stop": 250, "step": 1, "stpe": 2}},
     "analysis.frequency_hz.stpe", "not a key of a band"),
    ({"frequency_hz": [100, 120, 110]}, "analysis.frequency_hz[2]", "increase strictly"),
    ({"frequency_hz": [100, -5]}, "analysis.frequency_hz[1]", "out of range"),
    ({"frequency_hz": []}, "analysis.frequency_hz", "empty"),
])
def test_bad_bands_name_the_field_and_the_allowed_range(analysis, field, text):
    with pytest.raises(SceneError) as err:
        scene_from_dict(unit_scene(**analysis))
    assert err.value.field == field and text in str(err.value)


# ---------------------------------------------------------------- the operator


@pytest.fixture(scope="module")
def default_setup():
    return setup(scene_from_dict(unit_scene(frequency_hz={"start": 100, "stop": 250,
                                                         "step": 10})))


def test_lagrange_weights_reproduce_a_polynomial_and_its_slope():
    nodes = chebyshev_points(0.2, 0.9, 5)
    values, slopes = lagrange_weights(nodes, 0.37)
    f = 3 * nodes**4 - nodes**2 + 2
    assert values @ f == pytest.approx(3 * 0.37**4 - 0.37**2 + 2, rel=1e-13)
    assert slopes @ f == pytest.approx(12 * 0.37**3 - 2 * 0.37, rel=1e-12)


def test_pml_interpolation_converges_geometrically(default_setup):
    """The PML's element matrices interpolated in 1/omega: the error falls by a roughly
    constant factor per node (analytic in 1/omega on the band)."""
    p, op = default_setup.problem, default_setup.operator
    layer = op.pml[::4]  # a quarter of the layer's elements: the same functions of omega

    def Z(w: float) -> np.ndarray:
        K, M = stiffness_and_mass(p, layer, replace(p.domain.stretch, omega=w))
        return K - w**2 * M

    probe = 2 * np.pi * np.array([113.0, 238.0])
    exact = [Z(w) for w in probe]
    errors = []
    for n in (3, 5, 7):
        t = chebyshev_points(1 / (2 * np.pi * 250.0), 1 / (2 * np.pi * 100.0), n)
        at_nodes = np.stack([Z(1 / tj) for tj in t])
        errors.append(max(
            np.abs(np.tensordot(lagrange_weights(t, 1 / w)[0], at_nodes, axes=1) - ex).max()
            / np.abs(ex).max() for w, ex in zip(probe, exact, strict=True)))
    assert errors[0] > 5 * errors[1] > 25 * errors[2]
    assert errors[2] < 1e-5


def test_condensed_solver_equals_the_direct_harmonic_solve(default_setup):
    s = default_setup
    p = s.problem
    for f in (100.0, 250.0):  # band ends: nodes of no interpolation
        w = 2 * np.pi * f
        x = s.operator.solver(w).solve(s.operator.load)
        got = s.output_map(x[:, None])[:, :, 0]
        domain = replace(p.domain, stretch=replace(p.domain.stretch, omega=w))
        sol = solve_mode(domain, p.mode, p.load, w, OperatorLog(), extra=p.extra)
        ref = results.interpolate(s.points.stencil, sol.nodal())
        assert np.abs(got - ref).max() < 1e-6 * np.abs(ref).max()


def test_apply_matches_the_solver_residual(default_setup):
    """A x = b for the solver's x, with A applied term by term (the affine form and the
    condensed factorisation describe one operator)."""
    op = default_setup.operator
    w = 2 * np.pi * 163.0
    x = op.solver(w).solve(op.load)
    r = op.apply(op.coefficients(w), x) - op.load
    assert np.linalg.norm(r) < 1e-7 * np.linalg.norm(op.load)


# ---------------------------------------------------------------- the reduced model


@pytest.mark.parametrize("name, step", [("unit-sweep.toml", 10), ("forearm.toml", 15)])
def test_sweep_matches_direct_solves(name, step):
    scene = example(name)
    rom = sweep(scene)
    ref = direct_sweep(scene, rom.frequency_hz[::step])
    err = sweep_errors(rom, ref)
    assert max(v for k, v in err.items() if k.endswith("magnitude")) <= MAGNITUDE_TOL, err
    assert max(v for k, v in err.items() if k.endswith("phase_rad")) <= PHASE_TOL, err
    assert rom.error_estimate <= rom.tolerance
    assert rom.full_solves == len(rom.meta["expansions_hz"]) <= 6
    assert rom.meta["residual"] < 1e-2


def test_tolerance_buys_accuracy():
    scene = example("unit-bare-forward.toml")
    loose, tight = sweep(scene, tolerance=3e-2), sweep(scene, tolerance=1e-4)
    ref = direct_sweep(scene, loose.frequency_hz[::25])
    e_loose = max(sweep_errors(loose, ref).values())
    e_tight = max(sweep_errors(tight, ref).values())
    assert tight.full_solves >= loose.full_solves and e_tight < e_loose
    assert e_tight <= 1e-4 and tight.error_estimate <= 1e-4


def test_simulate_returns_the_sweep_and_its_document(tmp_path):
    scene = as_sweep(load_scene(ROOT / "examples" / "unit-bare-forward.toml"),
                     (120.0, 150.0, 180.0))
    res = simulate(scene)
    assert isinstance(res, SweepResult) and res.center.shape == (3, 3)
    doc = sweep_document(res, "x.toml")
    assert doc["kind"] == "hapticrom.simulate.sweep" and doc["schema_version"] == 1
    assert doc["analysis"]["frequency_hz"] == [120.0, 150.0, 180.0]
    assert len(doc["centre"]["ur_complex_um"]["re"]) == 3
    assert np.allclose(doc["centre"]["magnitude_um"], res.center_amplitude_um)
    assert doc["reduced_model"]["full_solves"] == res.full_solves >= 1
    assert len(doc["profile"]["magnitude_um"]) == 3
    assert "sweep of 3 frequencies" in res.summary("x.toml")


def test_unbalance_force_scales_the_load_with_omega_squared():
    """An ERM's force is m e omega^2: at equal operator, twice the frequency is four times the
    load, which the sweep's load scale carries."""
    s = setup(example("unit-bare-forward.toml"))
    assert s.load_scale[0] == pytest.approx((100.0 / 250.0) ** 2)
    assert s.load_scale[-1] == pytest.approx(1.0)


def test_extrema_mark_peaks_and_dips():
    f = np.linspace(100, 250, 151)
    curve = 1 + np.exp(-((f - 150) / 5) ** 2) - 0.5 * np.exp(-((f - 210) / 4) ** 2)
    peaks, dips = extrema(f, curve)
    assert peaks.tolist() == [150.0] and dips.tolist() == [210.0]
    assert extrema(f, np.ones_like(f))[0].size == 0
