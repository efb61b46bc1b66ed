"""Element matrices formed column by column: a few small products per radial column instead of
batched products over every element.

On an axis-aligned rectangle whose stretch does not depend on z (no PML in z), the physical
derivative d/dz is (2 / h_z) d/deta and the measure is (h_z / 2) times a function of r, so with
the strain operator B = B_r + B_z / h_z every element operator of a radial column (same r0, h_r,
stretch) is exactly

    Z(h_z) = h_z P + Q + R / h_z

per unit material coefficient: stiffness per unit shear modulus and per unit bulk modulus (also
the B-bar volumetric part, whose pressure mass and coupling scale the same way), mass per unit
density (only P). P, Q and R of a column follow from the existing element routines
(:mod:`fem.elements`) evaluated on three probe heights and a 3 x 3 solve, so the element
formulation lives in one place. Each element is then one row of a (n, 9) x (9, nd^2) product.

Measured on the default forearm (1,378 Q9 elements in 53 columns, mode 1, PML in r):
see bench/fem/solver.py, stage "element matrices". Results agree with the element-by-element
path to rounding (tests/fem/test_columns.py checks 1e-11 relative).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from . import elements
from .mesh import Mesh

#: Probe heights of a column relative to its median element height: well conditioned
#: (the 3 x 3 system [h, 1, 1/h] has condition number about 6).
_PROBES = np.array([0.5, 1.0, 2.0])
#: Rows P, Q, R from the probe samples: the inverse of [h, 1, 1/h] at the probes.
_FIT = np.linalg.inv(np.column_stack([_PROBES, np.ones(_PROBES.size), 1.0 / _PROBES]))


def column_path(mesh: Mesh, stretch) -> NDArray:
    """(ne,) bool: elements whose stretch does not depend on z (outside any PML in z), which
    :func:`column_matrices` forms exactly."""
    z_start = getattr(stretch, "z_start", None) if stretch is not None else None
    if z_start is None:
        return np.ones(mesh.n_elements, dtype=bool)
    return mesh.cell_z0 + mesh.cell_hz <= z_start * (1 + 1e-12)


def column_matrices(mesh: Mesh, idx: NDArray, stretch, mode: int, coef: NDArray,
                    volumetric: str = "bbar") -> NDArray:
    """Element matrices of elements ``idx`` (all on :func:`column_path`) as a linear combination
    ``coef[:, 0] K_mu + coef[:, 1] K_kappa (+ coef[:, 2] M)`` of the stiffness per unit shear
    modulus, per unit bulk modulus (N/m per Pa) and, only when ``coef`` has a third column, the
    mass per unit density (no mass is formed otherwise).

    Args:
        idx: element indices (k,).
        stretch: the PML (r stretch only on these elements) or None; applied to the columns
            inside it (``stretch.contains``).
        coef: (k, 2) or (k, 3) shear modulus (Pa), bulk modulus (Pa) and the mass factor (e.g.
            -omega^2 rho in kg/(m^3 s^2)); complex for hysteretic moduli.

    Returns:
        (k, nd, nd) element matrices, complex if ``coef`` or the stretch is.
    """
    r0, hr, hz = mesh.cell_r0[idx], mesh.cell_hr[idx], mesh.cell_hz[idx]
    in_pml = (stretch.contains(r0, np.zeros_like(r0)) if stretch is not None
              else np.zeros(idx.size, dtype=bool))
    keys, col = np.unique(np.column_stack([r0, hr, in_pml]), axis=0, return_inverse=True)
    col = col.ravel()
    order = np.argsort(col, kind="stable")  # elements grouped by column
    bounds = np.searchsorted(col[order], np.arange(keys.shape[0] + 1))
    nd = mesh.elements.shape[1] * elements.dofs_per_node(mode)
    dtype = np.result_type(coef, complex if in_pml.any() else float)
    out = np.empty((idx.size, nd * nd), dtype=dtype)
    sorted_out = np.empty((idx.size, nd * nd), dtype=dtype)
    h_ref = np.array([np.median(hz[order[bounds[c]:bounds[c + 1]]])
                      for c in range(keys.shape[0])])
    h = hz[order] / h_ref[col[order]]
    powers = np.column_stack([h, np.ones_like(h), 1.0 / h])  # (k, 3): P, Q, R
    kinds = coef.shape[1]
    if kinds not in (2, 3):
        raise ValueError(f"coef has {kinds} columns: allowed 2 (stiffness) or 3 (and mass)")
    weights = (coef[order][:, :, None] * powers[:, None, :]).reshape(idx.size, 3 * kinds)
    for pml in (False, True):
        cols = np.flatnonzero(keys[:, 2] == pml)
        if cols.size == 0:
            continue
        basis = _column_basis(mesh, keys[cols, 0], keys[cols, 1], h_ref[cols],
                              stretch if pml else None, mode, volumetric, kinds == 3
                              ).astype(dtype)
        for j, c in enumerate(cols):
            at = slice(bounds[c], bounds[c + 1])
            np.matmul(weights[at], basis[j], out=sorted_out[at])  # (n, 6|9) x (6|9, nd^2)
    out[order] = sorted_out
    return out.reshape(idx.size, nd, nd)


def _column_basis(mesh: Mesh, r0: NDArray, hr: NDArray, h_ref: NDArray, stretch, mode: int,
                  volumetric: str, with_mass: bool) -> NDArray:
    """(nc, 3 kinds, nd^2): for each column and each of (K_mu, K_kappa[, M]) the P, Q, R of
    Z(h) = h' P + Q + R / h' with h' = h / h_ref."""
    nc, npr = r0.size, _PROBES.size
    cells = np.arange(nc * npr)
    hz = np.outer(h_ref, _PROBES).ravel()
    # probes span z in [-h, 0], above any PML in z, where the stretch in z is exactly 1
    probe = replace(mesh, cell_r0=np.repeat(r0, npr), cell_hr=np.repeat(hr, npr), cell_z0=-hz,
                    cell_hz=hz)
    g = elements.gauss_data(probe, stretch, subset=cells)
    one, zero = np.ones(cells.size), np.zeros(cells.size)
    parts = [elements.stiffness(g, mode, one, zero, volumetric),
             elements.stiffness(g, mode, zero, one, volumetric)]
    if with_mass:
        parts.append(elements.mass(g, mode, one))
    kinds = len(parts)
    samples = np.stack(parts, axis=1)  # (nc * 3 probes, kinds, nd, nd)
    pqr = _FIT @ samples.reshape(nc, npr, -1).transpose(1, 0, 2).reshape(npr, -1)
    return pqr.reshape(3, nc, kinds, -1).transpose(1, 2, 0, 3).reshape(nc, 3 * kinds, -1)
