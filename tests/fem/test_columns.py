"""Column-wise element formation (fem.columns) against the element-by-element routines."""

from __future__ import annotations

import numpy as np
import pytest

from fem import columns, elements
from fem.absorbers import PML
from fem.mesh import build_mesh, graded_lines


def _mesh(order: int):
    r = graded_lines([0.0, 2e-3, 10e-3], lambda x: 0.3e-3 + 0.2 * x)
    z = graded_lines([0.0, 1.9e-3, 15e-3, 30e-3], lambda x: 0.4e-3 + 0.1 * x)
    material = np.zeros((z.size - 1, r.size - 1), dtype=int)
    material[:2, :3] = -1  # a void notch: columns of unequal length
    return build_mesh(r, z, material, order)


def _reference(mesh, idx, stretch, mode, coef, volumetric):
    g = elements.gauss_data(mesh, stretch, subset=idx)
    return (elements.stiffness(g, mode, coef[:, 0], coef[:, 1], volumetric)
            + coef[:, 2, None, None] * elements.mass(g, mode, np.ones(idx.size)))


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("mode", [0, 1, 2])
@pytest.mark.parametrize("volumetric", ["bbar", "full"])
def test_columns_match_element_by_element(order, mode, volumetric):
    mesh = _mesh(order)
    rng = np.random.default_rng(order + 10 * mode)
    idx = np.arange(mesh.n_elements)
    coef = np.column_stack([rng.uniform(1e3, 1e5, idx.size) * (1 + 0.3j),
                            rng.uniform(1e4, 1e6, idx.size) * (1 + 0.3j),
                            -rng.uniform(1e6, 1e8, idx.size)])
    got = columns.column_matrices(mesh, idx, None, mode, coef, volumetric)
    want = _reference(mesh, idx, None, mode, coef, volumetric)
    assert np.abs(got - want).max() <= 1e-11 * np.abs(want).max()


def test_columns_in_a_radial_pml_match():
    mesh = _mesh(2)
    pml = PML(omega=2 * np.pi * 120, speed=3.0, r_start=6e-3, r_thickness=4e-3)
    idx = np.arange(mesh.n_elements)
    assert columns.column_path(mesh, pml).all()  # no PML in z: every element by column
    coef = np.tile([1e4 + 3e3j, 3e5 + 1e5j, -6e8], (idx.size, 1))
    in_pml = pml.contains(mesh.cell_r0, mesh.cell_z0)
    got = columns.column_matrices(mesh, idx, pml, 1, coef)
    want = np.empty_like(got)
    for sel, st in ((~in_pml, None), (in_pml, pml)):
        want[sel] = _reference(mesh, idx[sel], st, 1, coef[sel], "bbar")
    assert np.abs(got - want).max() <= 1e-11 * np.abs(want).max()
    assert np.iscomplexobj(got) and np.abs(got[in_pml].imag).max() > 0


def test_elements_in_a_pml_in_z_are_left_to_the_element_path():
    mesh = _mesh(1)
    pml = PML(omega=1.0, speed=1.0, z_start=15e-3, z_thickness=15e-3)
    on = columns.column_path(mesh, pml)
    assert np.array_equal(on, mesh.cell_z0 + mesh.cell_hz <= 15e-3 * (1 + 1e-12))
    assert on.any() and not on.all()


def test_stiffness_only_forms_no_mass(monkeypatch):
    mesh = _mesh(2)
    idx = np.arange(mesh.n_elements)
    coef = np.tile([1e4, 3e5], (idx.size, 1))
    want = _reference(mesh, idx, None, 1, np.column_stack([coef, np.zeros(idx.size)]), "bbar")

    def forbidden(*args, **kwargs):
        raise AssertionError("mass formed for a stiffness-only combination")

    monkeypatch.setattr(elements, "mass", forbidden)
    got = columns.column_matrices(mesh, idx, None, 1, coef)
    assert np.abs(got - want).max() <= 1e-11 * np.abs(want).max()
    with pytest.raises(ValueError, match="coef has 4 columns"):
        columns.column_matrices(mesh, idx, None, 1, np.ones((idx.size, 4)))
