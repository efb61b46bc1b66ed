"""Consistent nodal loads of one Fourier mode (full dof vectors, N).

Traction amplitudes follow the symmetric set: for n >= 1 a load of horizontal direction x is
t_r = t cos(theta), t_theta = -t sin(theta), i.e. components (t, 0, -t) on (U_r, U_z, U_t).
The circumferential factor c_n makes the discrete work the true 3D work.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .assembly import UR, UT, UZ
from .domain import Domain
from .elements import circumferential_factor, dofs_per_node, lagrange_1d


def _full_vector(domain: Domain, mode: int) -> NDArray:
    return np.zeros(domain.mesh.n_nodes * dofs_per_node(mode))


def face_integrals(domain: Domain, z: float, r_in: float, r_out: float,
                   side: str = "below") -> tuple[NDArray, NDArray]:
    """Nodes and integrals of N r dr (m^2) over the annulus r_in < r < r_out of the face at
    depth z, using the cells below it (their top edges) or above it (their bottom edges).

    Returns (nodes (n_cells, p+1), weights (n_cells, p+1)); r_in and r_out must be cell lines.
    """
    m = domain.mesh
    p = m.order
    edge_z = m.cell_z0 if side == "below" else m.cell_z0 + m.cell_hz
    on_face = ((np.abs(edge_z - z) < 1e-12 * max(1.0, abs(z)) + 1e-15)
               & (m.cell_r0 >= r_in * (1 - 1e-12) - 1e-15)
               & (m.cell_r0 < r_out * (1 - 1e-12)))
    xg, wg = np.polynomial.legendre.leggauss(p + 2)
    L, _ = lagrange_1d(p, xg)
    r0, hr = m.cell_r0[on_face][:, None], m.cell_hr[on_face][:, None]
    r = r0 + 0.5 * (xg[None] + 1) * hr
    weights = np.einsum("eg,gi->ei", wg[None] * 0.5 * hr * r, L)
    first = 0 if side == "below" else p * (p + 1)  # local j = 0 (top edge) or j = p (bottom)
    return m.elements[on_face][:, first: first + p + 1], weights


def surface_traction(domain: Domain, mode: int, radius: float,
                     components: tuple[float, float, float], z: float = 0.0) -> NDArray:
    """Uniform traction (t_r, t_z, t_theta) in Pa on the disc r < radius of the face at depth z.

    Integrated exactly on the element edges of the face (radius must be a cell line).
    """
    nodes, weights = face_integrals(domain, z, 0.0, radius)
    nodal = weights * circumferential_factor(mode)
    f = _full_vector(domain, mode)
    ndpn = dofs_per_node(mode)
    for comp, t in zip((UR, UZ, UT), components, strict=True):
        if t and comp < ndpn:
            np.add.at(f, nodes.ravel() * ndpn + comp, t * nodal.ravel())
    return f


def axis_point_force(domain: Domain, mode: int, force: float, z: float = 0.0) -> NDArray:
    """A point force of ``force`` N on the axis at depth z: vertical (+z) for n = 0, horizontal
    (+x) for n = 1. The n = 1 axis tie U_t = -U_r makes the work Q U_r, so the load sits on U_r."""
    m = domain.mesh
    node = m.nodes_where(lambda r, zz: (r < 1e-12) & (np.abs(zz - z) < 1e-9))
    if node.size != 1:
        raise ValueError(f"no unique axis node at z = {z} m")
    f = _full_vector(domain, mode)
    f[node[0] * dofs_per_node(mode) + (UZ if mode == 0 else UR)] = force
    return f
