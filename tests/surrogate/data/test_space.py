"""Parameter spaces and sampling: mapping, paths, constraints, extendable designs, errors."""

from __future__ import annotations

import copy
import itertools
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fem.scene import scene_from_dict, scene_hash
from surrogate.data.sampling import SAMPLERS, unit_points
from surrogate.data.space import SpaceError, load_space, parse_path, space_from_dict

ROOT = Path(__file__).resolve().parents[3]
CHEAP_BASE = {"analysis": {"kind": "harmonic", "frequency_hz": 120.0},
              "mesh": {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1},
              "tissue": {"radius_mm": 30.0}}


def _space(params: list[dict[str, Any]], **extra: Any) -> dict[str, Any]:
    d = {"space": {"name": "t", "seed": 7}, "base": copy.deepcopy(CHEAP_BASE),
         "parameter": params}
    d.update(extra)
    return d


SKIN = {"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
        "low": 20.0, "high": 120.0, "scale": "log"}
FAT = {"name": "fat_thickness_mm", "type": "continuous", "path": "tissue.layer[1].thickness_mm",
       "low": 3.0, "high": 15.0}
SIDE = {"name": "side", "type": "categorical", "path": "tissue.side",
        "choices": ["absorbing", "fixed", "free"]}


# ----------------------------------------------------------------------------- sampling


@pytest.mark.parametrize("sampler", SAMPLERS)
@settings(max_examples=15, deadline=None)
@given(cuts=st.lists(st.integers(0, 700), min_size=1, max_size=4))
def test_points_do_not_depend_on_how_the_range_is_split(sampler: str, cuts: list[int]) -> None:
    whole = unit_points(sampler, 3, 11, 0, 700, lhs_batch=64)
    edges = [0, *sorted(cuts), 700]
    pieces = [unit_points(sampler, 3, 11, a, b - a, lhs_batch=64)
              for a, b in itertools.pairwise(edges)]
    np.testing.assert_array_equal(np.vstack(pieces), whole)


@pytest.mark.parametrize("sampler", SAMPLERS)
def test_extension_gives_new_points_and_seeds_matter(sampler: str) -> None:
    first = unit_points(sampler, 4, 3, 0, 128)
    more = unit_points(sampler, 4, 3, 128, 128)
    assert not (set(map(tuple, first)) & set(map(tuple, more)))
    assert np.all((first >= 0) & (first < 1))
    assert not np.allclose(unit_points(sampler, 4, 4, 0, 128), first)


def test_sobol_prefixes_are_stratified_nets() -> None:
    # Owen-scrambled Sobol' keeps the net property: the first 2^m points put exactly one point
    # in each of the 2^m slabs of every coordinate, also for the second block of 2^m points.
    for start in (0, 64):
        u = unit_points("sobol", 5, 123, start, 64)
        for k in range(5):
            assert sorted(np.floor(u[:, k] * 64).astype(int)) == list(range(64))


def test_lhs_batches_are_latin_hypercubes() -> None:
    u = unit_points("lhs", 3, 5, 0, 96, lhs_batch=32)
    for b in range(3):
        block = u[32 * b : 32 * (b + 1)]
        for k in range(3):
            assert sorted(np.floor(block[:, k] * 32).astype(int)) == list(range(32))


def test_sampler_errors_name_the_field() -> None:
    with pytest.raises(ValueError, match=r"sampler.*allowed"):
        unit_points("grid", 2, 0, 0, 4)
    with pytest.raises(ValueError, match=r"dimension"):
        unit_points("sobol", 0, 0, 0, 4)


# ----------------------------------------------------------------------------- values


def test_parameter_mappings_hit_their_ranges() -> None:
    space = space_from_dict(_space([SKIN, FAT, SIDE, {"name": "n", "type": "integer",
                                                       "path": "output.radii_mm[0]",
                                                       "low": 0, "high": 3}]),
                            check_scenes=False)
    u = np.linspace(0, 1, 4001)[:, None].repeat(space.dim, axis=1)
    v = space.values_from_unit(u)
    assert v["skin_E_kPa"][0] == pytest.approx(20.0) and v["skin_E_kPa"][-1] <= 120.0
    # log scale: the middle of the unit interval is the geometric mean.
    assert v["skin_E_kPa"][2000] == pytest.approx(math.sqrt(20.0 * 120.0))
    assert v["fat_thickness_mm"][2000] == pytest.approx(9.0)
    assert set(v["n"]) == {0, 1, 2, 3}
    assert np.bincount(v["n"]).min() >= 999  # equal shares of the unit interval
    assert list(np.unique(v["side"], return_counts=True)[1]) == pytest.approx([1334, 1333, 1334],
                                                                              abs=2)


