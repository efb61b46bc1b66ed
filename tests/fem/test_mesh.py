"""Fixed cells per segment (``fem.mesh.fit_cells``, ``mesh.cells_r`` / ``mesh.cells_z``): the
size rules' own counts reproduce their mesh exactly, more cells keep every bound and never
coarsen, the topology stays put while nodes move continuously, and bad plans name the key."""

from __future__ import annotations

import copy
import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fem import simulate
from fem.cost import estimate_cost
from fem.mesh import fit_cells, graded_lines, growing_size, segment_cells
from fem.problem import build_problem
from fem.scene import SceneError, scene_from_dict, scene_hash, scene_to_dict
from tests.fem.scene_cases import assert_round_trips

#: A coarse glued unit with two rings on the forearm: unit, ring, layer and absorber segments.
COARSE_UNIT = {
    "load": {"kind": "unit"},
    "analysis": {"kind": "harmonic", "frequency_hz": 150.0},
    "mesh": {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 2},
    "tissue": {"radius_mm": 30.0},
    "unit": {"encapsulation": ["dragon-skin-10-medium", "ecoflex-00-50"]},
}


def _with(d: dict, **mesh: object) -> dict:
    out = copy.deepcopy(d)
    out["mesh"].update(mesh)
    return out


def _fat(d: dict, fat_mm: float) -> dict:
    out = scene_to_dict(scene_from_dict(d))
    out["tissue"]["layer"][1]["thickness_mm"] = fat_mm
    return out


# Breakpoints on a 1e-5 mm grid: two closer than the sliver tolerance (1e-9 m,
# fem.mesh.distinct_breaks) are one breakpoint by definition, so a pair 1 ulp apart (drawn once:
# [0, 0.0005, 0.0005] mm) is not two bounds the mesh must keep.
breaks_st = st.lists(st.floats(0.5, 40.0).map(lambda x: round(x, 5)), min_size=1, max_size=5,
                     unique=True).map(lambda xs: np.array([0.0, *sorted(xs)]) * 1e-3)


@settings(max_examples=60, deadline=None)
@given(breaks=breaks_st, extra=st.lists(st.integers(0, 7), min_size=5, max_size=5))
def test_fit_cells_counts_bounds_and_no_coarsening(breaks, extra):
    lines = graded_lines(breaks, growing_size(5e-3, 0.5e-3, 3e-3), 1)
    needed = segment_cells(lines, breaks)
    assert np.array_equal(fit_cells(lines, breaks, needed), lines)  # own counts: same mesh
    cells = needed + np.array(extra[:needed.size])
    fitted = fit_cells(lines, breaks, cells)
    assert np.array_equal(segment_cells(fitted, breaks), cells)
    assert np.all(np.diff(fitted) > 0)
    assert np.all(np.isin(breaks, fitted))  # every bound stays a line
    for a, b in itertools.pairwise(breaks):
        old = np.diff(lines[(lines >= a) & (lines <= b)])
        new = np.diff(fitted[(fitted >= a) & (fitted <= b)])
        assert new.max() <= old.max() * (1 + 1e-12)


def test_fit_cells_refuses_mismatched_counts():
    lines = np.array([0.0, 1.0, 2.0, 4.0])
    with pytest.raises(ValueError, match="need 2 cell counts >= 1"):
        fit_cells(lines, np.array([0.0, 2.0, 4.0]), np.array([2, 1, 1]))
    with pytest.raises(ValueError, match="need 2 cell counts >= 1"):
        fit_cells(lines, np.array([0.0, 2.0, 4.0]), np.array([2, 0]))
    with pytest.raises(ValueError, match="must be a cell line"):
        segment_cells(lines, np.array([0.0, 1.5, 4.0]))


def test_needed_cells_reproduce_the_mesh_and_the_answer_exactly():
    scene = scene_from_dict(COARSE_UNIT)
    problem = build_problem(scene)
    cells_r, cells_z = problem.domain.cells_needed
    assert sum(cells_r) == problem.domain.mesh.r_lines.size - 1
    assert sum(cells_z) == problem.domain.mesh.z_lines.size - 1
    fixed = scene_from_dict(_with(COARSE_UNIT, cells_r=list(cells_r), cells_z=list(cells_z)))
    mesh = build_problem(fixed).domain.mesh
    assert np.array_equal(mesh.r_lines, problem.domain.mesh.r_lines)
    assert np.array_equal(mesh.z_lines, problem.domain.mesh.z_lines)
    a, b = simulate(scene), simulate(fixed)
    assert a.center_amplitude_um == b.center_amplitude_um
    assert a.edge_amplitude_um == b.edge_amplitude_um


