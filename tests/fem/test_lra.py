"""The LRA actuator (fem/actuators/lra.py): selected by ``load.kind = "lra"``, the rigid-disc
anchor at resonance, the same answer as a normal actuator of equal force at resonance, linear
in its force, and its resonance law in harmonic solves and sweep scaling."""

import analytic
import numpy as np
import pytest

from fem import simulate
from fem.actuators import ACTUATORS, actuator
from fem.scene import LoadKind, SceneError, load_scene, scene_from_dict, scene_to_dict

LRA = actuator("lra")
F0 = LRA.RESONANCE_HZ
NU = 0.4999  # bonded rigid disc (as tests/fem/test_haptic_unit.py): formulas are exact
MU = 100e3 / (2 * (1 + NU))
A = 3.5e-3


def _scene(kind, force_N=0.01, frequency_hz=F0, analysis="static", depth_mm=40.0):
    """A massless, effectively rigid unit bonded to a homogeneous body, pushed along z."""
    return scene_from_dict({
        "tissue": {"radius_mm": depth_mm, "side": "absorbing", "base": "absorbing",
                   "layer": [{"name": "h", "thickness_mm": depth_mm, "E_kPa": 100.0,
                              "density_kg_m3": 1000.0, "nu": NU}]},
        "load": {"kind": kind},
        "unit": {"motor": {"E_kPa": 1e8, "rotor_height_mm": 1.0},
                 "board": {"thickness_mm": 0.0}, "actuator": {"force_N": force_N}},
        "effects": {"unit_mass": False},
        "analysis": {"kind": analysis, "frequency_hz": frequency_hz},
        "mesh": {"near_size_mm": 0.25, "near_radius_mm": 5.0, "far_size_mm": 2.0},
        "output": {"radii_mm": [0.0, 1.75, 6.0]},
    })


def test_registered_as_a_unit_kind_of_mode_zero():
    assert list(ACTUATORS)[-1] == "lra" and LoadKind.LRA.is_unit
    assert LoadKind("lra").actuator is LRA
    for direction in ("normal", "tangential"):
        assert _scene("lra").load.__class__(kind="lra", direction=direction).fourier_mode == 0


def test_scene_file_selects_it_and_round_trips(tmp_path):
    path = tmp_path / "lra.toml"
    path.write_text('[tissue]\nradius_mm = 20.0\n[[tissue.layer]]\nname = "skin"\n'
                    'thickness_mm = 10.0\nE_kPa = 100.0\ndensity_kg_m3 = 1000.0\nnu = 0.45\n'
                    '[load]\nkind = "lra"\n[unit.actuator]\nforce_N = 1.4\n')
    scene = load_scene(path)
    assert scene.load.kind == "lra" and scene.unit.actuator.force_N == 1.4
    assert scene_from_dict(scene_to_dict(scene)) == scene


def test_bad_inputs_name_the_field():
    with pytest.raises(SceneError) as info:
        _scene("lra", force_N=0.0)
    assert info.value.field == "unit.actuator.force_N"
    with pytest.raises(SceneError) as info:  # the actuator table is not the ERM's
        scene_from_dict({**scene_to_dict(_scene("lra")), "load": {"kind": "unit"}})
    assert info.value.field == "unit.actuator" and '"lra"' in str(info.value)


def test_response_is_one_at_resonance_and_a_damped_resonator_elsewhere():
    q = LRA.QUALITY_FACTOR
    assert LRA.response(F0) == pytest.approx(1.0)
    r = 0.5  # |r^2 / (1 - r^2 + i r/Q)| / Q
    assert LRA.response(r * F0) == pytest.approx(r**2 / abs(1 - r**2 + 1j * r / q) / q)
    assert LRA.response(100 * F0) == pytest.approx(1 / q, rel=1e-3)  # a free mass