def test_center_and_paths_write_into_default_scene() -> None:
    space = space_from_dict(_space([SKIN, FAT]))
    row = space.center()
    scene = space.scene(row)
    assert scene.tissue.layers[0].E_kPa == pytest.approx(math.sqrt(20 * 120))
    assert scene.tissue.layers[1].thickness_mm == pytest.approx(9.0)
    # the other default layers are untouched
    default = scene_from_dict(CHEAP_BASE)
    assert scene.tissue.layers[2:] == default.tissue.layers[2:]
    assert scene.tissue.layers[0].nu == default.tissue.layers[0].nu
    # the same values written by hand into a scene dict hash identically
    by_hand = copy.deepcopy(CHEAP_BASE)
    by_hand["tissue"]["layer"] = [
        {"material": "skin", "thickness_mm": 1.9, "E_kPa": row["skin_E_kPa"]},
        {"material": "subcutaneous", "thickness_mm": 9.0},
        {"material": "muscle", "thickness_mm": 21.0}, {"material": "bone", "thickness_mm": 5.0}]
    assert scene_hash(scene) == scene_hash(scene_from_dict(by_hand))


def test_parse_path() -> None:
    assert parse_path("tissue.layer[0].E_kPa") == ("tissue", "layer", 0, "E_kPa")
    assert parse_path("a[1][2].b") == ("a", 1, 2, "b")
    for bad in ("", "a..b", "a[x]", "1a", "a.[0]", "a b"):
        with pytest.raises(ValueError, match=r"path"):
            parse_path(bad)


def _probe_params(max_probes: int) -> list[dict]:
    """Three probe radii written to output.radii_mm[i] and an n_probes list-length parameter."""
    radii = [{"name": f"r{i}", "type": "continuous", "path": f"output.radii_mm[{i}]",
              "low": 2.0 * i, "high": 2.0 * i + 1.0} for i in range(3)]
    return [*radii, {"name": "n_probes", "type": "integer", "path": "output.radii_mm",
                     "map": "list_length", "low": 1, "high": max_probes}]


def test_list_length_truncates_and_lists_grow() -> None:
    params = _probe_params(max_probes=3)
    d = _space(params)
    d["base"]["output"] = {"radii_mm": [0.5]}
    space = space_from_dict(d)
    for n in (1, 2, 3):
        scene = space.scene({"r0": 0.25, "r1": 2.5, "r2": 4.5, "n_probes": n})
        assert scene.output.radii_mm == (0.25, 2.5, 4.5)[:n]


def test_holes_in_lists_are_errors() -> None:
    d = _space([{"name": "r3", "type": "continuous", "path": "output.radii_mm[3]", "low": 1.0,
                 "high": 2.0}])
    d["base"]["output"] = {"radii_mm": [0.5]}
    with pytest.raises(SpaceError, match=r"radii_mm\[1\] is never set"):
        space_from_dict(d)


# ----------------------------------------------------------------------------- constraints


def test_constraints_evaluate_like_numpy() -> None:
    expr = "skin_E_kPa / 10 + fat_thickness_mm ** 1 <= 14 and not (side == 'free') or " \
           "abs(fat_thickness_mm - 9) < 0.5"
    space = space_from_dict(_space([SKIN, FAT, SIDE],
                                   constraint=[{"name": "c", "expr": expr}]))
    v = space.points(0, 512)
    want = ((v["skin_E_kPa"] / 10 + v["fat_thickness_mm"] <= 14) & (v["side"] != "free")) | \
        (np.abs(v["fat_thickness_mm"] - 9) < 0.5)
    np.testing.assert_array_equal(space.feasible(v), want)
    assert 0 < want.sum() < 512


@pytest.mark.parametrize("expr, message", [
    ("__import__('os').system('true')", "only the functions"),
    ("skin_E_kPa.real > 0", "Attribute is not allowed"),
    ("[skin_E_kPa][0] > 1", "not allowed"),
    ("bogus > 1", "unknown name 'bogus'"),
    ("skin_E_kPa >", "cannot parse"),
    ("lambda: 1", "Lambda is not allowed"),
])
def test_constraint_expressions_are_sandboxed(expr: str, message: str) -> None:
    with pytest.raises(SpaceError, match=message):
        space_from_dict(_space([SKIN], constraint=[{"expr": expr}]))


