"""Property: any scene either validates and solves to finite values, or raises a field error.

Scenes are valid starting points with one to three fields replaced by values drawn from far
outside any sensible range (zero, negative, 1e-30 .. 1e30, NaN, inf, wrong types). Every
outcome must be one of: a SceneError naming a field (validation, or the cost check refusing
a scene above the unknown limit) or a solve with finite amplitudes. Anything else -- another
exception, a NaN, a run past the limit -- fails. The fast tier runs a few hundred examples on
a small limit; ``make test-slow`` runs a thousand with transients too.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from fem import simulate
from fem.scene import SceneError, scene_from_dict

COARSE = {"near_size_mm": 2.0, "far_size_mm": 6.0, "order": 1}
BASES: dict[str, dict[str, Any]] = {
    "harmonic": {"analysis": {"kind": "harmonic"}, "mesh": COARSE},
    "static": {"analysis": {"kind": "static"}, "mesh": COARSE},
    "unit": {"analysis": {"kind": "harmonic"}, "mesh": COARSE, "load": {"kind": "unit"},
             "unit": {"encapsulation": ["A", "C"]}},
    "pogo": {"analysis": {"kind": "harmonic"}, "mesh": COARSE, "load": {"kind": "unit"},
             "unit": {"attachment": "pogo", "encapsulation": ["B"]}},
    "transient": {"analysis": {"kind": "transient", "duration_ms": 2.0, "time_step_ms": 0.5},
                  "mesh": COARSE, "load": {"kind": "unit"}, "unit": {}},
}
FIELDS = [
    "tissue.radius_mm", "tissue.layer.0.thickness_mm", "tissue.layer.0.E_kPa",
    "tissue.layer.1.nu", "tissue.layer.2.density_kg_m3", "tissue.layer.1.loss_factor",
    "load.radius_mm", "load.amplitude_Pa", "analysis.frequency_hz", "analysis.time_step_ms",
    "analysis.duration_ms", "mesh.near_size_mm", "mesh.far_size_mm", "mesh.near_radius_mm",
    "mesh.order", "output.profile_step_mm", "output.radii_mm", "unit.motor.diameter_mm",
    "unit.motor.mass_g", "unit.board.diameter_mm", "unit.board.thickness_mm",
    "unit.ring_thickness_mm", "unit.pogo.radius_mm", "unit.pogo.stiffness_N_m",
    "unit.pogo.length_mm", "unit.encapsulation", "tissue.side", "tissue.base",
]
moderate = st.floats(min_value=0.01, max_value=500.0).map(lambda x: float(f"{x:.3g}"))
values = st.one_of(
    *[moderate] * 8,  # mostly values a user might try: many of them solve
    st.sampled_from([0, 0.0, -1.0, 1e-30, 1e-9, 1e-3, 0.5, 1.0, 7.0, 1e3, 1e9, 1e30,
                     math.nan, math.inf, -math.inf, True, "A", "", "fixed", [], [1.0], None]),
    st.floats(min_value=1e-12, max_value=1e12, allow_nan=False).map(lambda x: float(f"{x:.3g}")),
    st.integers(min_value=-5, max_value=10**6),
)
UNIT_BASES = ("unit", "pogo", "transient")


def mutations(base: str) -> st.SearchStrategy[list[tuple[str, Any]]]:
    """One or two (field, value) changes; [unit] fields only where the base has a unit (on
    the others they are a validation error every time, which tests nothing new)."""
    fields = FIELDS if base in UNIT_BASES else [f for f in FIELDS if not f.startswith("unit.")]
    return st.lists(st.tuples(st.sampled_from(fields), values), min_size=1, max_size=2)


def cases(bases: list[str]) -> st.SearchStrategy[tuple[str, list[tuple[str, Any]]]]:
    return st.sampled_from(bases).flatmap(lambda b: st.tuples(st.just(b), mutations(b)))


def _set(d: dict[str, Any], path: str, value: Any) -> None:
    """Set a dotted path; numeric parts index a list (the forearm's layers are filled in)."""
    keys = path.split(".")
    if keys[:2] == ["tissue", "layer"]:
        d.setdefault("tissue", {}).setdefault("layer", [
            {"material": m, "thickness_mm": t}
            for m, t in (("skin", 1.9), ("fat", 14.0), ("muscle", 21.0), ("bone", 5.0))])
    node: Any = d
    for key in keys[:-1]:
        node = node[int(key)] if key.isdigit() else node.setdefault(key, {})
        if not isinstance(node, dict | list):
            return  # a previous mutation replaced the table by a value
    if isinstance(node, list):
        node[int(keys[-1])] = value
    else:
        node[keys[-1]] = value


def outcome(d: dict[str, Any], max_unknowns: float) -> str:
    """'invalid', 'refused' or 'solved' (finite); anything else raises."""
    try:
        scene = scene_from_dict(d)
    except SceneError as err:
        assert err.field, f"a field error without a field: {err}"
        return "invalid"
    try:
        res = simulate(scene, max_unknowns=max_unknowns)
    except SceneError as err:
        assert err.field, f"a field error without a field: {err}"
        return "refused"
    assert res.meta["dofs"] <= max_unknowns  # the estimate errs on the large side
    values = [res.center_amplitude_um, *np.abs(res.profile).ravel()]
    assert np.all(np.isfinite(values)), f"non-finite result for {d}"
    return "solved"


def _check(base: str, changes: list[tuple[str, Any]], max_unknowns: float) -> None:
    d = copy.deepcopy(BASES[base])
    for path, value in changes:
        _set(d, path, value)
    outcome(d, max_unknowns)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cases(["harmonic", "static", "unit", "pogo"]))
# found by this test: a deep unit scene whose mesh was 1 % above the estimate (rounding of the
# graded segments, and the rows above the skin, were not counted)
@example(("unit", [("tissue.layer.0.thickness_mm", 110.0)]))
@example(("pogo", [("tissue.layer.0.thickness_mm", 72.3)]))
# found by this test: a skin of 1e-30 kPa passed validation and made the static system singular
# (FloatingPointError); moduli now start at 0.001 kPa (1 Pa, softer than any tissue or gel)
@example(("static", [("tissue.layer.0.E_kPa", 1e-30)]))
def test_mutated_scenes_validate_and_solve_finite_or_raise_a_field_error(case):
    _check(*case, max_unknowns=20_000)


@pytest.mark.slow
@settings(max_examples=1000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cases(list(BASES)))
def test_a_thousand_mutated_scenes_including_transients(case):
    _check(*case, max_unknowns=50_000)
