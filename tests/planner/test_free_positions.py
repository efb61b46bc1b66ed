"""grid = "free": given site positions, checked and evaluated without a pitch search."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from planner import LayoutError, layout_from_dict, plan_layout
from planner.optimise import smallest_pitch, worst_load
from tests.planner.test_crosstalk_and_pitch import EDGE, R0, L, exponential_unit

ROOT = Path(__file__).resolve().parents[2]


def free(positions, max_ratio=0.05, superposition="worst"):
    return layout_from_dict({
        "array": {"grid": "free", "positions_mm": positions},
        "criterion": {"max_ratio": max_ratio, "superposition": superposition},
        "design": [{"name": "x"}]})


def test_two_sites_feasible_or_not_as_computed_by_hand():
    # ratio at distance D: R0 exp(-(D - EDGE) / L); the hand limit is D* = EDGE + L ln(R0/0.05)
    d_star = EDGE + L * math.log(R0 / 0.05)  # 14.59 mm
    f = exponential_unit()
    near = free([[0.0, 0.0], [0.6 * (d_star + 1.0), 0.8 * (d_star + 1.0)]])  # D = D* + 1
    assert smallest_pitch(f, near) == pytest.approx(d_star + 1.0)
    assert worst_load(f, near, 0.0, 0.0) == pytest.approx(R0 * math.exp(-(d_star + 1 - EDGE) / L)
                                                     / 0.05)
    assert worst_load(f, near, 0.0, 0.0) == pytest.approx(math.exp(-1.0 / L))  # margin e^(1/L)
    far = free([[0.0, 0.0], [d_star - 1.0, 0.0]])
    assert worst_load(f, far, 0.0, 0.0) == pytest.approx(math.exp(1.0 / L))
    assert smallest_pitch(f, far) is None


def test_three_free_sites_add_powers_by_hand():
    # an L-shaped triple: the corner site has two neighbours at 15 and 20 mm
    req = free([[0.0, 0.0], [15.0, 0.0], [0.0, 20.0]], max_ratio=0.05,
               superposition="incoherent")
    a = [R0 * math.exp(-(d - EDGE) / L) for d in (15.0, 20.0)]
    assert worst_load(exponential_unit(), req, 0.0, 0.0) == pytest.approx(
        math.hypot(*a) / 0.05)


@pytest.mark.parametrize("array, field", [
    ({"grid": "free"}, "array.positions_mm"),
    ({"grid": "free", "positions_mm": [[0, 0]]}, "array.positions_mm"),
    ({"grid": "free", "positions_mm": [[0, 0], [1, 2, 3]]}, "array.positions_mm[1]"),
    ({"grid": "free", "positions_mm": [[0, 0], [math.inf, 0]]}, "array.positions_mm[1][0]"),
    ({"grid": "free", "positions_mm": [[0, 0], [math.nan, 0]]}, "array.positions_mm[1][0]"),
    ({"grid": "free", "positions_mm": [[0, 0], ["a", 0]]}, "array.positions_mm[1][0]"),
    ({"grid": "free", "rows": 2, "positions_mm": [[0, 0], [9, 0]]}, "array.rows"),
    ({"grid": "square", "rows": 2, "cols": 2, "positions_mm": [[0, 0], [9, 0]]},
     "array.positions_mm"),
    ({"grid": "square", "rows": 2}, "array.cols"),
])
def test_bad_free_layouts_name_the_field(array, field):
    with pytest.raises(LayoutError) as info:
        layout_from_dict({"array": array, "design": [{"name": "x"}]})
    assert info.value.field == field


def _example_free(positions) -> dict:
    d = tomllib.loads((ROOT / "examples" / "forearm-layout.toml").read_text())
    d["model"]["path"] = str(ROOT / "models" / "nn-default")
    d["array"] = {"grid": "free", "positions_mm": positions}
    d["timing"] = {"enabled": False}
    return d


def test_free_plan_on_the_shipped_model_picks_the_largest_margin():
    plan = plan_layout(layout_from_dict(_example_free([[0, 0], [40, 0], [20, 30], [60, 30]])))
    feasible = [c for c in plan.candidates if c.pitch_mm is not None]
    assert plan.best is not None and feasible
    assert plan.best.load == min(c.load for c in feasible) and plan.margin >= 1.0
    # ranked on the 95 % bounds (the default): the winner's load is its load at the bounds
    assert plan.load_95 == pytest.approx(plan.best.load) and plan.margin >= 1 / plan.load_95
    np.testing.assert_allclose(plan.positions_mm, [[0, 0], [40, 0], [20, 30], [60, 30]])
    assert plan.best.pitch_mm == pytest.approx(36.0555, abs=1e-3)  # sqrt(20^2 + 30^2)


def test_overlapping_free_sites_are_refused_naming_the_site():
    with pytest.raises(LayoutError) as info:
        plan_layout(layout_from_dict(_example_free([[0, 0], [30, 0], [31, 0.5]])))
    assert info.value.field == "array.positions_mm[2]"
    assert "overlap" in str(info.value)


def test_cli_free_plan_with_any_writes_positions_and_winner_inputs(tmp_path):
    import json

    from hapticrom.cli import main

    text = (ROOT / "examples" / "forearm-layout.toml").read_text()
    text = text.replace('"models/nn-default"', repr(str(ROOT / "models" / "nn-default")))
    text = text.replace('rows = 4', 'positions_mm = [[0, 0], [30, 0], [0, 30]]')
    text = text.replace('cols = 4', '').replace('grid = "square"', 'grid = "free"')
    text += '\n[[design]]\nname = "any"\nany = true\nn_candidates = 16\n'
    layout, out, png = tmp_path / "l.toml", tmp_path / "plan.json", tmp_path / "plan.png"
    layout.write_text(text)
    assert main(["plan", str(layout), "--out", str(out), "--plot", str(png)]) == 0
    doc = json.loads(out.read_text())
    assert doc["positions_mm"] == [[0, 0], [30, 0], [0, 30]] and png.stat().st_size > 0
    assert len(doc["candidates"]) == (3 + 16) * 3 and doc["array"]["grid"] == "free"
    best = next(c for c in doc["candidates"] if c["name"] == doc["best"]
                and c["frequency_hz"] == doc["best_frequency_hz"])
    assert doc["best_inputs"] == best["inputs"] and best["worst_load"] <= 1.0
    assert doc["uncertainty"]["margin_95"] == pytest.approx(1 / best["worst_load"], rel=1e-3)
    assert doc["margin"] >= doc["uncertainty"]["margin_95"]