def test_constraints_that_reject_everything_fail_at_load() -> None:
    with pytest.raises(SpaceError, match=r"reject all"):
        space_from_dict(_space([SKIN], constraint=[{"expr": "skin_E_kPa > 500"}]))


# ----------------------------------------------------------------------------- errors


@pytest.mark.parametrize("change, field, message", [
    ({"low": 5.0, "high": 5.0}, "high",
     r"high = 5.0 is out of range: allowed .*low \(= 5\) < high"),
    ({"low": 9.0, "high": 5.0}, "high", "out of range"),
    ({"low": 0.0}, "low", "log scale needs 0 < low"),
    ({"scale": "cubic"}, "scale", "choose one of 'linear', 'log'"),
    ({"type": "gaussian"}, "type", "choose one of 'continuous', 'integer', 'categorical', 'fixed'"),
    ({"high": "big"}, "high", "expected a number"),
    ({"choices": ["a"]}, "choices", "unknown key"),
    ({"stiffness": 1}, "stiffness", "unknown key"),
    ({"name": "status"}, "name", "reserved"),
    ({"name": "9lives"}, "name", "letters"),
    ({"path": "tissue..x"}, "path", "malformed path"),
])
def test_malformed_parameters_name_the_field(change: dict[str, Any], field: str,
                                             message: str) -> None:
    with pytest.raises(SpaceError, match=message) as err:
        space_from_dict(_space([{**SKIN, **change}]))
    assert err.value.field.endswith(field)


def test_unknown_scene_path_names_parameter_and_path() -> None:
    bad = {**SKIN, "name": "stiff", "path": "tissue.layer[0].stiffness_kPa"}
    with pytest.raises(SpaceError, match=r"'stiff'.*tissue\.layer\[0\]\.stiffness_kPa.*"
                       r"unknown key") as err:
        space_from_dict(_space([bad]))
    assert "stiff" in err.value.field


def test_range_outside_the_scene_schema_names_parameter() -> None:
    nu = {"name": "skin_nu", "type": "continuous", "path": "tissue.layer[0].nu", "low": 0.3,
          "high": 0.7}
    with pytest.raises(SpaceError, match=r"'skin_nu'.*0 <= nu < 0.5"):
        space_from_dict(_space([nu]))


def test_dead_parameter_is_reported() -> None:
    # r2 writes radii_mm[2], but n_probes never keeps more than 2 entries
    params = _probe_params(max_probes=2)
    with pytest.raises(SpaceError, match=r"'r2'.*never changes what the solver reads"):
        space_from_dict(_space(params))


@pytest.mark.parametrize("base, param", [
    ({"load": {"kind": "unit"}, "unit": {"attachment": "glued"}},
     {"name": "pin_k", "type": "continuous", "path": "unit.pogo.stiffness_N_m",
      "low": 1000.0, "high": 5000.0}),
    ({"analysis": {"kind": "static"}},
     {"name": "f", "type": "continuous", "path": "analysis.frequency_hz",
      "low": 100.0, "high": 200.0}),
])
def test_a_parameter_the_solver_ignores_is_reported(base, param):
    """Pins under a glued unit, a frequency in a static analysis: the scene changes, the
    solution cannot."""
    d = _space([SKIN, param])
    d["base"] = {**d["base"], **base}
    with pytest.raises(SpaceError, match=rf"'{param['name']}'.*solver ignores it"):
        space_from_dict(d)


def test_space_level_errors() -> None:
    with pytest.raises(SpaceError, match=r"space.name is missing"):
        space_from_dict({"space": {}, "parameter": [SKIN]})
    with pytest.raises(SpaceError, match=r"no \[\[parameter\]\]"):
        space_from_dict({"space": {"name": "x"}})
    with pytest.raises(SpaceError, match=r"every parameter is fixed"):
        space_from_dict(_space([{"name": "f", "type": "fixed", "path": "analysis.frequency_hz",
                                 "value": 100.0}]))
    with pytest.raises(SpaceError, match=r"already used"):
        space_from_dict(_space([SKIN, SKIN]))
    with pytest.raises(SpaceError, match=r"also written by"):
        space_from_dict(_space([SKIN, {**FAT, "path": SKIN["path"]}]))
    with pytest.raises(SpaceError, match=r"space.sampler.*choose one of"):
        space_from_dict({**_space([SKIN]), "space": {"name": "x", "sampler": "grid"}})
    with pytest.raises(SpaceError, match=r"unknown key 'bases': did you mean 'base'"):
        space_from_dict({**_space([SKIN]), "bases": {}})


