"""Scene schema of the haptic unit: every bad value names its field and the allowed range, and
random valid units round-trip."""

from __future__ import annotations

import math

import pytest
from fem_cases import assert_scene_error
from hypothesis import given, settings
from hypothesis import strategies as st
from scene_cases import SILICONES, assert_round_trips, library_ring, unit_scene, with_value

from fem.scene import SceneError, scene_from_dict

# ----------------------------------------------------------------------------- errors

UNIT_ERRORS = [
    # unknown keys, with a suggestion
    (unit_scene(orientaton="forward"), "unit.orientaton", "did you mean 'orientation'"),
    (unit_scene(motor={"mass_kg": 1.0}), "unit.motor.mass_kg", "did you mean 'mass_g'"),
    (unit_scene(board={"thickness": 1.0}), "unit.board.thickness",
     "did you mean 'thickness_mm'"),
    (unit_scene(pogo={"stiffness": 1.0}), "unit.pogo.stiffness", "did you mean 'stiffness_N_m'"),
    (unit_scene(encapsulation=[{"material": "A", "thickness_mm": 1.0}]),
     "unit.encapsulation[0].thickness_mm", "allowed keys: name, material, E_kPa"),
    (unit_scene("normal_actuator", actuator={"force": 1.0}), "unit.actuator.force",
     "did you mean 'force_N'"),
    # wrong types and choices
    (unit_scene(orientation="sideways"), "unit.orientation", "'forward', 'reverse'"),
    (unit_scene(attachment="tape"), "unit.attachment", "'glued', 'pogo'"),
    (unit_scene(encapsulation="A"), "unit.encapsulation", "expected a list"),
    (unit_scene(encapsulation=[3]), "unit.encapsulation[0]", "material name or an inline table"),
    (unit_scene(encapsulation=["A"] * 6), "unit.encapsulation",
     "0 <= number of rings <= 5"),
    (unit_scene(encapsulation=["A", "ecoflex"]), "unit.encapsulation[1]", "dragon-skin-30"),
    (unit_scene(encapsulation=[{"material": "silly putty"}]),
     "unit.encapsulation[0].material", "unknown material"),
    (unit_scene(encapsulation=[{"E_kPa": 1.0, "nu": 0.4}]),
     "unit.encapsulation[0].density_kg_m3", "0 < density_kg_m3 <= 1e5"),
    (unit_scene(encapsulation=["A", {"material": "B", "nu": 0.5}]),
     "unit.encapsulation[1].nu", "0 <= nu < 0.5"),
    (unit_scene(board={"material": "pcbx"}), "unit.board.material", "unknown material"),
    (unit_scene(pogo={"count": 2.0}), "unit.pogo.count", "expected an integer"),
    (unit_scene(motor=[]), "unit.motor", "must be a table"),
    ({"load": {"kind": "unit"}, "unit": 1}, "unit", "must be a table"),
]


@pytest.mark.parametrize(("d", "field", "fragment"), UNIT_ERRORS)
def test_unit_errors_name_field_and_allowed(d: dict, field: str, fragment: str) -> None:
    assert_scene_error(d, field, fragment)


