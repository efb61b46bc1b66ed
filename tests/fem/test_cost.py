"""The cost estimate: close to the real size, and every runaway input refused by name first."""

from __future__ import annotations

import math

import pytest

from fem import simulate
from fem.cost import DEFAULT_MAX_UNKNOWNS, check_cost, estimate_cost
from fem.scene import SceneError, scene_from_dict
from hapticrom.cli import main

UNIT = {"load": {"kind": "unit"}, "unit": {"encapsulation": ["A", "C"]}}


@pytest.mark.parametrize("d", [
    {"analysis": {"kind": "harmonic"}},
    {"analysis": {"kind": "static"}},
    {"analysis": {"kind": "harmonic", "frequency_hz": 250}, "load": {"direction": "normal"}},
    {"analysis": {"kind": "harmonic"}, "mesh": {"order": 1}},
    {"analysis": {"kind": "harmonic"}, "tissue": {"side": "fixed", "base": "absorbing"}},
    {"analysis": {"kind": "harmonic"}, **UNIT},
], ids=["harmonic", "static", "normal-250", "order1", "absorbing-base", "unit"])
def test_the_estimate_is_the_real_size_within_a_safe_margin(d):
    s = scene_from_dict(d)
    ratio = estimate_cost(s).unknowns / simulate(s).meta["dofs"]
    assert 0.95 <= ratio <= 1.5  # errs on the large side: a refusal is never a surprise


@pytest.mark.parametrize("d, field", [
    ({"mesh": {"near_size_mm": 0.001}}, "mesh.near_size_mm"),
    ({"analysis": {"kind": "harmonic", "frequency_hz": 0.1}}, "analysis.frequency_hz"),
    ({"tissue": {"radius_mm": 1e5}}, "tissue.radius_mm"),
    ({"tissue": {"layer": [{"material": "skin", "thickness_mm": 10000}]}},
     "tissue.layer[0].thickness_mm"),
    ({"tissue": {"layer": [{"material": "skin", "E_kPa": 0.001, "thickness_mm": 5}]}},
     "tissue.layer[0].E_kPa"),
    ({"analysis": {"kind": "transient", "time_step_ms": 0.001, "duration_ms": 1000}, **UNIT},
     "analysis.duration_ms"),
])
def test_runaway_scenes_are_refused_before_allocating_and_name_the_driver(d, field):
    d = {"analysis": {"kind": "harmonic"}, **d}
    s = scene_from_dict(d)
    with pytest.raises(SceneError) as info:
        simulate(s)
    assert info.value.field == field
    assert str(info.value).startswith(f"{field}: ")
    assert "raise the limit" in str(info.value)
    check_cost(s, math.inf)  # the estimate itself is instant and always possible


def test_the_suggested_mesh_size_fits_the_limit():
    s = scene_from_dict({"mesh": {"near_size_mm": 0.001}})
    with pytest.raises(SceneError) as info:
        check_cost(s)
    suggested = float(str(info.value).split("mesh.near_size_mm >= ")[1].split()[0].rstrip("."))
    fixed = scene_from_dict({"mesh": {"near_size_mm": suggested}})
    assert estimate_cost(fixed).unknowns <= DEFAULT_MAX_UNKNOWNS


def test_profile_and_step_counts_are_limited_at_validation():
    with pytest.raises(SceneError) as info:
        scene_from_dict({"output": {"profile_step_mm": 1e-9}})
    assert info.value.field == "output.profile_step_mm" and "at most 100000" in str(info.value)
    with pytest.raises(SceneError) as info:
        scene_from_dict({"analysis": {"kind": "transient", "time_step_ms": 1e-4,
                                      "duration_ms": 1e4}, **UNIT})
    assert info.value.field == "analysis.time_step_ms"


def test_cli_refuses_with_exit_2_and_writes_nothing(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text("[mesh]\nnear_size_mm = 0.001\n")
    out = tmp_path / "r.json"
    assert main(["simulate", str(scene), "--json", str(out)]) == 2
    assert "mesh.near_size_mm" in capsys.readouterr().err
    assert not out.exists()
    assert main(["simulate", str(scene), "--max-unknowns", "10"]) == 2
    assert "allowed >= 1000 or inf" in capsys.readouterr().err
