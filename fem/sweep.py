"""Frequency sweep analysis: the complex response of one scene at every frequency of a band,
from a reduced-order model built on one mesh (``fem.sweep_rom``), with its error estimate and
the number of full solves it took.

The mesh is sized for the band's highest frequency (the shortest wavelength) and its absorbers
for the lowest (the longest), so one mesh serves the band. :func:`direct_sweep` solves the same
mesh once per frequency with the exact PML of that frequency: the reference the reduced model
is verified against (tests/fem/test_sweep.py) and measured against (bench/fem/sweep.py).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from . import SOLVER_VERSION, linalg, probes, results
from .cost import DEFAULT_MAX_UNKNOWNS, check_cost
from .problem import Problem, build_problem, resolution_warning
from .scene import Scene
from .solve import OperatorLog, solve_mode
from .sweep_operator import CHEBYSHEV_NODES, SweepOperator
from .sweep_output import sweep_document, sweep_summary
from .sweep_rom import KRYLOV_DEPTH, MAX_EXPANSIONS, greedy_model


@dataclass(frozen=True)
class SweepResult:
    """Surface response of one scene over a band.

    Attributes:
        scene: the scene solved.
        frequency_hz: (n_f,) the band.
        r_mm: (n_probe,) probe radii (mm); U: (n_f, n_probe, 3) complex (U_r, U_z, U_t) in m.
        edge_mm: radius of the load footprint's edge (mm), None for a point force.
        center, edge: (n_f, 3) complex amplitudes (m) at the centre (the unit's skin-side face
            at r = 0, depth ``centre_z_mm``) and on the skin at the edge.
        profile_mm: (n_p,) distances from the edge (mm); profile: (n_f, n_p, 3) complex (m).
        error_estimate: estimated largest relative error of centre, edge and profile over the
            band (see ``fem.sweep_rom``); tolerance: the one asked for.
        full_solves: factorisations of the full operator the model took.
        meta: mesh size, effects, expansion frequencies, back-solves, wall time, ...
    """

    scene: Scene
    frequency_hz: NDArray
    r_mm: NDArray
    U: NDArray
    edge_mm: float | None
    center: NDArray
    edge: NDArray
    profile_mm: NDArray
    profile: NDArray
    error_estimate: float
    tolerance: float
    full_solves: int
    meta: dict = field(default_factory=dict)
    centre_z_mm: float = 0.0

    @property
    def center_amplitude_um(self) -> NDArray | None:
        """(n_f,) magnitude of the centre amplitude (um), None for a point force."""
        return None if self.edge_mm is None else results.magnitude(self.center) * 1e6

    @property
    def edge_amplitude_um(self) -> NDArray | None:
        """(n_f,) magnitude of the edge amplitude (um), None for a point force."""
        return None if self.edge_mm is None else results.magnitude(self.edge) * 1e6

    def to_dict(self, scene_name: str | None = None) -> dict:
        """The versioned JSON document ``hapticrom.simulate.sweep`` (docs/output-schema.md)."""
        return sweep_document(self, scene_name)

    def summary(self, scene_name: str | None = None) -> str:
        """A short human-readable report (what it prints is defined in it)."""
        return sweep_summary(self, scene_name)


@dataclass(frozen=True)
class SweepSetup:
    """One sweep's discretisation: the problem, its operator over the band, the sampled
    points and the load scale per frequency."""

    scene: Scene
    problem: Problem
    operator: SweepOperator | None
    points: probes.OutputPoints
    frequency_hz: NDArray
    load_scale: NDArray

    @property
    def omegas(self) -> NDArray:
        return 2 * np.pi * self.frequency_hz

    def output_map(self, V: NDArray) -> NDArray:
        """Outputs (n_out, 3, k) of free-dof vectors V (n_free, k)."""
        dm = self.operator.dofmap
        full = dm.expand(V)  # (n_full, k)
        nodal = full.reshape(-1, dm.dofs_per_node, V.shape[1])
        padded = np.zeros((nodal.shape[0], 3, V.shape[1]), dtype=complex)
        padded[:, : dm.dofs_per_node] = nodal
        nodes, weights = self.points.stencil
        return np.einsum("ki,kicr->kcr", weights, padded[nodes])

    def groups(self) -> list[slice]:
        """Output groups compared as one: centre, edge, profile (probes are not controlled:
        they may sit where the field vanishes)."""
        n = self.points.n_probe
        if self.problem.edge is None:
            return [slice(n + 2, None)] if self.points.profile_mm.size else [slice(0, n)]
        return [slice(n, n + 1), slice(n + 1, n + 2), slice(n + 2, None)]


def setup(scene: Scene, n_nodes: int = CHEBYSHEV_NODES, operator: bool = True) -> SweepSetup:
    """Discretise a sweep scene once for its band (without the reduced model's operator when
    ``operator`` is False: what a direct solve per frequency needs)."""
    freqs = np.asarray(scene.analysis.frequencies_hz, dtype=float)
    problem = build_problem(scene)
    w = 2 * np.pi * freqs
    op = (SweepOperator.build(problem, float(w.min()), float(w.max()), n_nodes) if operator
          else None)
    points = probes.output_points(scene, problem)
    scale = scene.load.kind.actuator.load_scale(w, problem.omega, scene)  # an ERM's m e w^2
    return SweepSetup(scene, problem, op, points, freqs, scale)


@linalg.one_blas_thread()
def sweep(scene: Scene, *, tolerance: float | None = None,
          max_unknowns: float = DEFAULT_MAX_UNKNOWNS, depth: int = KRYLOV_DEPTH,
          max_expansions: int = MAX_EXPANSIONS) -> SweepResult:
    """Solve a sweep scene with the reduced-order model (see the module docstring); the
    tolerance is the scene's ``analysis.tolerance`` unless given."""
    t0 = time.perf_counter()
    tolerance = scene.analysis.tolerance if tolerance is None else tolerance
    check_cost(scene, max_unknowns)
    s = setup(scene)
    t_setup = time.perf_counter() - t0
    model, outputs, estimate, report = greedy_model(s.operator, s.omegas, s.output_map,
                                                    s.groups(), tolerance, depth,
                                                    max_expansions)
    t_model = time.perf_counter() - t0 - t_setup
    values = outputs * s.load_scale[:, None, None]
    wall = time.perf_counter() - t0
    meta = _meta(s, wall, s.operator.dofmap.n_free) | {
        "expansions_hz": [round(f, 6) for f in report.expansions_hz],
        "estimates": report.estimates, "back_solves": report.back_solves,
        "basis_size": int(model.basis.shape[1]), "chebyshev_nodes": int(
            s.operator.nodes_t.size), "residual": report.residual,
        "residual_hz": report.residual_hz, "worst_index": int(np.argmax(estimate)),
        "stages_s": {"setup": t_setup, **report.stages_s,
                     "output": wall - t_setup - t_model},
    }
    warnings = [w for w in (resolution_warning(scene, s.problem), s.points.cut) if w]
    converged = float(estimate.max()) <= tolerance
    if not converged:
        warnings.append(f"the error estimate {estimate.max():.2g} is above the tolerance "
                        f"{tolerance:g} after {report.factorisations} factorisations (the "
                        f"most allowed); the answer may be off by that much near "
                        f"{s.frequency_hz[int(np.argmax(estimate))]:g} Hz")
    if warnings:
        meta["warnings"] = warnings
    return _result(s, values, float(estimate.max()), tolerance, report.factorisations, meta)