# (path, [bad values], [good values], allowed text); load.kind = "unit" throughout
UNIT_RANGES = [
    ("unit.ring_thickness_mm", [0, 20.5], [0.01, 20], "0.001 <= ring_thickness_mm <= 20"),
    ("unit.motor.diameter_mm", [0, 100.5], [0.1, 40], "0.001 <= diameter_mm <= 100"),
    ("unit.motor.height_mm", [0, 50.5], [1.4, 50], "0.001 <= height_mm <= 50"),
    ("unit.motor.mass_g", [0, 1000.5], [1e-3, 1000], "0 < mass_g <= 1000"),
    ("unit.motor.unbalance_g_mm", [0, -1, 1001], [1e-6, 1000], "0 < unbalance_g_mm <= 1000"),
    ("unit.motor.rotor_height_mm", [-0.1, 2.01], [0, 2.0],
     "0 <= rotor_height_mm <= unit.motor.height_mm (= 2)"),
    ("unit.motor.E_kPa", [0, 1.1e9], [1, 1e9], "0.001 <= E_kPa <= 1e9"),
    ("unit.motor.nu", [-0.1, 0.5], [0, 0.499], "0 <= nu < 0.5"),
    ("unit.motor.rated_voltage_V", [0, 50.5], [0.5, 50], "0 < rated_voltage_V <= 50"),
    ("unit.motor.rated_frequency_hz", [0, 1e4 + 1], [1, 1e4], "0 < rated_frequency_hz <= 1e4"),
    ("unit.motor.start_voltage_V", [-0.1, 3.3, 4], [0, 3.29],
     "0 <= start_voltage_V < unit.motor.rated_voltage_V (= 3.3)"),
    ("unit.motor.tau_spinup_ms", [0, 1e4 + 1], [0.1, 1e4], "0 < tau_spinup_ms <= 1e4"),
    ("unit.motor.tau_spindown_ms", [0, 1e4 + 1], [0.1, 1e4], "0 < tau_spindown_ms <= 1e4"),
    ("unit.motor.force_at_hz", [0, 1e5 + 1], [], "0 < force_at_hz <= 1e5"),
    ("unit.board.thickness_mm", [-0.1, 10.5], [0, 10], "0 <= thickness_mm <= 10"),
    ("unit.board.diameter_mm", [0, 100.5], [0.5, 40], "0.001 <= diameter_mm <= 100"),
    ("unit.board.E_kPa", [0, 1.1e9], [1, 1e9], "0.001 <= E_kPa <= 1e9"),
    ("unit.board.density_kg_m3", [0, 1e5 + 1], [1, 1e5], "0 < density_kg_m3 <= 1e5"),
    ("unit.board.nu", [-0.1, 0.5], [0, 0.49], "0 <= nu < 0.5"),
    ("unit.pogo.count", [0, 65], [1, 64], "1 <= count <= 64"),
    ("unit.pogo.radius_mm", [0, 50.5], [0.1, 50], "0.001 <= radius_mm <= 50"),
    ("unit.pogo.stiffness_N_m", [0, 1.1e9], [1, 1e9], "0 < stiffness_N_m <= 1e9"),
    ("unit.pogo.length_mm", [0, 50.5], [0.31, 50], "0.001 <= length_mm <= 50"),
    ("unit.pogo.travel_mm", [-0.1, 2.4], [0, 2.39],
     "0 <= travel_mm < unit.pogo.length_mm (= 2.4)"),
    ("unit.pogo.tip_diameter_mm", [0, 5.5], [0.01, 5], "0.001 <= tip_diameter_mm <= 5"),
    ("unit.actuator.force_N", [0, 1001, -1001, math.nan, math.inf], [-1e3, 1e3, 1e-6],
     "-1e3 <= force_N <= 1e3, non-zero"),
]


@pytest.mark.parametrize(("path", "bad", "good", "allowed"), UNIT_RANGES)
def test_unit_range_limits(path: str, bad: list, good: list, allowed: str) -> None:
    kind = "normal_actuator" if path.startswith("unit.actuator") else "unit"
    base = unit_scene(kind)
    if path == "unit.motor.force_at_hz":
        base["unit"]["motor"] = {"force_N": 0.01}
    for value in good:
        scene_from_dict(with_value(path, value, base))
    for value in bad:
        with pytest.raises(SceneError) as info:
            scene_from_dict(with_value(path, value, base))
        assert info.value.field.startswith(path), (value, info.value.field)
        assert allowed in str(info.value), (value, str(info.value))


# ----------------------------------------------------------------------------- random units

_finite = {"allow_nan": False, "allow_infinity": False}
inline_rings = st.fixed_dictionaries(
    {"E_kPa": st.floats(1e-3, 1e6, **_finite), "density_kg_m3": st.floats(1, 1e4, **_finite),
     "nu": st.floats(0, 0.4999, **_finite)},
    optional={"name": st.text(max_size=8), "loss_factor": st.floats(0, 2, **_finite),
              "material": st.sampled_from(SILICONES)},
)
units = st.fixed_dictionaries(
    {"encapsulation": st.lists(st.one_of(st.sampled_from([*SILICONES, "A", "d"]), inline_rings),
                               max_size=5)},
    optional={
        "orientation": st.sampled_from(["forward", "reverse"]),
        "attachment": st.sampled_from(["glued", "pogo"]),
        "ring_thickness_mm": st.floats(0.01, 5, **_finite),
        "motor": st.fixed_dictionaries({}, optional={
            "mass_g": st.floats(1e-3, 1000, **_finite),
            "unbalance_g_mm": st.floats(1e-6, 1000, **_finite),
            "rotor_height_mm": st.floats(0, 2, **_finite)}),
        "pogo": st.fixed_dictionaries({}, optional={
            "count": st.integers(1, 64), "stiffness_N_m": st.floats(1, 1e6, **_finite)}),
    },
)


@settings(max_examples=100, deadline=None)
@given(units, st.sampled_from(["unit", "normal_actuator"]))
def test_random_units_round_trip(unit: dict, kind: str) -> None:
    s = scene_from_dict(unit_scene(kind, **unit))
    assert len(s.unit.encapsulation) == len(unit["encapsulation"])
    for given_ring, ring in zip(unit["encapsulation"], s.unit.encapsulation, strict=True):
        if isinstance(given_ring, str):
            assert ring == library_ring(given_ring)
        else:
            assert all(getattr(ring, k) == v for k, v in given_ring.items() if k != "material")
    for key, value in unit.get("motor", {}).items():
        assert getattr(s.unit.motor, key) == value
    assert_round_trips(s)
