"""Checks of the closed-form references in analytic.py against each other and known limits.

Nothing here calls the FE solver. Independent evidence comes from: finite-difference checks of
the Navier equations, traction-free surfaces and load resultants; quadrature of the point-load
solutions over loaded discs; Betti reciprocity; exact classical values.
"""

from __future__ import annotations

from collections.abc import Callable

import analytic as an
import numpy as np
import pytest
from scipy import integrate

MU, NU = 1.3e3, 0.3  # Pa, -; arbitrary but not 1 so wrong mu powers show up
Field = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


# --------------------------------------------------------------------------- helpers


def _cerruti_cartesian(x, y, z, Q, mu, nu):
    """Johnson (1985) ch. 3 Cerruti field, transcribed independently of tests/fem/analytic.py."""
    rho = np.sqrt(x**2 + y**2 + z**2)
    c, k = Q / (4 * np.pi * mu), 1 - 2 * nu
    u_x = c * (1 / rho + x**2 / rho**3 + k * (1 / (rho + z) - x**2 / (rho * (rho + z) ** 2)))
    u_y = c * (x * y / rho**3 - k * x * y / (rho * (rho + z) ** 2))
    u_z = c * (x * z / rho**3 + k * x / (rho * (rho + z)))
    return np.stack([u_x, u_y, u_z])


def _boussinesq_cartesian(x, y, z, P, mu, nu):
    r = np.hypot(x, y)
    u_r, u_z = an.boussinesq(r, z, P, mu, nu)
    r_safe = np.where(r > 0, r, 1.0)  # u_r = 0 on the axis
    return np.stack([u_r * x / r_safe, u_r * y / r_safe, u_z])


def _stress(field: Field, mu: float, nu: float, h: float) -> Field:
    """Cauchy stress (3, 3, N) of a displacement field by central differences, step h [m]."""
    lam = 2 * mu * nu / (1 - 2 * nu)

    def sigma(x, y, z):
        grad = np.stack(
            [
                (
                    field(x + h * e[0], y + h * e[1], z + h * e[2])
                    - field(x - h * e[0], y - h * e[1], z - h * e[2])
                )
                / (2 * h)
                for e in np.eye(3)
            ],
            axis=1,
        )  # grad[i, j] = d u_i / d x_j
        eps = 0.5 * (grad + grad.transpose(1, 0, *range(2, grad.ndim)))
        return lam * np.trace(eps)[None, None] * np.eye(3)[..., None] + 2 * mu * eps

    return sigma


def _div(tensor: Field, x, y, z, h: float) -> np.ndarray:
    out = 0.0
    for j, e in enumerate(np.eye(3)):
        plus = tensor(x + h * e[0], y + h * e[1], z + h * e[2])[:, j]
        minus = tensor(x - h * e[0], y - h * e[1], z - h * e[2])[:, j]
        out = out + (plus - minus) / (2 * h)
    return out


def _disc_quad(kernel, r: float, theta: float, a: float, epsabs: float = 0.0) -> float:
    """Integral over the disc |x'| <= a of kernel(s, phi) dA', with polar coordinates (s, phi)
    centered on the field point x = r(cos theta, sin theta): x' = x + s (cos phi, sin phi).
    dA' = s ds dphi removes the 1/s singularity of point-load kernels."""

    def bounds(phi):
        c = r * np.cos(phi - theta)
        disc = a**2 - r**2 * np.sin(phi - theta) ** 2
        root = np.sqrt(max(disc, 0.0))
        return max(0.0, -c - root), max(0.0, -c + root)

    if r > a:  # the disc is seen from outside under |phi - (theta + pi)| < asin(a/r)
        half = np.arcsin(a / r)
        lo_phi, hi_phi = theta + np.pi - half, theta + np.pi + half
    else:
        lo_phi, hi_phi = 0.0, 2 * np.pi
    val, _ = integrate.dblquad(
        lambda s, phi: kernel(s, phi) * s,
        lo_phi,
        hi_phi,
        lambda phi: bounds(phi)[0],
        lambda phi: bounds(phi)[1],
        epsabs=epsabs,
        epsrel=1e-10,
    )
    return val


