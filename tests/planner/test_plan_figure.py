"""Issue 27 item 6: the plan figure numbers the sites, highlights the chosen design, labels
the criterion and threshold lines, keeps the legend off the data, gives up to 16+ curves
distinct colours; a body site without threshold data of its own is warned about."""

from __future__ import annotations

import json

import pytest

import figstyle
from hapticrom.cli import main
from planner import layout_from_dict, plan_layout, plan_to_dict, write_plan_plot
from planner.figure import curve_styles
from tests.planner.thigh import thigh, toml_text


@pytest.mark.parametrize("n", [1, 8, 9, 16, 20, 21, 40])
def test_every_curve_gets_a_distinct_style(n):
    styles = curve_styles(n)
    assert len(styles) == n == len(set(styles))
    if n <= 20:  # up to 20 curves: distinct colours alone, solid lines
        assert len({c for c, _ in styles}) == n


def _figure(plan, monkeypatch, tmp_path):
    kept = {}
    monkeypatch.setattr(figstyle, "save", lambda fig, path, **kw: kept.update(fig=fig))
    write_plan_plot(plan, tmp_path / "plan.png")
    return kept["fig"]


def test_sites_numbered_chosen_highlighted_lines_labelled_legend_apart(monkeypatch, tmp_path):
    d = thigh()
    d["design"] += [{**d["design"][1], "name": f"double {k}", "ring_nu": 0.45 + 0.01 * k}
                    for k in range(3)]  # 6 designs x 3 reachable frequencies: 18 curves
    plan = plan_layout(layout_from_dict(d))
    fig = _figure(plan, monkeypatch, tmp_path)
    array_ax, profiles_ax, legend_ax = fig.axes[:3]
    numbers = sorted(int(t.get_text()) for t in array_ax.texts)
    assert numbers == list(range(36))  # pattern files address sites 0..35, row by row
    lines = [ln for ln in profiles_ax.get_lines() if not ln.get_label().startswith("_")]
    assert len(lines) == len(plan.shown()) >= 16
    chosen = [ln for ln in lines if ln.get_label().startswith("CHOSEN")]
    assert len(chosen) == 1 and chosen[0].get_linewidth() > 2 * max(
        ln.get_linewidth() for ln in lines if ln is not chosen[0])
    assert plan.best.name in chosen[0].get_label()
    styles = {(ln.get_color(), ln.get_linestyle()) for ln in lines}
    assert len(styles) == len(lines)  # no two curves alike
    labels = [t.get_text() for t in profiles_ax.texts]
    assert any(t.startswith("criterion: max_ratio 0.1") for t in labels)
    assert any(t.startswith("chosen pitch") for t in labels)
    assert profiles_ax.get_legend() is None and legend_ax.get_legend() is not None
    assert not legend_ax.axison  # the legend has a panel of its own, off the data


def test_perceptual_thresholds_labelled_and_the_borrowed_curve_warned(monkeypatch, tmp_path):
    plan = plan_layout(layout_from_dict(thigh(perceptual=True)))
    warnings = plan.request.criterion.warnings()
    assert len(warnings) == 1 and "'thigh'" in warnings[0] and "volar forearm" in warnings[0]
    assert plan_to_dict(plan)["warnings"] == warnings
    fig = _figure(plan, monkeypatch, tmp_path)
    labels = [t.get_text() for t in fig.axes[1].texts]
    for f in sorted({c.frequency_hz for c in plan.shown()}):
        assert any(t.startswith(f"threshold {f:g} Hz:") for t in labels)
    assert any("volar forearm" in t.get_text() for t in fig.texts)  # in the caption


def test_a_site_with_its_own_curve_is_not_warned_and_the_cli_prints_the_warning(
        tmp_path, capsys):
    d = thigh(perceptual=True)
    d["criterion"]["body_site"] = "forearm"
    assert layout_from_dict(d).criterion.warnings() == []
    layout, out = tmp_path / "layout.toml", tmp_path / "plan.json"
    layout.write_text(toml_text(perceptual=True))
    assert main(["plan", str(layout), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "warning: criterion.body_site = 'thigh' has no threshold data" in printed
    assert json.loads(out.read_text())["criterion"]["body_site"] == "thigh"
