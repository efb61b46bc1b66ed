"""Static verification against closed-form elasticity (Boussinesq, Cerruti, Lame; Johnson 1985,
Contact Mechanics, ch. 3; Timoshenko & Goodier 1970)."""

import analytic
import numpy as np
import pytest
from fem_cases import half_space_solid, hollow_cylinder, inner_pressure_load, l2_relative_error

from fem import simulate
from fem.assembly import UR, UT, UZ
from fem.domain import MeshSpec, layered_domain
from fem.loads import axis_point_force
from fem.scene import scene_from_dict
from fem.solve import solve_mode

SPEC = MeshSpec(near_size=0.01, near_radius=0.1, far_size=0.05, order=2)


def _truncated_half_space(nu):
    """Unit cube of half-space (mu = 1) with free side/base: exact data will be prescribed."""
    return layered_domain([(1.0, half_space_solid(nu))], 1.0, "free", "free", SPEC, "static")


def _outer_nodes(domain):
    r, z = domain.mesh.nodes.T
    return np.flatnonzero(np.isclose(r, 1.0) | np.isclose(z, 1.0))


def _surface(domain, sol, radii):
    nodes = domain.surface_nodes()
    r = domain.mesh.nodes[nodes, 0]
    U = sol.nodal().real[nodes]
    return np.column_stack([np.interp(radii, r, U[:, c]) for c in range(3)])


@pytest.mark.parametrize("nu", [0.3, 0.47, 0.4999])
def test_boussinesq_point_load_with_exact_boundary_data(nu):
    d = _truncated_half_space(nu)
    bnd = _outer_nodes(d)
    r, z = d.mesh.nodes[bnd].T
    ur, uz = analytic.boussinesq(r, z, 1.0, 1.0, nu)
    sol = solve_mode(d, 0, axis_point_force(d, 0, 1.0), prescribed=[(bnd, UR, ur), (bnd, UZ, uz)])
    radii = np.array([0.1, 0.2, 0.4, 0.7])
    U = _surface(d, sol, radii)
    ur_ex, uz_ex = analytic.boussinesq(radii, 0 * radii, 1.0, 1.0, nu)
    assert np.allclose(U[:, 1], uz_ex, rtol=0.01)
    assert np.allclose(U[:, 0], ur_ex, rtol=0.01, atol=0.01 * np.abs(uz_ex))


@pytest.mark.parametrize("nu", [0.3, 0.49])
def test_cerruti_tangential_point_load_mode_1(nu):
    d = _truncated_half_space(nu)
    bnd = _outer_nodes(d)
    r, z = d.mesh.nodes[bnd].T
    Ur, Ut, Uz = analytic.cerruti(r, z, 1.0, 1.0, nu)
    sol = solve_mode(d, 1, axis_point_force(d, 1, 1.0),
                     prescribed=[(bnd, UR, Ur), (bnd, UZ, Uz), (bnd, UT, Ut)])
    radii = np.array([0.1, 0.2, 0.4, 0.7])
    U = _surface(d, sol, radii)
    Ur_ex, Ut_ex, Uz_ex = analytic.cerruti(radii, 0 * radii, 1.0, 1.0, nu)
    assert np.allclose(U[:, 0], Ur_ex, rtol=0.02)
    assert np.allclose(U[:, 2], Ut_ex, rtol=0.02)
    # u_z carries (1 - 2 nu): compare on the scale of the dominant component
    assert np.allclose(U[:, 1], Uz_ex, atol=0.02 * np.abs(Ur_ex))


@pytest.mark.parametrize("nu", [0.3, 0.49])
def test_uniform_pressure_patch_on_half_space_through_the_static_far_field(nu):
    """The scene path: absorbing side and base become a graded far-field extension."""
    scene = scene_from_dict({
        "tissue": {"radius_mm": 20.0, "side": "absorbing", "base": "absorbing",
                   "layer": [{"name": "h", "thickness_mm": 20.0, "E_kPa": 100.0,
                              "density_kg_m3": 1000.0, "nu": nu}]},
        "load": {"kind": "pressure_patch", "direction": "normal", "radius_mm": 2.0,
                 "amplitude_Pa": 1000.0},
        "analysis": {"kind": "static"},
        "mesh": {"near_size_mm": 0.25, "near_radius_mm": 4.0, "far_size_mm": 2.0},
        "output": {"radii_mm": [0.0, 1.0, 2.0, 3.0, 5.0]},
    })
    res = simulate(scene)
    mu = 100e3 / (2 * (1 + nu))
    exact = analytic.uniform_pressure_surface(res.r_mm * 1e-3, 1000.0, 2e-3, mu, nu)
    assert np.allclose(res.U[:, 1].real, exact, rtol=0.01)  # center, inside, edge, outside
    assert "static far field (side)" in res.meta["effects"]


def _cylinder_error(nu, order, n_r, volumetric="bbar"):
    E, a, b, p = 1.0, 1.0, 2.0, 1.0
    solid = half_space_solid(nu, mu=E / (2 * (1 + nu)))
    d = hollow_cylinder(a, b, 0.25, n_r, 1, order, solid)
    sol = solve_mode(d, 0, inner_pressure_load(d, p), volumetric=volumetric)
    ur = sol.nodal().real[:, 0]
    exact = lambda r: analytic.thick_cylinder_plane_strain(r, p, a, b, E, nu)  # noqa: E731
    inner = np.isclose(d.mesh.nodes[:, 0], a)
    return abs(ur[inner].mean() / exact(a) - 1), l2_relative_error(d, ur, exact)


@pytest.mark.parametrize("nu", [0.3, 0.45, 0.49, 0.499, 0.4999])
@pytest.mark.parametrize("order", [1, 2])
def test_thick_cylinder_is_locking_free(nu, order):
    err_inner, _ = _cylinder_error(nu, order, 8 if order == 2 else 16)
    assert err_inner < 0.005


def test_full_integration_would_lock():
    bbar, _ = _cylinder_error(0.4999, 1, 16)
    full, _ = _cylinder_error(0.4999, 1, 16, volumetric="full")
    assert bbar < 0.005
    assert full > 0.3  # full integration: the inner-wall displacement halves (0.50 measured)


@pytest.mark.parametrize("order", [1, 2])
def test_convergence_rate_matches_element_order(order):
    """L2 error of displacement falls as h^(p+1)."""
    sizes = [4, 8, 16]
    errs = [_cylinder_error(0.3, order, n)[1] for n in sizes]
    rates = np.diff(np.log(errs)) / np.diff(np.log(1.0 / np.array(sizes)))
    assert rates[-1] == pytest.approx(order + 1, abs=0.25)
