"""The FE check on a tiny case: one unit swept once over two frequencies; the verdict is
plan --verify's; an FE of another site refutes the winner."""

from __future__ import annotations

import pytest
from design_requests import example_dict

from hapticrom.commands.design_verify import band_solver
from planner.design.request import design_request_from_dict
from planner.design.run import design
from planner.design.verify import verify_search


@pytest.fixture(scope="module")
def tiny():
    d = example_dict()
    d["drive"] = {"frequencies_hz": [120.0, 150.0]}
    d["space"] = {"orientations": ["reverse"], "attachments": ["pogo"], "n_rings": [1],
                  "catalogue": ["A"]}
    d["search"] = {"budget": 8}
    d["verify"] = {"top": 1}
    d["reference"] = {"scenes": d["reference"]["scenes"][:1]}
    req = design_request_from_dict(d)
    return design(req, seed=0), req


def test_fe_check_sweeps_each_unit_once(tiny):
    outcome, req = tiny
    calls = []
    solve = band_solver(outcome.layout.model, outcome.layout.site)

    def counted(inputs, materials, freqs):
        calls.append((inputs["n_rings"], materials, freqs))
        return solve(inputs, materials, freqs)

    v = verify_search(outcome.evaluator, outcome.finalists, req.references, counted)
    assert len(calls) == 2  # the winner and the reference, each one sweep for both frequencies
    assert calls[0] == (1, ("ecoflex-00-10",), (120.0, 150.0))
    assert calls[1][1] == ()  # the bare prototype: no rings
    assert v["top_k"] == 2  # the winner at both frequencies, re-ranked on the FE
    fe = {c["frequency_hz"]: c["fe"]["pitch_mm"] for c in v["candidates"]}
    assert v["designs"][0]["fe_pitch_mm"] == min(fe.values())
    assert v["confirmed"] == (v["winner_agrees"] and v["within_tolerance"] and v["holds"])
    assert v["fe_check_wall_s"] > 0


def test_fe_of_another_site_refutes(tiny):
    outcome, _req = tiny
    other = {**outcome.layout.site, "skin_E_kPa": 120.0, "fat_thickness_mm": 4.0}
    v = verify_search(outcome.evaluator, outcome.finalists, (),
                      band_solver(outcome.layout.model, other))
    assert not v["confirmed"] and v["refuted_because"]
    assert v["references"] == [] and v["target"]["best_reference"] is None
