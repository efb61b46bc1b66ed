"""Issue 20 item 7: ``plan --verify`` re-plans the surrogate's top K candidates on FE fields.
Here the FE is a fake field function (no solver): the re-ranking, the verdict and its reasons,
the plan record's ``verify`` block and the ``--verify-top`` validation."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from hapticrom.cli import main
from hapticrom.documents import schema
from planner.crosstalk import UnitField
from planner.layout import CriterionSpec, LayoutRequest
from planner.optimise import DesignResult, Plan, judge, ranked, smallest_pitch
from planner.plan_record import PlanRecord, PlanRecordError, schema_problems
from planner.verify import PITCH_TOLERANCE, FeSolve, rerank, surrogate_ranking

ROOT = Path(__file__).resolve().parents[2]
GRID = np.linspace(0.0, 20.0, 41)  # profile distances from the unit's edge [mm]


def _field(center_um: float, decay_mm: float, edge_mm: float = 4.0) -> UnitField:
    """A unit whose surface amplitude falls as exp(-d / decay) from its centre value."""
    return UnitField(center_um, edge_mm, GRID, center_um * np.exp(-GRID / decay_mm))


def _request(**kw) -> LayoutRequest:
    crit = CriterionSpec(0.1, "incoherent", holds_at=kw.pop("holds_at", "nominal"))
    base = dict(model="fake", rows=2, cols=2, grid="square", min_pitch_mm=5.0,
                max_pitch_mm=80.0, site={}, frequencies_hz=(100.0, 150.0), criterion=crit,
                designs=())
    return LayoutRequest(**{**base, **kw})


def _plan(req: LayoutRequest, decays: dict[tuple[str, float], float],
          unplayable: tuple[tuple[str, float], ...] = (), bound: float = 1.05) -> Plan:
    """A plan whose candidates (design, frequency) have the surrogate fields of ``decays``
    (the bound field ``bound`` times the nominal one), ranked by the plan's own code."""
    cands = []
    for (name, f), decay in decays.items():
        unit = _field(10.0, decay)
        upper = UnitField(10.0, 4.0, GRID, unit.profile_um * bound, floor=unit)
        cands.append(judge(req, DesignResult(name, f, {"n_rings": 0}, 10.0, 4.0, 0.02, 0.02,
                                             False, None, None, unit, upper, edge_um=9.0,
                                             family=name)))
    skipped = [{"name": n, "frequency_hz": f, "reason": "no timing"} for n, f in unplayable]
    order = [r for r in ranked(cands, req.positions_mm is not None)
             if (r.name, r.frequency_hz) not in unplayable]
    return Plan(req, cands, order[0], unplayable=skipped)


def _solver(decays: dict[tuple[str, float], float], calls: list | None = None):
    def solve(r: DesignResult) -> FeSolve:
        if calls is not None:
            calls.append((r.name, r.frequency_hz))
        return FeSolve(_field(10.0, decays[(r.name, r.frequency_hz)]), 9.5, 1000, 0.1,
                       {"frequency_hz": r.frequency_hz})
    return solve


SURROGATE = {("A", 150.0): 3.0, ("B", 150.0): 3.2, ("C", 100.0): 3.4, ("D", 100.0): 3.6}


def test_the_fe_reorders_the_winners_and_the_verdict_says_they_disagree():
    plan = _plan(_request(), SURROGATE)
    assert [r.name for r in surrogate_ranking(plan)] == ["A", "B", "C", "D"]
    # on the FE, A leaks further than B and C: B wins
    fe = {("A", 150.0): 3.5, ("B", 150.0): 3.2, ("C", 100.0): 3.4, ("D", 100.0): 3.6}
    calls: list = []
    v = rerank(plan, 3, _solver(fe, calls))
    assert calls == [("A", 150.0), ("B", 150.0), ("C", 100.0)]  # the top 3 only, in order
    assert v["top_k"] == 3 and [c["design"] for c in v["candidates"]] == ["A", "B", "C"]
    assert [c["fe_rank"] for c in v["candidates"]] == [3, 1, 2]
    assert v["fe_winner"] == {"design": "B", "frequency_hz": 150.0}
    assert v["winner_agrees"] is False and v["confirmed"] is False
    assert "the FE's winner is B at 150 Hz" in v["refuted_because"]
    # the compared pitch: the surrogate's nominal one against the FE field's, same search
    a = v["candidates"][0]
    assert a["fe"]["value"] == pytest.approx(smallest_pitch(_field(10.0, 3.5), plan.request),
                                             abs=1e-3)
    assert a["rel_diff"] == pytest.approx(a["surrogate"]["value"] / a["fe"]["value"] - 1,
                                          abs=1e-4)
    assert a["rel_diff"] < -PITCH_TOLERANCE and v["rel_diff"] == a["rel_diff"]
    assert any("off the FE's" in r for r in v["refuted_because"])
    # a slower decay at the planned pitch loads the sites above 1: the criterion fails too
    assert v["holds"] is False and v["fe"]["criterion_load_at_plan_pitch"] > 1


