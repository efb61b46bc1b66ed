"""A dataset's mesh plan: one mesh topology per discrete design (``mesh_topology = "per_design"``).

By default every sample is meshed by the size rules for its own values (``per_sample``): the
element sizes follow the shortest shear wavelength, and segment lengths (a layer thickness)
and the absorber's reach follow the parameters, so the number of cells in a segment changes in
steps as a continuous parameter moves. Each step is a small jump of the answer (the
discretisation error changes), and two samples of one design rarely share a sparsity pattern.

With ``per_design``, every sample of one discrete design (the values of its categorical,
integer and fixed parameters) gets the same cells per segment (``mesh.cells_r`` /
``mesh.cells_z`` of its scene): for each segment the most any point of the design's box
needs, found on the corners of the continuous parameters that move the mesh (the counts grow
monotonically with frequency, softness and segment length). The nodes then move with the
continuous values (``fem.mesh.fit_cells``), so the answers vary smoothly along them, and the
solver's per-topology work (scatter map, symbolic analysis) is shared by the whole design. The
cost is size: most samples get more cells than their own rules ask for
(``docs/solver-performance.md`` measures both sides).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np

from fem.problem import build_problem
from fem.scene import SceneError, scene_from_dict
from surrogate.data.errors import SpaceError
from surrogate.data.parameters import Parameter

__all__ = ["MAX_MESH_PARAMETERS", "MESH_TOPOLOGIES", "MeshPlan"]

MESH_TOPOLOGIES = ("per_sample", "per_design")
#: Most continuous parameters that may move the mesh of one design: its plan meshes every
#: corner of their box (2^12 = 4096 corners, about 15 s per design at ~3 ms each).
MAX_MESH_PARAMETERS = 12

Cells = tuple[tuple[int, ...], tuple[int, ...]]


class Space(Protocol):
    """What a plan reads of its space (:class:`surrogate.data.space.Space` is one; the space
    makes its plan, so this module names what it needs rather than importing it)."""

    parameters: tuple[Parameter, ...]

    def resolve(self, row: Mapping[str, Any]) -> dict[str, Any]: ...

    def _scene_error(self, err: Any, row: Mapping[str, Any]) -> SpaceError: ...


class MeshPlan:
    """Cells per segment along r and z for every discrete design of ``space``, computed on
    first use and kept (a plan depends on the space alone, so a resumed or extended dataset
    gets the same topologies)."""

    def __init__(self, space: Space) -> None:
        self.space = space
        self._cells: dict[tuple[Any, ...], Cells] = {}

    def design(self, row: Mapping[str, Any]) -> tuple[Any, ...]:
        """The discrete design of a row: its values of every non-continuous parameter."""
        return tuple(row[p.name] for p in self.space.parameters if p.type != "continuous")

    def cells(self, row: Mapping[str, Any]) -> Cells:
        """(cells_r, cells_z) of the design of ``row``."""
        key = self.design(row)
        if key not in self._cells:
            self._cells[key] = self._plan(row)
        return self._cells[key]

    def _domain(self, row: Mapping[str, Any]) -> Any:
        """The discretised body of ``row``'s scene without a plan (``fem.domain.Domain``)."""
        try:
            return build_problem(scene_from_dict(self.space.resolve(row))).domain
        except SceneError as err:
            raise self.space._scene_error(err, row) from None

    def _plan(self, row: Mapping[str, Any]) -> Cells:
        continuous = [p for p in self.space.parameters if p.type == "continuous"]
        # seen from the middle and from the two extreme corners, so that a parameter that
        # matters only where another one is extreme (a ring's density when it is the
        # softest part) is found; the points these probes share are meshed once
        domains: dict[tuple[Any, ...], Any] = {}

        def domain(point: Mapping[str, Any]) -> Any:
            key = tuple(point[p.name] for p in continuous)
            if key not in domains:
                domains[key] = self._domain(point)
            return domains[key]

        bases = [{**row, **{p.name: _ends(p)[i] for p in continuous}} for i in range(3)]
        centre = bases[0]
        moving = [p for p in continuous if any(_moves_mesh(domain, b, p) for b in bases)]
        if len(moving) > MAX_MESH_PARAMETERS:
            names = ", ".join(p.name for p in moving)
            raise SpaceError("space.mesh_topology", f"space.mesh_topology = 'per_design': "
                             f"{len(moving)} continuous parameters move the mesh ({names}); "
                             f"the plan meshes every corner of their box, allowed at most "
                             f"{MAX_MESH_PARAMETERS}: use mesh_topology = 'per_sample'")
        plans = [domain({**centre, **dict(zip([p.name for p in moving], corner,
                                              strict=True))}).cells_needed
                 for corner in itertools.product(*(_ends(p)[1:] for p in moving))]
        shapes = {(len(r), len(z)) for r, z in plans}
        if len(shapes) > 1:
            raise SpaceError("space.mesh_topology", f"space.mesh_topology = 'per_design': in "
                             f"design {self._label(row)} the mesh segments change between "
                             f"corners of the continuous parameters (segments along r, z: "
                             f"{sorted(shapes)}); a parameter moves one breakpoint across "
                             "another: use mesh_topology = 'per_sample'")
        return tuple(tuple(int(n) for n in np.max([plan[axis] for plan in plans], axis=0))
                     for axis in (0, 1))  # type: ignore[return-value]

    def _label(self, row: Mapping[str, Any]) -> str:
        return ", ".join(f"{p.name} = {row[p.name]!r}" for p in self.space.parameters
                         if p.type != "continuous")


def _moves_mesh(domain: Any, base: Mapping[str, Any], p: Parameter) -> bool:
    """Whether moving ``p`` from its low to its high end changes the mesh lines of ``base``
    (``domain`` meshes a point)."""
    low, high = (domain({**base, p.name: value}).mesh for value in _ends(p)[1:])
    return not (np.array_equal(low.r_lines, high.r_lines)
                and np.array_equal(low.z_lines, high.z_lines))


def _ends(p: Parameter) -> tuple[Any, Any, Any]:
    """(middle, low, high) of a continuous parameter, as the space samples them."""
    u = np.array([0.5, 0.0, 1.0])
    return tuple(float(v) for v in p.from_unit(u))  # type: ignore[return-value]
