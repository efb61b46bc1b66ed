"""From a validated scene to a solved, sampled result: the one entry point users call.

The scene decides what is built. A normal load solves Fourier mode 0 only, a tangential one
mode 1 only; a static analysis assembles no mass; fixed or free boundaries add no absorber;
without loss factors no complex moduli are formed. ``SimulationResult.meta`` lists what was
included and what was skipped.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from . import SOLVER_VERSION, loads, results
from .domain import Domain, MeshSpec, Solid, layered_domain
from .scene import Scene
from .solve import OperatorLog, has_hysteresis, solve_mode

#: Distances from the edge (mm) of the profile every result carries.
PROFILE_DISTANCES_MM = np.arange(0.0, 20.0 + 1e-9, 1.0)


@dataclass(frozen=True)
class SimulationResult:
    """Surface response of one scene.

    Attributes:
        scene: the scene solved.
        r_mm: probe radii (mm).
        U: (n_probe, 3) complex Fourier amplitudes (U_r, U_z, U_t) in m at the probe radii.
        edge_mm: radius of the load footprint's edge (mm), None for a point force.
        center: (3,) amplitudes at r = 0 (m); edge: at edge_mm; profile: (n_profile, 3).
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
    nodal: NDArray = field(repr=False)

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

    def to_dict(self) -> dict:
        """JSON-ready dict: surface amplitudes (um) at the probe radii, unit figures, meta."""
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
        return out

    def surface_curve(self) -> tuple[NDArray, NDArray]:
        """Radii (mm) of all surface nodes within the model and their amplitudes (n, 3) in m."""
        nodes = self.domain.surface_nodes()
        return self.domain.mesh.nodes[nodes, 0] * 1e3, self.nodal[nodes]

    def summary(self) -> str:
        """A short human-readable report."""
        m = self.meta
        lines = [
            f"hapticrom {SOLVER_VERSION}: {self.scene.analysis.kind} analysis"
            + (f" at {self.scene.analysis.frequency_hz:g} Hz"
               if self.scene.analysis.kind != "static" else ""),
            f"  elements {m['elements']}, dofs {m['dofs']}, order {self.scene.mesh.order}, "
            f"Fourier modes {m['modes']}, wall time {m['wall_s'] * 1e3:.1f} ms",
            f"  included: {', '.join(m['effects']) or 'none'}",
            f"  skipped:  {', '.join(m['skipped']) or 'none'}",
        ]
        lines += [f"  {'r (mm)':>8} {'|u_r| um':>11} {'|u_z| um':>11} {'|u_t| um':>11} "
                  f"{'magn. um':>11}"]
        mag = results.magnitude(self.U)
        for r, u, a in zip(self.r_mm, self.U, mag, strict=True):
            lines.append(f"  {r:8.2f} {abs(u[0]) * 1e6:11.4g} {abs(u[1]) * 1e6:11.4g} "
                         f"{abs(u[2]) * 1e6:11.4g} {a * 1e6:11.4g}")
        if self.edge_mm is not None:
            lines.append(f"  centre {self.center_amplitude_um:.4g} um, edge "
                         f"({self.edge_mm:g} mm) {self.edge_amplitude_um:.4g} um, normalized "
                         f"edge {self.normalized_edge:.3f}")
        return "\n".join(lines)


def tissue_layers(scene: Scene) -> list[tuple[float, Solid]]:
    """The scene's layers as (thickness m, Solid)."""
    return [(ly.thickness_m, Solid(ly.E_Pa, ly.nu, ly.density_kg_m3, ly.loss_factor, ly.name))
            for ly in scene.tissue.layers]


def mesh_spec(scene: Scene) -> MeshSpec:
    m = scene.mesh
    return MeshSpec(m.near_size_mm * 1e-3, m.near_radius_mm * 1e-3, m.far_size_mm * 1e-3,
                    m.order)


def build_domain(scene: Scene) -> Domain:
    """Discretise the scene's tissue with the absorbers its analysis needs."""
    a = scene.analysis
    omega = 2 * np.pi * a.frequency_hz if a.kind != "static" else 0.0
    breaks = [scene.load.radius_m] if scene.load.kind == "pressure_patch" else []
    return layered_domain(tissue_layers(scene), scene.tissue.radius_m, scene.tissue.side,
                          scene.tissue.base, mesh_spec(scene), a.kind, omega, breaks)


def load_vector(scene: Scene, domain: Domain, mode: int) -> NDArray:
    """Full nodal load (N) of the scene's load in Fourier mode ``mode``."""
    ld = scene.load
    if ld.kind == "point_force":
        return loads.axis_point_force(domain, mode, ld.force_N)
    t = ld.amplitude_Pa
    comps = (0.0, t, 0.0) if mode == 0 else (t, 0.0, -t)
    return loads.surface_traction(domain, mode, ld.radius_m, comps)


def simulate(scene: Scene) -> SimulationResult:
    """Solve a scene and sample the skin surface."""
    t0 = time.perf_counter()
    domain = build_domain(scene)
    mode = 0 if scene.load.direction == "normal" else 1
    omega = (2 * np.pi * scene.analysis.frequency_hz
             if scene.analysis.kind == "harmonic" else 0.0)
    log = OperatorLog()
    sol = solve_mode(domain, mode, load_vector(scene, domain, mode), omega, log)
    nodal = sol.nodal()
    wall = time.perf_counter() - t0

    effects = list(domain.effects)
    skipped = list(domain.skipped)
    (effects if omega > 0 else skipped).append("inertia")
    (effects if has_hysteresis(domain) else skipped).append("hysteretic damping")
    skipped.append(f"Fourier mode {1 - mode}")

    edge_m = scene.load.radius_m if scene.load.kind == "pressure_patch" else None
    r_probe = np.asarray(scene.output.radii_m)
    prof_m = _profile_radii(edge_m or 0.0, scene.tissue.radius_m)
    sample = results.surface_interpolator(
        domain, np.concatenate([r_probe, [0.0, edge_m or 0.0], prof_m]))
    vals = sample(nodal)
    n = r_probe.size
    meta = {
        "dofs": sol.n_dofs, "elements": domain.mesh.n_elements, "modes": [mode],
        "effects": effects, "skipped": skipped, "operators": log.built, "wall_s": wall,
        "time_convention": "exp(+i omega t)", "solver_version": SOLVER_VERSION,
    }
    edge_mm = None if edge_m is None else edge_m * 1e3
    return SimulationResult(scene, r_probe * 1e3, vals[:n], edge_mm, vals[n], vals[n + 1],
                            (prof_m - (edge_m or 0.0)) * 1e3, vals[n + 2:], meta, domain, nodal)


def _profile_radii(edge: float, radius: float) -> NDArray:
    r = edge + PROFILE_DISTANCES_MM * 1e-3
    return r[r <= radius * (1 + 1e-12)]