def _cerruti_surface_xyz(s, phi, Q, mu, nu):
    """Cartesian surface displacement at x from a load Q (+x) at x' = x + s e_phi."""
    U_r, U_t, U_z = an.cerruti(s, 0.0, Q, mu, nu)
    alpha = phi + np.pi  # polar angle of x - x'
    ca, sa = np.cos(alpha), np.sin(alpha)
    return U_r * ca**2 - U_t * sa**2, (U_r + U_t) * sa * ca, U_z * ca


# --------------------------------------------------------------------------- point loads


def test_boussinesq_surface_limits():
    r = np.array([1e-3, 0.02, 0.5, 7.0])
    u_r, u_z = an.boussinesq(r, 0.0, 2.0, MU, NU)
    np.testing.assert_allclose(u_z, 2.0 * (1 - NU) / (2 * np.pi * MU * r), rtol=1e-13)
    np.testing.assert_allclose(u_r, -2.0 * (1 - 2 * NU) / (4 * np.pi * MU * r), rtol=1e-13)


def test_boussinesq_on_axis_and_broadcast():
    z = np.array([0.1, 1.0, 3.0])
    u_r, u_z = an.boussinesq(0.0, z, 1.0, MU, NU)
    np.testing.assert_array_equal(u_r, 0.0)
    # Johnson: on the axis u_z = P (3 - 2 nu) / (4 pi mu z)
    np.testing.assert_allclose(u_z, (3 - 2 * NU) / (4 * np.pi * MU * z), rtol=1e-13)
    u_r, u_z = an.boussinesq(np.linspace(0.1, 1, 4)[:, None], z[None, :], 1.0, MU, NU)
    assert u_r.shape == u_z.shape == (4, 3)


def test_cerruti_surface_limits():
    r = np.array([1e-3, 0.02, 0.5, 7.0])
    Q = 3.0
    U_r, U_t, U_z = an.cerruti(r, 0.0, Q, MU, NU)
    np.testing.assert_allclose(U_r, Q / (2 * np.pi * MU * r), rtol=1e-13)
    np.testing.assert_allclose(U_t, -Q * (1 - NU) / (2 * np.pi * MU * r), rtol=1e-13)
    np.testing.assert_allclose(U_z, (1 - 2 * NU) * Q / (4 * np.pi * MU * r), rtol=1e-13)


@pytest.mark.parametrize("z", [0.0, 0.3, 2.0])
def test_cerruti_amplitudes_reproduce_cartesian_field(z):
    r = np.array([0.05, 0.4, 1.0, 3.0])[:, None]
    theta = np.array([0.0, np.pi / 6, np.pi / 2, 2.0, np.pi, 4.5])[None, :]
    U_r, U_t, U_z = an.cerruti(r, z, 1.7, MU, NU)
    u = _cerruti_cartesian(r * np.cos(theta), r * np.sin(theta), z, 1.7, MU, NU)
    u_r = u[0] * np.cos(theta) + u[1] * np.sin(theta)
    u_t = -u[0] * np.sin(theta) + u[1] * np.cos(theta)
    scale = np.abs(U_r)
    np.testing.assert_allclose(u_r, U_r * np.cos(theta), rtol=0, atol=1e-12 * scale.max())
    np.testing.assert_allclose(u_t, U_t * np.sin(theta), rtol=0, atol=1e-12 * scale.max())
    np.testing.assert_allclose(u[2], U_z * np.cos(theta), rtol=0, atol=1e-12 * scale.max())


def test_betti_reciprocity_between_surface_point_loads():
    # P u_z(origin | Q at (r, 0)) = Q u_x((r, 0) | P at origin): the origin sits at theta = pi
    # from the tangential load, so -U_z(r) = u_r(r) per unit loads.
    r = np.array([0.01, 0.3, 4.0])
    u_r, _ = an.boussinesq(r, 0.0, 1.0, MU, NU)
    _, _, U_z = an.cerruti(r, 0.0, 1.0, MU, NU)
    np.testing.assert_allclose(-U_z, u_r, rtol=1e-13)


_POINTS = np.array(
    [[0.6, 0.3, 0.5], [0.2, -0.7, 0.9], [-0.5, 0.4, 0.2], [0.1, 0.1, 1.2], [-0.8, -0.9, 0.35]]
).T