def test_fixed_cells_keep_the_topology_while_nodes_move_continuously():
    need_thin = build_problem(scene_from_dict(_fat(COARSE_UNIT, 4.0))).domain.cells_needed
    need_thick = build_problem(scene_from_dict(_fat(COARSE_UNIT, 12.0))).domain.cells_needed
    assert need_thin != need_thick  # the size rules change the topology along this sweep
    cells = tuple(np.maximum(np.array(a), np.array(b)).tolist()
                  for a, b in zip(need_thin, need_thick, strict=True))
    planned = _with(COARSE_UNIT, cells_r=cells[0], cells_z=cells[1])
    meshes = [build_problem(scene_from_dict(_fat(planned, t))).domain.mesh
              for t in (4.0, 8.0, 8.0 + 1e-6, 12.0)]
    for m in meshes[1:]:
        assert np.array_equal(m.elements, meshes[0].elements)  # one topology
    step = np.abs(meshes[2].nodes - meshes[1].nodes).max()
    assert 0 < step < 1e-8  # a 1 nm change of the layer moves nodes by at most ~1 nm


def test_fixed_cells_answer_is_smooth_along_the_layer_thickness():
    """Second differences of a smooth answer shrink 4x when the step halves; a jump of the
    discretisation would not."""
    cells = build_problem(scene_from_dict(_fat(COARSE_UNIT, 12.0))).domain.cells_needed
    planned = _with(COARSE_UNIT, cells_r=cells[0], cells_z=cells[1])

    def kink(step_mm: float) -> float:
        y = [simulate(scene_from_dict(_fat(planned, 8.0 + k * step_mm))).edge_amplitude_um
             for k in (-1, 0, 1)]
        return abs(y[0] - 2 * y[1] + y[2])

    ratio = kink(0.4) / kink(0.2)
    assert 3.0 < ratio < 5.0


def test_fixed_cells_round_trip_and_leave_other_hashes_alone():
    plain = scene_from_dict(COARSE_UNIT)
    assert "cells_r" not in scene_to_dict(plain)["mesh"]  # absent unless given
    fixed = scene_from_dict(_with(COARSE_UNIT, cells_r=[9, 3, 3, 9, 9], cells_z=[4] * 9))
    assert fixed.mesh.cells_r == (9, 3, 3, 9, 9)
    assert_round_trips(fixed)
    assert scene_hash(fixed) != scene_hash(plain)


@pytest.mark.parametrize(("value", "field", "words"), [
    ([0, 3], "mesh.cells_r[0]", "out of range"),
    ([2.5], "mesh.cells_r[0]", "expected an integer"),
    ("12", "mesh.cells_r", "list of whole numbers"),
    ([], "mesh.cells_r", "non-empty"),
])
def test_bad_cell_lists_are_refused_by_name(value, field, words):
    with pytest.raises(SceneError, match=words) as err:
        scene_from_dict(_with(COARSE_UNIT, cells_r=value))
    assert err.value.field == field


def test_plans_that_do_not_fit_the_body_name_the_axis_and_the_need():
    cells_r, cells_z = build_problem(scene_from_dict(COARSE_UNIT)).domain.cells_needed
    with pytest.raises(SceneError, match=f"{len(cells_z)} segments along z") as err:
        build_problem(scene_from_dict(_with(COARSE_UNIT, cells_z=[*cells_z, 3])))
    assert err.value.field == "mesh.cells_z"
    short = [*cells_r]
    short[-1] -= 1
    with pytest.raises(SceneError, match=f"at least {cells_r[-1]}") as err:
        build_problem(scene_from_dict(_with(COARSE_UNIT, cells_r=short)))
    assert err.value.field == "mesh.cells_r"


def test_cost_estimate_bounds_a_mesh_with_more_cells():
    cells_r, cells_z = build_problem(scene_from_dict(COARSE_UNIT)).domain.cells_needed
    scene = scene_from_dict(_with(COARSE_UNIT, cells_r=[2 * n for n in cells_r],
                                  cells_z=[2 * n for n in cells_z]))
    mesh = build_problem(scene).domain.mesh
    assert estimate_cost(scene).unknowns >= 3 * mesh.n_nodes
