"""The haptic unit model: analytic anchors, the smeared pins, effects switched on and off."""

import json

import analytic
import numpy as np
import pytest

from fem import elements, simulate
from fem.haptic_unit import pin_compression
from fem.problem import build_problem
from fem.scene import SceneError, load_scene, scene_from_dict, scene_to_dict
from hapticrom.cli import main

POGO = "examples/unit-triple-reverse-pogo.toml"
GLUED = "examples/unit-double-forward.toml"
NU = 0.4999  # bonded rigid disc: the normal-tangential coupling vanishes, formulas are exact
MU = 100e3 / (2 * (1 + NU))
A = 3.5e-3


def _rigid_disc_scene(kind, rocking=True, analysis="static"):
    """A massless, effectively rigid motor (E 1e8 kPa on 100 kPa tissue: contrast 1e6) bonded
    to a deep homogeneous body with a static far field."""
    return scene_from_dict({
        "tissue": {"radius_mm": 40.0, "side": "absorbing", "base": "absorbing",
                   "layer": [{"name": "h", "thickness_mm": 40.0, "E_kPa": 100.0,
                              "density_kg_m3": 1000.0, "nu": NU}]},
        "load": {"kind": kind},
        "unit": {"motor": {"E_kPa": 1e8, "rotor_height_mm": 1.0},
                 "board": {"thickness_mm": 0.0}, "actuator": {"force_N": 0.01}}
        if kind == "normal_actuator" else
        {"motor": {"E_kPa": 1e8, "rotor_height_mm": 1.0}, "board": {"thickness_mm": 0.0}},
        "effects": {"unit_mass": False, **({"rocking": rocking} if kind == "unit" else {})},
        "analysis": {"kind": analysis, "frequency_hz": 120.0},
        "mesh": {"near_size_mm": 0.25, "near_radius_mm": 5.0, "far_size_mm": 2.0},
        "output": {"radii_mm": [0.0, 1.75]},
    })


def test_rigid_disc_vertical_stiffness():
    res = simulate(_rigid_disc_scene("normal_actuator"))
    k = analytic.rigid_disc_stiffness(MU, NU, A)["vertical"]
    assert res.U[0, 1].real == pytest.approx(0.01 / k, rel=0.02)


def test_rigid_disc_horizontal_stiffness_and_rocking():
    scene = _rigid_disc_scene("unit", rocking=False)
    force = scene.unit.motor.force_N_at(120.0)
    k = analytic.rigid_disc_stiffness(MU, NU, A)
    slide = simulate(scene)
    assert slide.U[0, 0].real == pytest.approx(force / k["horizontal"], rel=0.02)
    assert abs(slide.U[1, 1]) < 0.02 * abs(slide.U[0, 0])  # no tilt without a moment
    tilt = simulate(_rigid_disc_scene("unit", rocking=True))
    h = 1.0e-3  # rotor plane above the contact face (forward orientation, no board)
    rotation = np.abs(tilt.U[1, 1]) / 1.75e-3  # U_z = phi r under the rigid disc
    assert rotation == pytest.approx(force * h / k["rocking"], rel=0.03)


def test_smeared_pins_keep_total_and_rocking_stiffness_of_three_pins():
    scene = load_scene(POGO)
    p = build_problem(scene)
    pins, pogo = p.layout.pins, scene.unit.pogo
    assert pins.mode_stiffness(0) == pytest.approx(3 * pogo.stiffness_N_m)
    dofs, b = pin_compression(p.domain, 1, pins)
    nodes = dofs // elements.dofs_per_node(1)
    r, z = p.domain.mesh.nodes[nodes].T
    tilt = np.where(z < 0, r, 0.0)  # board turned by phi = 1 about a horizontal axis
    compression = b @ tilt
    rocking = pins.mode_stiffness(1) * compression**2
    discrete = sum(pogo.stiffness_N_m * (pogo.radius_m * np.cos(t)) ** 2
                   for t in 2 * np.pi * np.arange(3) / 3)
    assert rocking == pytest.approx(discrete, rel=0.01)  # footprint averaging: < 1 %


def test_glued_unit_center_is_the_skin_and_pogo_center_is_the_board():
    glued = simulate(load_scene("examples/unit-bare-forward.toml"))
    skin = simulate(scene_from_dict({**scene_to_dict(load_scene(
        "examples/unit-bare-forward.toml")), "output": {"radii_mm": [0.0]}}))
    assert glued.center_amplitude_um == pytest.approx(float(np.linalg.norm(skin.U[0]) * 1e6))
    pogo = simulate(load_scene(POGO))
    lay = build_problem(load_scene(POGO)).layout
    nodes = pogo.domain.mesh.nodes
    board = np.flatnonzero((nodes[:, 0] == 0) & np.isclose(nodes[:, 1], lay.contact_z))
    assert lay.contact_z == pytest.approx(-2.4e-3)  # the pins hold the board 2.4 mm up
    assert pogo.center_amplitude_um == pytest.approx(
        float(np.linalg.norm(pogo.nodal[board[0]]) * 1e6))
    assert pogo.center_amplitude_um != pytest.approx(float(np.linalg.norm(pogo.U[0]) * 1e6))


