"""Issue 27 item 2: ``plan --verify`` judges the plan with the plan's own criterion on the FE
solve: a load above 1 at the planned pitch is a failure (exit 3, a clear line with the pitch
the FE needs), not "it holds"."""

from __future__ import annotations

import json

from hapticrom.cli import main
from hapticrom.commands.plan import EXIT_VERIFY_FAILED
from hapticrom.documents import schema
from planner.plan_record import PlanRecord
from tests.planner.thigh import toml_text


def _run(tmp_path, text, capsys):
    layout, out = tmp_path / "layout.toml", tmp_path / "plan.json"
    layout.write_text(text)
    code = main(["plan", str(layout), "--verify", "--out", str(out)])
    doc = json.loads(out.read_text())
    assert PlanRecord.from_json(doc, schema("plan")).verify_confirmed is doc["verify"][
        "confirmed"]  # the written verify block meets the shipped schema
    return code, capsys.readouterr().out, doc


def test_a_load_above_one_on_the_fe_fails_with_its_own_exit_code(tmp_path, capsys):
    # the perceptual thigh layout ranked on the nominal prediction: the FE load at the
    # planned pitch is 1.18 (issue 27: printed "<= 1: it holds", exit 0)
    text = toml_text(perceptual=True).replace('holds_at = "bounds_95"', 'holds_at = "nominal"')
    code, out, doc = _run(tmp_path, text, capsys)
    v = doc["verify"]
    load = v["fe"]["criterion_load_at_plan_pitch"]
    assert load > 1.0 and v["holds"] is False
    assert code == EXIT_VERIFY_FAILED == 3
    assert "criterion: FAILS on the FE" in out and f"criterion load {load:.3f} > 1" in out
    assert v["confirmed"] is False and "verdict: REFUTED" in out
    assert any("the criterion fails at the FE field" in r for r in v["refuted_because"])
    # the pitch the FE needs, on the same criterion, is longer than the planned one
    assert v["fe"]["pitch_mm"] > v["surrogate"]["pitch_mm"]
    assert f"the FE needs {v['fe']['pitch_mm']:.2f} mm" in out
    assert "it holds" not in out


def test_a_criterion_the_fe_field_meets_is_said_and_the_exit_code_follows_the_verdict(
        tmp_path, capsys):
    code, out, doc = _run(tmp_path, toml_text(), capsys)  # ratio, 95 % bounds (default)
    v = doc["verify"]
    load = v["fe"]["criterion_load_at_plan_pitch"]
    assert v["holds"] is (load <= 1.0) is True
    assert f"criterion: HOLDS on the FE: criterion load {load:.3f} <= 1" in out
    # the verdict also asks for the same winner and the pitch within 2 % (issue 20)
    assert v["confirmed"] is (v["winner_agrees"] and v["within_tolerance"])
    assert code == (0 if v["confirmed"] else EXIT_VERIFY_FAILED)
    assert ("verdict: CONFIRMED" in out) is v["confirmed"]
    assert v["fe"]["pitch_mm"] <= v["surrogate"]["pitch_mm"]
