"""A space's mesh plan (``mesh_topology = "per_design"``): one topology per discrete design,
never coarser than any sample's own mesh, stable across runs, off by default (hashes of
existing spaces unchanged), and clear errors."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

import surrogate.data.mesh_plan as mesh_plan
from fem.problem import build_problem
from surrogate.data.errors import SpaceError
from surrogate.data.plan import plan_samples
from surrogate.data.space import load_space, space_from_dict
from surrogate.data.topology import topology_key
from tests.surrogate.data.test_topology import UNIT_SPACE


def _space(topology: str | None = "per_design", **head: Any):
    d = copy.deepcopy(UNIT_SPACE)
    # the wavelength rule on, so skin modulus moves lines as well as fat thickness does
    d["base"]["mesh"]["follow_wavelength"] = True
    if topology is not None:
        d["space"]["mesh_topology"] = topology
    d["space"].update(head)
    return space_from_dict(d)


def test_one_topology_per_design_and_never_coarser_than_the_own_mesh():
    own, planned = _space("per_sample"), _space()
    points, _ = plan_samples(planned, 24)
    keys: dict[tuple, set[str]] = {}
    own_keys = set()
    for p in points:
        design = planned.mesh_plan.design(p.values)
        keys.setdefault(design, set()).add(topology_key(p.scene))
        own_keys.add(topology_key(own.scene(p.values)))
        need_r, need_z = build_problem(own.scene(p.values)).domain.cells_needed
        cells_r, cells_z = planned.mesh_plan.cells(p.values)
        assert np.all(np.array(cells_r) >= need_r) and np.all(np.array(cells_z) >= need_z)
        assert p.scene["mesh"]["cells_r"] == list(cells_r)
    assert all(len(k) == 1 for k in keys.values())  # one topology per design
    assert len(own_keys) > len(keys)  # the own meshes change with the continuous values


def test_plan_depends_on_the_space_alone():
    a, b = _space(), _space()
    row = {**a.center(), "attachment": "pogo", "n_rings": 1}
    assert a.mesh_plan.cells(row) == b.mesh_plan.cells({**row, "fat_thickness_mm": 3.0})
    first, _ = plan_samples(a, 8)
    again, _ = plan_samples(b, 12)
    assert [p.sample_id for p in first] == [p.sample_id for p in again[:8]]


def test_per_sample_is_the_default_and_leaves_hashes_alone():
    default = load_space("datasets/spaces/default.toml")
    assert default.mesh_topology == "per_sample"
    assert "mesh_topology" not in default.to_dict()["space"]
    assert _space(None).space_hash() == _space("per_sample").space_hash()
    planned = _space()
    assert planned.to_dict()["space"]["mesh_topology"] == "per_design"
    assert space_from_dict(planned.to_dict()).space_hash() == planned.space_hash()
    assert planned.space_hash() != _space(None).space_hash()
    p, _ = plan_samples(_space(None), 1)
    assert "cells_r" not in p[0].scene["mesh"]


def test_unknown_mesh_topology_names_the_key_and_the_choices():
    with pytest.raises(SpaceError, match=r"per_sample.*per_design") as err:
        _space("fixed")
    assert err.value.field == "space.mesh_topology"


def test_too_many_mesh_parameters_are_refused(monkeypatch):
    monkeypatch.setattr(mesh_plan, "MAX_MESH_PARAMETERS", 1)
    with pytest.raises(SpaceError, match="2 continuous parameters move the mesh") as err:
        _space()
    assert err.value.field == "space.mesh_topology"