@pytest.mark.parametrize("nu", [0.25, 0.47])
@pytest.mark.parametrize("which", ["boussinesq", "cerruti"])
def test_point_load_fields_satisfy_navier(which, nu):
    make = _boussinesq_cartesian if which == "boussinesq" else _cerruti_cartesian
    field = lambda x, y, z: make(x, y, z, 1.0, MU, nu)  # noqa: E731
    h = 2e-4  # the FD residual falls like h^2 (about 1e-5 relative here at nu = 0.47)
    sigma = _stress(field, MU, nu, h)
    residual = _div(sigma, *_POINTS, h)
    scale = np.abs(sigma(*_POINTS)).max(axis=(0, 1)) / np.linalg.norm(_POINTS, axis=0)
    assert np.all(np.abs(residual) < 2e-5 * scale)


@pytest.mark.parametrize("which", ["boussinesq", "cerruti"])
def test_point_load_surface_is_traction_free(which):
    make = _boussinesq_cartesian if which == "boussinesq" else _cerruti_cartesian
    field = lambda x, y, z: make(x, y, z, 1.0, MU, NU)  # noqa: E731
    h = 1e-5
    x, y = np.array([0.3, -0.2, 1.0, 0.05]), np.array([0.4, 0.5, -1.5, 0.0])
    sigma = _stress(field, MU, NU, h)
    # FD needs z - h >= 0: extrapolate linearly to z = 0 from z = 2h and 4h (error O(z^2)).
    sig = 2 * sigma(x, y, np.full_like(x, 2 * h)) - sigma(x, y, np.full_like(x, 4 * h))
    scale = np.abs(sig).max(axis=(0, 1))  # in-plane stresses are O(P/r^2) on the surface
    assert np.all(scale * (x**2 + y**2) > 1e-3)
    assert np.all(np.abs(sig[2]) < 1e-5 * scale)


def test_point_load_resultants():
    # Slab 0 < z < 1: the applied load plus the traction sigma . e_z on z = 1 must balance.
    h = 1e-4
    bous = _stress(lambda x, y, z: _boussinesq_cartesian(x, y, z, 1.0, MU, NU), MU, NU, h)
    cerr = _stress(lambda x, y, z: _cerruti_cartesian(x, y, z, 1.0, MU, NU), MU, NU, h)
    one = np.ones(1)

    def fz(r):
        return bous(r * one, 0 * one, one)[2, 2, 0] * 2 * np.pi * r

    def fx(r):  # n = 1: sigma_zx = A cos^2 + B sin^2, so its theta integral is pi (A + B)
        a = cerr(r * one, 0 * one, one)[0, 2, 0]
        b = cerr(0 * one, r * one, one)[0, 2, 0]
        return np.pi * (a + b) * r

    Fz = integrate.quad(fz, 0, np.inf, epsabs=1e-10, limit=200)[0]
    Fx = integrate.quad(fx, 0, np.inf, epsabs=1e-10, limit=200)[0]
    assert Fz == pytest.approx(-1.0, rel=1e-6)
    assert Fx == pytest.approx(-1.0, rel=1e-6)


# --------------------------------------------------------------------------- loaded discs

A_DISC = 2e-3  # m


def test_uniform_pressure_center_edge_and_johnson_form():
    p = 500.0
    E = 2 * MU * (1 + NU)
    w0 = p * A_DISC * (1 - NU) / MU
    w = an.uniform_pressure_surface(np.array([0.0, A_DISC]), p, A_DISC, MU, NU)
    np.testing.assert_allclose(w, [w0, 2 * w0 / np.pi], rtol=1e-13)
    np.testing.assert_allclose(w0, 2 * (1 - NU**2) * p * A_DISC / E, rtol=1e-13)


def test_uniform_load_continuity_at_edge_and_far_field():
    a, p = A_DISC, 1.0
    r = a * np.array([1 - 1e-9, 1.0, 1 + 1e-9])
    w = an.uniform_pressure_surface(r, p, a, MU, NU)
    ur = an.uniform_pressure_surface_radial(r, p, a, MU, NU)
    shear = an.uniform_shear_surface(r, p, a, MU, NU)
    for f in (w, ur, *shear):
        np.testing.assert_allclose(f, f[1], rtol=1e-6)
    # Far away the disc acts as a point load of p pi a^2 (correction O((a/r)^2)).
    far = 100 * a
    P = p * np.pi * a**2
    u_r, u_z = an.boussinesq(far, 0.0, P, MU, NU)
    assert an.uniform_pressure_surface(far, p, a, MU, NU) == pytest.approx(u_z, rel=2e-5)
    assert an.uniform_pressure_surface_radial(far, p, a, MU, NU) == pytest.approx(u_r, rel=1e-12)
    np.testing.assert_allclose(
        an.uniform_shear_surface(far, p, a, MU, NU), an.cerruti(far, 0.0, P, MU, NU), rtol=5e-5
    )