def test_load_space_reports_toml_syntax(tmp_path: Path) -> None:
    p = tmp_path / "s.toml"
    p.write_text("[space\nname = 'x'\n")
    with pytest.raises(SpaceError, match=r"invalid TOML"):
        load_space(p)
    with pytest.raises(SpaceError, match=r"cannot read"):
        load_space(tmp_path / "missing.toml")


def test_base_scene_file_and_round_trip(tmp_path: Path) -> None:
    (tmp_path / "scene.toml").write_text('[analysis]\nkind = "harmonic"\n'
                                         "[mesh]\nnear_size_mm = 1.0\nfar_size_mm = 4.0\n"
                                         "order = 1\n[tissue]\nradius_mm = 30.0\n")
    (tmp_path / "s.toml").write_text(
        '[space]\nname = "f"\nbase_scene = "scene.toml"\n[base.analysis]\nfrequency_hz = 150.0\n'
        '[[parameter]]\nname = "skin_E_kPa"\ntype = "continuous"\n'
        'path = "tissue.layer[0].E_kPa"\nlow = 20.0\nhigh = 120.0\n')
    space = load_space(tmp_path / "s.toml")
    assert space.base["analysis"] == {"kind": "harmonic", "frequency_hz": 150.0}
    again = space_from_dict(space.to_dict())
    assert again.space_hash() == space.space_hash()
    assert space_from_dict({**space.to_dict(), "space": {"name": "f", "seed": 1}}
                           ).space_hash() != space.space_hash()


def test_check_value_for_external_data() -> None:
    space = space_from_dict(_space([SKIN, SIDE]), check_scenes=False)
    assert space.parameter("skin_E_kPa").check_value("49") == 49.0
    with pytest.raises(SpaceError, match=r"outside the space: allowed 20.0 <= skin_E_kPa <= "
                       r"120.0"):
        space.parameter("skin_E_kPa").check_value("200")
    with pytest.raises(SpaceError, match=r"one of 'absorbing', 'fixed', 'free'"):
        space.parameter("side").check_value("wobbly")
    with pytest.raises(SpaceError, match=r"expected a float64"):
        space.parameter("skin_E_kPa").check_value("soft")


# ----------------------------------------------------------------------------- shipped spaces


@pytest.mark.parametrize("name", ["default", "transient"])
def test_shipped_spaces_load_and_resolve(name: str) -> None:
    space = load_space(ROOT / "datasets" / "spaces" / f"{name}.toml")
    v = space.points(0, 16)
    mask = space.feasible(v)
    assert mask.any()
    hashes = {scene_hash(space.scene({k: c[i] for k, c in v.items()}))
              for i in np.flatnonzero(mask)}
    assert len(hashes) == mask.sum()


def test_resolve_at_makes_a_sweep_space_one_harmonic_solve_at_the_frequency():
    """What plan --verify and calibrate --verify solve for a sweep-trained model: the design's
    scene with its band replaced by one frequency (the sweep's tolerance dropped)."""
    from sweep_fixture import coarse_space_dict

    d = coarse_space_dict()
    d["band"]["tolerance"] = 0.01
    space = space_from_dict(d, check_scenes=False)
    row = space.center()
    sweep = space.resolve(row)
    assert sweep["analysis"] == {"kind": "sweep", "tolerance": 0.01,
                                 "frequency_hz": {"start": 100.0, "stop": 250.0, "step": 10.0}}
    one = space.resolve_at(row, 135.0)
    assert one["analysis"] == {"kind": "harmonic", "frequency_hz": 135.0}
    assert {k: v for k, v in one.items() if k != "analysis"} == {
        k: v for k, v in sweep.items() if k != "analysis"}  # the same design, 40 mm profile
    assert one["output"]["profile_length_mm"] == 40.0


def test_resolve_at_on_a_single_frequency_space_sets_its_frequency_parameter():
    space = load_space("datasets/spaces/default.toml", check_scenes=False)
    row = space.center()
    assert space.resolve_at(row, 135.0) == space.resolve({**row, "frequency_hz": 135.0})
    assert space.resolve_at(row, 135.0)["analysis"]["frequency_hz"] == 135.0
