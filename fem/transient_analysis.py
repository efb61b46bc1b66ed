"""Transient analysis of a discretised scene: spin-up, steady running and spin-down of a unit.

The ERM's rotating force F(t) (cos phi(t), sin phi(t)), F = m e omega(t)^2 (``fem.motor``), is
one n = 1 spatial pattern (a horizontal force at the rotor plane) with two time columns: the
x component F cos phi and the y component F sin phi. The y response is the x response turned
by 90 degrees, so on the theta = 0 meridian

    u_r(t) = U_r^x(t),   u_z(t) = U_z^x(t),   u_theta(t) = -U_t^y(t),

where ^x and ^y denote the two columns. In steady state this reproduces the harmonic amplitudes.
Time integration is generalised-alpha with one factorisation (``fem.transient``); the outer side
and base absorb through a graded damping layer (``fem.absorbers.DampingLayer``). Hysteretic loss
factors, which have no causal time-domain form, become stiffness-proportional damping
C = (eta / omega_ref) K with the same loss per cycle at the reference frequency.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from . import elements, linalg
from .assembly import assemble_matrix, assemble_vector, build_dofmap
from .problem import Problem, drive_omega
from .scene import Scene
from .solve import OperatorLog, damping_layer_matrices
from .transient import solve_transient


@dataclass(frozen=True)
class Histories:
    """Surface time histories on the theta = 0 meridian.

    Attributes:
        t: (nt,) times in s.
        radii: (n_points,) radii in m.
        u: (nt, n_points, 3) displacements (u_r, u_z, u_theta) in m.
        n_dofs: unknowns of the time-stepped system.
    """

    t: NDArray
    radii: NDArray
    u: NDArray
    n_dofs: int

    def amplitude(self, start: float = 0.0) -> NDArray:
        """(n_points, 3) per-component peak |u| over t >= start (m)."""
        return np.abs(self.u[self.t >= start]).max(axis=0)


def system_matrices(problem: Problem, omega_ref: float, log: OperatorLog):
    """Reduced K, M, C (real, sparse) and the dof map of the problem's mode."""
    d, mode = problem.domain, problem.mode
    dm = build_dofmap(d.mesh, mode, d.fixed(), ties=d.ties)
    g = elements.gauss_data(d.mesh)
    mu, kappa = d.element_property("mu"), d.element_property("kappa")
    density = d.element_property("density")
    Ke = elements.stiffness(g, mode, mu, kappa)
    K = assemble_matrix(dm, Ke)
    log.add("stiffness", mode)
    for name, edofs, Kx in problem.extra:
        K = K + assemble_matrix(dm, Kx, edofs)
        log.add(name, mode)
    M = assemble_matrix(dm, elements.mass(g, mode, density))
    log.add("mass", mode)
    C = None
    eta = d.element_property("loss_factor")
    if np.any(eta > 0):
        C = assemble_matrix(dm, Ke * (eta / omega_ref)[:, None, None])
        log.add("hysteretic damping (Rayleigh)", mode)
    if d.damping is not None:
        C_layer = assemble_matrix(dm, damping_layer_matrices(d, g, mode, density))
        C = C_layer if C is None else C + C_layer
        log.add("damping layer", mode)
    return dm, K, M, C


def load_history(scene: Scene, problem: Problem):
    """Amplitude columns of the load pattern against time, and k."""
    return scene.load.kind.actuator.load_history(scene, problem)


@linalg.one_blas_thread()
def run(scene: Scene, problem: Problem, stencil: tuple[NDArray, NDArray], radii: NDArray,
        log: OperatorLog, progress: Callable[[int, int], None] | None = None) -> Histories:
    """Integrate the scene's transient and sample it with ``stencil`` (nodes, weights) at the
    points whose radii (m) are ``radii``. ``progress(done, total)`` receives the steps done
    about 200 times per run."""
    a = scene.analysis
    omega_ref = drive_omega(scene)
    dm, K, M, C = system_matrices(problem, omega_ref, log)
    nodes, weights = stencil
    used = np.unique(nodes)
    ndpn = dm.dofs_per_node
    full = (used[:, None] * ndpn + np.arange(ndpn)).ravel()
    masters = dm.master[full]
    record = np.unique(masters[masters >= 0])

    history, k = load_history(scene, problem)
    f = assemble_vector(dm, problem.load)
    dt = a.time_step_s
    n_steps = max(1, round(a.duration_ms / a.time_step_ms))
    res = solve_transient(M, K, np.repeat(f[:, None], k, axis=1), history, dt, n_steps, C=C,
                          rho_inf=a.rho_inf, record_dofs=record,
                          record_every=scene.output.history_every,
                          **_progress_hook(progress, n_steps))
    # full-dof values of the used nodes: (nt, n_used, ndpn, k)
    pos = np.searchsorted(record, np.maximum(masters, 0))
    vals = np.where((masters >= 0)[None, :, None], res.u[:, pos, :], 0.0)
    vals = (vals * dm.coef[full][None, :, None]).reshape(len(res.t), used.size, ndpn, k)
    nodal = np.zeros((len(res.t), used.size, 3, k))
    nodal[:, :, :ndpn] = vals
    local = np.searchsorted(used, nodes)
    at = np.einsum("ki,tkicj->tkcj", weights, nodal[:, local])  # (nt, npts, 3, k)
    u = at[..., 0].copy()
    if k == 2:  # theta = 0 meridian of the rotating load: u_theta from the y column
        u[..., 2] = -at[..., 2, 1]
    return Histories(res.t, np.asarray(radii), u, dm.n_free)


def _progress_hook(progress: Callable[[int, int], None] | None, n_steps: int) -> dict:
    """Keyword arguments of :func:`fem.transient.solve_transient` that report progress
    through its snapshot callback (the state arrays are ignored)."""
    if progress is None:
        return {}
    return {"on_snapshot": lambda step, *_: progress(int(step), n_steps),
            "snapshot_every": max(1, n_steps // 200)}