def test_pogo_preload_check_reports_contact():
    d = scene_to_dict(load_scene(POGO))
    d["effects"] = {"preload": True}
    res = simulate(scene_from_dict(d))
    pre = res.extras["preload"]
    assert pre["preload_per_pin_N"] == pytest.approx(2942.0 * 0.3e-3)
    assert 0 < pre["dynamic_pin_force_N"] < pre["preload_per_pin_N"]
    assert pre["contact_maintained"] is True


@pytest.mark.parametrize("example", ["unit-bare-forward", "unit-double-forward",
                                     "unit-triple-reverse-pogo"])
def test_paper_prototypes_simulate_from_the_cli(tmp_path, example):
    out = tmp_path / "r.json"
    assert main(["simulate", f"examples/{example}.toml", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["normalized_edge"] == pytest.approx(
        data["edge"]["magnitude_um"] / data["centre"]["magnitude_um"])
    prof = data["profile"]
    assert prof["distance_from_edge_mm"][:3] == [0.0, 1.0, 2.0]  # exact, no float noise
    assert prof["magnitude_um"][0] == pytest.approx(data["edge"]["magnitude_um"])
    assert len(prof["uz_amplitude_um"]) == len(prof["magnitude_um"])


# --------------------------------------------------------------------------- effects on demand


def _scene(example=POGO, **effects):
    d = scene_to_dict(load_scene(example))
    d["effects"] = effects
    return scene_from_dict(d)


def test_skipped_inertia_never_builds_a_mass_matrix(monkeypatch):
    def forbidden(*args, **kwargs):
        raise AssertionError("mass assembled although inertia is off")

    monkeypatch.setattr(elements, "mass", forbidden)
    res = simulate(_scene(GLUED, inertia=False))
    assert "inertia" in res.meta["skipped"]
    assert not any(op.startswith("mass") for op in res.meta["operators"])


def test_skipped_encapsulation_meshes_no_rings_and_keeps_the_nominal_edge():
    full = build_problem(load_scene(POGO))
    bare = build_problem(_scene(encapsulation=False))
    assert bare.domain.mesh.n_elements < full.domain.mesh.n_elements
    assert bare.edge == full.edge
    assert {s.name for s in bare.domain.solids}.isdisjoint(
        {r.name for r in load_scene(POGO).unit.encapsulation})


def test_skipped_unit_mass_and_rocking_change_the_model():
    full = build_problem(load_scene(GLUED))
    light = build_problem(_scene(GLUED, unit_mass=False, rocking=False))
    motor = next(s for s in light.domain.solids if s.name == "motor")
    assert motor.density_kg_m3 == 0.0
    assert light.layout.rotor_z == light.layout.contact_z - 0.1e-3  # at the motor's base face
    assert full.layout.rotor_z < light.layout.rotor_z
    assert simulate(_scene(GLUED, unit_mass=False)).center_amplitude_um > 0


def _contact(contact, example=POGO, **effects):
    d = scene_to_dict(_scene(example, **effects))
    d["unit"]["ring_contact"] = contact
    return scene_from_dict(d)


@pytest.mark.parametrize("effect", ["inertia", "unit_mass"])
def test_unit_floating_on_frictionless_pins_needs_inertia(effect):
    """Rings that do not touch the unit (ring_contact = "none") leave only its inertia holding
    it sideways: switching that off is rejected; a ring contact makes it well-posed."""
    with pytest.raises(SceneError) as err:
        build_problem(_contact("none", **{effect: False}))
    assert err.value.field == f"effects.{effect}" and "ring_contact" in str(err.value)
    for contact in ("frictionless", "bonded"):
        res = simulate(_contact(contact, **{effect: False}))
        assert np.isfinite(res.normalized_edge) and res.center_amplitude_um > 0


def test_frictionless_ring_contact_ties_only_the_radial_displacement():
    res = simulate(load_scene(POGO))  # default: frictionless
    p = build_problem(load_scene(POGO))
    ring, core, comp = p.domain.ties[0]
    assert comp == 0 and ring.size == core.size > 4
    U = res.nodal
    assert np.allclose(U[ring, 0], U[core, 0])  # u_r continuous across the slit
    assert not np.allclose(U[ring, 1], U[core, 1])  # u_z free: no shear through the contact
    none = simulate(_contact("none"))
    bonded = simulate(_contact("bonded"))
    assert bonded.edge_mm == pytest.approx(res.edge_mm - 0.05)  # no slit when bonded
    assert len({round(x.normalized_edge, 3) for x in (res, none, bonded)}) == 3


def test_glued_unit_builds_no_pin_operator():
    res = simulate(load_scene("examples/unit-double-forward.toml"))
    assert not any("pogo" in op for op in res.meta["operators"])
    assert "pogo" in res.meta["skipped"]


@pytest.mark.parametrize(("effects", "field"), [
    ({"pogo": False}, "effects.pogo"),
    ({"spin_up": True}, "effects.spin_up"),
])
def test_impossible_effect_requests_are_rejected(effects, field):
    with pytest.raises(SceneError) as err:
        build_problem(_scene(**effects))
    assert err.value.field == field


def test_inertia_requested_for_a_static_scene_is_rejected():
    d = scene_to_dict(load_scene(POGO))
    d["analysis"]["kind"] = "static"
    d["effects"] = {"inertia": True}
    with pytest.raises(SceneError, match=r"effects\.inertia"):
        build_problem(scene_from_dict(d))
