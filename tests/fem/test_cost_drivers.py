"""Cost refusals name the scene field that really drives the size, with a value that passes;
every scene error is raised at load naming scene fields (issue 21, item 4)."""

from __future__ import annotations

import re
import tomllib

import pytest

from fem.cost import check_cost
from fem.scene import SceneError, scene_from_dict


def _forearm(**mesh) -> dict:
    d = tomllib.loads(open("examples/forearm.toml", encoding="utf-8").read())
    d["mesh"].update(mesh)
    return d


def _erm_transient(rated_frequency_hz: float) -> dict:
    d = tomllib.loads(open("examples/unit-transient.toml", encoding="utf-8").read())
    d["tissue"].update(radius_mm=20.0, base="absorbing")
    d["output"].update(radii_mm=[0.0, 2.0, 4.0], profile_length_mm=5.0)
    d["unit"]["motor"]["rated_frequency_hz"] = rated_frequency_hz
    return d


def test_fixed_cells_are_named_and_the_suggestion_passes():
    """Before: mesh.cells_r = [100000] was blamed on tissue.radius_mm, and following that
    advice was refused again."""
    with pytest.raises(SceneError) as err:
        check_cost(scene_from_dict(_forearm(cells_r=[100000])))
    assert err.value.field == "mesh.cells_r"
    suggested = re.search(r"use mesh\.cells_r = (\[[0-9, ]+\])", str(err.value)).group(1)
    counts = [int(x) for x in suggested.strip("[]").split(",")]
    assert check_cost(scene_from_dict(_forearm(cells_r=counts))).unknowns <= 1e6
    with pytest.raises(SceneError) as err:
        check_cost(scene_from_dict(_forearm(cells_z=[3000, 3000, 3000, 3000])))
    assert err.value.field == "mesh.cells_z"


def test_an_erm_transient_names_the_motor_speed_and_a_value_that_passes():
    """Before: refused on analysis.frequency_hz (unused by an ERM transient), and still
    refused after raising it to 5000 Hz."""
    with pytest.raises(SceneError) as err:
        check_cost(scene_from_dict(_erm_transient(5.0)))
    assert err.value.field == "unit.motor.rated_frequency_hz"
    assert "3 wavelengths" in str(err.value)
    value = float(re.search(r"rated_frequency_hz >= ([0-9.e+]+)", str(err.value)).group(1))
    assert check_cost(scene_from_dict(_erm_transient(value))).unknowns <= 1e6


def test_a_harmonic_frequency_refusal_suggests_a_value_that_passes():
    d = _forearm()
    d["tissue"].update(base="absorbing")
    d["analysis"]["frequency_hz"] = 2.0
    with pytest.raises(SceneError) as err:
        check_cost(scene_from_dict(d))
    assert err.value.field == "analysis.frequency_hz"
    value = float(re.search(r"frequency_hz >= ([0-9.e+]+)", str(err.value)).group(1))
    d["analysis"]["frequency_hz"] = value
    check_cost(scene_from_dict(d))


def test_rated_voltage_above_the_erm_drive_is_refused_at_load():
    """Before: the scene loaded, then the solve failed naming ERMMotor.max_voltage_V."""
    d = tomllib.loads(open("examples/unit-transient.toml", encoding="utf-8").read())
    d["unit"]["motor"]["rated_voltage_V"] = 6
    with pytest.raises(SceneError) as err:
        scene_from_dict(d)
    assert err.value.field == "unit.motor.rated_voltage_V"
    assert "<= 4.5 V" in str(err.value) and "ERMMotor" not in str(err.value)
    d["analysis"]["voltage_schedule"] = [[0.0, 6.0], [100.0, 0.0]]  # a 6 V drive: fine
    scene_from_dict(d)