def test_static_rigid_disc_at_resonance_matches_boussinesq():
    res = simulate(_scene("lra", force_N=0.01))
    k = analytic.rigid_disc_stiffness(MU, NU, A)["vertical"]
    assert res.U[0, 1].real == pytest.approx(0.01 / k, rel=0.02)


@pytest.mark.parametrize("frequency_hz", [F0, 120.0])
def test_harmonic_equals_a_normal_actuator_of_its_force_and_is_linear(frequency_hz):
    kw = {"analysis": "harmonic", "frequency_hz": frequency_hz, "depth_mm": 20.0}
    lra = simulate(_scene("lra", force_N=0.5, **kw)).U
    lra3 = simulate(_scene("lra", force_N=1.5, **kw)).U
    force = 0.5 * float(LRA.response(frequency_hz))  # the normal actuator's flat force
    normal = simulate(_scene("normal_actuator", force_N=force, **kw)).U
    assert np.abs(lra).max() > 0
    np.testing.assert_allclose(lra, normal, rtol=1e-9, atol=1e-12 * np.abs(normal).max())
    np.testing.assert_allclose(lra3, 3 * lra, rtol=1e-9, atol=1e-12 * np.abs(lra).max())


def test_sweep_scaling_follows_the_force_of_each_frequency():
    freqs = np.array([120.0, 160.0, F0, 200.0])
    scale = LRA.load_scale(2 * np.pi * freqs, 2 * np.pi * 200.0)
    force = [LRA.force_N(_scene("lra", force_N=0.3, frequency_hz=f)) for f in freqs]
    np.testing.assert_allclose(scale, np.array(force) / force[-1], rtol=1e-12)


def test_unit_lra_table_sets_the_resonator_and_round_trips():
    d = scene_to_dict(_scene("lra", frequency_hz=150.0))
    assert "lra" not in d["unit"]  # absent: not written (scene hashes unchanged)
    d["unit"]["lra"] = {"resonance_hz": 150.0, "quality_factor": 5.0, "moving_mass_g": 2.0}
    scene = scene_from_dict(d)
    assert scene.unit.lra.resonance_hz == 150.0 and scene.unit.lra.moving_mass_kg == 2e-3
    assert LRA.law(scene).tau_s == pytest.approx(5.0 / (np.pi * 150.0))
    assert LRA.force_N(scene) == pytest.approx(0.01)  # driven at its own resonance
    assert LRA.force_N(_scene("lra", frequency_hz=150.0)) < 0.01  # the default resonance
    assert scene_from_dict(scene_to_dict(scene)) == scene


@pytest.mark.parametrize(("key", "value", "allowed"), [
    ("resonance_hz", 5.0, "20"), ("quality_factor", 0.0, "0.5"),
    ("moving_mass_g", 1e3, "100"), ("max_voltage_V", 1.0, "rated_voltage_V")])
def test_unit_lra_table_out_of_range_names_the_field(key, value, allowed):
    d = scene_to_dict(_scene("lra"))
    d["unit"]["lra"] = {key: value}
    with pytest.raises(SceneError) as info:
        scene_from_dict(d)
    assert info.value.field == f"unit.lra.{key}" and allowed in str(info.value)


def test_unit_lra_table_only_with_an_lra():
    d = scene_to_dict(_scene("normal_actuator"))
    d["unit"]["lra"] = {"resonance_hz": 150.0}
    with pytest.raises(SceneError) as info:
        scene_from_dict(d)
    assert info.value.field == "unit.lra" and '"lra"' in str(info.value)


def test_the_solver_and_the_run_time_share_one_drive_law():
    from motorlaw import ResonantDrive, drive_law

    assert LRA.law() == ResonantDrive() == drive_law(LRA.kind)  # registered by its load.kind
    assert (LRA.RESONANCE_HZ, LRA.QUALITY_FACTOR) == (LRA.law().resonance_hz,
                                                      LRA.law().quality_factor)
    assert drive_law(actuator("unit").kind).kind == "unit"  # the ERM's speed law
