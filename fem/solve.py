"""Operators of one Fourier mode and the static, harmonic and modal solves.

Only the operators an analysis needs are built: a static solve assembles no mass, a harmonic
solve forms the dynamic element matrices K* - omega^2 M (+ i omega C) and assembles them once.
``OperatorLog`` records what was built so tests and the summary can prove it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from . import elements
from .assembly import DofMap, assemble_matrix, assemble_vector, build_dofmap, prescribed_load
from .domain import Domain


@dataclass
class OperatorLog:
    """Names of the element operators built, in order (e.g. "stiffness[n=1]")."""

    built: list[str] = field(default_factory=list)

    def add(self, name: str, mode: int) -> None:
        self.built.append(f"{name}[n={mode}]")


def moduli(domain: Domain, hysteretic: bool) -> tuple[NDArray, NDArray]:
    """Per-element shear and bulk moduli (Pa), complex E (1 + i eta) when hysteretic."""
    mu = domain.element_property("mu")
    kappa = domain.element_property("kappa")
    if hysteretic:
        factor = 1.0 + 1j * domain.element_property("loss_factor")
        return mu * factor, kappa * factor
    return mu, kappa


def has_hysteresis(domain: Domain) -> bool:
    return bool(np.any(domain.element_property("loss_factor") > 0))


def dynamic_element_matrices(domain: Domain, mode: int, omega: float, log: OperatorLog,
                             volumetric: str = "bbar", stretch=None) -> NDArray:
    """K* - omega^2 M + i omega C per element (PML stretch and damping layer included)."""
    g = elements.gauss_data(domain.mesh, stretch)
    mu, kappa = moduli(domain, has_hysteresis(domain))
    Z = elements.stiffness(g, mode, mu, kappa, volumetric)
    log.add("stiffness", mode)
    if omega > 0:
        Z = Z - omega**2 * elements.mass(g, mode, domain.element_property("density"))
        log.add("mass", mode)
        if domain.damping is not None:
            rate = domain.damping.rate(g.r, g.z) * domain.element_property("density")[:, None]
            Z = Z + 1j * omega * elements.weighted_mass(g, mode, rate)
            log.add("damping layer", mode)
    return Z


@dataclass(frozen=True)
class ModeSolution:
    """Solution of one Fourier mode: full nodal dofs and the map that numbers them."""

    mode: int
    dofmap: DofMap
    u_full: NDArray
    n_dofs: int

    def nodal(self) -> NDArray:
        """(n_nodes, 3) complex (U_r, U_z, U_t) in m."""
        return self.dofmap.nodal(self.u_full)


def solve_mode(domain: Domain, mode: int, load_full: NDArray, omega: float = 0.0,
               log: OperatorLog | None = None, volumetric: str = "bbar",
               prescribed=()) -> ModeSolution:
    """Static (omega = 0) or harmonic solve of one mode with one sparse LU factorisation.

    Args:
        load_full: full nodal load vector (N) of this mode.
        omega: angular frequency (rad/s); 0 for static.
        prescribed: (nodes, component, values) Dirichlet data, e.g. exact fields on a boundary.
    """
    log = log if log is not None else OperatorLog()
    stretch = domain.stretch if omega > 0 else None
    dm = build_dofmap(domain.mesh, mode, domain.fixed(), prescribed)
    Ze = dynamic_element_matrices(domain, mode, omega, log, volumetric, stretch)
    A = assemble_matrix(dm, Ze)
    rhs = assemble_vector(dm, load_full) + prescribed_load(dm, Ze)
    u = factorize(A).solve(rhs.astype(A.dtype))
    return ModeSolution(mode, dm, dm.expand(u), dm.n_free)


def factorize(A: sp.spmatrix):
    """Sparse LU of A (SuperLU with a fill-reducing ordering), reusable across right-hand sides."""
    return spla.splu(sp.csc_matrix(A), permc_spec="COLAMD")


def natural_frequencies(domain: Domain, mode: int, k: int = 6, sigma_hz: float = 0.0) -> NDArray:
    """The k natural frequencies (Hz) of ``mode`` nearest ``sigma_hz`` (shift-invert Lanczos)."""
    freqs, _ = natural_modes(domain, mode, k, sigma_hz)
    return freqs


def natural_modes(domain: Domain, mode: int, k: int = 6,
                  sigma_hz: float = 0.0) -> tuple[NDArray, NDArray]:
    """Natural frequencies (Hz, ascending) and full-dof mode shapes (n_full, k) of ``mode``."""
    dm = build_dofmap(domain.mesh, mode, domain.fixed())
    g = elements.gauss_data(domain.mesh)
    mu, kappa = moduli(domain, hysteretic=False)
    K = assemble_matrix(dm, elements.stiffness(g, mode, mu, kappa))
    M = assemble_matrix(dm, elements.mass(g, mode, domain.element_property("density")))
    sigma = (2 * np.pi * sigma_hz) ** 2
    vals, vecs = spla.eigsh(K, k=k, M=M, sigma=sigma, which="LM")
    order = np.argsort(vals)
    freqs = np.sqrt(np.abs(vals[order])) / (2 * np.pi)
    return freqs, dm.expand(vecs[:, order])
