"""Scene schema: defaults, round trips, hashing and every kind of validation error."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fem_cases import assert_scene_error
from hypothesis import given, settings
from hypothesis import strategies as st
from scene_cases import assert_round_trips

from fem.materials import MATERIALS
from fem.scene import (
    EFFECT_NAMES,
    Analysis,
    Effects,
    Layer,
    Load,
    MeshSettings,
    Output,
    Scene,
    SceneError,
    Tissue,
    dump_scene_toml,
    load_scene,
    scene_from_dict,
    scene_hash,
    scene_to_dict,
)

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "forearm.toml"

# Guo et al. 2025 (Biomimetics 10:597), Table 1 as read here: name, thickness [mm], E [kPa],
# density [kg/m3], nu.
PAPER_FOREARM = [
    ("skin", 1.9, 49.0, 1116.0, 0.47),
    ("subcutaneous", 14.0, 10.0, 1116.0, 0.47),
    ("muscle", 21.0, 53.0, 1116.0, 0.47),
    ("bone", 5.0, 2.94e6, 2000.0, 0.32),
]


def _layer(**kw: Any) -> dict[str, Any]:
    return {"thickness_mm": 1.0, "E_kPa": 10.0, "density_kg_m3": 1000.0, "nu": 0.4, **kw}


def _scene(**tables: dict[str, Any]) -> dict[str, Any]:
    return copy.deepcopy(tables)


# ----------------------------------------------------------------------------- defaults


def test_defaults_are_the_paper_forearm() -> None:
    s = scene_from_dict({})
    got = [(la.name, la.thickness_mm, la.E_kPa, la.density_kg_m3, la.nu) for la in s.tissue.layers]
    assert got == PAPER_FOREARM
    # Damping is not the paper's (its model is undamped) but the sourced library default.
    assert [la.loss_factor for la in s.tissue.layers] == [0.3, 0.3, 0.3, 0.02]
    assert s.tissue.depth_mm == pytest.approx(41.9)
    assert (s.tissue.radius_mm, s.tissue.side, s.tissue.base) == (50.0, "absorbing", "fixed")
    assert s.load == Load("pressure_patch", "normal", 2.0, 1000.0, 1.0)
    assert s.analysis == Analysis("static", 120.0)
    assert s.mesh == MeshSettings(0.5, 8.0, 2.0, 2)
    assert s.output == Output((0.0, 2.0, 4.0, 8.0, 12.0, 16.0, 20.0))
    assert (s.analysis.time_step_ms, s.analysis.duration_ms, s.analysis.rho_inf,
            s.analysis.voltage_schedule) == (0.05, 200.0, 0.9, ((0.0, 3.3),))
    assert (s.output.profile_step_mm, s.output.profile_length_mm, s.output.history_every) == (
        1.0, 20.0, 1)
    assert s.unit is None and s.effects == Effects()
    assert all(getattr(s.effects, name) is None for name in EFFECT_NAMES)  # all auto
    # A [tissue] table without layers still gets the forearm.
    assert scene_from_dict({"tissue": {"radius_mm": 60.0}}).tissue.layers == s.tissue.layers


def test_si_properties() -> None:
    s = scene_from_dict({})
    skin = s.tissue.layers[0]
    assert skin.E_Pa == pytest.approx(49e3)
    assert skin.thickness_m == pytest.approx(1.9e-3)
    assert s.tissue.radius_m == pytest.approx(0.05)
    assert s.load.radius_m == pytest.approx(2e-3)
    assert s.output.radii_m[-1] == pytest.approx(0.02)


def test_example_file() -> None:
    s = load_scene(EXAMPLE)
    assert s.tissue.layers == scene_from_dict({}).tissue.layers
    assert s.analysis == Analysis("harmonic", 120.0)
    assert s.load.direction == "tangential"
    assert_round_trips(s)
    for line in EXAMPLE.read_text().splitlines():
        assert not line.strip() or "#" in line, f"uncommented line: {line!r}"


# ----------------------------------------------------------------------------- round trips


def test_round_trip_custom_scene() -> None:
    d = _scene(
        tissue={"radius_mm": 30, "side": "free", "base": "absorbing",
                "layer": [{"material": "A", "thickness_mm": 1, "E_kPa": 21},
                          _layer(name='odd "name"\\\n\t\x7fé', loss_factor=0.3),
                          _layer()]},
        load={"kind": "point_force", "direction": "tangential", "force_N": -0.25},
        analysis={"kind": "harmonic", "frequency_hz": 250},
        mesh={"near_size_mm": 0.25, "near_radius_mm": 30, "far_size_mm": 0.25, "order": 1},
        output={"radii_mm": [20, 0, 3.5]},
    )
    s = scene_from_dict(d)
    silicone, custom, unnamed = s.tissue.layers
    # material values, overridden by the explicit E; the canonical name replaces the alias
    assert silicone == Layer("ecoflex-00-10", 1.0, 21.0, 1040.0, 0.49,
                             MATERIALS["ecoflex-00-10"].loss_factor, "ecoflex-00-10")
    assert custom.material is None and custom.loss_factor == 0.3
    assert unnamed.name == "layer2"
    assert s.output.radii_mm == (20.0, 0.0, 3.5)  # stored as given, not sorted
    assert isinstance(s.analysis.frequency_hz, float) and isinstance(s.mesh.order, int)
    assert_round_trips(s)


def test_to_dict_is_toml_shaped_and_complete() -> None:
    d = scene_to_dict(scene_from_dict({}))
    assert list(d) == ["tissue", "load", "analysis", "mesh", "output"]
    assert len(d["tissue"]["layer"]) == 4
    assert d["mesh"] == {"near_size_mm": 0.5, "near_radius_mm": 8.0, "far_size_mm": 2.0,
                         "order": 2, "follow_wavelength": True}


def test_transient_analysis_round_trip() -> None:
    d = {"analysis": {"kind": "transient", "time_step_ms": 0.1, "duration_ms": 50,
                      "rho_inf": 0, "voltage_schedule": [[0, 3], [10.5, -3.3], [20, 0]]},
         "output": {"history_every": 7, "profile_step_mm": 4, "profile_length_mm": 20},
         "load": {"kind": "unit"}, "unit": {}}  # a transient drives a unit
    s = scene_from_dict(d)
    a = s.analysis
    assert a.voltage_schedule == ((0.0, 3.0), (10.5, -3.3), (20.0, 0.0))
    assert all(isinstance(x, float) for pair in a.voltage_schedule for x in pair)
    assert np.allclose(a.voltage_schedule_s, [[0.0, 3.0], [0.0105, -3.3], [0.02, 0.0]])
    assert (a.time_step_s, a.duration_s) == pytest.approx((1e-4, 0.05))
    assert s.output.history_every == 7 and isinstance(s.output.history_every, int)
    # paper: amplitude every 4 mm from 0 to 20 mm from the unit edge
    assert s.output.profile_distances_mm == (0.0, 4.0, 8.0, 12.0, 16.0, 20.0)
    assert Output(profile_step_mm=3.0, profile_length_mm=10.0).profile_distances_mm == (
        0.0, 3.0, 6.0, 9.0)
    assert len(Output(profile_step_mm=0.1, profile_length_mm=1.0).profile_distances_mm) == 11
    assert "voltage_schedule = [[0.0, 3.0], [10.5, -3.3], [20.0, 0.0]]" in dump_scene_toml(s)
    assert_round_trips(s)
    # a directly built analysis with lists is stored hashable, and validated
    direct = Scene(s.tissue, load=s.load, unit=s.unit,
                   analysis=Analysis("transient", voltage_schedule=[[0, 1], [5, 2]]))
    assert direct.analysis.voltage_schedule == ((0, 1), (5, 2))
    assert scene_hash(direct) == scene_hash(scene_from_dict(
        {"analysis": {"kind": "transient", "voltage_schedule": [[0.0, 1.0], [5.0, 2.0]]},
         "load": {"kind": "unit"}, "unit": {}}))
    with pytest.raises(SceneError) as info:
        Scene(s.tissue, analysis=Analysis(voltage_schedule=((1.0, 3.3),)))
    assert info.value.field == "analysis.voltage_schedule[0][0]"


def test_effects_round_trip_and_hash() -> None:
    auto = scene_from_dict({"effects": {}})
    assert auto == scene_from_dict({}) and "effects" not in scene_to_dict(auto)
    s = scene_from_dict({"effects": {"inertia": False, "rocking": True,
                                     "spin_up": np.bool_(True)}})
    assert s.effects == Effects(inertia=False, rocking=True, spin_up=True)
    assert scene_to_dict(s)["effects"] == {"inertia": False, "rocking": True, "spin_up": True}
    assert "[effects]\ninertia = false\nrocking = true" in dump_scene_toml(s)
    assert_round_trips(s)
    hashes = {scene_hash(scene_from_dict({"effects": e}))
              for e in ({}, {"pogo": True}, {"pogo": False}, {"preload": True})}
    assert len(hashes) == 4  # auto, on and off are three different scenes
    direct = Scene(s.tissue, effects=Effects(inertia=np.bool_(False), rocking=True,
                                             spin_up=True))
    assert scene_hash(direct) == scene_hash(s)  # numpy scalars hash as Python ones
    assert s.effects.resolve("inertia", True) is False
    assert s.effects.resolve("pogo", True) is True and s.effects.resolve("pogo", False) is False


def test_hash() -> None:
    a = scene_from_dict({})
    h = scene_hash(a)
    assert len(h) == 64 and int(h, 16) >= 0
    assert scene_hash(scene_from_dict({"analysis": {"frequency_hz": 120}})) == h  # int == float
    assert scene_hash(scene_from_dict({"analysis": {"frequency_hz": 120.00000000000001}})) != h
    assert scene_hash(scene_from_dict({"tissue": {"layer": [_layer(nu=0.4)]}})) != scene_hash(
        scene_from_dict({"tissue": {"layer": [_layer(nu=0.41)]}}))


def test_direct_construction_is_validated() -> None:
    good = Layer("x", 1.0, 10.0, 1000.0, 0.4)
    Scene(Tissue([good]))  # a list is accepted and stored as a tuple
    with pytest.raises(SceneError) as info:
        Scene(Tissue((good, Layer("y", 1.0, 10.0, 1000.0, 0.6))))
    assert info.value.field == "tissue.layer[1].nu"
    assert "0 <= nu < 0.5" in str(info.value)


names = st.text(st.characters(blacklist_categories=("Cs",)), max_size=12)


def _num(lo: float, hi: float, exclude_min: bool = False) -> st.SearchStrategy[float]:
    ints = st.integers(math.ceil(lo) + (1 if exclude_min else 0), math.floor(hi))
    return st.one_of(ints, st.floats(lo, hi, exclude_min=exclude_min))


layers = st.fixed_dictionaries(
    {
        "thickness_mm": _num(0.001, 1e4),
        "E_kPa": _num(0.001, 1e9),
        "density_kg_m3": _num(0, 1e5, exclude_min=True),
        "nu": st.floats(0, 0.5, exclude_max=True),
    },
    optional={
        "name": names,
        "loss_factor": _num(0, 2),
        "material": st.sampled_from([*MATERIALS, "A", "Fat", "dragon skin 10"]),
    },
)


schedules = st.lists(
    st.tuples(st.floats(0.001, 1000, allow_nan=False), st.floats(-50, 50, allow_nan=False)),
    max_size=6,
).map(lambda steps: [[0, 3.3]] + [[sum(dt for dt, _ in steps[: i + 1]), v]
                                  for i, (_, v) in enumerate(steps)])


@settings(max_examples=100, deadline=None)
@given(schedules)
def test_random_schedules_round_trip(schedule: list[list[float]]) -> None:
    s = scene_from_dict({"analysis": {"kind": "transient", "voltage_schedule": schedule},
                         "load": {"kind": "unit"}, "unit": {}})
    assert s.analysis.voltage_schedule == tuple((float(t), float(v)) for t, v in schedule)
    assert_round_trips(s)


@settings(max_examples=150, deadline=None)
@given(st.lists(layers, min_size=1, max_size=6), st.lists(_num(0, 50), min_size=1, max_size=5))
def test_random_valid_layers_round_trip(layer_dicts: list[dict], radii: list[float]) -> None:
    s = scene_from_dict({"tissue": {"layer": layer_dicts}, "output": {"radii_mm": radii}})
    for given_layer, layer in zip(layer_dicts, s.tissue.layers, strict=True):
        for key, value in given_layer.items():
            if key != "material":
                assert getattr(layer, key) == value
    assert s.output.radii_mm == tuple(float(r) for r in radii)
    assert_round_trips(s)


# ----------------------------------------------------------------------------- errors

ERRORS = [
    # unknown keys, with a suggestion
    (_scene(mesh={"near_sise_mm": 1.0}), "mesh.near_sise_mm", "did you mean 'near_size_mm'"),
    (_scene(analysys={}), "analysys", "did you mean 'analysis'"),
    (_scene(tissue={"layers": []}), "tissue.layers", "did you mean 'layer'"),
    (_scene(tissue={"layer": [_layer(thicknes_mm=2.0)]}), "tissue.layer[0].thicknes_mm",
     "did you mean 'thickness_mm'"),
    # wrong types
    (_scene(analysis={"frequency_hz": "120"}), "analysis.frequency_hz", "expected a number"),
    (_scene(load={"amplitude_Pa": True}), "load.amplitude_Pa", "true/false is not a number"),
    (_scene(tissue={"layer": [_layer(nu=False)]}), "tissue.layer[0].nu", "not a number"),
    (_scene(mesh={"order": True}), "mesh.order", "expected an integer"),
    (_scene(mesh={"order": 2.0}), "mesh.order", "expected an integer"),
    (_scene(tissue={"side": 1}), "tissue.side", "expected a string"),
    (_scene(tissue={"layer": [_layer(name=3)]}), "tissue.layer[0].name", "expected a string"),
    (_scene(output={"radii_mm": 4.0}), "output.radii_mm", "list of numbers"),
    (_scene(output={"radii_mm": [1.0, "x"]}), "output.radii_mm[1]", "expected a number"),
    (_scene(load=3), "load", "must be a table"),
    (_scene(tissue={"layer": {"name": "skin"}}), "tissue.layer", "[[tissue.layer]]"),
    (_scene(tissue={"layer": [3]}), "tissue.layer[0]", "must be a table"),
    # bad enum choices
    (_scene(tissue={"side": "open"}), "tissue.side", "'absorbing', 'fixed', 'free'"),
    (_scene(tissue={"base": "free"}), "tissue.base", "'fixed', 'absorbing'"),
    (_scene(load={"kind": "ring"}), "load.kind", "'pressure_patch', 'point_force'"),
    (_scene(load={"direction": "up"}), "load.direction", "'normal', 'tangential'"),
    (_scene(analysis={"kind": "modal"}), "analysis.kind", "'static', 'harmonic', 'transient'"),
    (_scene(mesh={"order": 3}), "mesh.order", "choose one of 1, 2"),
    # effects: booleans only, unknown keys with a suggestion
    (_scene(effects={"inertai": True}), "effects.inertai", "did you mean 'inertia'"),
    (_scene(effects={"spinup": True}), "effects.spinup", "did you mean 'spin_up'"),
    (_scene(effects={"pogo": "auto"}), "effects.pogo", "expected true or false"),
    (_scene(effects={"rocking": 1}), "effects.rocking", "leave the key out for auto"),
    (_scene(effects=[]), "effects", "must be a table"),
    (_scene(output={"history_every": 2.0}), "output.history_every", "expected an integer"),
    (_scene(analysis={"time_step": 0.1}), "analysis.time_step", "did you mean 'time_step_ms'"),
    # voltage schedule: [t_ms, volts] pairs from t = 0, strictly increasing, |volts| <= 50
    (_scene(analysis={"voltage_schedule": [[5.0, 3.3]]}), "analysis.voltage_schedule[0][0]",
     "must start at t_ms = 0"),
    (_scene(analysis={"voltage_schedule": [[0, 3.3], [100, 0], [50, 1]]}),
     "analysis.voltage_schedule[2][0]",
     "increase strictly, allowed t_ms > analysis.voltage_schedule[1][0] (= 100)"),
    (_scene(analysis={"voltage_schedule": [[0, 3.3], [0, 0]]}),
     "analysis.voltage_schedule[1][0]", "allowed t_ms > analysis.voltage_schedule[0][0] (= 0)"),
    (_scene(analysis={"voltage_schedule": [[-1, 3.3]]}), "analysis.voltage_schedule[0][0]",
     "0 <= t_ms <= 1e5"),
    (_scene(analysis={"voltage_schedule": [[0, 3.3], [math.inf, 0]]}),
     "analysis.voltage_schedule[1][0]", "0 <= t_ms <= 1e5"),
    (_scene(analysis={"voltage_schedule": [[0, 3.3], [1, -50.5]]}),
     "analysis.voltage_schedule[1][1]", "-50 <= volts <= 50"),
    (_scene(analysis={"voltage_schedule": [[0, math.nan]]}), "analysis.voltage_schedule[0][1]",
     "-50 <= volts <= 50"),
    (_scene(analysis={"voltage_schedule": []}), "analysis.voltage_schedule",
     "non-empty list of [t_ms, volts] pairs"),
    (_scene(analysis={"voltage_schedule": 3.3}), "analysis.voltage_schedule",
     "non-empty list of [t_ms, volts] pairs"),
    (_scene(analysis={"voltage_schedule": [[0, 1, 2]]}), "analysis.voltage_schedule[0]",
     "[t_ms, volts] pair"),
    (_scene(analysis={"voltage_schedule": [0, 3.3]}), "analysis.voltage_schedule[0]",
     "[t_ms, volts] pair"),
    (_scene(analysis={"voltage_schedule": [[0, "3.3"]]}), "analysis.voltage_schedule[0][1]",
     "expected a number"),
    # missing layer values, unknown material, layer count
    (_scene(tissue={"layer": [{"thickness_mm": 1.0, "E_kPa": 1.0, "nu": 0.3}]}),
     "tissue.layer[0].density_kg_m3", "0 < density_kg_m3 <= 1e5"),
    (_scene(tissue={"layer": [_layer(), {"material": "skin"}]}),
     "tissue.layer[1].thickness_mm", "0.001 <= thickness_mm <= 10000"),
    (_scene(tissue={"layer": [{"material": "skn", "thickness_mm": 1.0}]}),
     "tissue.layer[0].material", "muscle"),
    (_scene(tissue={"layer": []}), "tissue.layer", "1 <= number of layers <= 50"),
    (_scene(tissue={"layer": [_layer()] * 51}), "tissue.layer", "1 <= number of layers <= 50"),
]


def _bad_value(path: str, value: Any, **extra: dict[str, Any]) -> tuple[dict, str]:
    """A scene dict with ``value`` at ``table.key`` or ``tissue.layer[0].key``."""
    d: dict[str, Any] = copy.deepcopy(extra)
    if path.startswith("tissue.layer[0]."):
        d.setdefault("tissue", {})["layer"] = [_layer(**{path.rsplit(".", 1)[1]: value})]
    else:
        table, key = path.split(".")
        d.setdefault(table, {})[key] = value
    return d, path


# (path, [bad values], [good values], allowed text, extra tables needed by the good values)
RANGES = [
    ("tissue.layer[0].thickness_mm", [0, -1, 1e-4, 10000.5], [0.001, 10000],
     "0.001 <= thickness_mm <= 10000",
     {}),
    ("tissue.layer[0].E_kPa", [0.0, 1e-30, 9e-4, 1.1e9], [1e-3, 1e9], "0.001 <= E_kPa <= 1e9",
     {}),
    ("tissue.layer[0].density_kg_m3", [0, 100001], [0.1, 1e5], "0 < density_kg_m3 <= 1e5", {}),
    ("tissue.layer[0].nu", [-0.01, 0.5, 0.6, math.nan], [0, 0.49999], "0 <= nu < 0.5", {}),
    ("tissue.layer[0].loss_factor", [-0.1, 2.01], [0, 2], "0 <= loss_factor <= 2", {}),
    ("tissue.radius_mm", [0, 1e5 + 1], [20, 1e5], "0.001 <= radius_mm <= 1e5", {}),
    ("load.radius_mm", [0, 1e-4, 50, 51], [0.01, 49.9],
     "0.001 <= radius_mm < tissue.radius_mm (= 50)", {}),
    ("load.amplitude_Pa", [0, 1.5e9, -1.5e9, math.inf], [-1e9, 1e9, -3],
     "-1e9 <= amplitude_Pa <= 1e9, non-zero", {}),
    ("load.force_N", [0.0, 2e9, -2e9], [-1e9, 1e9, 1e-3], "-1e9 <= force_N <= 1e9, non-zero", {}),
    ("analysis.frequency_hz", [0, -5, 1e5 + 1], [1e-3, 1e5], "0 < frequency_hz <= 1e5", {}),
    ("mesh.near_size_mm", [0, 100.5], [0.01, 2.0], "0 < near_size_mm <= 100", {}),
    ("mesh.near_size_mm", [], [100], "", {"mesh": {"far_size_mm": 100.0}}),
    ("mesh.far_size_mm", [0.49, 1000.5], [0.5, 1000], "mesh.near_size_mm (= 0.5) <= far_size_mm "
     "<= 1000", {}),
    ("mesh.near_radius_mm", [0, 50.1], [0.1, 50], "0 < near_radius_mm <= tissue.radius_mm", {}),
    ("output.radii_mm", [[-1.0], [0.0, 50.5], []], [[50.0], [0, 0]],
     "0 <= radii_mm <= tissue.radius_mm (= 50)", {}),
    ("analysis.time_step_ms", [0, -1, 100.5], [1e-4, 100], "0 < time_step_ms <= 100", {}),
    ("analysis.duration_ms", [0, 0.04, 1e5 + 1], [0.05, 1e5],
     "analysis.time_step_ms (= 0.05) <= duration_ms <= 1e5", {}),
    ("analysis.duration_ms", [0.99], [1.0], "analysis.time_step_ms (= 1) <= duration_ms",
     {"analysis": {"time_step_ms": 1.0}}),
    ("analysis.rho_inf", [-0.01, 1.01, math.nan], [0, 1, 0.5], "0 <= rho_inf <= 1", {}),
    ("output.profile_step_mm", [0, 100.5], [0.01, 100], "0 < profile_step_mm <= 100", {}),
    ("output.profile_length_mm", [0, -2, 1000.5], [0.01, 1000], "0 < profile_length_mm <= 1000",
     {}),
    ("output.history_every", [0, -1, 10**6 + 1], [1, 10**6], "1 <= history_every <= 1e6", {}),
]


@pytest.mark.parametrize(("d", "field", "fragment"), ERRORS)
def test_errors_name_field_and_allowed(d: dict, field: str, fragment: str) -> None:
    assert isinstance(assert_scene_error(d, field, fragment), ValueError)


@pytest.mark.parametrize(("path", "bad", "good", "allowed", "extra"), RANGES)
def test_range_limits(path: str, bad: list, good: list, allowed: str, extra: dict) -> None:
    for value in good:
        scene_from_dict(_bad_value(path, value, **extra)[0])
    for value in bad:
        d, _ = _bad_value(path, value, **extra)
        with pytest.raises(SceneError) as info:
            scene_from_dict(d)
        assert info.value.field.startswith(path), value
        assert allowed in str(info.value), (value, str(info.value))


def test_out_of_range_message_format() -> None:
    d = {"tissue": {"layer": [_layer(), _layer(nu=0.6)]}}
    with pytest.raises(SceneError) as info:
        scene_from_dict(d)
    assert info.value.field == "tissue.layer[1].nu"
    assert str(info.value) == "tissue.layer[1].nu = 0.6 is out of range: allowed 0 <= nu < 0.5"


def test_radii_element_field() -> None:
    with pytest.raises(SceneError) as info:
        scene_from_dict({"output": {"radii_mm": [1.0, 2.0, 70.0]}})
    assert info.value.field == "output.radii_mm[2]"


def test_toml_syntax_error(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[tissue]\nradius_mm = = 3\n")
    with pytest.raises(SceneError) as info:
        load_scene(bad)
    assert info.value.field == "<file>"
    assert "line 2" in str(info.value)


def test_load_scene_validates(tmp_path: Path) -> None:
    f = tmp_path / "s.toml"
    f.write_text("[[tissue.layer]]\nmaterial = 'Fat'\nthickness_mm = 3\n[load]\nradius_mm = 1\n")
    s = load_scene(f)
    assert s.tissue.layers == (Layer("subcutaneous", 3.0, 10.0, 1116.0, 0.47, 0.3,
                                     "subcutaneous"),)
    f.write_text("[mesh]\norder = 4\n")
    with pytest.raises(SceneError, match="choose one of 1, 2"):
        load_scene(f)
