"""Small model builders shared by the FE verification tests (SI units)."""

from __future__ import annotations

import numpy as np

from fem.assembly import UR, UZ
from fem.domain import Domain
from fem.elements import circumferential_factor, gauss_data, lagrange_1d
from fem.materials import Material
from fem.mesh import build_mesh
from fem.scene import SceneError, scene_from_dict


def half_space_solid(nu: float, mu: float = 1.0, density: float = 1.0) -> Material:
    return Material("half-space", 2.0 * mu * (1.0 + nu), density, nu)


def hollow_cylinder(a: float, b: float, length: float, n_r: int, n_z: int, order: int,
                    solid: Material) -> Domain:
    """Plane-strain thick cylinder a < r < b, 0 < z < length, u_z = 0 on both ends."""
    mesh = build_mesh(np.linspace(a, b, n_r + 1), np.linspace(0.0, length, n_z + 1),
                      np.zeros((n_z, n_r), dtype=int), order)
    ends = mesh.nodes_where(lambda r, z: np.isclose(z, 0.0) | np.isclose(z, length))
    return Domain(mesh, (solid,), b, length, "free", "free", constraints=((ends, UZ),))


def inner_pressure_load(domain: Domain, pressure: float) -> np.ndarray:
    """Consistent nodal load (mode 0) of an internal pressure on the face r = r_min."""
    m = domain.mesh
    p = m.order
    a = m.r_lines[0]
    on_face = np.isclose(m.cell_r0, a)
    xg, wg = np.polynomial.legendre.leggauss(p + 1)
    L, _ = lagrange_1d(p, xg)
    nodal = np.einsum("g,gj->j", wg, L)[None, :] * 0.5 * m.cell_hz[on_face][:, None]
    face_nodes = m.elements[on_face][:, :: p + 1]  # local i = 0, j = 0..p
    f = np.zeros(m.n_nodes * 2)
    np.add.at(f, face_nodes.ravel() * 2 + UR,
              (circumferential_factor(0) * pressure * a * nodal).ravel())
    return f


def l2_relative_error(domain: Domain, nodal_ur: np.ndarray, exact) -> float:
    """Relative L2 error (weighted by r) of U_r against exact(r) over the mesh."""
    g = gauss_data(domain.mesh)
    u_h = np.einsum("ga,ea->eg", g.N, nodal_ur[domain.mesh.elements])
    u_ex = exact(g.r)
    return float(np.sqrt(np.sum(g.weight * (u_h - u_ex) ** 2) / np.sum(g.weight * u_ex**2)))


def assert_scene_error(d: dict, field: str, fragment: str) -> SceneError:
    """``scene_from_dict(d)`` must fail on ``field`` with ``fragment`` in its message."""
    import pytest

    with pytest.raises(SceneError) as info:
        scene_from_dict(d)
    assert info.value.field == field
    assert fragment in str(info.value)
    return info.value
