"""Structured, graded r-z meshes of axis-aligned rectangles.

The domain is a tensor grid of cell lines in r (radius, from the axis outwards) and z (depth,
positive into the tissue, z = 0 at the skin surface). Every cell carries a material index, or -1
for void, so a haptic unit sitting on the skin (z < 0) is painted as rectangles onto the same
grid. Elements
are Lagrange quadrilaterals of order p (1: 4 nodes, 2: 9 nodes) whose nodes sit on the refined
tensor grid, so conformity across layer interfaces is by construction.

All lengths are in metres.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


def graded_lines(breaks: NDArray, size_at: callable, min_per_segment: int = 1) -> NDArray:
    """Cell lines through every breakpoint with local size close to ``size_at(x)``.

    Inside each segment the lines equidistribute the integral of 1/h, which grades the mesh
    smoothly without hand-tuned ratios.

    Args:
        breaks: sorted breakpoints (m) that must be cell lines (layer interfaces, load edges).
        size_at: target cell size (m) as a vectorised function of position.
        min_per_segment: minimum number of cells in every segment.
    """
    breaks = distinct_breaks(breaks)
    lines = [breaks[:1]]
    for a, b in itertools.pairwise(breaks):
        x = np.linspace(a, b, 257)
        density = 1.0 / size_at(x)
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(x))])
        n = max(min_per_segment, int(np.ceil(cum[-1] - 1e-9)))
        targets = np.linspace(0.0, cum[-1], n + 1)[1:]
        lines.append(np.interp(targets, cum, x))
        lines[-1][-1] = b
    return np.concatenate(lines)


def distinct_breaks(breaks: NDArray) -> NDArray:
    """Sorted breakpoints (m), those closer than the sliver tolerance counted once: breakpoints
    reached by different float paths (3.5 + 2 x 1 mm) must not make sliver cells."""
    breaks = np.unique(np.asarray(breaks, dtype=float))
    tol = 1e-9 * max(1.0, float(np.abs(breaks).max()))
    return breaks[np.concatenate([[True], np.diff(breaks) > tol])]


def growing_size(x0: float, h0: float, h1: float, growth: float = 0.2) -> callable:
    """Size function equal to h0 up to x0, then growing linearly (rate ``growth``) to h1."""

    def size_at(x: NDArray) -> NDArray:
        return np.minimum(h1, h0 + growth * np.maximum(0.0, np.asarray(x) - x0))

    return size_at


def geometric_extension(start: float, h0: float, h_max: float, length: float,
                        ratio: float = 1.25) -> NDArray:
    """Cell lines after ``start`` growing by ``ratio`` from h0 up to h_max, spanning ``length``.

    Returns the lines strictly after ``start`` (the last one at ``start + length``).
    """
    lines, x, h = [], start, h0
    end = start + length
    while x < end - 1e-12 * max(1.0, abs(end)):
        h = min(h * ratio, h_max)
        x = min(x + h, end)
        if end - x < 0.3 * h:  # avoid a sliver cell at the end
            x = end
        lines.append(x)
    return np.asarray(lines)


def refine_lines(lines: NDArray, order: int) -> NDArray:
    """Node coordinates along one direction: the cell lines plus order-1 interior points."""
    lines = np.asarray(lines, dtype=float)
    if order == 1:
        return lines.copy()
    frac = np.arange(order) / order
    inner = lines[:-1, None] + np.diff(lines)[:, None] * frac[None, :]
    return np.concatenate([inner.ravel(), lines[-1:]])


@dataclass(frozen=True)
class Mesh:
    """A structured mesh of order-p Lagrange rectangles.

    Attributes:
        nodes: (n_nodes, 2) node coordinates (r, z) in m.
        elements: (n_elements, (p+1)**2) node indices, local index a = i + (p+1) j with i along r
            and j along z (tensor-product ordering).
        order: polynomial order p.
        material: (n_elements,) material index of each element.
        cell_r0, cell_z0, cell_hr, cell_hz: (n_elements,) lower corner and size of each element.
        r_lines, z_lines: the cell lines of the underlying grid (m).
    """

    nodes: NDArray
    elements: NDArray
    order: int
    material: NDArray
    cell_r0: NDArray
    cell_z0: NDArray
    cell_hr: NDArray
    cell_hz: NDArray
    r_lines: NDArray
    z_lines: NDArray

    @property
    def n_nodes(self) -> int:
        return self.nodes.shape[0]

    @property
    def n_elements(self) -> int:
        return self.elements.shape[0]

    def nodes_where(self, mask_fn) -> NDArray:
        """Indices of nodes whose (r, z) satisfy a vectorised predicate."""
        return np.flatnonzero(mask_fn(self.nodes[:, 0], self.nodes[:, 1]))


def build_mesh(r_lines: NDArray, z_lines: NDArray, cell_material: NDArray, order: int) -> Mesh:
    """Build the element and node tables of a tensor grid with a material per cell.

    Args:
        r_lines: (nr+1,) increasing radial cell lines (m), starting at 0 for a solid body.
        z_lines: (nz+1,) increasing depth cell lines (m).
        cell_material: (nz, nr) material index per cell, -1 for void (no element).
        order: 1 or 2.
    """
    r_lines = np.asarray(r_lines, dtype=float)
    z_lines = np.asarray(z_lines, dtype=float)
    for name, lines in (("r_lines", r_lines), ("z_lines", z_lines)):
        widths = np.diff(lines)
        if widths.size == 0 or widths.min() <= 1e-9 * max(1.0, float(np.abs(lines).max())):
            raise ValueError(f"{name} must be strictly increasing without sliver cells")
    nr, nz = r_lines.size - 1, z_lines.size - 1
    if cell_material.shape != (nz, nr):
        raise ValueError(f"cell_material has shape {cell_material.shape}, expected {(nz, nr)}")
    rn, zn = refine_lines(r_lines, order), refine_lines(z_lines, order)
    n_r_nodes = rn.size

    jz, ir = np.nonzero(cell_material >= 0)
    local = np.arange(order + 1)
    # tensor index of local node (i, j) of cell (ir, jz): (p jz + j) * n_r_nodes + p ir + i
    gi = order * ir[:, None, None] + local[None, None, :]
    gj = order * jz[:, None, None] + local[None, :, None]
    tensor_ids = (gj * n_r_nodes + gi).reshape(ir.size, -1)

    used, elements = np.unique(tensor_ids, return_inverse=True)
    elements = elements.reshape(tensor_ids.shape)
    nodes = np.column_stack([rn[used % n_r_nodes], zn[used // n_r_nodes]])
    return Mesh(
        nodes=nodes,
        elements=elements,
        order=order,
        material=cell_material[jz, ir],
        cell_r0=r_lines[ir],
        cell_z0=z_lines[jz],
        cell_hr=np.diff(r_lines)[ir],
        cell_hz=np.diff(z_lines)[jz],
        r_lines=r_lines,
        z_lines=z_lines,
    )


def segment_cells(lines: NDArray, bounds: NDArray) -> NDArray:
    """Cells between consecutive ``bounds`` (sorted coordinates, m, each a cell line of
    ``lines``; breakpoints closer than the mesher's sliver tolerance count once)."""
    lines = np.asarray(lines, dtype=float)
    return np.diff(_bound_indices(lines, bounds))


def fit_cells(lines: NDArray, bounds: NDArray, cells: NDArray) -> NDArray:
    """``lines`` with exactly ``cells[i]`` cells between bounds i and i + 1.

    A segment keeps its own lines when its count is already ``cells[i]``; otherwise its lines
    are placed at equal steps of its cell index (the piecewise-linear map from index to
    position through the given lines), which keeps the grading of the given lines and, with
    more cells than given, never makes a cell larger than the largest given cell it overlaps.
    So a mesh
    topology fixed by ``cells`` moves its nodes smoothly with the breakpoints and the size
    rules, and equals the size rules' own mesh where it has the same counts.

    Args:
        lines: increasing cell lines (m) holding every bound.
        bounds: the segment ends (m), sorted.
        cells: cells per segment, at least 1 each.
    """
    lines = np.asarray(lines, dtype=float)
    at = _bound_indices(lines, bounds)
    cells = np.asarray(cells, dtype=int)
    if cells.shape != (at.size - 1,) or cells.min(initial=1) < 1:
        raise ValueError(f"need {at.size - 1} cell counts >= 1, got {cells.tolist()}")
    out = [lines[:1]]
    for (a, b), n in zip(itertools.pairwise(at), cells, strict=True):
        seg = lines[a:b + 1]
        if n == b - a:
            out.append(seg[1:])
            continue
        fitted = np.interp(np.arange(1, n + 1) * (b - a) / n, np.arange(b - a + 1), seg)
        fitted[-1] = seg[-1]
        out.append(fitted)
    return np.concatenate(out)


def _bound_indices(lines: NDArray, bounds: NDArray) -> NDArray:
    """Index of the line at each distinct bound (ValueError if a bound is not a line)."""
    bounds = distinct_breaks(bounds)
    tol = 1e-9 * max(1.0, float(np.abs(lines).max()))
    at = np.clip(np.searchsorted(lines, bounds - tol), 0, lines.size - 1)
    if not np.allclose(lines[at], bounds, rtol=0.0, atol=tol):
        raise ValueError("every segment bound must be a cell line")
    return at