@linalg.one_blas_thread()
def direct_sweep(scene: Scene, frequency_hz: NDArray | None = None) -> SweepResult:
    """The reference: one direct solve per frequency on the sweep's mesh with the exact PML
    of that frequency (``fem.solve.solve_mode``, as the harmonic analysis solves)."""
    t0 = time.perf_counter()
    s = setup(scene, operator=False)
    freqs = s.frequency_hz if frequency_hz is None else np.asarray(frequency_hz, float)
    p = s.problem
    stretch = p.domain.stretch
    scales = scene.load.kind.actuator.load_scale(2 * np.pi * freqs, p.omega, scene)
    values, dofs = [], 0
    for f, scale in zip(freqs, scales, strict=True):
        w = 2 * np.pi * f
        domain = p.domain if stretch is None else replace(p.domain,
                                                          stretch=replace(stretch, omega=w))
        sol = solve_mode(domain, p.mode, p.load * scale, w, OperatorLog(), extra=p.extra)
        values.append(results.interpolate(s.points.stencil, sol.nodal()))
        dofs = sol.n_dofs
    s = replace(s, frequency_hz=freqs)
    meta = _meta(s, time.perf_counter() - t0, dofs)
    return _result(s, np.array(values), 0.0, 0.0, freqs.size, meta)


