"""The cached scatter-map assembly equals COO -> CSR assembly to round-off."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fem.assembly import (
    assemble_matrix,
    assemble_matrix_coo,
    build_dofmap,
    scatter_map,
)
from fem.mesh import build_mesh
from fem.problem import build_problem
from fem.scene import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _random_mesh(rng, order):
    r = np.r_[0.0, np.cumsum(rng.uniform(0.2, 1.0, 6))]
    z = np.r_[0.0, np.cumsum(rng.uniform(0.2, 1.0, 5))]
    cells = rng.integers(0, 3, (z.size - 1, r.size - 1))
    return build_mesh(r, z, cells, order)


def _random_matrices(rng, shape, complex_values):
    Ke = rng.standard_normal(shape)
    if complex_values:
        Ke = Ke + 1j * rng.standard_normal(shape)
    return Ke


def _assert_same(A, B):
    A, B = A.tocsr(), B.tocsr()
    assert A.shape == B.shape and A.dtype == B.dtype
    assert A.has_sorted_indices and B.has_sorted_indices
    np.testing.assert_array_equal(A.indptr, B.indptr)
    np.testing.assert_array_equal(A.indices, B.indices)
    scale = np.abs(B.data).max()
    np.testing.assert_allclose(A.data, B.data, rtol=0, atol=1e-13 * scale)


@pytest.mark.parametrize("mode", [0, 1, 2])
@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("complex_values", [False, True])
def test_scatter_map_equals_coo_on_a_random_mesh(mode, order, complex_values):
    rng = np.random.default_rng(100 * mode + 10 * order + complex_values)
    mesh = _random_mesh(rng, order)
    base = mesh.nodes_where(lambda r, z: z <= 1e-12)
    side = mesh.nodes_where(lambda r, z: r >= mesh.r_lines[-1] - 1e-12)
    top = mesh.nodes_where(lambda r, z: z >= mesh.z_lines[-1] - 1e-12)
    # fixed base, a prescribed side, and a tie on the top (as a frictionless contact passes)
    dm = build_dofmap(mesh, mode, fixed=[(base, 0), (base, 1)],
                      prescribed=[(side, 0, np.full(side.size, 1e-6))],
                      ties=[(top[1:3], top[3:5], 1)])
    Ke = _random_matrices(rng, (*dm.element_dofs.shape, dm.element_dofs.shape[1]),
                          complex_values)
    _assert_same(assemble_matrix(dm, Ke), assemble_matrix_coo(dm, Ke))
    # a second operator on the same map (mass after stiffness) reuses the cached map
    smap = scatter_map(dm)
    Me = _random_matrices(rng, Ke.shape, complex_values)
    _assert_same(assemble_matrix(dm, Me), assemble_matrix_coo(dm, Me))
    assert scatter_map(dm) is smap
    # an extra operator on its own dofs (a rank-1 spring) gets its own map
    edofs = rng.choice(dm.n_full, size=(1, 5), replace=False)
    Ks = _random_matrices(rng, (1, 5, 5), complex_values)
    _assert_same(assemble_matrix(dm, Ks, edofs), assemble_matrix_coo(dm, Ks, edofs))
    assert scatter_map(dm, edofs) is not smap


def test_replaced_dofmap_starts_an_empty_cache():
    rng = np.random.default_rng(7)
    mesh = _random_mesh(rng, 2)
    dm = build_dofmap(mesh, 1)
    smap = scatter_map(dm)
    dm2 = replace(dm, element_dofs=dm.element_dofs[:, :8])
    assert scatter_map(dm2) is not smap
    assert scatter_map(dm2).shape == (mesh.n_elements, 8, 8)


def test_mismatched_element_matrices_are_refused():
    mesh = _random_mesh(np.random.default_rng(3), 1)
    dm = build_dofmap(mesh, 0)
    with pytest.raises(ValueError, match="do not match the element dofs"):
        assemble_matrix(dm, np.zeros((mesh.n_elements, 4, 4)))


def test_pin_spring_operator_assembles_as_coo():
    problem = build_problem(load_scene(EXAMPLES / "unit-triple-reverse-pogo.toml"))
    assert problem.extra, "the pogo scene carries the pin-spring operator"
    d = problem.domain
    dm = build_dofmap(d.mesh, problem.mode, d.fixed(), ties=d.ties)
    for _name, edofs, Ks in problem.extra:
        for values in (Ks, Ks * (1.0 + 0.3j)):
            _assert_same(assemble_matrix(dm, values, edofs),
                         assemble_matrix_coo(dm, values, edofs))
