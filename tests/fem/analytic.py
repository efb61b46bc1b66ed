"""Closed-form reference solutions used to verify the FE solver.

Conventions (shared with the FE code):

- cylindrical coordinates (r, theta, z), z positive INTO the half-space, free surface z = 0;
- loads pushing into the body are positive, so a downward point load P > 0 gives u_z > 0;
- SI units throughout: lengths and displacements in m, forces in N, tractions, pressures and
  moduli in Pa, densities in kg/m^3, speeds in m/s, frequencies in Hz;
- n = 1 (non-axisymmetric) fields are returned as Fourier amplitudes in the symmetric set
  u_r = U_r cos(theta), u_theta = U_t sin(theta), u_z = U_z cos(theta).

Every function broadcasts over numpy arrays of the coordinates and returns numpy arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq
from scipy.special import ellipe, ellipkm1

FloatArray = NDArray[np.float64]


def _require(ok: bool | np.bool_, field: str, allowed: str) -> None:
    if not ok:
        raise ValueError(f"{field} must be {allowed}")


def _check_half_space(mu: float, nu: float) -> None:
    _require(mu > 0, "mu", "> 0 Pa")
    _require(-1.0 < nu <= 0.5, "nu", "in (-1, 0.5]")


def _check_coords(**coords: ArrayLike) -> list[FloatArray]:
    out = []
    for name, value in coords.items():
        arr = np.asarray(value, dtype=float)
        _require(bool(np.all(arr >= 0)), name, ">= 0 m")
        out.append(arr)
    return list(np.broadcast_arrays(*out))


# --------------------------------------------------------------------------- point loads


def boussinesq(
    r: ArrayLike, z: ArrayLike, P: float, mu: float, nu: float
) -> tuple[FloatArray, FloatArray]:
    """Vertical point load P [N] at the origin of a half-space: interior field (u_r, u_z) [m].

    Boussinesq (1885); Johnson, Contact Mechanics (1985), ch. 3 "Point loading of an elastic
    half-space", sec. 3.2 (concentrated normal force):
        u_r = P/(4 pi mu) [r z/rho^3 - (1-2nu) r/(rho (rho+z))],
        u_z = P/(4 pi mu) [z^2/rho^3 + 2(1-nu)/rho],   rho = sqrt(r^2 + z^2).
    On the surface: u_z = P(1-nu)/(2 pi mu r), u_r = -P(1-2nu)/(4 pi mu r).
    Singular (inf/nan) at r = z = 0.
    """
    _check_half_space(mu, nu)
    r, z = _check_coords(r=r, z=z)
    rho = np.hypot(r, z)
    c = P / (4.0 * np.pi * mu)
    u_r = c * (r * z / rho**3 - (1 - 2 * nu) * r / (rho * (rho + z)))
    u_z = c * (z**2 / rho**3 + 2 * (1 - nu) / rho)
    return u_r, u_z


def cerruti(
    r: ArrayLike, z: ArrayLike, Q: float, mu: float, nu: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Tangential point load Q [N] in +x at the origin: n = 1 amplitudes (U_r, U_t, U_z) [m].

    Cerruti (1882); Johnson (1985) ch. 3 (concentrated tangential force). The Cartesian field
        u_x = Q/(4 pi mu) [1/rho + x^2/rho^3 + (1-2nu)(1/(rho+z) - x^2/(rho (rho+z)^2))],
        u_y = Q/(4 pi mu) [x y/rho^3 - (1-2nu) x y/(rho (rho+z)^2)],
        u_z = Q/(4 pi mu) [x z/rho^3 + (1-2nu) x/(rho (rho+z))],
    with x = r cos(theta), y = r sin(theta) projects exactly onto
        u_r = U_r cos(theta), u_theta = U_t sin(theta), u_z = U_z cos(theta):
        U_r = Q/(4 pi mu) [1/rho + r^2/rho^3 + (1-2nu)(1/(rho+z) - r^2/(rho (rho+z)^2))],
        U_t = -Q/(4 pi mu) [1/rho + (1-2nu)/(rho+z)],
        U_z = Q/(4 pi mu) [r z/rho^3 + (1-2nu) r/(rho (rho+z))].
    On the surface: U_r = Q/(2 pi mu r), U_t = -Q(1-nu)/(2 pi mu r), U_z = (1-2nu)Q/(4 pi mu r).
    Singular (inf/nan) at r = z = 0.
    """
    _check_half_space(mu, nu)
    r, z = _check_coords(r=r, z=z)
    rho = np.hypot(r, z)
    c = Q / (4.0 * np.pi * mu)
    k = 1 - 2 * nu
    U_r = c * (1 / rho + r**2 / rho**3 + k * (1 / (rho + z) - r**2 / (rho * (rho + z) ** 2)))
    U_t = -c * (1 / rho + k / (rho + z))
    U_z = c * (r * z / rho**3 + k * r / (rho * (rho + z)))
    return U_r, U_t, U_z


