"""Sampling solutions on the skin surface, and writing the field for ParaView (VTK); the JSON
document is :mod:`fem.output`, the PNG :mod:`fem.plots`.

Amplitudes are the Fourier amplitudes of the solved mode: U_r and U_z multiply cos(n theta) (the
theta = 0 meridian), U_t multiplies sin(n theta) (its value at theta = 90 deg for n = 1). The
displacement magnitude is sqrt(|U_r|^2 + |U_t|^2 + |U_z|^2): for n = 0 the exact amplitude, for a
rotating n = 1 load (an ERM) the theta-independent amplitude, and for a one-directional n = 1 load
sqrt(2) times the RMS over theta.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .domain import Domain
from .elements import lagrange_1d


def surface_stencil(domain: Domain, radii: NDArray, z: float = 0.0,
                    side: str = "below") -> tuple[NDArray, NDArray]:
    """Nodes (k, p+1) and weights (k, p+1) that interpolate nodal values at ``radii`` (m) on the
    face at depth z, with the shape functions of the edges of the cells just below (or above)
    it: the accuracy of the discretisation."""
    m = domain.mesh
    p = m.order
    radii = np.asarray(radii, dtype=float)
    edge_z = m.cell_z0 if side == "below" else m.cell_z0 + m.cell_hz
    row = np.flatnonzero(np.abs(edge_z - z) < 1e-12 + 1e-9 * abs(z))
    row = row[np.argsort(m.cell_r0[row])]
    r0, hr = m.cell_r0[row], m.cell_hr[row]
    k = np.clip(np.searchsorted(r0, radii, side="right") - 1, 0, row.size - 1)
    xi = 2.0 * (radii - r0[k]) / hr[k] - 1.0
    if np.any(np.abs(xi) > 1 + 1e-9):
        raise ValueError("a probe radius lies outside the meshed surface")
    L, _ = lagrange_1d(p, xi)
    first = 0 if side == "below" else p * (p + 1)
    return m.elements[row[k]][:, first: first + p + 1], L


def interpolate(stencil: tuple[NDArray, NDArray], nodal: NDArray) -> NDArray:
    """Values (k, 3) at the stencil's points from nodal (n_nodes, 3) amplitudes."""
    nodes, weights = stencil
    return np.einsum("ki,kic->kc", weights, nodal[nodes])


def magnitude(U: NDArray) -> NDArray:
    """sqrt(|U_r|^2 + |U_z|^2 + |U_t|^2) of (..., 3) complex amplitudes (see module doc)."""
    return np.sqrt(np.sum(np.abs(U) ** 2, axis=-1))


def complex_um(values: NDArray) -> dict[str, list[float]]:
    """A complex array in m as {"re": [...], "im": [...]} in micrometres."""
    v = np.asarray(values) * 1e6
    return {"re": np.real(v).tolist(), "im": np.imag(v).tolist()}


_VTK_ORDER = {1: [0, 1, 3, 2], 2: [0, 2, 8, 6, 1, 5, 7, 3, 4]}
_VTK_TYPE = {1: "quad", 2: "quad9"}


def write_vtk(path: str, domain: Domain, nodal: NDArray) -> None:
    """Write the (r, z) field for ParaView: coordinates in mm, displacements in um, real and
    imaginary parts of each Fourier amplitude, the magnitude, and the material per cell."""
    # optional: only the VTU export needs it
    import meshio

    m = domain.mesh
    points = np.column_stack([m.nodes * 1e3, np.zeros(m.n_nodes)])
    cells = [(_VTK_TYPE[m.order], m.elements[:, _VTK_ORDER[m.order]])]
    U = nodal * 1e6
    data = {f"{name}_um_{part}": getattr(U[:, c], part)
            for c, name in enumerate(("ur", "uz", "ut")) for part in ("real", "imag")}
    data["magnitude_um"] = magnitude(U)
    meshio.write(path, meshio.Mesh(points, cells, point_data=data,
                                   cell_data={"material": [m.material.astype(np.int32)]}))
