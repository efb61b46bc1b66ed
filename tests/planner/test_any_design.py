"""[[design]] any = true: candidates drawn from the model's trained range."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from planner import LayoutError, layout_from_dict, plan_layout
from planner.candidates import latin_hypercube
from surrogate.runtime import load_predictor

ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / "models" / "nn-default"


def _request(any_design: dict, frequencies=(150.0,)) -> dict:
    d = tomllib.loads((ROOT / "examples" / "forearm-layout.toml").read_text())
    d["model"]["path"] = str(MODEL)
    d["drive"]["frequencies_hz"] = list(frequencies)
    d["timing"] = {"enabled": False}
    d["design"].append({"name": "any", "any": True, **any_design})
    return d


def test_latin_hypercube_has_one_point_per_stratum_and_is_deterministic():
    u = latin_hypercube(10, 3, seed=5)
    assert u.shape == (10, 3) and ((u >= 0) & (u < 1)).all()
    for j in range(3):
        assert sorted(np.floor(u[:, j] * 10).astype(int)) == list(range(10))
    np.testing.assert_array_equal(u, latin_hypercube(10, 3, seed=5))
    assert not np.array_equal(u, latin_hypercube(10, 3, seed=6))


@pytest.fixture(scope="module")
def plan():
    return plan_layout(layout_from_dict(_request({"n_candidates": 32})))


def test_every_candidate_lies_in_the_trained_range_and_site_inputs_are_kept(plan):
    specs = load_predictor(MODEL).specs
    drawn = [c for c in plan.candidates if c.family == "any"]
    assert len(drawn) == 32
    site = plan.request.site
    for c in drawn:
        assert not c.extrapolated
        for s in specs:
            if s.name == "frequency_hz":
                continue
            v = c.inputs[s.name] if s.name in c.inputs else site[s.name]
            if s.name in site:
                assert s.name not in c.inputs
            elif s.type == "categorical":
                assert v in s.choices
            else:
                assert s.low <= v <= s.high
                if s.type == "integer":
                    assert v == int(v)
    # the 2 x 2 x 4 categorical and ring-count combinations are all enumerated, twice each
    combos = [(c.inputs["orientation"], c.inputs["attachment"], c.inputs["n_rings"])
              for c in drawn]
    assert len(set(combos)) == 16 and all(combos.count(x) == 2 for x in set(combos))


def test_the_winner_is_no_worse_than_any_named_design(plan):
    named = [c for c in plan.candidates if c.family == c.name]
    assert plan.best is not None and len(named) == 3
    assert all(c.pitch_mm is None or plan.best.pitch_mm <= c.pitch_mm for c in named)
    drawn = [c.pitch_mm for c in plan.candidates if c.family == "any" and c.pitch_mm]
    assert plan.best.pitch_mm == min([*drawn, *(c.pitch_mm for c in named if c.pitch_mm)])
    assert [c.name for c in plan.shown()][-1].startswith("any #")


def test_fixed_inputs_of_the_any_table_are_kept():
    plan = plan_layout(layout_from_dict(_request(
        {"orientation": "reverse", "attachment": "pogo", "n_candidates": 8, "seed": 3})))
    drawn = [c for c in plan.candidates if c.family == "any"]
    assert len(drawn) == 8
    assert {(c.inputs["orientation"], c.inputs["attachment"]) for c in drawn} == {
        ("reverse", "pogo")}
    assert sorted(c.inputs["n_rings"] for c in drawn) == [0, 0, 1, 1, 2, 2, 3, 3]


@pytest.mark.parametrize("extra, field, at_plan", [
    ({"n_candidates": 4}, "design[3].n_candidates", False),
    ({"n_candidates": 2000}, "design[3].n_candidates", False),
    ({"any": "yes"}, "design[3].any", False),
    ({"n_candidates": 8}, "design[3].n_candidates", True),  # 16 combinations
    ({"stiffness": 1.0}, "design[3].stiffness", True),
])
def test_bad_any_designs_name_the_field(extra, field, at_plan):
    d = _request(extra)
    with pytest.raises(LayoutError) as info:
        plan_layout(layout_from_dict(d)) if at_plan else layout_from_dict(d)
    assert info.value.field == field


def test_sampling_keys_need_any():
    d = _request({})
    d["design"][0]["seed"] = 1
    with pytest.raises(LayoutError) as info:
        layout_from_dict(d)
    assert info.value.field == "design[0].seed"