# --------------------------------------------------------------------------- loaded discs


def _one_minus_m_times_k(m: FloatArray) -> FloatArray:
    """(1 - m) K(m), continuous at m = 1 where it tends to 0 (K has a log singularity)."""
    p = 1.0 - m
    safe = np.where(p > 0, p, 1.0)
    return np.where(p > 0, p * ellipkm1(safe), 0.0)


def _disc_potentials(r: FloatArray, a: float) -> tuple[FloatArray, FloatArray]:
    """Surface potentials of a uniform unit density on the disc |x'| <= a, both in m.

    phi(r) = integral over the disc of dA'/|x - x'| (Johnson's w/p up to the material factor),
    psi(r) = Psi'(r)/r with Psi(r) = integral over the disc of |x - x'| dA'.
    Since the 2D Laplacian of |x| is 1/|x|, (r Psi')' = r phi, so
    psi = r^-2 int_0^r t phi(t) dt; with int k E(k) dk = [(1+k^2)E - (1-k^2)K]/3 = H(k)/3:
        r <= a, m = (r/a)^2: phi = 4a E(m),                  psi = 4a H(m) / (3m),
        r >= a, m = (a/r)^2: phi = 4r [E(m) - (1-m) K(m)],   psi = 4r H(m) / 3.
    scipy's ellipe/ellipk take the parameter m = k^2.
    """
    inside = r <= a
    ratio = np.where(inside, r / a, a / np.where(r > 0, r, 1.0))
    m = ratio**2
    e = ellipe(m)
    h = (1 + m) * e - _one_minus_m_times_k(m)
    # H(m)/m cancels badly as m -> 0; use its series 3 pi/4 (1 - m/8 + O(m^2)) there.
    small = m < 1e-6
    h_over_m = np.where(small, 0.75 * np.pi * (1 - m / 8), h / np.where(small, 1.0, m))
    phi = np.where(inside, 4 * a * e, 4 * r * (e - _one_minus_m_times_k(m)))
    psi = np.where(inside, 4 * a * h_over_m / 3, 4 * r * h / 3)
    return phi, psi


def _disc_field(r: FloatArray, a: float) -> FloatArray:
    """Radial 2D "Coulomb" field of the unit disc, int (x - x')/|x - x'|^2 dA' [m] (Gauss)."""
    return np.pi * np.where(r <= a, r, a**2 / np.where(r > 0, r, 1.0))


def _check_disc(a: float, mu: float, nu: float) -> None:
    _check_half_space(mu, nu)
    _require(a > 0, "a", "> 0 m")


def uniform_pressure_surface(r: ArrayLike, p: float, a: float, mu: float, nu: float) -> FloatArray:
    """Surface deflection u_z [m] under uniform pressure p [Pa] on a disc of radius a [m].

    Johnson (1985) ch. 3, pressure on a circular region, eqs 3.27-3.28 (with E = 2 mu (1+nu)):
        r <= a: u_z = 4(1-nu^2) p a E(r/a) / (pi E),
        r >  a: u_z = 4(1-nu^2) p r [E(a/r) - (1 - a^2/r^2) K(a/r)] / (pi E),
    complete elliptic integrals of modulus k. Center w0 = p a (1-nu)/mu, edge 2 w0/pi.
    """
    _check_disc(a, mu, nu)
    (r,) = _check_coords(r=r)
    phi, _ = _disc_potentials(r, a)
    return (1 - nu) * p * phi / (2 * np.pi * mu)


