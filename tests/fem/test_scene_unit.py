"""Scene schema, haptic unit: [unit] tables, rings, motor resolution, cross-field checks,
examples and round trips."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scene_cases import assert_round_trips, library_ring, unit_scene, with_value

from fem.materials import MATERIALS
from fem.scene import (
    Actuator,
    Board,
    Load,
    Motor,
    Pogo,
    Ring,
    Scene,
    SceneError,
    Unit,
    dump_scene_toml,
    load_scene,
    scene_from_dict,
    scene_hash,
    scene_to_dict,
)

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
UNIT_EXAMPLES = sorted(EXAMPLES.glob("unit-*.toml"))


# ----------------------------------------------------------------------------- examples


@pytest.mark.parametrize("path", UNIT_EXAMPLES, ids=lambda p: p.name)
def test_examples_load_round_trip_and_are_commented(path: Path) -> None:
    s = load_scene(path)
    assert_round_trips(s)
    assert s.load.kind == "unit" and s.unit is not None
    assert s.tissue.layers == scene_from_dict({}).tissue.layers  # the default forearm
    assert (s.tissue.side, s.tissue.base) == ("absorbing", "fixed")
    assert s.unit.motor.rated_frequency_hz == 120.0  # paper: 120 rev/s
    assert s.unit.board.thickness_mm == 0.1
    for line in path.read_text().splitlines():
        assert not line.strip() or "#" in line, f"uncommented line: {line!r}"


def test_the_four_examples_exist() -> None:
    names = {p.name for p in UNIT_EXAMPLES}
    assert {"unit-bare-forward.toml", "unit-double-forward.toml",
            "unit-triple-reverse-pogo.toml", "unit-transient.toml"} <= names


def test_examples_are_the_paper_designs() -> None:
    bare = load_scene(EXAMPLES / "unit-bare-forward.toml")
    double = load_scene(EXAMPLES / "unit-double-forward.toml")
    triple = load_scene(EXAMPLES / "unit-triple-reverse-pogo.toml")
    for s in (bare, double, triple):
        assert s.analysis.kind == "harmonic" and s.analysis.frequency_hz == 120.0
    assert (bare.unit.orientation, bare.unit.attachment, bare.unit.encapsulation) == (
        "forward", "glued", ())
    assert (double.unit.orientation, double.unit.attachment) == ("forward", "glued")
    assert double.unit.encapsulation == (library_ring("A"), library_ring("D"))
    assert (triple.unit.orientation, triple.unit.attachment) == ("reverse", "pogo")
    assert triple.unit.encapsulation == tuple(library_ring(x) for x in "ACD")
    # Guo et al. 2025: three PZ8116 pins, 2.25 mm from the center, 2.4 mm long, 0.3 mm
    # travel, 2942 N/m
    p = triple.unit.pogo
    assert (p.count, p.radius_mm, p.length_mm, p.travel_mm, p.stiffness_N_m) == (
        3, 2.25, 2.4, 0.3, 2942.0)
    # 7 mm motor, 0.05 mm gap (rings not tied to the motor), 1 mm rings: edges 3.5, 5.55, 6.55
    assert [s.unit.outer_radius_mm for s in (bare, double, triple)] == pytest.approx(
        [3.5, 5.55, 6.55])


def test_transient_example_is_design_3_switched_on_and_off() -> None:
    triple = scene_to_dict(load_scene(EXAMPLES / "unit-triple-reverse-pogo.toml"))
    trans = load_scene(EXAMPLES / "unit-transient.toml")
    a = trans.analysis
    assert (a.kind, a.time_step_ms, a.duration_ms) == ("transient", 0.05, 150.0)
    assert a.voltage_schedule == ((0.0, 3.3), (100.0, 0.0))
    assert a.voltage_schedule_s == ((0.0, 3.3), (0.1, 0.0))
    d = scene_to_dict(trans)
    assert d["unit"] == triple["unit"]
    assert {k: v for k, v in d.items() if k != "analysis"} == {
        k: v for k, v in triple.items() if k != "analysis"}


# ----------------------------------------------------------------------------- defaults


def test_unit_defaults() -> None:
    s = scene_from_dict(unit_scene())
    assert s.unit == Unit()
    u = s.unit
    assert (u.orientation, u.attachment, u.encapsulation, u.ring_thickness_mm) == (
        "forward", "glued", (), 1.0)
    assert u.motor == Motor(7.0, 2.0, 0.6, 0.006, 1.4, 5.0e6, 0.3, 3.3, 120.0, 0.4, 20.0, 35.0)
    assert u.pogo == Pogo(3, 2.25, 2942.0, 2.4, 0.3, 0.5)
    assert u.actuator == Actuator(0.1)
    pcb = MATERIALS["pcb"]  # the board defaults are the library's polyimide
    assert u.board == Board(0.1, 7.0, "pcb", pcb.E_Pa / 1e3, pcb.density_kg_m3, pcb.nu)
    assert s.load == Load(kind="unit")  # the patch keys keep their (unused) defaults
    # the board default material accepts aliases and stores the canonical name
    alias = scene_from_dict(with_value("unit.board.material", "Kapton"))
    assert alias.unit.board == u.board


def test_motor_si_properties() -> None:
    m = Motor()
    assert m.mass_kg == pytest.approx(0.6e-3)
    assert m.unbalance_kg_m == pytest.approx(0.006e-6)
    assert m.free_displacement_m == pytest.approx(10e-6)  # m e / M: about 10 um
    assert m.radius_m == pytest.approx(3.5e-3) and m.height_m == pytest.approx(2e-3)
    assert m.density_kg_m3 == pytest.approx(0.6e-3 / (math.pi * 3.5e-3**2 * 2e-3))
    assert m.E_Pa == pytest.approx(5e9)
    assert (m.tau_spinup_s, m.tau_spindown_s) == pytest.approx((0.020, 0.035))
    # F = m e omega^2 at 120 rev/s
    assert m.force_N_at(120.0) == pytest.approx(0.006e-6 * (2 * math.pi * 120) ** 2)


def test_unit_geometry_properties() -> None:
    rings = tuple(library_ring(x) for x in "ABC")
    u = Unit(encapsulation=list(rings), ring_thickness_mm=1.5)
    assert u.encapsulation == rings  # list stored as a tuple
    assert u.core_radius_mm == 3.5
    assert np.allclose(u.ring_radii_mm, ((3.55, 5.05), (5.05, 6.55), (6.55, 8.05)))
    assert u.outer_radius_mm == pytest.approx(8.05) and u.outer_radius_m == pytest.approx(8.05e-3)
    big_board = Unit(board=Board(diameter_mm=10.0))
    assert big_board.core_radius_mm == 5.0
    no_board = Unit(board=Board(thickness_mm=0.0, diameter_mm=10.0))  # absent board: no size
    assert no_board.core_radius_mm == 3.5 and not no_board.board.present
    fwd = Unit(motor=Motor(height_mm=2.0, rotor_height_mm=1.4))
    rev = Unit(orientation="reverse", motor=Motor(height_mm=2.0, rotor_height_mm=1.4))
    assert fwd.rotor_above_base_mm == 1.4
    assert rev.rotor_above_base_mm == pytest.approx(0.6)
    p = Pogo()
    assert p.total_stiffness_N_m == 3 * 2942.0
    assert p.preload_N == pytest.approx(2942.0 * 0.3e-3)
    assert (p.radius_m, p.length_m, p.travel_m, p.tip_diameter_m) == pytest.approx(
        (2.25e-3, 2.4e-3, 0.3e-3, 0.5e-3))


def test_fourier_mode_of_each_load_kind() -> None:
    assert Load(kind="unit", direction="normal").fourier_mode == 1  # rotating, parallel to skin
    assert Load(kind="normal_actuator", direction="tangential").fourier_mode == 0
    assert Load(direction="normal").fourier_mode == 0
    assert Load(kind="point_force", direction="tangential").fourier_mode == 1


# ----------------------------------------------------------------------------- motor force


def test_force_resolves_to_unbalance() -> None:
    f_hz, me_kg_m = 150.0, 0.02e-6
    force = me_kg_m * (2 * math.pi * f_hz) ** 2  # F = m e omega^2
    s = scene_from_dict(unit_scene(motor={"force_N": force, "force_at_hz": f_hz}))
    assert s.unit.motor.unbalance_g_mm == pytest.approx(0.02, rel=1e-12)
    assert s.unit.motor.force_N_at(f_hz) == pytest.approx(force, rel=1e-12)
    d = scene_to_dict(s)["unit"]["motor"]
    assert "force_N" not in d and "force_at_hz" not in d  # stored resolved
    assert_round_trips(s)


@pytest.mark.parametrize(("motor", "field", "fragment"), [
    ({"force_N": 0.01, "force_at_hz": 100.0, "unbalance_g_mm": 0.006}, "unit.motor.force_N",
     "either unbalance_g_mm or force_N"),
    ({"force_N": 0.01, "unbalance_g_mm": 0.006}, "unit.motor.force_N", "not both"),
    ({"force_N": 0.01}, "unit.motor.force_at_hz", "0 < force_at_hz <= 1e5"),
    ({"force_at_hz": 100.0}, "unit.motor.force_N", "0 < force_N <= 1e3"),
    ({"force_N": 0.0, "force_at_hz": 100.0}, "unit.motor.force_N", "0 < force_N <= 1e3"),
    ({"force_N": 1e3, "force_at_hz": 1e-3}, "unit.motor.force_N",
     "0 < unbalance_g_mm <= 1000"),
    ({"force_N": 0.01, "force_at_hz": 0.0}, "unit.motor.force_at_hz", "0 < force_at_hz <= 1e5"),
])
def test_force_errors(motor: dict, field: str, fragment: str) -> None:
    with pytest.raises(SceneError) as info:
        scene_from_dict(unit_scene(motor=motor))
    assert info.value.field == field
    assert fragment in str(info.value)


# ----------------------------------------------------------------------------- rings


def test_rings_by_name_alias_and_inline() -> None:
    s = scene_from_dict(unit_scene(encapsulation=[
        "A", "Dragon Skin 10",  # aliases
        {"material": "dragon-skin-30", "loss_factor": 0.05},  # library values, one override
        {"name": "gel", "E_kPa": 30, "density_kg_m3": 980, "nu": 0.45},  # no material
        {"E_kPa": 30.0, "density_kg_m3": 980.0, "nu": 0.45, "loss_factor": 0.2},
    ]))
    a, c, d, gel, unnamed = s.unit.encapsulation
    assert a == library_ring("ecoflex-00-10") and c == library_ring("dragon-skin-10-medium")
    ds30 = MATERIALS["dragon-skin-30"]
    assert d == Ring("dragon-skin-30", ds30.E_Pa / 1e3, ds30.density_kg_m3, ds30.nu, 0.05,
                     "dragon-skin-30")
    assert gel == Ring("gel", 30.0, 980.0, 0.45, 0.0, None)
    assert unnamed.name == "ring4" and unnamed.loss_factor == 0.2
    written = scene_to_dict(s)["unit"]["encapsulation"]
    # library-exact rings come back as canonical names, the others as full inline tables
    assert written[:2] == ["ecoflex-00-10", "dragon-skin-10-medium"]
    assert written[2] == {"name": "dragon-skin-30", "material": "dragon-skin-30",
                          "E_kPa": ds30.E_Pa / 1e3, "density_kg_m3": ds30.density_kg_m3,
                          "nu": ds30.nu, "loss_factor": 0.05}
    assert written[3] == {"name": "gel", "E_kPa": 30.0, "density_kg_m3": 980.0, "nu": 0.45,
                          "loss_factor": 0.0}
    assert_round_trips(s)
    assert "encapsulation = [" in dump_scene_toml(s)


def test_renamed_library_ring_is_inline() -> None:
    s = scene_from_dict(unit_scene(encapsulation=[{"material": "B", "name": "outer"}]))
    (ring,) = scene_to_dict(s)["unit"]["encapsulation"]
    assert isinstance(ring, dict) and ring["name"] == "outer"
    assert_round_trips(s)


def test_ring_values_change_the_hash() -> None:
    base = scene_hash(scene_from_dict(unit_scene(encapsulation=["A"])))
    assert scene_hash(scene_from_dict(unit_scene(encapsulation=["B"]))) != base
    assert scene_hash(scene_from_dict(unit_scene(encapsulation=["A", "A"]))) != base
    same = scene_from_dict(unit_scene(encapsulation=[{"material": "ecoflex 00-10"}]))
    assert scene_hash(same) == base  # the same ring, written another way


# ----------------------------------------------------------------------------- cross-checks


def test_unit_table_needs_a_unit_load() -> None:
    for kind in ("pressure_patch", "point_force"):
        with pytest.raises(SceneError) as info:
            scene_from_dict(unit_scene(kind))
        assert info.value.field == "unit"
        assert 'load.kind = "unit" or "normal_actuator"' in str(info.value)
    for kind in ("unit", "normal_actuator"):
        with pytest.raises(SceneError) as info:
            scene_from_dict({"load": {"kind": kind}})
        assert info.value.field == "unit" and "needs a [unit] table" in str(info.value)


def test_actuator_only_with_normal_actuator() -> None:
    s = scene_from_dict(unit_scene("normal_actuator"))
    assert s.unit.actuator == Actuator(0.1)
    assert scene_to_dict(s)["unit"]["actuator"] == {"force_N": 0.1}
    s = scene_from_dict(unit_scene("normal_actuator", actuator={"force_N": -0.5}))
    assert s.unit.actuator.force_N == -0.5
    assert_round_trips(s)
    assert "actuator" not in scene_to_dict(scene_from_dict(unit_scene()))["unit"]
    with pytest.raises(SceneError) as info:
        scene_from_dict(unit_scene(actuator={"force_N": 0.1}))
    assert info.value.field == "unit.actuator" and "normal_actuator" in str(info.value)


def test_pogo_tips_must_fit_under_the_board() -> None:
    # board radius 3.5 mm, tip 0.5 mm: pin radius up to 3.25 mm
    scene_from_dict(unit_scene(attachment="pogo", pogo={"radius_mm": 3.25}))
    for radius, board in ((3.26, 7.0), (2.25, 4.9), (3.5, 7.0)):
        with pytest.raises(SceneError) as info:
            scene_from_dict(unit_scene(attachment="pogo", pogo={"radius_mm": radius},
                                        board={"diameter_mm": board}))
        assert info.value.field == "unit.pogo.radius_mm"
        assert (f"radius_mm + tip_diameter_mm / 2 <= unit.board.diameter_mm / 2 "
                f"(= {board / 2:g})") in str(info.value)
    with pytest.raises(SceneError, match=r"i\.e\. radius_mm <= 2$"):  # 3.5 - 3 / 2
        scene_from_dict(unit_scene(attachment="pogo", pogo={"tip_diameter_mm": 3.0}))
    # unused pins are range-checked but not placed
    scene_from_dict(unit_scene(attachment="glued", pogo={"radius_mm": 10.0}))
    with pytest.raises(SceneError) as info:
        scene_from_dict(unit_scene(attachment="glued", pogo={"count": 0}))
    assert info.value.field == "unit.pogo.count"


def test_defaults_are_checked_against_given_bounds() -> None:
    # a given bound below a default: the default is reported, not silently kept
    for path, value, field in (("unit.pogo.length_mm", 0.3, "unit.pogo.travel_mm"),
                               ("unit.motor.height_mm", 1.0, "unit.motor.rotor_height_mm"),
                               ("unit.motor.rated_voltage_V", 0.4,
                                "unit.motor.start_voltage_V")):
        with pytest.raises(SceneError) as info:
            scene_from_dict(with_value(path, value))
        assert info.value.field == field
        assert "(the default) is out of range" in str(info.value)
        assert f"{path} (= {value:g})" in str(info.value)


def test_pogo_needs_a_board() -> None:
    scene_from_dict(unit_scene(board={"thickness_mm": 0.0}))  # glued straight to the skin
    with pytest.raises(SceneError) as info:
        scene_from_dict(unit_scene(attachment="pogo", board={"thickness_mm": 0.0}))
    assert info.value.field == "unit.board.thickness_mm"
    assert "0.001 <= thickness_mm <= 10" in str(info.value) and "pogo" in str(info.value)


@pytest.mark.parametrize(("unit", "tissue_mm", "field"), [
    ({"encapsulation": ["A", "C", "D"]}, 6.55, "unit.encapsulation"),  # 3.5 + 0.05 + 3 = 6.55
    ({"encapsulation": ["A"], "ring_thickness_mm": 20.0}, 23.55, "unit.encapsulation"),
    ({"motor": {"diameter_mm": 12.0}}, 6.0, "unit.motor.diameter_mm"),
    ({"board": {"diameter_mm": 12.0}}, 6.0, "unit.board.diameter_mm"),
])
def test_unit_must_fit_in_the_tissue(unit: dict, tissue_mm: float, field: str) -> None:
    d = {**unit_scene(**unit), "tissue": {"radius_mm": tissue_mm},
         "mesh": {"near_radius_mm": tissue_mm}, "output": {"radii_mm": [0.0]}}
    with pytest.raises(SceneError) as info:
        scene_from_dict(d)
    assert info.value.field == field
    assert f"outer radius < tissue.radius_mm (= {tissue_mm:g})" in str(info.value)
    d["tissue"]["radius_mm"] = tissue_mm + 0.01
    scene_from_dict(d)


def test_board_without_thickness_does_not_size_the_unit() -> None:
    d = {**unit_scene(board={"thickness_mm": 0.0, "diameter_mm": 12.0}),
         "tissue": {"radius_mm": 5.0}, "mesh": {"near_radius_mm": 5.0},
         "output": {"radii_mm": [0.0]}}
    assert scene_from_dict(d).unit.outer_radius_mm == 3.5


def test_direct_construction_is_validated() -> None:
    tissue = scene_from_dict({}).tissue
    rings = (library_ring("A"), Ring("soft", 20.0, 1000.0, 0.45, 0.1))
    s = Scene(tissue, Load(kind="unit"), unit=Unit(encapsulation=list(rings)))
    assert s.unit.encapsulation == rings
    assert_round_trips(s)
    with pytest.raises(SceneError) as info:
        Scene(tissue, unit=Unit())  # default load: a pressure patch
    assert info.value.field == "unit"
    with pytest.raises(SceneError) as info:
        Scene(tissue, Load(kind="unit"), unit=Unit(actuator=Actuator(0.5)))
    assert info.value.field == "unit.actuator"
    with pytest.raises(SceneError) as info:
        Scene(tissue, Load(kind="unit"), unit=Unit(encapsulation=(Ring("x", 1, 1, 0.7),)))
    assert info.value.field == "unit.encapsulation[0].nu"
    with pytest.raises(SceneError) as info:
        Scene(tissue, Load(kind="unit"), unit=Unit(board=Board(material="unobtainium")))
    assert info.value.field == "unit.board.material"
