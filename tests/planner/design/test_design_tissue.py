"""`--tissue`: the search on the calibrated point estimate, the finalists re-ranked on their
pitch over the person's posterior draws (the plan's posterior_pitch)."""

from __future__ import annotations

import pytest

from hapticrom.cli import main
from planner.design.request import design_request_from_dict
from planner.design.run import design
from planner.tissue import load_tissue
from surrogate.runtime.defaults import default_model_path


@pytest.fixture(scope="module")
def tissue(tmp_path_factory):
    """The calibration on the default harmonic model, the one the request (no `[model] path`)
    plans on: `--tissue` refuses a calibration of another model."""
    out = tmp_path_factory.mktemp("cal") / "cal.json"
    assert main(["calibrate", "examples/measurement-forearm.csv", "--model",
                 str(default_model_path("harmonic")),
                 "--fit", "skin_E_kPa,fat_thickness_mm,tissue_loss_factor", "--walkers", "16",
                 "--steps", "200", "--out", str(out)]) == 0
    return load_tissue(out)


def test_finalists_ranked_over_the_posterior(request_dict, tissue):
    request_dict["space"] = {"catalogue": ["A", "D"], "n_rings": [1],
                             "attachments": ["glued"]}
    request_dict["search"] = {"budget": 8}
    request_dict["reference"] = {"scenes": []}
    outcome = design(design_request_from_dict(request_dict), seed=0, tissue=tissue)
    for k, v in tissue.point.items():
        assert outcome.layout.site[k] == v
    rows = outcome.posterior
    assert rows and outcome.tissue["finalists"] == len(rows)
    keys = [(r["pitch_95_for_plan_mm"] is None, r["pitch_95_for_plan_mm"] or 0) for r in rows]
    assert keys == sorted(keys)
    assert rows[0]["design"] == outcome.winner.name
    # the posterior's 95 % bound asks for at least the point estimate's room
    assert all(r["pitch_95_for_plan_mm"] is None or
               r["pitch_95_for_plan_mm"] >= r["pitch_mm_median"] for r in rows)
