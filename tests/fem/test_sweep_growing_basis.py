"""The growing basis of the sweep's reduced model: its incremental projection equals the
projection from scratch, whatever the block sizes; the tolerance is a scene field."""

from __future__ import annotations

import numpy as np
import pytest
from sweep_cases import example

from fem.scene import scene_from_dict, scene_to_dict
from fem.scene.model import SceneError
from fem.sweep import setup
from fem.sweep_basis import GrowingBasis


@pytest.fixture(scope="module")
def pogo_setup():
    return setup(example("unit-triple-reverse-pogo.toml"))


def _random_orthonormal(model: GrowingBasis, k: int, rng: np.random.Generator) -> list:
    cols: list = []
    n = model.op.dofmap.n_free
    for _ in range(k):
        q = model.orthogonal_part(rng.standard_normal(n) + 1j * rng.standard_normal(n), cols)
        cols.append(q)
    return cols


def test_incremental_projection_equals_the_projection_from_scratch(pogo_setup):
    s = pogo_setup
    rng = np.random.default_rng(3)
    model = GrowingBasis(s.operator, s.output_map, capacity=2)  # grows twice
    for k in (2, 3, 1, 4):
        model.append(_random_orthonormal(model, k, rng))
    V = model.basis
    assert np.allclose(V.conj().T @ V, np.eye(10), atol=1e-12)
    ref = s.operator.project(V)
    for term in range(s.operator.n_terms):
        scale = np.abs(ref[term]).max()
        assert np.abs(model.reduced[term] - ref[term]).max() <= 1e-12 * scale, term
    assert np.allclose(model.load, V.conj().T @ s.operator.load, rtol=1e-13, atol=0)
    assert np.allclose(model.outputs, s.output_map(V), rtol=1e-13, atol=0)


def test_leading_columns_are_the_smaller_model(pogo_setup):
    s = pogo_setup
    rng = np.random.default_rng(4)
    model = GrowingBasis(s.operator, s.output_map, capacity=8)
    model.append(_random_orthonormal(model, 6, rng))
    coef = np.array([s.operator.coefficients(w) for w in s.omegas[:5]])
    small = GrowingBasis(s.operator, s.output_map, capacity=4)
    small.append([model.basis[:, i].copy() for i in range(4)])
    assert np.allclose(model.evaluate(coef, 4), small.evaluate(coef), rtol=1e-10, atol=0)


def test_a_dependent_direction_is_dropped(pogo_setup):
    s = pogo_setup
    model = GrowingBasis(s.operator, s.output_map, capacity=4)
    cols = _random_orthonormal(model, 2, np.random.default_rng(5))
    model.append(cols)
    assert model.orthogonal_part(cols[0] * 3.0 - 2j * cols[1]) is None


def test_the_tolerance_is_a_scene_field_written_only_when_set():
    base = {"analysis": {"kind": "sweep", "frequency_hz": [100.0, 120.0]}}
    default = scene_from_dict(base)
    assert "tolerance" not in scene_to_dict(default)["analysis"]  # older hashes hold
    loose = scene_from_dict({"analysis": base["analysis"] | {"tolerance": 0.01}})
    assert loose.analysis.tolerance == 0.01
    assert scene_from_dict(scene_to_dict(loose)) == loose
    allowed = r"analysis\.tolerance = 0\.5 is out of range: allowed 1e-6 <= tolerance <= 0\.1"
    with pytest.raises(SceneError, match=allowed):
        scene_from_dict({"analysis": base["analysis"] | {"tolerance": 0.5}})
