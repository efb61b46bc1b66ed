"""objective = "max_sites": the largest grid that fits a region, on cases known by hand."""

from __future__ import annotations

import itertools
import math
import tomllib
from pathlib import Path

import pytest

from planner import LayoutError, layout_from_dict, plan_layout
from planner.optimise import PITCH_TOL_MM, _fill_region, smallest_pitch
from planner.region import largest_array, largest_pitch
from tests.planner.test_crosstalk_and_pitch import EDGE, R0, L, exponential_unit

ROOT = Path(__file__).resolve().parents[2]
P_STAR = EDGE + L * math.log(R0 / 0.05)  # one neighbour at 5 %: 14.59 mm


def region_request(w: float, h: float, grid: str = "square", superposition: str = "worst"):
    return layout_from_dict({
        "array": {"objective": "max_sites", "region_mm": [w, h], "grid": grid,
                  "min_pitch_mm": 1.0, "max_pitch_mm": 200.0},
        "criterion": {"max_ratio": 0.05, "superposition": superposition},
        "design": [{"name": "x"}]})


def test_largest_pitch_by_hand():
    assert largest_pitch(2, 4, "square", (50.0, 30.0), 3.0) == pytest.approx(min(44 / 3, 24))
    assert largest_pitch(3, 2, "hex", (50.0, 30.0), 3.0) == pytest.approx(
        min(44 / 1.5, 24 / math.sqrt(3)))
    assert largest_pitch(1, 1, "square", (10.0, 10.0), 3.0) == math.inf
    assert largest_pitch(1, 1, "square", (5.0, 10.0), 3.0) == -math.inf


def test_the_staircase_finds_the_brute_force_optimum():
    for a, b in [(3.0, 7.0), (5.5, 2.0), (10.0, 10.0), (0.5, 0.5)]:
        def fits(r: int, c: int, a=a, b=b) -> bool:  # monotone: under r/a + c/b = 1
            return r / a + c / b <= 1.0 + 1e-12 or (r * c <= 1 and a >= 1)
        shapes = [(r, c) for r, c in itertools.product(range(1, 13), repeat=2) if fits(r, c)]
        found = largest_array(fits, 12)
        if not shapes:
            assert found is None
            continue
        assert found[0] * found[1] == max(r * c for r, c in shapes)


def test_most_sites_in_a_region_by_hand():
    # worst neighbour only: any pitch >= P_STAR works; 4 columns need 2 EDGE + 3 P_STAR wide,
    # 2 rows need 2 EDGE + P_STAR high
    req = region_request(2 * EDGE + 3 * P_STAR + 0.5, 2 * EDGE + P_STAR + 0.5)
    f = exponential_unit()
    shaped = _fill_region(f, req, 0.0)
    assert (shaped.rows, shaped.cols) == (2, 4)
    assert smallest_pitch(f, shaped) == pytest.approx(P_STAR, abs=PITCH_TOL_MM)
    # a hair narrower: only 3 columns; the height then allows 2 rows
    narrow = _fill_region(f, region_request(2 * EDGE + 3 * P_STAR - 0.5,
                                            2 * EDGE + P_STAR + 0.5), 0.0)
    assert (narrow.rows, narrow.cols) == (2, 3)
    # too small for two units at P_STAR: one unit; smaller than a unit: nothing
    assert (lambda s: (s.rows, s.cols))(_fill_region(f, region_request(20.0, 20.0), 0.0)) \
        == (1, 1)
    assert _fill_region(f, region_request(5.0, 20.0), 0.0) is None


@pytest.mark.parametrize("array, field", [
    ({"objective": "max_sites"}, "array.region_mm"),
    ({"objective": "max_sites", "region_mm": [50.0]}, "array.region_mm"),
    ({"objective": "max_sites", "region_mm": [50.0, 50.0], "rows": 2}, "array.rows"),
    ({"objective": "max_sites", "region_mm": [50.0, 50.0], "grid": "free",
      "positions_mm": [[0, 0], [20, 0]]}, "array.objective"),
    ({"rows": 2, "cols": 2, "region_mm": [50.0, 50.0]}, "array.region_mm"),
    ({"objective": "most", "region_mm": [50.0, 50.0]}, "array.objective"),
])
def test_bad_region_requests_name_the_field(array, field):
    with pytest.raises(LayoutError) as info:
        layout_from_dict({"array": array, "design": [{"name": "x"}]})
    assert info.value.field == field


def test_max_sites_plan_on_the_shipped_model():
    d = tomllib.loads((ROOT / "examples" / "forearm-layout.toml").read_text())
    d["model"]["path"] = str(ROOT / "models" / "nn-default")
    d["array"] = {"objective": "max_sites", "region_mm": [60.0, 120.0], "grid": "hex"}
    d["drive"]["frequencies_hz"] = [150.0]
    d["timing"] = {"enabled": False}
    plan = plan_layout(layout_from_dict(d))
    best = plan.best
    assert best is not None and best.shape == (plan.request.rows, plan.request.cols)
    n = best.shape[0] * best.shape[1]
    assert all(c.shape is None or c.shape[0] * c.shape[1] <= n for c in plan.candidates)
    assert plan.positions_mm.shape == (n, 2) and plan.margin >= 1.0
    lo, hi = plan.positions_mm.min(axis=0), plan.positions_mm.max(axis=0)
    assert (hi - lo + 2 * best.edge_radius_mm <= [60.0 + 1e-9, 120.0 + 1e-9]).all()
