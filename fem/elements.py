"""Fourier-mode axisymmetric Lagrange elements, vectorised over all elements at once.

For a body of revolution, a displacement field of circumferential order n in the symmetric set

    u_r = U_r(r, z) cos(n theta),  u_z = U_z(r, z) cos(n theta),  u_theta = U_t(r, z) sin(n theta)

decouples from every other order, so each mode is a 2D problem in (r, z). Strains (engineering
shear), after Smith, Griffiths & Margetts, Programming the Finite Element Method, Program 5.2:

    e_r = U_r,r    e_z = U_z,z    e_t = (U_r + n U_t) / r
    g_rz = U_r,z + U_z,r    g_zt = -n U_z / r + U_t,z    g_rt = -n U_r / r + U_t,r - U_t / r

Energies carry the circumferential integral c_n (2 pi for n = 0, pi for n >= 1), so the discrete
operators are the true 3D energies and point loads enter with their physical value.

Near incompressibility (tissue nu = 0.47, silicones 0.49 and above) locks plain full integration.
The volumetric energy is therefore integrated against a discontinuous pressure space of degree
p - 1 per element (Q1-P0 mean dilatation for p = 1, Q2-P1 for p = 2), i.e. B-bar (Hughes 1980),
which is exact for the dilatation that includes n U_t / r for n >= 1.

Absorbing layers are complex coordinate stretches (a PML): derivatives d/dr become
(1/s_r) d/dr, 1/r becomes 1/r~ and the measure r dr dz becomes r~ s_r s_z dr dz. With
s = 1 this is the plain element, so one code path serves both.

Node dofs are ordered (U_r, U_z) for n = 0 (torsion decouples and is not loaded) and
(U_r, U_z, U_t) for n >= 1. Element dof index = a * dofs_per_node + component.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .mesh import Mesh

#: A coordinate stretch: (r, z) arrays in m -> (s_r, s_z, r_tilde), complex or real arrays.
Stretch = Callable[[NDArray, NDArray], tuple[NDArray, NDArray, NDArray]]

_SQRT_I0 = np.sqrt(np.array([2.0, 2.0, 2.0, 1.0, 1.0, 1.0]))


def circumferential_factor(mode: int) -> float:
    """c_n: the integral of cos^2(n theta) over a full turn (2 pi for n = 0, pi otherwise)."""
    return 2.0 * np.pi if mode == 0 else np.pi


def dofs_per_node(mode: int) -> int:
    """2 for the axisymmetric mode (torsion is left out), 3 for n >= 1."""
    return 2 if mode == 0 else 3


def lagrange_1d(order: int, x: NDArray) -> tuple[NDArray, NDArray]:
    """Equispaced Lagrange basis on [-1, 1]: values and derivatives, each (len(x), order+1)."""
    nodes = np.linspace(-1.0, 1.0, order + 1)
    x = np.asarray(x, dtype=float)[:, None]
    vals = np.ones((x.shape[0], order + 1))
    ders = np.zeros((x.shape[0], order + 1))
    for i, xi in enumerate(nodes):
        others = np.delete(nodes, i)
        denom = np.prod(xi - others)
        terms = x - others[None, :]
        vals[:, i] = np.prod(terms, axis=1) / denom
        for k in range(others.size):
            ders[:, i] += np.prod(np.delete(terms, k, axis=1), axis=1) / denom
    return vals, ders


@dataclass(frozen=True)
class GaussData:
    """Shape data at the Gauss points of every element (index e = element, g = Gauss point).

    Attributes:
        N: (ng, nen) shape values.
        dN_dr, dN_dz: (ne, ng, nen) physical (stretched) derivatives, 1/m.
        inv_r: (ne, ng) 1 / r~, 1/m.
        weight: (ne, ng) w_g |J| r~ s_r s_z, m^3 per radian (no c_n).
        psi: (ng, npress) discontinuous pressure basis.
        r, z: (ne, ng) physical Gauss point coordinates, m.
    """

    N: NDArray
    dN_dr: NDArray
    dN_dz: NDArray
    inv_r: NDArray
    weight: NDArray
    psi: NDArray
    r: NDArray
    z: NDArray


def gauss_data(mesh: Mesh, stretch: Stretch | None = None, n_gauss: int | None = None,
               subset: NDArray | None = None) -> GaussData:
    """Evaluate shapes, derivatives and weights at tensor Gauss points of the elements
    (all, or the indices in ``subset``)."""
    p = mesh.order
    ng1 = n_gauss or p + 1
    xg, wg = np.polynomial.legendre.leggauss(ng1)
    L, dL = lagrange_1d(p, xg)
    # point g = gi + ng1 * gj ; node a = i + (p+1) * j
    N = np.einsum("gi,hj->hgji", L, L).reshape(ng1 * ng1, -1)
    dN_dxi = np.einsum("gi,hj->hgji", dL, L).reshape(ng1 * ng1, -1)
    dN_deta = np.einsum("gi,hj->hgji", L, dL).reshape(ng1 * ng1, -1)
    xi = np.tile(xg, ng1)
    eta = np.repeat(xg, ng1)
    w = np.tile(wg, ng1) * np.repeat(wg, ng1)

    sel = slice(None) if subset is None else subset
    hr, hz = mesh.cell_hr[sel, None], mesh.cell_hz[sel, None]
    r = mesh.cell_r0[sel, None] + 0.5 * (xi[None, :] + 1.0) * hr
    z = mesh.cell_z0[sel, None] + 0.5 * (eta[None, :] + 1.0) * hz
    if stretch is None:
        s_r = s_z = np.ones_like(r)
        r_t = r
    else:
        s_r, s_z, r_t = stretch(r, z)
    dN_dr = dN_dxi[None] * (2.0 / hr)[..., None] / s_r[..., None]
    dN_dz = dN_deta[None] * (2.0 / hz)[..., None] / s_z[..., None]
    weight = w[None] * 0.25 * hr * hz * r_t * s_r * s_z
    psi = np.column_stack([np.ones_like(xi), xi, eta])[:, : (1 if p == 1 else 3)]
    return GaussData(N, dN_dr, dN_dz, 1.0 / r_t, weight, psi, r, z)


def strain_operator(g: GaussData, mode: int) -> NDArray:
    """B: (ne, ng, 6, nen * dofs_per_node) engineering strains (e_r, e_z, e_t, g_rz, g_zt, g_rt)."""
    ne, ng, nen = g.dN_dr.shape
    ndpn = dofs_per_node(mode)
    dtype = np.result_type(g.dN_dr, g.inv_r)
    B = np.zeros((ne, ng, 6, nen, ndpn), dtype=dtype)
    n_over_r = g.N[None] * g.inv_r[..., None]
    B[:, :, 0, :, 0] = g.dN_dr
    B[:, :, 1, :, 1] = g.dN_dz
    B[:, :, 2, :, 0] = n_over_r
    B[:, :, 3, :, 0] = g.dN_dz
    B[:, :, 3, :, 1] = g.dN_dr
    B[:, :, 4, :, 1] = -mode * n_over_r
    B[:, :, 5, :, 0] = -mode * n_over_r
    if ndpn == 3:
        B[:, :, 2, :, 2] = mode * n_over_r
        B[:, :, 4, :, 2] = g.dN_dz
        B[:, :, 5, :, 2] = g.dN_dr - n_over_r
    return B.reshape(ne, ng, 6, nen * ndpn)


def _gram(A: NDArray, w: NDArray) -> NDArray:
    """Sum over Gauss points g and strain rows i of w_gi A_gi^T A_gi: A (ne, ng, k, nd) and
    w (ne, ng, k) -> (ne, nd, nd).

    Uses the transpose, not the conjugate: the operators are complex symmetric.
    """
    ne, ng, k, nd = A.shape
    flat = A.reshape(ne, ng * k, nd)
    return np.matmul(flat.transpose(0, 2, 1), flat * w.reshape(ne, ng * k, 1))


def stiffness(g: GaussData, mode: int, mu: NDArray, kappa: NDArray,
              volumetric: str = "bbar") -> NDArray:
    """Element stiffness matrices (ne, nd, nd) of Fourier mode ``mode``.

    Args:
        g: Gauss data of the elements.
        mode: circumferential order n.
        mu, kappa: (ne,) shear and bulk moduli in Pa (complex for hysteretic damping).
        volumetric: "bbar" (locking-free, projected dilatation) or "full" (plain full
            integration; locks for nu -> 1/2, kept to demonstrate exactly that).
    """
    c = circumferential_factor(mode)
    B = strain_operator(g, mode)
    div = B[:, :, 0] + B[:, :, 1] + B[:, :, 2]  # (ne, ng, nd)
    wmu = c * g.weight * mu[:, None]
    K = _gram(B, wmu[:, :, None] * _SQRT_I0[None, None, :] ** 2)
    K -= (2.0 / 3.0) * _gram(div[:, :, None, :], wmu[:, :, None])
    if volumetric == "full":
        cw = c * g.weight * kappa[:, None]
        return K + np.einsum("eg,ega,egb->eab", cw, div, div)
    if volumetric != "bbar":
        raise ValueError(f"volumetric = {volumetric!r}: allowed 'bbar' or 'full'")
    cw = c * g.weight
    Mp = np.einsum("eg,gp,gq->epq", cw, g.psi, g.psi)
    G = np.einsum("eg,gp,ega->epa", cw, g.psi, div)
    return K + kappa[:, None, None] * np.matmul(G.transpose(0, 2, 1), np.linalg.solve(Mp, G))


def mass(g: GaussData, mode: int, density: NDArray) -> NDArray:
    """Consistent element mass matrices (ne, nd, nd), density (ne,) in kg/m^3."""
    return weighted_mass(g, mode, np.broadcast_to(density[:, None], g.weight.shape))


def weighted_mass(g: GaussData, mode: int, coefficient: NDArray) -> NDArray:
    """Mass-like element matrices with a coefficient per Gauss point (ne, ng): the density
    (kg/m^3), or a graded damping layer's c(r, z) rho (kg/(m^3 s))."""
    c = circumferential_factor(mode)
    ndpn = dofs_per_node(mode)
    scalar = np.einsum("eg,ga,gb->eab", c * g.weight * coefficient, g.N, g.N)
    ne, nen, _ = scalar.shape
    M = np.zeros((ne, nen, ndpn, nen, ndpn), dtype=scalar.dtype)
    for comp in range(ndpn):  # the same scalar block on every displacement component
        M[:, :, comp, :, comp] = scalar
    return M.reshape(ne, nen * ndpn, nen * ndpn)
