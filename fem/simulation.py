"""From a validated scene to a solved, sampled result: the one entry point users call.

The scene decides what is built. A normal load solves Fourier mode 0 only, a tangential one
mode 1 only; a static analysis assembles no mass; fixed or free boundaries add no absorber;
without loss factors no complex moduli are formed. ``SimulationResult.meta`` lists what was
included and what was skipped.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from . import SOLVER_VERSION, probes, results, transient_analysis
from .cost import DEFAULT_MAX_UNKNOWNS, check_cost
from .domain import Domain
from .haptic_unit import pin_contact_check
from .output import result_document
from .problem import (
    build_problem,
    drive_omega,
    resolution_warning,
)
from .scene import Scene
from .solve import OperatorLog, solve_mode
from .sweep import SweepResult, sweep


@dataclass(frozen=True)
class SimulationResult:
    """Surface response of one scene.

    Attributes:
        scene: the scene solved.
        r_mm: probe radii (mm).
        U: (n_probe, 3) complex Fourier amplitudes (U_r, U_z, U_t) in m at the probe radii.
        edge_mm: radius of the load footprint's edge (mm), None for a point force.
        center: (3,) amplitudes at the centre (m): r = 0 on the unit's skin-side face, depth
            ``centre_z_mm`` (the skin itself when glued or without a unit); edge: on the skin
            at edge_mm; profile: (n_profile, 3).
        profile_mm: distances from the edge of the profile samples (mm).
        meta: dofs, elements, modes, effects, skipped effects, operators built, wall time.
        domain, nodal: the discretisation and nodal amplitudes, for VTK export and plots.
    """

    scene: Scene
    r_mm: NDArray
    U: NDArray
    edge_mm: float | None
    center: NDArray
    edge: NDArray
    profile_mm: NDArray
    profile: NDArray
    meta: dict
    domain: Domain = field(repr=False)
    nodal: NDArray | None = field(repr=False)
    histories: transient_analysis.Histories | None = field(default=None, repr=False)
    extras: dict = field(default_factory=dict)
    centre_z_mm: float = 0.0

    @property
    def center_amplitude_um(self) -> float | None:
        return None if self.edge_mm is None else float(results.magnitude(self.center) * 1e6)

    @property
    def edge_amplitude_um(self) -> float | None:
        return None if self.edge_mm is None else float(results.magnitude(self.edge) * 1e6)

    @property
    def normalized_edge(self) -> float | None:
        if self.edge_mm is None:
            return None
        return self.edge_amplitude_um / self.center_amplitude_um

    def to_dict(self, scene_name: str | None = None) -> dict:
        """The self-describing JSON document, schema version 1 (:mod:`fem.output`,
        docs/output-schema.md)."""
        return result_document(self, scene_name)

    def to_dict_v0(self) -> dict:
        """The unversioned layout written before schema version 1 (kept for one release)."""
        out = {
            "surface": {
                "r_mm": self.r_mm.tolist(),
                "ur_um": results.complex_um(self.U[:, 0]),
                "ut_um": results.complex_um(self.U[:, 2]),
                "uz_um": results.complex_um(self.U[:, 1]),
                "magnitude_um": (results.magnitude(self.U) * 1e6).tolist(),
            },
            "center_amplitude_um": self.center_amplitude_um,
            "edge_amplitude_um": self.edge_amplitude_um,
            "normalized_edge": self.normalized_edge,
            "profile": {
                "distance_from_edge_mm": self.profile_mm.tolist(),
                "uz_um": (np.abs(self.profile[:, 1]) * 1e6).tolist(),
                "magnitude_um": (results.magnitude(self.profile) * 1e6).tolist(),
            },
            "meta": dict(self.meta),
        }
        out.update(self.extras)
        if self.histories is not None:
            h = self.histories
            out["histories"] = {"t_s": h.t.tolist(), "points": [
                {"r_mm": float(r * 1e3),
                 **{f"{c}_um": (h.u[:, i, k] * 1e6).tolist()
                    for k, c in enumerate(("ur", "uz", "ut"))},
                 "magnitude_um": (np.linalg.norm(h.u[:, i], axis=-1) * 1e6).tolist()}
                for i, r in enumerate(h.radii[: self.r_mm.size])]}
        return out

    def surface_curve(self) -> tuple[NDArray, NDArray]:
        """Radii (mm) and amplitudes (n, 3) in m along the skin surface: every surface node of a
        steady solve, the probes and profile of a transient (peak amplitudes)."""
        if self.nodal is None:
            r = np.concatenate([self.r_mm, self.profile_mm + (self.edge_mm or 0.0)])
            order = np.argsort(r)
            return r[order], np.concatenate([self.U, self.profile])[order]
        nodes = self.domain.surface_nodes()
        return self.domain.mesh.nodes[nodes, 0] * 1e3, self.nodal[nodes]

    def summary(self, scene_name: str | None = None) -> str:
        """A short human-readable report that defines what it prints."""
        m = self.meta
        kind = self.scene.analysis.kind
        what = {"harmonic": "|U| = modulus of the complex Fourier amplitude",
                "static": "|u| = static displacement",
                "transient": "|u| = peak over the run"}[kind]
        freq = ("" if kind == "static" else f" at {m['frequency_hz']:g} Hz" if kind == "harmonic"
                else f" (drive frequency {m['frequency_hz']:g} Hz)")
        lines = [
            f"hapticrom {SOLVER_VERSION}: {kind} analysis{freq}"
            + (f" of {scene_name}" if scene_name else ""),
            f"  elements {m['elements']}, dofs {m['dofs']}, order {self.scene.mesh.order}, "
            f"Fourier modes {m['modes']}, wall time {m['wall_s'] * 1e3:.1f} ms",
            f"  included: {', '.join(m['effects']) or 'none'}",
            f"  skipped:  {', '.join(m['skipped']) or 'none'}",
        ]
        lines += [f"  skin surface (z = 0) on the theta = 0 meridian; {what}; "
                  "magn. = sqrt(|u_r|^2 + |u_z|^2 + |u_t|^2)",
                  f"  {'r (mm)':>8} {'|u_r| um':>11} {'|u_z| um':>11} {'|u_t| um':>11} "
                  f"{'magn. um':>11}"]
        mag = results.magnitude(self.U)
        for r, u, a in zip(self.r_mm, self.U, mag, strict=True):
            lines.append(f"  {r:8.2f} {abs(u[0]) * 1e6:11.4g} {abs(u[1]) * 1e6:11.4g} "
                         f"{abs(u[2]) * 1e6:11.4g} {a * 1e6:11.4g}")
        if self.edge_mm is not None:
            face = ("the unit's skin-side face at r = 0, z = "
                    f"{self.centre_z_mm:g} mm; the r = 0 row of the table is the skin under it"
                    if self.centre_z_mm != 0.0 else "the skin at r = 0")
            lines.append(f"  centre magn. {self.center_amplitude_um:.4g} um ({face})")
            lines.append(f"  edge magn. {self.edge_amplitude_um:.4g} um (skin at the footprint "
                         f"edge, r = {self.edge_mm:g} mm); normalized edge = edge / centre = "
                         f"{self.normalized_edge:.3f}")
        if self.histories is not None:
            lines.append(f"  transient: {self.histories.t.size} recorded steps; every amplitude "
                         "is the peak over the run, magn. the magnitude of the peaks")
        for key, value in self.extras.items():
            lines.append(f"  {key}: {value}")
        lines += [f"  warning: {w}" for w in m.get("warnings", [])]
        return "\n".join(lines)


def simulate(scene: Scene, *, max_unknowns: float = DEFAULT_MAX_UNKNOWNS,
             progress: Callable[[int, int], None] | None = None
             ) -> SimulationResult | SweepResult:
    """Solve a scene and sample the skin surface (a sweep scene: at every frequency of its
    band, :func:`fem.sweep.sweep`).

    ``progress(done, total)`` is called with time steps done and the total during a transient
    (a few hundred times per run; never for a steady solve).

    The size is estimated first (:func:`fem.cost.check_cost`): a scene above ``max_unknowns``
    is refused with a :class:`fem.scene.SceneError` naming the fields that drive its size,
    before anything is allocated. Pass a larger ``max_unknowns`` (``math.inf``) to run it."""
    if scene.analysis.kind == "sweep":
        return sweep(scene, max_unknowns=max_unknowns)
    t0 = time.perf_counter()
    check_cost(scene, max_unknowns)
    problem = build_problem(scene)
    log = OperatorLog()
    edge = problem.edge
    pts = probes.output_points(scene, problem)
    r_probe, prof_mm, cut, radii, stencil = (pts.r_probe, pts.profile_mm, pts.cut, pts.radii,
                                             pts.stencil)
    histories, extras = None, {}
    if scene.analysis.kind == "transient":
        histories = transient_analysis.run(scene, problem, stencil, radii, log, progress)
        vals = histories.amplitude().astype(complex)
        nodal, n_dofs = None, histories.n_dofs
    else:
        sol = solve_mode(problem.domain, problem.mode, problem.load, problem.omega, log,
                         extra=problem.extra)
        nodal, n_dofs = sol.nodal(), sol.n_dofs
        vals = results.interpolate(stencil, nodal)
        if problem.effects["preload"]:
            extras["preload"] = pin_contact_check(problem.domain, problem.mode,
                                                  problem.layout.pins, problem.unit.pogo,
                                                  sol.u_full)
    wall = time.perf_counter() - t0
    included, skipped = problem.effect_lists()
    meta = {
        "dofs": n_dofs, "elements": problem.domain.mesh.n_elements, "modes": [problem.mode],
        "effects": included, "skipped": skipped, "operators": log.built, "wall_s": wall,
        "time_convention": "exp(+i omega t)", "solver_version": SOLVER_VERSION,
        "frequency_hz": None if scene.analysis.kind == "static"
        else round(float(drive_omega(scene) / (2 * np.pi)), 9),
    }
    warnings = [w for w in (resolution_warning(scene, problem), cut) if w]
    if warnings:
        meta["warnings"] = warnings
    n = r_probe.size
    edge_mm = None if edge is None else edge * 1e3
    centre_z_mm = 0.0 if problem.layout is None else float(problem.layout.contact_z * 1e3)
    return SimulationResult(scene, r_probe * 1e3, vals[:n], edge_mm, vals[n], vals[n + 1],
                            prof_mm, vals[n + 2:], meta, problem.domain, nodal, histories, extras,
                            centre_z_mm)