@pytest.mark.parametrize("r_over_a", [0.0, 0.5, 0.9, 1.1, 2.0])
def test_uniform_pressure_matches_boussinesq_quadrature(r_over_a):
    a, p, r = A_DISC, 700.0, r_over_a * A_DISC

    def kz(s, phi):
        return p * an.boussinesq(s, 0.0, 1.0, MU, NU)[1]

    def kr(s, phi):  # u_r(s) points from the source to the field point, i.e. along -e_phi
        return p * an.boussinesq(s, 0.0, 1.0, MU, NU)[0] * -np.cos(phi)

    tol = 1e-12 * p * a / MU  # absolute floor: u_r vanishes at r = 0
    w_ref = _disc_quad(kz, r, 0.0, a, epsabs=tol)
    assert an.uniform_pressure_surface(r, p, a, MU, NU) == pytest.approx(w_ref, rel=1e-4)
    ur = an.uniform_pressure_surface_radial(r, p, a, MU, NU)
    if r == 0:
        assert ur == 0.0 and abs(_disc_quad(kr, r, 0.0, a, epsabs=tol)) < 1e-9 * w_ref
    else:
        assert ur == pytest.approx(_disc_quad(kr, r, 0.0, a, epsabs=tol), rel=1e-4)


@pytest.mark.parametrize("r_over_a", [0.0, 0.3, 0.7, 1.5, 3.0])
@pytest.mark.parametrize("nu", [0.0, 0.3, 0.49])
def test_uniform_shear_matches_cerruti_quadrature(r_over_a, nu):
    a, q, r = A_DISC, 250.0, r_over_a * A_DISC
    U_r, U_t, U_z = an.uniform_shear_surface(r, q, a, MU, nu)

    def comp(i):
        return lambda s, phi: q * _cerruti_surface_xyz(s, phi, 1.0, MU, nu)[i]

    def quad(i, theta):  # epsabs: u_y vanishes identically for nu = 0
        return _disc_quad(comp(i), r, theta, a, epsabs=1e-12 * q * a / MU)

    # theta = 0: u_r = u_x = U_r, u_z = U_z; theta = pi/2: u_theta = -u_x = U_t.
    assert U_r == pytest.approx(quad(0, 0.0), rel=1e-4)
    assert U_t == pytest.approx(-quad(0, np.pi / 2), rel=1e-4)
    uz = quad(2, 0.0)
    if r == 0:
        assert U_z == 0.0 and abs(uz) < 1e-10 * U_r
    else:
        assert U_z == pytest.approx(uz, rel=1e-4)
    # theta = pi/4 checks the cos/sin structure of the superposed field too.
    c = np.sqrt(0.5)
    ux, uy = quad(0, np.pi / 4), quad(1, np.pi / 4)
    scale = abs(U_r) + abs(U_t)
    assert (ux + uy) * c == pytest.approx(U_r * c, abs=1e-4 * scale)
    assert (uy - ux) * c == pytest.approx(U_t * c, abs=1e-4 * scale)


def test_uniform_shear_small_radius_series_is_continuous():
    # The center uses a series for H(m)/m below m = 1e-6 (r = 1e-3 a); both sides must agree.
    r = 1e-3 * A_DISC * np.array([1 - 1e-9, 1 + 1e-9])
    U_r, U_t, _ = an.uniform_shear_surface(r, 1.0, A_DISC, MU, NU)  # U_z ~ r: excluded
    for f in (U_r, U_t):
        np.testing.assert_allclose(f[0], f[1], rtol=5e-9)


def test_uniform_shear_center_satisfies_axis_condition():
    U_r, U_t, U_z = an.uniform_shear_surface(0.0, 1.0, A_DISC, MU, NU)
    assert U_r == pytest.approx(-U_t, rel=1e-13)
    assert U_r == pytest.approx((2 - NU) * A_DISC / (2 * MU), rel=1e-13)
    assert U_z == 0.0