def _meta(s: SweepSetup, wall: float, dofs: int) -> dict:
    """The result's meta; ``dofs``: unknowns of the discretisation, element interiors in."""
    included, skipped = s.problem.effect_lists()
    return {"dofs": int(dofs),
            "elements": int(s.problem.domain.mesh.n_elements), "modes": [s.problem.mode],
            "effects": included, "skipped": skipped, "wall_s": wall,
            "time_convention": "exp(+i omega t)", "solver_version": SOLVER_VERSION,
            "mesh_frequency_hz": round(float(s.problem.omega / (2 * np.pi)), 9),
            "frequencies": int(s.frequency_hz.size)}


def _result(s: SweepSetup, values: NDArray, estimate: float, tolerance: float, solves: int,
            meta: dict) -> SweepResult:
    n = s.points.n_probe
    edge = s.problem.edge
    lay = s.problem.layout
    centre_z_mm = 0.0 if lay is None else float(lay.contact_z * 1e3)
    return SweepResult(s.scene, s.frequency_hz, s.points.r_probe * 1e3, values[:, :n],
                       None if edge is None else edge * 1e3, values[:, n], values[:, n + 1],
                       s.points.profile_mm, values[:, n + 2:], estimate, tolerance, solves,
                       meta, centre_z_mm)


#: Phase errors are judged where a component's magnitude exceeds this share of the largest
#: magnitude of its quantity (centre, edge or profile) at that frequency.
PHASE_FLOOR = 0.01


def sweep_errors(result: SweepResult, reference: SweepResult) -> dict[str, float]:
    """Largest errors of ``result`` against ``reference`` at the reference's frequencies (a
    subset of the result's): for centre, edge and profile, the relative error of the magnitude
    (the profile's relative to its largest magnitude at that frequency) and the phase error
    (rad) of every component whose magnitude exceeds :data:`PHASE_FLOOR` of its quantity's
    largest."""
    at = np.searchsorted(result.frequency_hz, reference.frequency_hz)
    if not np.allclose(result.frequency_hz[at], reference.frequency_hz, rtol=0, atol=1e-9):
        raise ValueError("the reference frequencies are not on the result's grid")
    out: dict[str, float] = {}
    for name in ("center", "edge", "profile"):
        got, ref = getattr(result, name)[at], getattr(reference, name)
        if ref.size == 0:
            continue
        got, ref = got.reshape(got.shape[0], -1, 3), ref.reshape(ref.shape[0], -1, 3)
        mag_got, mag_ref = results.magnitude(got), results.magnitude(ref)  # (n_f, n_p)
        scale = mag_ref.max(axis=1, keepdims=True) if name == "profile" else mag_ref
        out[f"{name}_magnitude"] = float(np.max(np.abs(mag_got - mag_ref) / scale))
        big = np.abs(ref) > PHASE_FLOOR * np.abs(ref).max(axis=(1, 2), keepdims=True)
        phase = np.abs(np.angle(got[big] / ref[big]))
        out[f"{name}_phase_rad"] = float(phase.max()) if phase.size else 0.0
    return out
