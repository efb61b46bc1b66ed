"""Transient analysis of a discretised scene: spin-up, steady running and spin-down of a unit.

The ERM's rotating force F(t) (cos phi(t), sin phi(t)), F = m e omega(t)^2 (``fem.motor``), is
one n = 1 spatial pattern (a horizontal force at the rotor plane) with two time columns: the
x component F cos phi and the y component F sin phi. The y response is the x response turned
by 90 degrees, so on the theta = 0 meridian

    u_r(t) = U_r^x(t),   u_z(t) = U_z^x(t),   u_theta(t) = -U_t^y(t),

where ^x and ^y denote the two columns. In steady state this reproduces the harmonic amplitudes.
Time integration is generalised-alpha with one factorisation (``fem.transient``); the outer side
and base absorb through a graded damping layer (``fem.absorbers.DampingLayer``). Hysteretic loss
factors have no causal time-domain form; ``[analysis] damping`` chooses what stands for them,
both built on the loss matrix K_eta = sum_m eta_m K_m (:func:`loss_matrix`):

- ``"viscous_at_drive"`` (default): stiffness-proportional damping C = K_eta / omega_ref, the
  same loss per cycle at the reference frequency (the motor's rated speed), eta f / f_ref at
  another frequency f;
- ``"hysteretic_band"``: a Prony series following 1 + i eta over 20-300 Hz
  (``fem.viscoelastic``): stiffness K - c K_eta and relaxation terms acting through K_eta.
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
from .viscoelastic import Relaxation, default_fit

DAMPING_MODELS = ("viscous_at_drive", "hysteretic_band")
"""Choices of ``[analysis] damping`` (see the module docstring)."""


@dataclass(frozen=True, eq=False)
class TransientSystem:
    """The reduced real sparse operators of a transient (SI: K and K_eta in N/m, M in kg,
    C in N s/m) and the dof map.

    Attributes:
        dm: dof map of the problem's mode.
        K: stiffness handed to the integrator (K - c K_eta for the band model).
        M: mass.
        C: viscous damping (the damping layer, plus K_eta / omega_ref for the viscous model),
            or None.
        K_eta: loss matrix sum_m eta_m K_m, or None without loss factors.
        relaxation: the band model's Maxwell terms, or None.
    """

    dm: object
    K: object
    M: object
    C: object
    K_eta: object
    relaxation: Relaxation | None


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


def loss_matrix(dm, Ke: NDArray, eta: NDArray):
    """K_eta = sum_m eta_m K_m [N/m]: the element stiffness matrices ``Ke`` (n_el, nd, nd)
    times each element's loss factor ``eta`` (n_el,), assembled. The harmonic solver's
    hysteretic operator is K + i K_eta on the same elements (``fem.solve``)."""
    return assemble_matrix(dm, Ke * eta[:, None, None])


def system_matrices(problem: Problem, omega_ref: float, log: OperatorLog):
    """Reduced K, M, C (real, sparse) and the dof map of the problem's mode, with the loss
    factors as viscous damping K_eta / omega_ref (``"viscous_at_drive"``)."""
    s = transient_system(problem, omega_ref, log)
    return s.dm, s.K, s.M, s.C


def transient_system(problem: Problem, omega_ref: float, log: OperatorLog,
                     damping: str = "viscous_at_drive") -> TransientSystem:
    """The operators of the problem's transient with the loss model ``damping`` (one of
    :data:`DAMPING_MODELS`); ``omega_ref`` [rad/s] is the viscous model's reference."""
    if damping not in DAMPING_MODELS:
        raise ValueError(f"damping must be one of {DAMPING_MODELS}, got {damping!r}")
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
    C = K_eta = relaxation = None
    eta = d.element_property("loss_factor")
    if np.any(eta > 0):
        K_eta = loss_matrix(dm, Ke, eta)
        if damping == "viscous_at_drive":
            C = K_eta * (1.0 / omega_ref)
            log.add("hysteretic damping (Rayleigh)", mode)
        else:
            fit = default_fit()
            K = K - fit.c * K_eta
            relaxation = Relaxation.from_fit(K_eta, fit)
            log.add("hysteretic damping (Prony band)", mode)
    if d.damping is not None:
        C_layer = assemble_matrix(dm, damping_layer_matrices(d, g, mode, density))
        C = C_layer if C is None else C + C_layer
        log.add("damping layer", mode)
    return TransientSystem(dm, K, M, C, K_eta, relaxation)


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
    system = transient_system(problem, omega_ref, log, a.damping)
    dm = system.dm
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
    res = solve_transient(system.M, system.K, np.repeat(f[:, None], k, axis=1), history, dt,
                          n_steps, C=system.C, relaxation=system.relaxation,
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
