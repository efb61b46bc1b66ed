"""The discretised body: mesh, materials per element, absorbers and boundary conditions.

This layer knows SI quantities only; ``fem.problem`` translates a scene into it. A domain is the
layered tissue (top to bottom, z = 0 at the skin surface, z positive into the body) out to a
radius R, optionally with rectangles painted above the skin (a haptic unit), and whatever the
outer side and base need (``fem.absorbers``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from fieldspec import FieldError

from . import absorbers
from .assembly import UR, UT, UZ
from .materials import Material
from .mesh import Mesh, build_mesh, fit_cells, graded_lines, growing_size, segment_cells

SIDES = ("absorbing", "fixed", "free")
# assembly name -> Material attribute (the names the element routines use)
_ELEMENT_PROPERTIES = {"mu": "mu_Pa", "kappa": "bulk_Pa", "density": "density_kg_m3",
                       "loss_factor": "loss_factor"}
BASES = ("fixed", "absorbing", "free")


@dataclass(frozen=True)
class Block:
    """A rectangle of material painted onto the grid (r0..r1, z0..z1 in m; z < 0 is above the
    skin)."""

    r0: float
    r1: float
    z0: float
    z1: float
    solid: Material


@dataclass(frozen=True)
class MeshSpec:
    """Element sizes (m) and order: ``near_size`` within ``near_radius`` of the axis (and near the
    surface), growing to ``far_size``. ``cells_r`` / ``cells_z``, when given, fix the number of
    cells in every segment along r / z (see :attr:`Domain.cells_needed`): the topology is then
    the same for every body with the same segments, and the sizes place the nodes."""

    near_size: float = 0.5e-3
    near_radius: float = 8e-3
    far_size: float = 2e-3
    order: int = 2
    growth: float = 0.2
    cells_r: tuple[int, ...] | None = None
    cells_z: tuple[int, ...] | None = None


class CellPlanError(FieldError):
    """Fixed cell counts that do not fit the body: ``axis`` is "r" or "z" (``field`` is
    ``cells_r`` or ``cells_z``)."""

    def __init__(self, axis: str, message: str) -> None:
        super().__init__(f"cells_{axis}", message)
        self.axis = axis


@dataclass(frozen=True)
class Domain:
    """A meshed body ready for assembly.

    Attributes:
        mesh: the mesh (tissue, unit blocks, absorbing regions).
        solids: material of each material index.
        radius: physical radius R of the tissue model (m).
        depth: total tissue thickness (m).
        side, base: boundary treatments asked for.
        stretch: PML stretch (harmonic with absorbing boundaries) or None.
        damping: graded damping layer (transient absorber) or None.
        constraints: (nodes, component) pairs held at zero; a fixed boundary lists its nodes
            for every component, a roller only the normal one.
        ties: (follower nodes, leader nodes, component) pairs with equal displacement.
        effects: physical effects the discretisation includes, for the summary.
        skipped: effects left out because the scene does not need them.
        cells_needed: cells per segment along r and along z that the size rules give (the
            mesh has these, or the counts of ``MeshSpec.cells_r`` / ``cells_z``). Segments
            run between the axis, the load and unit radii, ``near_radius``, the tissue radius
            and the end of the side absorber (r); and between the top of the unit, its part
            boundaries, the skin, the layer interfaces, the tissue base and the end of the
            base absorber (z); breakpoints that coincide count once.
    """

    mesh: Mesh
    solids: tuple[Material, ...]
    radius: float
    depth: float
    side: str
    base: str
    stretch: absorbers.PML | None = None
    damping: absorbers.DampingLayer | None = None
    constraints: tuple[tuple[NDArray, int], ...] = ()
    ties: tuple[tuple[NDArray, NDArray, int], ...] = ()
    effects: tuple[str, ...] = ()
    skipped: tuple[str, ...] = ()
    cells_needed: tuple[tuple[int, ...], tuple[int, ...]] = ((), ())

    def element_property(self, name: str) -> NDArray:
        """Per-element array of a material property by its assembly name: "mu" (shear modulus,
        Pa), "kappa" (bulk modulus, Pa), "density" (kg/m3) or "loss_factor" (-)."""
        attribute = _ELEMENT_PROPERTIES[name]
        values = np.array([getattr(s, attribute) for s in self.solids])
        return values[self.mesh.material]

    def fixed(self) -> list[tuple[NDArray, int]]:
        """Homogeneous constraints as (nodes, component) pairs for ``build_dofmap``."""
        return list(self.constraints)

    def boundary_nodes(self, where: str) -> NDArray:
        """Nodes on the outermost "side" (largest r) or "base" (largest z) of the mesh."""
        nodes = self.mesh.nodes
        if where == "side":
            at_end = np.isclose(nodes[:, 0], self.mesh.r_lines[-1])
            return np.flatnonzero(at_end & (nodes[:, 1] >= 0))
        if where == "base":
            return np.flatnonzero(np.isclose(nodes[:, 1], self.mesh.z_lines[-1]))
        raise ValueError(f"where = {where!r}: allowed 'side' or 'base'")

    def surface_nodes(self) -> NDArray:
        """Nodes on the skin surface z = 0 inside the physical radius, sorted by r."""
        m = self.mesh
        idx = m.nodes_where(lambda r, z: (np.abs(z) < 1e-12) & (r <= self.radius * (1 + 1e-12)))
        return idx[np.argsort(m.nodes[idx, 0])]


def layered_domain(layers: Sequence[tuple[float, Material]], radius: float, side: str, base: str,
                   spec: MeshSpec, analysis: str, omega: float = 0.0,
                   r_breaks: Sequence[float] = (), blocks: Sequence[Block] = (),
                   damping_rate: float | None = None, z_breaks: Sequence[float] = (),
                   absorber_omega: float | None = None) -> Domain:
    """Mesh layered tissue (top to bottom: (thickness m, Material)) with the treatments asked for.

    Args:
        radius: physical radius R (m).
        side: "absorbing" | "fixed" | "free" outer radial boundary.
        base: "fixed" | "absorbing" | "free" bottom boundary.
        spec: element sizes and order.
        analysis: "static" | "harmonic" | "transient" (decides the absorber).
        omega: angular frequency (rad/s) the elements are sized for (the shortest wavelength)
            and the absorbers are tuned for.
        absorber_omega: angular frequency (rad/s) whose wavelength sets the absorbers' extent
            (default ``omega``); a sweep passes its lowest, so that one mesh serves the band.
        r_breaks: radii (m) that must be cell lines (load edges, unit radii).
        z_breaks: depths (m, negative) above the skin that must be cell lines (rotor plane).
        blocks: rectangles above the skin (z < 0) or replacing tissue.
        damping_rate: peak rate (1/s) of the transient damping layer
            (default ``absorbers.DAMPING_LAYER_RATE`` x omega).
    """
    if side not in SIDES or base not in BASES:
        raise ValueError(f"side must be one of {SIDES} and base one of {BASES}")
    thick = np.array([t for t, _ in layers])
    tissue = [s for _, s in layers]
    depth = float(thick.sum())
    size_r = growing_size(spec.near_radius, spec.near_size, spec.far_size, spec.growth)
    size_z = growing_size(0.0, spec.near_size, spec.far_size, spec.growth)
    min_cells = 2 if spec.order == 1 else 1

    r_pts = [0.0, radius, *(b for b in r_breaks if 0 < b < radius)]
    if spec.near_radius < radius:
        r_pts.append(spec.near_radius)
    for b in blocks:
        r_pts += [b.r0, b.r1]
    r_lines = graded_lines(np.array(r_pts), size_r, min_cells)
    z_iface = np.concatenate([[0.0], np.cumsum(thick)])
    z_lines = graded_lines(z_iface, size_z, min_cells)

    effects, skipped = [], []
    c_s = np.array([s.shear_speed_m_s for s in tissue])
    wave = analysis != "static"
    lam_min = float(c_s.min()) * 2 * np.pi / omega if wave else np.inf
    h_wave = lam_min * spec.order / absorbers.ELEMENTS_PER_WAVELENGTH
    lam_ref = (absorbers.reference_speed(c_s) * 2 * np.pi / (absorber_omega or omega) if wave
               else np.inf)

    def beyond(end: float, lines: NDArray, size: float, kind: str) -> absorbers.AxisLayout:
        h_last = float(lines[-1] - lines[-2])
        if analysis == "static":
            effects.append(f"static far field ({kind})")
            return absorbers.static_extension(end, h_last, size)
        harmonic = analysis == "harmonic"
        effects.append(f"{'PML' if harmonic else 'damping layer'} ({kind})")
        return absorbers.pml_layout(end, h_last, size, lam_ref, min(h_wave, 4 * spec.far_size),
                                    1.0 if harmonic else absorbers.DAMPING_LAYER_WAVELENGTHS)

    r_lay = beyond(radius, r_lines, radius, "side") if side == "absorbing" else None
    z_lay = beyond(depth, z_lines, max(depth, radius), "base") if base == "absorbing" else None
    if r_lay is not None:
        r_lines = np.concatenate([r_lines, r_lay.lines])
    if z_lay is not None:
        z_lines = np.concatenate([z_lines, z_lay.lines])
    z_above: list[float] = []
    if blocks:
        z_top = min(b.z0 for b in blocks)
        z_above = sorted({b.z0 for b in blocks} | {b.z1 for b in blocks if b.z1 < 0} | {z_top}
                         | {z for z in z_breaks if z_top <= z < 0})
        above = graded_lines(np.array([*z_above, 0.0]), lambda x: np.full_like(x, spec.near_size),
                             min_cells)
        z_lines = np.concatenate([above[:-1], z_lines])
    # the absorbers (extension and layer) form one segment: its count is what the wave needs
    r_bounds = np.array([*r_pts, r_lines[-1]])
    z_bounds = np.array([*z_above, *z_iface, z_lines[-1]])
    needed = (tuple(segment_cells(r_lines, r_bounds).tolist()),
              tuple(segment_cells(z_lines, z_bounds).tolist()))
    r_lines = _fixed_cells(r_lines, r_bounds, spec.cells_r, needed[0], "r")
    z_lines = _fixed_cells(z_lines, z_bounds, spec.cells_z, needed[1], "z")

    solids, cell = _paint(r_lines, z_lines, z_iface, tissue, blocks)
    mesh = build_mesh(r_lines, z_lines, cell, spec.order)

    stretch = damping = None
    pml_r = r_lay.pml_start if r_lay else None
    pml_z = z_lay.pml_start if z_lay else None
    if analysis == "harmonic" and (pml_r is not None or pml_z is not None):
        stretch = absorbers.PML(omega, absorbers.reference_speed(c_s), pml_r,
                                r_lay.pml_thickness if r_lay else 0.0, pml_z,
                                z_lay.pml_thickness if z_lay else 0.0)
    if analysis == "transient" and (pml_r is not None or pml_z is not None):
        rate = damping_rate or absorbers.DAMPING_LAYER_RATE * omega
        damping = absorbers.DampingLayer(rate, pml_r,
                                         r_lay.pml_thickness if r_lay else 0.0, pml_z,
                                         z_lay.pml_thickness if z_lay else 0.0)

    for name, on in (("fixed side", side == "fixed"), ("fixed base", base == "fixed")):
        (effects if on else skipped).append(name)
    if side != "absorbing" and base != "absorbing":
        skipped.append("absorbing boundary")
    domain = Domain(mesh, solids, radius, depth, side, base, stretch, damping, (), (),
                    tuple(effects), tuple(skipped), needed)
    held = [domain.boundary_nodes(w) for w, kind in (("side", side), ("base", base))
            if kind in ("absorbing", "fixed")]
    nodes = np.unique(np.concatenate(held)) if held else np.empty(0, dtype=int)
    return replace(domain, constraints=tuple((nodes, c) for c in (UR, UZ, UT)))


def _fixed_cells(lines: NDArray, bounds: NDArray, cells: Sequence[int] | None,
                 needed: tuple[int, ...], axis: str) -> NDArray:
    """``lines`` refitted to the fixed counts ``cells`` (None: as they are), which must match
    the segments and give each at least the cells the size rules need."""
    if cells is None:
        return lines
    if len(cells) != len(needed):
        raise CellPlanError(axis, f"{len(cells)} cell counts along {axis} for a body with "
                            f"{len(needed)} segments along {axis} (it needs at least "
                            f"{list(needed)})")
    short = [i for i, (n, m) in enumerate(zip(cells, needed, strict=True)) if n < m]
    if short:
        i = short[0]
        raise CellPlanError(axis, f"segment {i} along {axis} gets {cells[i]} cells where the "
                            f"element sizes need at least {needed[i]} (all segments need at "
                            f"least {list(needed)})")
    return fit_cells(lines, bounds, np.asarray(cells))


def _paint(r_lines: NDArray, z_lines: NDArray, z_iface: NDArray, tissue: list[Material],
           blocks: Sequence[Block]) -> tuple[tuple[Material, ...], NDArray]:
    """Material index per cell: tissue layers by depth (the last layer continues into a base
    absorber), then blocks painted on top in order; cells above the skin not covered are void."""
    rc = 0.5 * (r_lines[1:] + r_lines[:-1])
    zc = 0.5 * (z_lines[1:] + z_lines[:-1])
    layer = np.clip(np.searchsorted(z_iface, zc, side="right") - 1, 0, len(tissue) - 1)
    cell = np.where(zc[:, None] > 0, layer[:, None], -1) * np.ones((1, rc.size), dtype=int)
    solids = list(tissue)
    for b in blocks:
        inside = ((zc[:, None] > b.z0) & (zc[:, None] < b.z1)
                  & (rc[None, :] > b.r0) & (rc[None, :] < b.r1))
        solids.append(b.solid)
        cell[inside] = len(solids) - 1
    return tuple(solids), cell
