"""The plan record (shared interface 3): ``hapticrom plan`` writes a sealed plan whose digest
is the sha256 of the canonical JSON without it; ``check_plan`` finds an edit, reads the old
layout, and refuses every out-of-range number naming its key; the shipped JSON Schema agrees."""

from __future__ import annotations

import copy
import hashlib
import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hapticrom.cli import main
from hapticrom.documents import schema
from planner.plan_record import (
    KIND,
    SCHEMA_KEYWORDS,
    TIMING_RANGES,
    PlanRecordError,
    check_plan,
    plan_digest,
    schema_problems,
    seal_plan,
)

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "forearm-layout.toml"


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """The plan `hapticrom plan` writes for the example layout cut to 2 x 2."""
    tmp = tmp_path_factory.mktemp("plan")
    layout = tmp / "layout.toml"
    layout.write_text(EXAMPLE.read_text().replace('"models/nn-default"', repr(str(
        ROOT / "models" / "nn-default"))).replace("rows = 4", "rows = 2").replace(
        "cols = 4", "cols = 2"))
    out = tmp / "plan.json"
    assert main(["plan", str(layout), "--out", str(out)]) == 0
    return json.loads(out.read_text())


def test_the_written_plan_is_sealed_with_the_canonical_digest(written):
    assert written["schema_version"] == 1 and written["kind"] == KIND
    assert "format" not in written and "version" not in written
    body = {k: v for k, v in written.items() if k != "plan_sha256"}
    canonical = json.dumps(body, sort_keys=True, separators=(",", ":"),
                           ensure_ascii=False).encode("utf-8")
    assert written["plan_sha256"] == hashlib.sha256(canonical).hexdigest() == plan_digest(
        written)
    rec = check_plan(written, schema("plan"))
    assert rec.status == "sealed" and rec.trusted


def test_the_written_plan_conforms_to_the_shipped_schema(written):
    s = schema("plan")
    assert schema_problems(written, s) == []
    assert s["properties"]["kind"]["const"] == KIND
    # the schema's timing ranges are the checker's
    for key, (lo, hi, lo_incl) in TIMING_RANGES.items():
        p = s["properties"]["timing"]["properties"][key]
        assert p["minimum" if lo_incl else "exclusiveMinimum"] == lo and p["maximum"] == hi


@pytest.mark.parametrize("edit", [
    lambda d: d["timing"].update(overdrive_level=5.0),
    lambda d: d["timing"].update(brake_ms=d["timing"]["brake_ms"] + 1),
    lambda d: d["crosstalk_um"][0].__setitem__(1, 0.0),
    lambda d: d.update(best_frequency_hz=100.0),
    lambda d: d.update(limits={"max_level": 8.0}),
])
def test_any_edit_is_reported_as_edited_and_resealing_makes_it_sealed_again(written, edit):
    d = copy.deepcopy(written)
    edit(d)
    rec = check_plan(d)
    assert rec.status == "edited" and not rec.trusted
    assert rec.recorded == written["plan_sha256"] != rec.actual
    assert "edited" in rec.describe()
    assert check_plan(seal_plan(d)).status == "sealed"  # a digest is not a signature


def test_the_old_layout_is_read_as_unsealed_and_migrated_by_sealing(written):
    old = {"format": "hapticrom-plan", "version": 1,
           **{k: v for k, v in written.items() if k not in ("schema_version", "kind",
                                                            "plan_sha256")}}
    rec = check_plan(old, schema("plan"))
    assert rec.status == "unsealed" and rec.recorded is None
    new = seal_plan(old)
    assert {"format", "version"}.isdisjoint(new) and check_plan(new).status == "sealed"
    assert new["kind"] == KIND and schema_problems(new, schema("plan")) == []
    with pytest.raises(PlanRecordError) as err:
        check_plan({**old, "version": 2})
    assert err.value.field == "version"


