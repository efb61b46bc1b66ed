"""What the solver tells the user: refusals that name the key the user wrote or the default
behind them, warnings when a requested output is cut to the model, summaries that define what
they print, and progress of a transient."""

from __future__ import annotations

import pytest
from scene_cases import unit_scene

from fem import simulate
from fem.problem import build_problem
from fem.scene import SceneError, load_scene, scene_from_dict, scene_to_dict

COARSE = {"order": 1, "near_size_mm": 1.0, "far_size_mm": 4.0}


def _bare_pogo(**analysis):
    d = unit_scene(attachment="pogo")
    d["analysis"] = analysis
    return scene_from_dict(d)


def test_static_pogo_refusal_names_the_default_not_a_key_the_user_never_wrote():
    with pytest.raises(SceneError) as err:
        build_problem(_bare_pogo(kind="static"))
    assert err.value.field == "analysis.kind"
    text = str(err.value)
    assert "defaults to false for a static analysis" in text
    assert "analysis.kind = 'harmonic'" in text and "ring_contact" in text


def test_an_explicit_inertia_false_is_named_as_written():
    d = unit_scene(attachment="pogo")
    d["analysis"] = {"kind": "harmonic"}
    d["effects"] = {"inertia": False}
    with pytest.raises(SceneError) as err:
        build_problem(scene_from_dict(d))
    assert err.value.field == "effects.inertia"
    assert "effects.inertia = false" in str(err.value)


def _forearm(kind="harmonic", **output):
    d = scene_to_dict(load_scene("examples/forearm.toml"))
    d["analysis"]["kind"] = kind
    d["mesh"].update(COARSE)
    d["tissue"]["radius_mm"] = 20.0
    d["output"].update(output)
    return scene_from_dict(d)


def test_a_profile_longer_than_the_model_is_cut_with_a_warning_naming_the_keys():
    res = simulate(_forearm(profile_length_mm=1000.0, radii_mm=[0.0, 4.0]))
    room = 20.0 - res.edge_mm
    assert res.profile_mm[-1] <= room + 1e-9
    (warning,) = [w for w in res.meta["warnings"] if "profile_length_mm" in w]
    assert "output.profile_length_mm = 1000" in warning and "tissue.radius_mm = 20" in warning
    assert f"cut to {res.profile_mm[-1]:g} mm" in warning
    assert "warning: output.profile_length_mm" in res.summary()
    ok = simulate(_forearm(profile_length_mm=5.0, radii_mm=[0.0, 4.0]))
    assert not any("profile_length_mm" in w for w in ok.meta.get("warnings", []))


def test_summary_defines_centre_edge_and_what_the_columns_are():
    text = simulate(_forearm(radii_mm=[0.0, 4.0])).summary("forearm.toml")
    assert "harmonic analysis at 120 Hz of forearm.toml" in text
    assert "|U| = modulus of the complex Fourier amplitude" in text
    assert "centre magn." in text and "(the skin at r = 0)" in text
    assert "normalized edge = edge / centre" in text
    static = simulate(_forearm("static", radii_mm=[0.0, 4.0])).summary("s.toml")
    assert static.splitlines()[0].endswith(": static analysis of s.toml")
    assert "|u| = static displacement" in static


def test_summary_of_a_unit_on_pins_says_the_centre_is_its_face_not_the_skin_row():
    d = scene_to_dict(load_scene("examples/unit-triple-reverse-pogo.toml"))
    d["mesh"].update(COARSE)
    d["tissue"]["radius_mm"] = 20.0
    res = simulate(scene_from_dict(d))
    assert res.centre_z_mm < 0  # the board's underside stands above the skin (z into tissue)
    text = res.summary()
    assert f"the unit's skin-side face at r = 0, z = {res.centre_z_mm:g} mm" in text
    assert "the r = 0 row of the table is the skin under it" in text


def test_transient_progress_reaches_the_total():
    d = scene_to_dict(load_scene("examples/unit-transient.toml"))
    d["mesh"].update(COARSE)
    d["tissue"]["radius_mm"] = 20.0
    d["analysis"].update(duration_ms=4.0, time_step_ms=0.2)
    calls = []
    simulate(scene_from_dict(d), progress=lambda done, total: calls.append((done, total)))
    assert calls and all(total == 20 for _, total in calls)
    assert [c[0] for c in calls] == sorted(c[0] for c in calls)
    assert calls[-1][0] == 20
