"""Typed records between stages (issue 22): one design record, shared by the dataset plan and
the accuracy study."""

from __future__ import annotations

from dataclasses import fields

from studies.accuracy.designs import Design, load_study_data, pick_designs
from surrogate.data.plan import Planned


def test_the_study_design_is_the_planned_design_with_its_row():
    assert issubclass(Design, Planned)
    assert [f.name for f in fields(Design)] == [f.name for f in fields(Planned)] + ["row"]


def test_picked_designs_carry_their_sequence_index_and_values():
    sd = load_study_data()
    [d] = pick_designs(sd, 1)
    assert d.index == sd.extras["sample_index"][d.row]
    assert d.sample_id == sd.sample_id[d.row] and set(d.values) == {
        s.name for s in sd.data.specs}
