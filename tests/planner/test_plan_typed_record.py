"""plan.json as a typed record (issue 22): ``PlanRecord.to_json`` writes what ``hapticrom
plan`` always wrote (sealed), ``from_json`` reads it back field for field, keeps keys it does
not name, and refuses what ``check_plan`` refuses, naming the key."""

from __future__ import annotations

import json
import tomllib
from dataclasses import replace
from pathlib import Path

import pytest

from hapticrom.cli import main
from hapticrom.documents import schema
from planner import layout_from_dict, plan_as_record, plan_layout, plan_to_dict
from planner.plan_record import PlanRecord, PlanRecordError, plan_digest, seal_plan

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def plan():
    d = tomllib.loads((ROOT / "examples" / "forearm-layout.toml").read_text())
    d["array"].update(rows=2, cols=2)
    d["drive"]["frequencies_hz"] = [100.0]
    return plan_layout(layout_from_dict(d))


def test_the_record_writes_what_the_dict_form_wrote(plan):
    record = plan_as_record(plan)
    assert record.to_json() == seal_plan(plan_to_dict(plan))
    assert json.loads(json.dumps(record.to_json())) == record.to_json()


def test_from_json_reads_back_every_field_and_keeps_unknown_keys(plan):
    sealed = seal_plan({**plan_to_dict(plan), "note": "kept"})
    back = PlanRecord.from_json(json.loads(json.dumps(sealed)), schema("plan"))
    assert back.check is not None and back.check.status == "sealed"
    assert back.extra == {"note": "kept"} and back.best == plan.best.name
    assert back.to_json() == sealed  # same content, same digest
    assert replace(back, check=None) == back  # the integrity is not part of the content


def test_an_edited_record_reads_as_edited_and_a_bad_one_is_refused(plan):
    sealed = seal_plan(plan_to_dict(plan))
    sealed["pitch_mm"] = sealed["pitch_mm"] + 1.0
    assert PlanRecord.from_json(sealed).check.status == "edited"
    assert plan_digest(sealed) != sealed["plan_sha256"]
    bad = dict(sealed, schema_version=2)
    with pytest.raises(PlanRecordError, match=r"plan.schema_version = 2") as err:
        PlanRecord.from_json(bad)
    assert err.value.field == "schema_version"


def test_hapticrom_plan_writes_the_record(tmp_path, capsys):
    layout = tmp_path / "layout.toml"
    text = (ROOT / "examples" / "forearm-layout.toml").read_text()
    layout.write_text(text.replace('"models/nn-default"', repr(str(ROOT / "models" /
                                                                    "nn-default")))
                      .replace("rows = 4", "rows = 2").replace("cols = 4", "cols = 2"))
    out = tmp_path / "plan.json"
    assert main(["plan", str(layout), "--out", str(out)]) == 0
    record = PlanRecord.from_json(json.loads(out.read_text()), schema("plan"))
    assert record.check.status == "sealed" and record.best is not None
    assert len(record.crosstalk_um) == len(record.positions_mm) == 4