def test_an_fe_equal_to_the_surrogate_confirms_the_plan():
    plan = _plan(_request(), SURROGATE)
    v = rerank(plan, 5, _solver(SURROGATE))
    assert v["top_k"] == 4 and v["top_k_requested"] == 5  # only four are feasible
    assert [c["fe_rank"] for c in v["candidates"]] == [1, 2, 3, 4]
    assert v["winner_agrees"] and v["holds"] and v["rel_diff"] == 0.0
    assert v["confirmed"] is True and v["refuted_because"] == []


def test_the_same_winner_with_its_pitch_off_by_more_than_the_tolerance_is_refuted():
    # every FE field decays 6 % slower: the order stays, the winner's pitch moves by > 2 %
    req = _request(holds_at="bounds_95")
    plan = _plan(req, SURROGATE, bound=1.5)
    v = rerank(plan, 2, _solver({k: d * 1.06 for k, d in SURROGATE.items()}))
    assert v["winner_agrees"] is True and v["within_tolerance"] is False
    assert v["confirmed"] is False and len(v["refuted_because"]) == 1
    assert "more than 2%" in v["refuted_because"][0]
    # at the 95 % bounds the planned pitch still holds on the FE field
    assert v["holds"] is True and v["surrogate"]["pitch_mm"] > v["surrogate"]["pitch_nominal_mm"]


def test_candidates_skipped_as_not_playable_are_not_re_solved():
    plan = _plan(_request(), SURROGATE, unplayable=(("A", 150.0),))
    assert plan.best.name == "B"
    calls: list = []
    v = rerank(plan, 5, _solver(SURROGATE, calls))
    assert ("A", 150.0) not in calls and v["design"] == "B" and v["top_k"] == 3


def test_free_positions_compare_the_worst_load_at_the_sites():
    req = _request(grid="free", rows=1, cols=3,
                   positions_mm=((0.0, 0.0), (25.0, 0.0), (12.5, 20.0)))
    plan = _plan(req, SURROGATE)
    fe = {k: d * 1.05 for k, d in SURROGATE.items()}
    v = rerank(plan, 4, _solver(fe))
    assert v["compared"] == "worst_load"
    a = v["candidates"][0]
    assert a["surrogate"]["value"] == a["surrogate"]["load_at_plan_pitch"]
    assert a["fe"]["value"] == a["fe"]["load_at_plan_pitch"] > a["surrogate"]["value"]
    assert v["rel_diff"] < -PITCH_TOLERANCE and not v["within_tolerance"]


def test_the_verify_block_round_trips_through_the_plan_record_and_its_schema():
    plan = _plan(_request(), SURROGATE)
    v = rerank(plan, 3, _solver(SURROGATE))
    rec = PlanRecord(model="fake", verify=v)
    doc = json.loads(json.dumps(rec.to_json()))
    back = PlanRecord.from_json(doc)
    assert back.verify == v and back.check.status == "sealed"
    assert schema_problems(doc["verify"], schema("plan")["properties"]["verify"]) == []
    assert back.verify_confirmed is True
    # a verify block written before the re-ranking (the winner alone) is still read
    old = {k: v[k] for k in ("design", "frequency_hz", "edge_radius_mm", "holds",
                             "criterion", "surrogate", "fe", "scene_inputs")}
    old_doc = PlanRecord(model="fake", verify=old).to_json()
    assert PlanRecord.from_json(old_doc).verify_confirmed is None
    assert schema_problems(old, schema("plan")["properties"]["verify"]) == []
    # a verdict that is not a boolean is refused, naming the key
    bad = PlanRecord(model="fake", verify={**v, "confirmed": "yes"}).to_json()
    with pytest.raises(PlanRecordError) as err:
        PlanRecord.from_json(bad)
    assert err.value.field == "verify.confirmed"
    with pytest.raises(PlanRecordError, match=r"verify\.candidates"):
        PlanRecord.from_json(PlanRecord(model="fake", verify={
            **v, "candidates": [{"frequency_hz": -1.0}]}).to_json())


def test_the_winner_must_lead_the_plans_ranking():
    plan = _plan(_request(), SURROGATE)
    with pytest.raises(ValueError, match="not first"):
        rerank(replace(plan, best=plan.candidates[2]), 3, _solver(SURROGATE))


@pytest.mark.parametrize("value", ["0", "33", "-1", "five", "2.5"])
def test_verify_top_outside_1_to_32_is_refused_naming_the_option(tmp_path, capsys, value):
    out = tmp_path / "plan.json"
    code = main(["plan", str(ROOT / "examples" / "forearm-layout.toml"),
                 "--verify-top", value, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "--verify-top" in err and "1 to 32" in err
    assert not out.exists()
