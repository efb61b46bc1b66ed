"""Treatments of the truncated outer side and base: PML, graded damping, static far field.

A model of tissue is truncated at radius R (and, for a half-space, at a depth). What lies beyond
depends on the analysis:

* harmonic: a perfectly matched layer (complex coordinate stretch, Kucukcoban & Kallivokas 2011)
  s(x) = alpha(x) - i beta(x) / omega with alpha = 1 + alpha0 (x/L)^m, beta = beta0 (x/L)^m and
  beta0 = (m + 1) c ln(1/R) / (2 L) (time convention exp(+i omega t)). When the wavelength is
  long compared with the model (low frequency) the layer is preceded by a graded extension so
  that the quasi-static near field is not clipped at R.
* static: a geometrically graded extension to far away (100 R), held fixed at its end; the
  static fields decay like 1/r, so the clipping error is of order R / (100 R).
* transient: a graded mass-proportional damping layer (see ``DampingLayer``), the simple
  time-domain absorber.

All lengths in m, speeds in m/s, frequencies in rad/s unless a name says otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .mesh import geometric_extension

#: Nominal PML reflection for the reference (shear) wave at normal incidence. Set far below the
#: usual 1e-3 because faster components (P-type, c_P = 4 c_S at nu = 0.47) see ln(1/R) divided by
#: their speed ratio: 1e-9 leaves about 1e-3 for a wave three times faster. Measured on the
#: forearm (bench/fem/absorber.py): moving the boundary 50 -> 80 mm changes the surface
#: amplitude within 20 mm by 3.3 % at 1e-3 and 0.08 % at 1e-9, with the same mesh.
PML_REFLECTION = 1e-9
#: Polynomial order of the PML profile.
PML_POWER = 2
#: Real stretch amplitude: damps evanescent components that beta alone does not.
PML_ALPHA0 = 1.0
#: Static far field: the extension reaches this multiple of the model size.
STATIC_EXTENSION_FACTOR = 100.0
#: Elements per wavelength of the slowest shear wave, times the element order, in the layers.
ELEMENTS_PER_WAVELENGTH = 10.0
#: Graded damping layer (time domain): thickness in reference wavelengths and peak rate / omega.
#: Measured on the triple-ring pogo unit at 120 Hz against the PML (bench/fem/absorber.py):
#: 1 wavelength reflects 7-19 %, 2 wavelengths at 1.0 omega 1 %, 3 wavelengths at 1.5 omega
#: 0.2 %, the PML's own level.
DAMPING_LAYER_WAVELENGTHS = 3.0
DAMPING_LAYER_RATE = 1.5


def reference_speed(shear_speeds: NDArray) -> float:
    """The wave speed a PML is tuned for: the fastest shear speed among the soft layers.

    A layer more than ten times faster than the slowest one (bone under soft tissue) carries no
    propagating wave at the scale of the model, and tuning for it would make the layer's decay
    unresolvably fast for the waves that matter.
    """
    c = np.asarray(shear_speeds, dtype=float)
    soft = c[c <= 10.0 * c.min()]
    return float(soft.max())


@dataclass(frozen=True)
class AxisLayout:
    """Cell lines beyond the physical model along one axis, and where a PML starts.

    Attributes:
        lines: extra cell lines after the physical end (m).
        pml_start: coordinate where the PML begins (m), or None without a PML.
        pml_thickness: PML thickness (m), 0 without a PML.
    """

    lines: NDArray
    pml_start: float | None = None
    pml_thickness: float = 0.0


def static_extension(end: float, h_last: float, size: float) -> AxisLayout:
    """Graded far-field extension for static analysis, to STATIC_EXTENSION_FACTOR x ``size``."""
    length = STATIC_EXTENSION_FACTOR * size
    return AxisLayout(geometric_extension(end, h_last, 0.25 * length, length))


def pml_layout(end: float, h_last: float, model_size: float, wavelength_ref: float,
               h_wave: float, wavelengths: float = 1.0) -> AxisLayout:
    """Extension (when the reference wavelength exceeds the model) followed by an absorbing
    layer ``wavelengths`` reference wavelengths thick, meshed at ``h_wave``."""
    start = max(end, min(wavelength_ref, 20.0 * model_size))
    ext = (geometric_extension(end, h_last, h_wave, start - end)
           if start > end * (1 + 1e-12) else np.empty(0))
    thickness = wavelengths * wavelength_ref
    n_cells = max(6, int(np.ceil(thickness / h_wave)))
    pml = start + thickness * np.arange(1, n_cells + 1) / n_cells
    return AxisLayout(np.concatenate([ext, pml]), start, thickness)


@dataclass(frozen=True)
class PML:
    """Complex coordinate stretch in r beyond r_start and in z beyond z_start.

    Callable as a ``Stretch``: (r, z) -> (s_r, s_z, r_tilde).
    """

    omega: float
    speed: float
    r_start: float | None = None
    r_thickness: float = 0.0
    z_start: float | None = None
    z_thickness: float = 0.0
    alpha0: float = PML_ALPHA0
    power: int = PML_POWER
    reflection: float = PML_REFLECTION

    def _beta0(self, thickness: float) -> float:
        return (self.power + 1) * self.speed * np.log(1.0 / self.reflection) / (2.0 * thickness)

    def _profile(self, x: NDArray, start: float | None, thickness: float):
        """Stretch s(x) and its integral over the layer, both zero-based beyond start."""
        if start is None:
            return np.ones_like(x, dtype=complex), np.zeros_like(x, dtype=complex)
        xi = np.clip((x - start) / thickness, 0.0, None)
        amp = self.alpha0 - 1j * self._beta0(thickness) / self.omega
        s = 1.0 + amp * xi**self.power
        extra = amp * thickness * xi ** (self.power + 1) / (self.power + 1)
        return s, extra

    def contains(self, r0: NDArray, z0: NDArray) -> NDArray:
        """Whether cells with lower corner (r0, z0) lie in the layer (its start is a cell line)."""
        inside = np.zeros(np.broadcast(r0, z0).shape, dtype=bool)
        for x, start in ((r0, self.r_start), (z0, self.z_start)):
            if start is not None:
                inside |= np.asarray(x) >= start * (1 - 1e-12)
        return inside

    def __call__(self, r: NDArray, z: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        s_r, r_extra = self._profile(r, self.r_start, self.r_thickness)
        s_z, _ = self._profile(z, self.z_start, self.z_thickness)
        return s_r, s_z, r + r_extra


@dataclass(frozen=True)
class DampingLayer:
    """Graded viscous absorber: mass-proportional damping coefficient (1/s) rising as x^power
    from zero at the layer start to ``max_rate`` at its end, in r and/or z.

    Used in the time domain (and in harmonic solves that must match a transient one). With
    ``max_rate`` of a few omega and a layer a wavelength or more thick, reflections stay at the
    per-cent level; measure them for the case at hand (bench/).
    """

    max_rate: float
    r_start: float | None = None
    r_thickness: float = 0.0
    z_start: float | None = None
    z_thickness: float = 0.0
    power: int = 2

    def rate(self, r: NDArray, z: NDArray) -> NDArray:
        """Damping rate c(r, z) in 1/s at the given points (m)."""
        out = np.zeros(np.broadcast(r, z).shape)
        for x, start, thick in ((r, self.r_start, self.r_thickness),
                                (z, self.z_start, self.z_thickness)):
            if start is not None:
                xi = np.clip((np.asarray(x) - start) / thick, 0.0, 1.0)
                out = np.maximum(out, self.max_rate * xi**self.power)
        return out