# --------------------------------------------------------------------------- rigid disc


def _sqrt_edge_quad(density, kernel, r, theta, a):
    """Integral over the disc of density(x', y') / sqrt(a^2 - |x'|^2) * kernel(s, phi) dA', for
    an interior field point; the edge singularity is handled by quad's algebraic weight."""

    def inner(phi):
        c = r * np.cos(phi - theta)
        root = np.sqrt(a**2 - r**2 * np.sin(phi - theta) ** 2)
        s_lo, s_hi = -c - root, -c + root  # a^2 - |x'|^2 = (s_hi - s)(s - s_lo)

        def f(s):
            xp, yp = r * np.cos(theta) + s * np.cos(phi), r * np.sin(theta) + s * np.sin(phi)
            return density(xp, yp) * kernel(s, phi) * s / np.sqrt(s - s_lo)

        return integrate.quad(f, 0.0, s_hi, weight="alg", wvar=(0.0, -0.5), epsabs=0)[0]

    return integrate.quad(inner, 0.0, 2 * np.pi, epsabs=0, epsrel=1e-10, limit=200)[0]


@pytest.mark.parametrize("nu", [0.2, 0.45])
def test_rigid_disc_stiffness_from_punch_tractions(nu):
    a, F = A_DISC, 1.0
    k = an.rigid_disc_stiffness(MU, nu, a)
    for r, theta in [(0.0, 0.0), (0.4 * a, 0.0), (0.8 * a, 1.0), (0.6 * a, np.pi / 2)]:
        # Flat punch: p = P / (2 pi a sqrt(a^2 - r^2)) gives a uniform settlement P / K_v.
        w = _sqrt_edge_quad(
            lambda x, y: F / (2 * np.pi * a),
            lambda s, phi: an.boussinesq(s, 0.0, 1.0, MU, nu)[1],
            r,
            theta,
            a,
        )
        assert w == pytest.approx(F / k["vertical"], rel=1e-6)
        # Same shape of tangential traction: uniform u_x = Q / K_h (Johnson, Mindlin).
        ux = _sqrt_edge_quad(
            lambda x, y: F / (2 * np.pi * a),
            lambda s, phi: _cerruti_surface_xyz(s, phi, 1.0, MU, nu)[0],
            r,
            theta,
            a,
        )
        assert ux == pytest.approx(F / k["horizontal"], rel=1e-6)
    for r, theta in [(0.3 * a, 0.0), (0.8 * a, 0.5), (0.5 * a, np.pi)]:
        # Rocking: p = 3 M x / (2 pi a^3 sqrt(a^2 - r^2)) gives w = (M / K_r) x.
        w = _sqrt_edge_quad(
            lambda x, y: 3 * F * x / (2 * np.pi * a**3),
            lambda s, phi: an.boussinesq(s, 0.0, 1.0, MU, nu)[1],
            r,
            theta,
            a,
        )
        assert w == pytest.approx(F / k["rocking"] * r * np.cos(theta), rel=1e-6)


def test_rigid_disc_vs_uniform_pressure_energy_bound():
    # For equal total force, the rigid punch minimises the work integral p w dA, so its
    # settlement is below the mean deflection under uniform pressure.
    a, P = A_DISC, 1.0
    p = P / (np.pi * a**2)
    mean_w = integrate.quad(
        lambda r: an.uniform_pressure_surface(r, p, a, MU, NU) * 2 * np.pi * r,
        0,
        a,
        epsabs=0,
        epsrel=1e-12,
        limit=200,
    )[0] / (np.pi * a**2)
    rigid = P / an.rigid_disc_stiffness(MU, NU, a)["vertical"]
    assert rigid < mean_w < 1.1 * rigid
    assert mean_w == pytest.approx(8 * (1 - NU) * p * a / (3 * np.pi * MU), rel=1e-8)


def test_rigid_disc_stiffness_values():
    k = an.rigid_disc_stiffness(2.0, 0.5, 0.1)
    assert k == pytest.approx(
        {"vertical": 1.6, "horizontal": 1.6 / 1.5 * 1.0, "rocking": 8 * 2.0 * 1e-3 / 1.5}
    )
