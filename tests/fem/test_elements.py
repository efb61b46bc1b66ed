"""Invariants of the Fourier-mode element operators."""

import numpy as np
import pytest

from fem import elements
from fem.assembly import assemble_matrix, build_dofmap
from fem.mesh import build_mesh

R_LINES = np.array([0.0, 0.4, 1.0, 2.5])
Z_LINES = np.array([0.0, 0.3, 1.2])


def _mesh(order):
    return build_mesh(R_LINES, Z_LINES, np.array([[0, 0, 1], [1, 0, 0]]), order)


def _element_values(mesh, field, mode):
    ndpn = elements.dofs_per_node(mode)
    dofs = (mesh.elements[:, :, None] * ndpn + np.arange(ndpn)).reshape(mesh.n_elements, -1)
    return field[:, :ndpn].ravel()[dofs]


def _rigid_modes(mesh, mode):
    r, z = mesh.nodes[:, 0], mesh.nodes[:, 1]
    one, zero = np.ones_like(r), np.zeros_like(r)
    if mode == 0:
        return {"vertical translation": np.column_stack([zero, one])}
    return {  # (U_r, U_z, U_t) of a horizontal translation and a rotation about the y axis
        "horizontal translation": np.column_stack([one, zero, -one]),
        "rotation about horizontal axis": np.column_stack([z, -r, -z]),
    }


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("mode", [0, 1])
@pytest.mark.parametrize("volumetric", ["bbar", "full"])
def test_rigid_body_modes_carry_no_strain_energy(order, mode, volumetric):
    mesh = _mesh(order)
    g = elements.gauss_data(mesh)
    mu = np.array([1.0, 50.0])[mesh.material]
    kappa = np.array([30.0, 4000.0])[mesh.material]
    K = elements.stiffness(g, mode, mu, kappa, volumetric)
    scale = np.abs(K).max()
    for name, field in _rigid_modes(mesh, mode).items():
        u = _element_values(mesh, field, mode)
        energy = np.einsum("ea,eab,eb->", u, K, u)
        assert abs(energy) < 1e-12 * scale * mesh.n_elements, name


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("mode", [0, 1, 2])
def test_operators_are_symmetric_and_positive(order, mode):
    mesh = _mesh(order)
    g = elements.gauss_data(mesh)
    mu, kappa = np.full(mesh.n_elements, 2.0), np.full(mesh.n_elements, 90.0)
    dm = build_dofmap(mesh, mode, fixed=[(mesh.nodes_where(lambda r, z: z > 1.1), c)
                                         for c in range(3)])
    K = assemble_matrix(dm, elements.stiffness(g, mode, mu, kappa)).toarray()
    M = assemble_matrix(dm, elements.mass(g, mode, np.full(mesh.n_elements, 3.0))).toarray()
    assert np.allclose(K, K.T, atol=1e-12 * np.abs(K).max())
    assert np.allclose(M, M.T, atol=1e-14 * np.abs(M).max())
    assert np.linalg.eigvalsh(K).min() > 0  # constrained: no rigid motion left
    assert np.linalg.eigvalsh(M).min() > 0


@pytest.mark.parametrize("mode", [0, 1])
def test_mass_of_a_translation_is_the_body_mass(mode):
    """u^T M u for a unit translation is the mass of the body of revolution: for n = 1 the
    kinetic energy pi * (U_r^2 + U_t^2) = 2 pi per unit r dr dz, as for n = 0."""
    mesh = _mesh(2)
    g = elements.gauss_data(mesh)
    density = np.array([1000.0, 2000.0])[mesh.material]
    M = elements.mass(g, mode, density)
    field = _rigid_modes(mesh, mode)["vertical translation" if mode == 0 else
                                     "horizontal translation"]
    u = _element_values(mesh, field, mode)
    rings = np.pi * ((mesh.cell_r0 + mesh.cell_hr) ** 2 - mesh.cell_r0**2) * mesh.cell_hz
    body_mass = np.sum(rings * density)
    assert np.einsum("ea,eab,eb->", u, M, u) == pytest.approx(body_mass, rel=1e-12)


def test_pml_operator_is_complex_symmetric_and_reduces_to_plain_without_stretch():
    from fem.absorbers import PML

    mesh = _mesh(2)
    pml = PML(omega=2 * np.pi * 100, speed=5.0, r_start=1.0, r_thickness=1.5)
    mu, kappa = np.full(mesh.n_elements, 2.0), np.full(mesh.n_elements, 90.0)
    K = elements.stiffness(elements.gauss_data(mesh, pml), 1, mu, kappa)
    assert np.iscomplexobj(K)
    assert np.allclose(K, K.transpose(0, 2, 1), atol=1e-12 * np.abs(K).max())
    inside = ~pml.contains(mesh.cell_r0, mesh.cell_z0)
    K0 = elements.stiffness(elements.gauss_data(mesh), 1, mu, kappa)
    assert np.allclose(K[inside], K0[inside], rtol=1e-13, atol=1e-13 * np.abs(K0).max())
    assert not np.allclose(K[~inside], K0[~inside])


def test_lagrange_basis_is_a_partition_of_unity_with_kronecker_nodes():
    x = np.linspace(-1, 1, 7)
    for p in (1, 2, 3):
        vals, ders = elements.lagrange_1d(p, x)
        assert np.allclose(vals.sum(axis=1), 1.0)
        assert np.allclose(ders.sum(axis=1), 0.0, atol=1e-12)
        nodes_vals, _ = elements.lagrange_1d(p, np.linspace(-1, 1, p + 1))
        assert np.allclose(nodes_vals, np.eye(p + 1))