@pytest.mark.parametrize("edit, field", [
    (lambda d: d.update(kind="hapticrom.predict"), "kind"),
    (lambda d: d.update(schema_version=2), "schema_version"),
    (lambda d: d.update(plan_sha256="x" * 64), "plan_sha256"),
    (lambda d: d.update(best_frequency_hz=0.0), "best_frequency_hz"),
    (lambda d: d.update(best_frequency_hz=2e4), "best_frequency_hz"),
    (lambda d: d.update(pitch_mm=-1.0), "pitch_mm"),
    (lambda d: d["positions_mm"][1].__setitem__(0, 1e6), "positions_mm[1][0]"),
    (lambda d: d["positions_mm"][1].pop(), "positions_mm[1]"),
    (lambda d: d["crosstalk_um"][0].__setitem__(1, -0.1), "crosstalk_um[0][1]"),
    (lambda d: d["crosstalk_um"][2].__setitem__(2, 0.0), "crosstalk_um[2][2]"),
    (lambda d: d["crosstalk_um"][1].__setitem__(0, float("nan")), "crosstalk_um[1][0]"),
    (lambda d: d["crosstalk_um"][0].__setitem__(0, 1e9), "crosstalk_um[0][0]"),
    (lambda d: d["timing"].update(overdrive_level=9.0), "timing.overdrive_level"),
    (lambda d: d["timing"].update(overdrive_level=0.5), "timing.overdrive_level"),
    (lambda d: d["timing"].update(rise_ms=-1.0), "timing.rise_ms"),
    (lambda d: d["timing"].update(brake_ms=1e7), "timing.brake_ms"),
    (lambda d: d["timing"].update(min_isi_ms="short"), "timing.min_isi_ms"),
    (lambda d: d["timing"].update(nominal_voltage_V=0.0), "timing.nominal_voltage_V"),
    (lambda d: d["timing"].update(brake_voltage_V=4.5), "timing.brake_voltage_V"),
    (lambda d: d["candidates"][0].update(frequency_hz=-5.0), "candidates[0].frequency_hz"),
    (lambda d: d["criterion"].update(drive_level=100.0), "criterion.drive_level"),
    (lambda d: d.update(leakage_um=[1.0]), "leakage_um"),
])
def test_out_of_range_numbers_are_refused_naming_the_key_and_the_schema_agrees(written, edit,
                                                                               field):
    d = copy.deepcopy(written)
    edit(d)
    d = seal_plan(d) if field not in ("kind", "schema_version", "plan_sha256") else d
    with pytest.raises(PlanRecordError) as err:
        check_plan(d)
    assert err.value.field == field, str(err.value)
    assert field.split("[")[0].split(".")[0] in str(err.value)
    if field not in ("plan_sha256", "crosstalk_um[1][0]", "crosstalk_um[2][2]", "leakage_um"):
        # the JSON Schema catches the same value (NaN is not JSON; a zero own amplitude and a
        # list as long as the sites are cross-field rules the schema cannot state)
        assert any(p.startswith(field.split("[")[0]) for p, _ in
                   schema_problems(d, schema("plan"))), field


def test_the_schema_checker_refuses_keywords_it_does_not_know():
    assert {"maximum", "exclusiveMaximum", "maxItems"} <= SCHEMA_KEYWORDS
    with pytest.raises(ValueError, match="not supported"):
        schema_problems(1, {"multipleOf": 2})
    assert schema_problems(3, {"type": "number", "maximum": 2}) == [("<plan>",
                                                                     "3 breaks maximum 2")]


def _leaves(d, path=()):
    """Every (path, value) of the scalars in a JSON tree."""
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield from _leaves(v, (*path, i))
    else:
        yield path, d


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_any_single_changed_value_is_never_taken_for_the_sealed_plan(written, data):
    leaves = [p for p, v in _leaves(written) if p != ("plan_sha256",)]
    path = data.draw(st.sampled_from(leaves))
    new = data.draw(st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(),
                              st.text(max_size=5), st.booleans(), st.none()))
    d = copy.deepcopy(written)
    node = d
    for key in path[:-1]:
        node = node[key]
    if node[path[-1]] == new and type(node[path[-1]]) is type(new):
        return
    node[path[-1]] = new
    try:
        rec = check_plan(d, schema("plan"))
    except PlanRecordError as err:  # refused naming a key, never another exception
        assert err.field
        return
    assert rec.status == "edited"