def uniform_pressure_surface_radial(
    r: ArrayLike, p: float, a: float, mu: float, nu: float
) -> FloatArray:
    """Surface radial displacement u_r [m] under uniform pressure p [Pa] on a disc of radius a.

    Johnson (1985) ch. 3, pressure on a circular region (eq. 3.29 family), E = 2 mu (1+nu):
        r <= a: u_r = -(1-2nu)(1+nu) p r / (2E)       = -(1-2nu) p r / (4 mu),
        r >  a: u_r = -(1-2nu)(1+nu) p a^2 / (2E r)   = -(1-2nu) p a^2 / (4 mu r).
    It follows from superposing the Boussinesq surface u_r ~ 1/s, a 2D Coulomb field (Gauss).
    """
    _check_disc(a, mu, nu)
    (r,) = _check_coords(r=r)
    return -(1 - 2 * nu) * p * _disc_field(r, a) / (4 * np.pi * mu)


def uniform_shear_surface(
    r: ArrayLike, q: float, a: float, mu: float, nu: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Surface n = 1 amplitudes (U_r, U_t, U_z) [m] under uniform shear q [Pa] (+x) on a disc.

    Derived here by superposing Cerruti's surface field (Johnson 1985 ch. 3)
        u_x = Q/(2 pi mu) [(1-nu)/s + nu dx^2/s^3], u_y = Q nu dx dy/(2 pi mu s^3),
        u_z = (1-2nu) Q dx/(4 pi mu s^2)
    over the disc. With phi, psi from `_disc_potentials` (dx^2/s^3 = 1/s - d^2 s/dx^2):
        U_r = q/(2 pi mu) [(1-nu) phi + nu psi],   U_t = q/(2 pi mu) [-phi + nu psi],
        U_z = (1-2nu) q r/(4 mu) inside,   (1-2nu) q a^2/(4 mu r) outside.
    Center: U_r = -U_t = (2-nu) q a/(2 mu); far field: the Cerruti solution with Q = q pi a^2.
    Verified against quadrature of `cerruti` in tests/test_analytic.py.
    """
    _check_disc(a, mu, nu)
    (r,) = _check_coords(r=r)
    phi, psi = _disc_potentials(r, a)
    c = q / (2 * np.pi * mu)
    U_r = c * ((1 - nu) * phi + nu * psi)
    U_t = c * (-phi + nu * psi)
    U_z = (1 - 2 * nu) * q * _disc_field(r, a) / (4 * np.pi * mu)
    return U_r, U_t, U_z


# --------------------------------------------------------------------------- Lame problems


def _check_shell(a: float, b: float, E: float, nu: float) -> None:
    _require(0 < a < b, "a, b", "0 < a < b (inner and outer radius, m)")
    _require(E > 0, "E", "> 0 Pa")
    _require(-1.0 < nu <= 0.5, "nu", "in (-1, 0.5]")


def thick_cylinder_plane_strain(
    r: ArrayLike, p: float, a: float, b: float, E: float, nu: float
) -> FloatArray:
    """Radial displacement u_r [m] of a thick cylinder, internal pressure p [Pa], plane strain.

    Lame solution; Timoshenko & Goodier, Theory of Elasticity (3rd ed. 1970), "stress
    distribution symmetrical about an axis" (thick-walled cylinder), with u_z = 0:
        u_r = (1+nu) p a^2 / (E (b^2 - a^2)) [(1-2nu) r + b^2/r],   a <= r <= b.
    """
    _check_shell(a, b, E, nu)
    (r,) = _check_coords(r=r)
    return (1 + nu) * p * a**2 / (E * (b**2 - a**2)) * ((1 - 2 * nu) * r + b**2 / r)


def thick_sphere(R: ArrayLike, p: float, a: float, b: float, E: float, nu: float) -> FloatArray:
    """Radial displacement u_R [m] of a thick hollow sphere under internal pressure p [Pa].

    Lame solution; Timoshenko & Goodier (3rd ed. 1970), "symmetrical stress distribution in a
    sphere":  u_R = p a^3 [(1-2nu) R + (1+nu) b^3/(2 R^2)] / (E (b^3 - a^3)),  a <= R <= b.
    """
    _check_shell(a, b, E, nu)
    (R,) = _check_coords(R=R)
    return p * a**3 * ((1 - 2 * nu) * R + (1 + nu) * b**3 / (2 * R**2)) / (E * (b**3 - a**3))


# --------------------------------------------------------------------------- rigid disc


def rigid_disc_stiffness(mu: float, nu: float, a: float) -> dict[str, float]:
    """Static stiffness of a rigid disc of radius a [m] bonded on a half-space.

    vertical [N/m] 4 mu a/(1-nu) (Boussinesq 1885, Sneddon 1946; Johnson 1985 ch. 3 flat punch),
    horizontal [N/m] 8 mu a/(2-nu) (Mindlin 1949; Johnson 1985 ch. 3, traction
    q0 (1-r^2/a^2)^(-1/2), normal-tangential coupling neglected),
    rocking [N m/rad] 8 mu a^3/(3(1-nu)) (Borowicka 1943; Bycroft 1956).
    """
    _check_disc(a, mu, nu)
    return {
        "vertical": 4 * mu * a / (1 - nu),
        "horizontal": 8 * mu * a / (2 - nu),
        "rocking": 8 * mu * a**3 / (3 * (1 - nu)),
    }


# --------------------------------------------------------------------------- waves


def p_wave_speed(E: float, nu: float, rho: float) -> float:
    """P-wave speed [m/s] from the constrained modulus M = E(1-nu)/((1+nu)(1-2nu)).

    Graff, Wave Motion in Elastic Solids (1975), ch. 5: c_P = sqrt((lambda + 2 mu)/rho).
    """
    _require(E > 0, "E", "> 0 Pa")
    _require(-1.0 < nu < 0.5, "nu", "in (-1, 0.5) (c_P is infinite at 0.5)")
    _require(rho > 0, "rho", "> 0 kg/m^3")
    return float(np.sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu) * rho)))


def s_wave_speed(E: float, nu: float, rho: float) -> float:
    """S-wave speed [m/s], c_S = sqrt(mu/rho) with mu = E/(2(1+nu)) (Graff 1975, ch. 5)."""
    _require(E > 0, "E", "> 0 Pa")
    _require(-1.0 < nu <= 0.5, "nu", "in (-1, 0.5]")
    _require(rho > 0, "rho", "> 0 kg/m^3")
    return float(np.sqrt(E / (2 * (1 + nu) * rho)))


def column_resonances(H: float, c: float, k_max: int) -> FloatArray:
    """First k_max resonances [Hz] of a layer of depth H [m] on a rigid base, free top.

    One-dimensional quarter-wave column: f_k = (2k-1) c/(4H), k = 1..k_max, with c the P-wave
    speed for vertical (n = 0, u_r = 0 at the outer radius) and the S-wave speed for horizontal
    (n = 1, u_z = 0 at the outer radius) motion; Graff (1975), ch. 1 (string/rod modes).
    """
    _require(H > 0, "H", "> 0 m")
    _require(c > 0, "c", "> 0 m/s")
    _require(int(k_max) == k_max and k_max >= 1, "k_max", "an integer >= 1")
    k = np.arange(1, int(k_max) + 1)
    return (2 * k - 1) * c / (4 * H)


def _rayleigh_ratio_scalar(nu: float) -> float:
    g = (1 - 2 * nu) / (2 * (1 - nu))  # (c_S/c_P)^2

    def f(x: float) -> float:
        return (2 - x**2) ** 2 - 4 * np.sqrt(1 - x**2) * np.sqrt(1 - g * x**2)

    # f(x) ~ -2(1-g) x^2 < 0 near the spurious root x = 0 and f(1) = 1 > 0; the Rayleigh root
    # lies above 0.69 for every nu in (-1, 0.5], so [0.1, 1] brackets it alone.
    return float(brentq(f, 0.1, 1.0, xtol=1e-14, rtol=1e-14))


def rayleigh_speed_ratio(nu: ArrayLike) -> FloatArray:
    """Rayleigh-wave speed over shear-wave speed, c_R/c_S, for Poisson ratio nu in (-1, 0.5].

    Exact root x in (0, 1) of the Rayleigh equation (Graff 1975, sec. 6.3)
        (2 - x^2)^2 = 4 sqrt(1 - x^2) sqrt(1 - g x^2),   g = (1-2nu)/(2(1-nu)).
    0.9326 at nu = 1/3, 0.9516 at nu = 0.47; Viktorov (0.87 + 1.12 nu)/(1 + nu) approximates it.
    """
    nu_arr = np.asarray(nu, dtype=float)
    _require(bool(np.all((nu_arr > -1) & (nu_arr <= 0.5))), "nu", "in (-1, 0.5]")
    flat = [_rayleigh_ratio_scalar(v) for v in nu_arr.ravel()]  # not a hot path
    return np.asarray(flat, dtype=float).reshape(nu_arr.shape)


# --------------------------------------------------------------------------- published table


@dataclass(frozen=True)
class HarmonicPointLoadTable:
    """Harmonic point load on a half-space: surface displacements at r0 = omega r / c_S.

    Entries are mu r u / P (dimensionless), time factor e^{+i omega t} (take the complex
    conjugate for e^{-i omega t}). Vertical load: U_r, U_z. Horizontal unit load in x: the n = 1
    Fourier amplitudes U_r (multiplies cos theta) and U_t (multiplies sin theta).
    """

    nu: float
    accuracy: float
    r0: FloatArray
    Ur_vertical: NDArray[np.complex128]
    Uz_vertical: NDArray[np.complex128]
    Ur_horizontal: NDArray[np.complex128]
    Ut_horizontal: NDArray[np.complex128]


def _frozen(values: list[complex] | list[float]) -> NDArray:
    arr = np.array(values)
    arr.setflags(write=False)
    return arr


APSEL_TABLE = HarmonicPointLoadTable(
    nu=1.0 / 3.0,
    accuracy=0.005,
    r0=_frozen([0.5, 1.0, 2.0, 3.0, 5.0]),
    Ur_vertical=_frozen(
        [-0.0324 + 0.0072j, -0.0333 + 0.0256j, 0.0062 + 0.0610j, 0.0740 + 0.0354j, 0.0052 - 0.1208j]
    ),
    Uz_vertical=_frozen(
        [0.0877 - 0.0618j, 0.0372 - 0.1028j, -0.0875 - 0.0768j, -0.1137 + 0.0534j, 0.1278 + 0.0629j]
    ),
    Ur_horizontal=_frozen(
        [0.1464 - 0.0586j, 0.1113 - 0.1058j, 0.0086 - 0.1369j, -0.0678 - 0.0889j, -0.0519 + 0.0043j]
    ),
    Ut_horizontal=_frozen(
        [
            -0.0906 + 0.0578j,
            -0.0467 + 0.0993j,
            0.0726 + 0.0933j,
            0.1287 - 0.0194j,
            -0.0864 - 0.1294j,
        ]
    ),
)
"""Harmonic point load table, nu = 1/3, stated accuracy about 0.005.

Source: Wong (1975), Caltech EERL 75-01; Apsel (1979), UCSD PhD thesis, Table 5.1.
r0 = omega r / c_S; entries mu r u / P; time factor e^{+i omega t}.
Horizontal entries are the Fourier amplitudes for a horizontal unit load in x: u_r = U_r
cos(theta), u_theta = U_t sin(theta). Static limits (r0 -> 0): U_z = (1-nu)/(2 pi),
U_r = -(1-2nu)/(4 pi) (vertical); U_r = 1/(2 pi), U_t = -(1-nu)/(2 pi) (horizontal).
"""
