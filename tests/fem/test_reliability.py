"""Regressions of inputs that once crashed or misled (one test per reported case)."""

from __future__ import annotations

import numpy as np
import pytest
from scene_cases import unit_scene

from fem import simulate
from fem.scene import SceneError, scene_from_dict

COARSE = {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1}


@pytest.mark.parametrize("kind", ["pressure_patch", "point_force"])
def test_a_transient_without_a_unit_is_a_field_error(kind):
    with pytest.raises(SceneError) as info:
        scene_from_dict({"load": {"kind": kind}, "analysis": {"kind": "transient"}})
    assert info.value.field == "analysis.kind"
    assert 'load.kind = "unit"' in str(info.value) and repr(kind) in str(info.value)


def test_load_kinds_are_named_by_their_value_in_messages():
    with pytest.raises(SceneError) as info:
        scene_from_dict({"unit": {}})
    assert "(load.kind is 'pressure_patch')" in str(info.value)
    assert "LoadKind" not in str(info.value)


@pytest.mark.parametrize("motor_mm", [5.0, 6.0, 8.0])
def test_rings_on_a_motor_wider_or_narrower_than_the_board_solve(motor_mm):
    """Frictionless ring contact ties the ring only where the core has a face."""
    d = unit_scene(encapsulation=["A", "C"], motor={"diameter_mm": motor_mm})
    d |= {"analysis": {"kind": "harmonic", "frequency_hz": 150.0}, "mesh": COARSE}
    res = simulate(scene_from_dict(d))
    assert np.isfinite(res.center_amplitude_um) and res.center_amplitude_um > 0
    assert np.isfinite(res.normalized_edge) and res.normalized_edge > 0


def test_ring_contact_is_continuous_in_the_motor_diameter():
    """A motor 0.01 mm wider than the board gives nearly the answer of an equal one."""
    out = []
    for motor_mm in (7.0, 7.01):
        d = unit_scene(encapsulation=["A"], motor={"diameter_mm": motor_mm})
        d |= {"analysis": {"kind": "harmonic", "frequency_hz": 150.0}, "mesh": COARSE}
        out.append(simulate(scene_from_dict(d)))
    assert out[1].center_amplitude_um == pytest.approx(out[0].center_amplitude_um, rel=0.02)
    assert out[1].normalized_edge == pytest.approx(out[0].normalized_edge, rel=0.02)


def test_a_scene_file_saved_with_a_byte_order_mark_loads(tmp_path):
    from fem.scene import load_scene

    f = tmp_path / "bom.toml"
    f.write_bytes("\ufeff[analysis]\nkind = \"harmonic\"\n".encode())
    assert load_scene(f).analysis.kind == "harmonic"


def test_unused_fields_follow_the_scene():
    from fem.scene import effective_scene_dict, unused_fields

    glued = scene_from_dict(unit_scene(encapsulation=[]))
    assert {"unit.pogo", "unit.ring_thickness_mm", "load.radius_mm"} <= set(unused_fields(glued))
    assert "pogo" not in effective_scene_dict(glued)["unit"]
    pogo = scene_from_dict(unit_scene(attachment="pogo", encapsulation=["A"]))
    assert "pogo" in effective_scene_dict(pogo)["unit"]
    assert "unit.ring_contact" not in unused_fields(pogo)
    static = scene_from_dict({"analysis": {"kind": "static"}})
    assert "frequency_hz" not in effective_scene_dict(static)["analysis"]
    assert "load.radius_mm" not in unused_fields(static)  # the default patch load uses it


@pytest.mark.parametrize("skin_mm", [0.001, 0.01])
def test_a_pogo_unit_on_a_micron_thin_skin_layer_solves(skin_mm):
    """Once blamed the pin footprint; the thinnest allowed layer now meshes and solves."""
    d = unit_scene(attachment="pogo", encapsulation=["A"])
    d |= {"analysis": {"kind": "harmonic", "frequency_hz": 150.0}, "mesh": COARSE,
          "tissue": {"layer": [{"material": "skin", "thickness_mm": skin_mm},
                               {"material": "fat", "thickness_mm": 10.0}]}}
    res = simulate(scene_from_dict(d))
    assert np.isfinite(res.center_amplitude_um) and res.center_amplitude_um > 0
