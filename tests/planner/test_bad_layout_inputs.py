"""Issue 27 item 5: every bad input of the list named correctly, without a traceback: a wrong
type or choice is not answered with extrapolation advice, an unknown ``[site]`` key is
reported under ``site``, a long input is summarised, and ``--watchdog-ms`` is reported in ms
with its range."""

from __future__ import annotations

import copy
import tomllib

import pytest

from hapticrom.cli import main
from planner import LayoutError, layout_from_dict, plan_layout
from tests.planner.thigh import thigh, toml_text


def _first_design(key, value):
    return lambda d: d["design"][0].update({key: value})


@pytest.mark.parametrize("change, field, says, advice", [
    (_first_design("orientation", "sideways"), "design[0].orientation", "'forward', 'reverse'",
     False),
    (_first_design("n_rings", 1.5), "design[0].n_rings", "an integer in [0, 3]", False),
    (lambda d: d["site"].update(fat_thickness_mm="18"), "site.fat_thickness_mm",
     "expected a number in [3, 20] mm", False),
    (lambda d: d["site"].update(tissue_los_factor=0.3), "site.tissue_los_factor",
     "not an input of", False),
    (lambda d: d["site"].update(skin_E_kPa=5.0), "site.skin_E_kPa", "validity domain", True),
    (_first_design("ring_nu", float("nan")), "design[0].ring_nu", "finite", False),
])
def test_each_bad_value_is_named_with_what_is_allowed(change, field, says, advice):
    d = thigh()
    change(d)
    with pytest.raises(LayoutError) as info:
        plan_layout(layout_from_dict(d))
    assert info.value.field == field
    assert says in str(info.value) and str(info.value).startswith(field)
    assert ("allow_extrapolation" in str(info.value)) is advice


def test_ten_thousand_free_sites_are_summarised_not_echoed():
    d = thigh()
    d["array"] = {"grid": "free", "positions_mm": [[30.0 * (i % 100), 30.0 * (i // 100)]
                                                   for i in range(10_000)]}
    with pytest.raises(LayoutError) as info:
        layout_from_dict(d)
    assert info.value.field == "array.positions_mm"
    assert "a list of 10000 positions" in str(info.value) and len(str(info.value)) < 200


@pytest.mark.parametrize("edit, field", [
    (lambda t: t.replace('orientation = "forward"', 'orientation = "sideways"', 1),
     "design[0].orientation"),
    (lambda t: t.replace("n_rings = 0", "n_rings = 1.5", 1), "design[0].n_rings"),
    (lambda t: t.replace("fat_thickness_mm = 18.0", 'fat_thickness_mm = "18"'),
     "site.fat_thickness_mm"),
    (lambda t: t.replace("tissue_loss_factor = 0.3 ", "tissue_los_factor = 0.3 "),
     "site.tissue_los_factor"),
    (lambda t: t.replace('orientation = "forward"', f'orientation = "{"z" * 10_000}"', 1),
     "design[0].orientation"),
])
def test_cli_exits_2_naming_the_field_without_a_traceback(tmp_path, capsys, edit, field):
    layout, out = tmp_path / "layout.toml", tmp_path / "plan.json"
    text = edit(toml_text())
    tomllib.loads(text)  # still valid TOML: the planner, not the parser, refuses it
    layout.write_text(text)
    assert main(["plan", str(layout), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"error: {field}" in err and "Traceback" not in err
    assert "allow_extrapolation" not in err and len(err) < 600
    assert not out.exists()


def test_watchdog_ms_is_reported_in_ms_with_its_range(tmp_path, capsys):
    code = main(["play", str(tmp_path / "plan.json"), str(tmp_path / "pattern.toml"),
                 "--device", "log", "--out", str(tmp_path / "out"), "--watchdog-ms", "100000"])
    err = capsys.readouterr().err
    assert code == 2 and "--watchdog-ms" in err and "(0, 60000] ms" in err
    assert "watchdog_s" not in err and "Traceback" not in err


BAD_VALUES = ("sideways", 1.5, -1, 1e9, float("nan"), True, [], {}, "14")


def test_every_value_of_the_thigh_layout_mutated_is_a_named_error_or_a_plan():
    """Each key of every table (and of the first design) set to each bad value: the answer is
    a plan or a LayoutError naming that key's table, never another exception, never a long
    echo."""
    base = thigh()
    keys = [(table, k) for table, t in base.items() if isinstance(t, dict) for k in t]
    keys += [("design", k) for k in base["design"][0]]
    n_errors = 0
    for table, key in keys:
        for value in BAD_VALUES:
            d = copy.deepcopy(base)
            (d["design"][0] if table == "design" else d[table])[key] = value
            try:
                plan_layout(layout_from_dict(d))
            except LayoutError as err:
                n_errors += 1
                assert err.field.split(".")[0].split("[")[0] == table, (table, key, value)
                assert key in err.field or key in str(err), (table, key, value, str(err))
                assert len(str(err)) < 600
    assert n_errors > 250
