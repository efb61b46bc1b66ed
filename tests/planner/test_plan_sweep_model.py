"""Plans on a sweep-trained model (profile to 40 mm from the unit's edge): the planner reads
the crosstalk from the model's own profile where the single-frequency models' 20 mm profile
ends and the log-slope extension takes over."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from planner import layout_from_dict, plan_layout
from planner.crosstalk import site_positions

LAYOUTS = ("examples/forearm-layout.toml", "examples/thigh-layout.toml",
           "bench/planner/layouts/square.toml", "bench/planner/layouts/hex.toml",
           "bench/planner/layouts/free.toml", "bench/planner/layouts/thick-fat.toml")


def _plan(layout: str, model: str):
    d = tomllib.loads(open(layout).read())
    d.setdefault("model", {})["path"] = model
    return plan_layout(layout_from_dict(d))


@pytest.mark.parametrize("layout", LAYOUTS)
def test_the_nearest_neighbours_are_read_from_the_models_40_mm_profile(layout, sweep_model):
    plan = _plan(layout, str(sweep_model))
    best = plan.best
    assert plan.profile_end_mm == 40.0  # distance from the edge where the model's profile ends
    assert best is not None
    end_mm = best.unit.profile_end_mm  # centre distance of that point
    assert end_mm == pytest.approx(best.unit.edge_radius_mm + 40.0)
    req = plan.request
    pos = (np.asarray(req.positions_mm, dtype=float) if req.positions_mm is not None else
           site_positions(req.rows, req.cols, best.pitch_mm, req.grid))
    r = np.linalg.norm(pos[:, None] - pos[None], axis=2)
    nearest = r[~np.eye(len(pos), dtype=bool)].min()
    assert nearest <= end_mm  # no neighbour that sets the pitch rests on the extension
    # the far neighbours beyond 40 mm carry a small share of the power
    assert 0.0 <= best.beyond_profile < 0.1


def test_on_the_20_mm_single_frequency_model_the_leakage_is_mostly_extrapolated():
    """What the 40 mm profile removes: nn-default's profile ends 20 mm from the edge, short of
    the forearm plan's neighbours."""
    best = _plan(LAYOUTS[0], "models/nn-default").best
    assert best.unit.profile_end_mm < best.pitch_mm
    assert best.beyond_profile > 0.9
