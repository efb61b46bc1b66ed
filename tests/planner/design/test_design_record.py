"""The design record: sealed, read back, an edit detected; a small search end to end."""

from __future__ import annotations

import json

import pytest
from design_requests import example_dict

from planner.design.layout_file import layout_toml
from planner.design.record import SCHEMA_VERSION, check_design_record, design_record
from planner.design.request import design_request_from_dict
from planner.design.run import design
from planner.layout import layout_from_dict
from planner.plan_record import PlanRecordError


@pytest.fixture(scope="module")
def outcome():
    d = example_dict()
    d["space"] = {"catalogue": ["A", "D"], "n_rings": [0, 1, 2]}
    d["search"] = {"budget": 16, "batch": 8}
    return design(design_request_from_dict(d), seed=0)


def test_record_round_trip(outcome):
    rec = json.loads(json.dumps(design_record(outcome)))
    assert rec["schema_version"] == SCHEMA_VERSION and rec["kind"] == "hapticrom.design"
    assert check_design_record(rec) == "sealed"
    assert len(rec["history"]) == outcome.evaluator.unique
    assert rec["winner"]["order"] == outcome.winner.order
    assert [r["name"] for r in rec["references"]] == ["unit-bare-forward", "unit-double-forward",
                                                      "unit-triple-reverse-pogo"]
    assert all(0 <= i < len(rec["history"]) for i in rec["pareto"])
    rec["history"][0]["score"] += 1.0
    assert check_design_record(rec) == "edited"


@pytest.mark.parametrize(("edit", "field"), [
    (lambda r: r.update(kind="hapticrom.plan"), "kind"),
    (lambda r: r.update(schema_version=99), "schema_version"),
    (lambda r: r.pop("design_sha256"), "design_sha256"),
    (lambda r: r.update(history={}), "history"),
])
def test_bad_record_names_the_key(outcome, edit, field):
    rec = design_record(outcome)
    edit(rec)
    with pytest.raises(PlanRecordError) as err:
        check_design_record(rec)
    assert err.value.field == field


def test_winner_is_the_best_score_and_felt(outcome):
    w = outcome.winner
    feasible = [e for e in outcome.history if e.feasible and e.perceptible]
    assert w.score == min(e.score for e in feasible)
    assert w.center_low_um >= w.threshold_um
    assert w.pitch_95_mm >= w.pitch_nominal_mm  # the bounds never ask for less room


def test_layout_file_plans_the_winner_first(outcome):
    import tomllib

    from planner.optimise import plan_layout

    req = layout_from_dict(tomllib.loads(layout_toml(outcome)))
    assert next(d["name"] for d in req.designs) == outcome.winner.name
    plan = plan_layout(req)
    assert plan.best.name == outcome.winner.name
    assert plan.best.pitch_mm == pytest.approx(outcome.winner.pitch_mm)
