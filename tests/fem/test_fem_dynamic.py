"""Dynamic verification: column resonances, the published harmonic half-space table, and the
absorbing boundary's independence of where it is placed."""

import dataclasses

import analytic
import numpy as np
import pytest
from fem_cases import half_space_solid

from fem import simulate
from fem.assembly import UR, UZ
from fem.domain import MeshSpec, layered_domain
from fem.loads import axis_point_force
from fem.materials import Material
from fem.scene import load_scene, scene_from_dict, scene_to_dict
from fem.solve import natural_modes, solve_mode

EXAMPLE = "examples/forearm.toml"


def _column(mode, roller_component, nu=0.47):
    """A 10 mm soft layer on a rigid base, 2.5 mm radius, roller side."""
    solid = Material("skin", 49e3, 1116.0, nu)
    spec = MeshSpec(near_size=0.5e-3, near_radius=1e-3, far_size=0.5e-3, order=2)
    d = layered_domain([(10e-3, solid)], 2.5e-3, "free", "fixed", spec, "static")
    side = d.boundary_nodes("side")
    return dataclasses.replace(d, constraints=(*d.constraints, (side, roller_component))), solid


@pytest.mark.parametrize(("mode", "roller", "speed"), [(0, UR, "p"), (1, UZ, "s")])
def test_layer_on_rigid_base_column_resonances(mode, roller, speed):
    d, s = _column(mode, roller)
    H = 10e-3
    c = (analytic.p_wave_speed(s.E_Pa, s.nu, s.density_kg_m3) if speed == "p"
         else analytic.s_wave_speed(s.E_Pa, s.nu, s.density_kg_m3))
    for f_exact in analytic.column_resonances(H, c, 3):
        freqs, shapes = natural_modes(d, mode, k=4, sigma_hz=0.98 * f_exact)
        k = np.argmin(np.abs(freqs - f_exact))
        assert freqs[k] == pytest.approx(f_exact, rel=0.005)
        U = d.mesh.nodes  # the matched mode is a column mode: uniform across the radius
        shape = shapes[:, k].reshape(U.shape[0], -1)
        moving = UZ if mode == 0 else UR
        top = np.isclose(U[:, 1], 0.0)
        assert np.ptp(shape[top, moving]) < 1e-6 * np.abs(shape[:, moving]).max()


@pytest.fixture(scope="module")
def apsel_solutions():
    """Homogeneous half-space, nu = 1/3, mu = rho = 1 (c_S = 1), omega = 1, PML side and base."""
    solid = half_space_solid(1.0 / 3.0)
    spec = MeshSpec(near_size=0.1, near_radius=1.0, far_size=0.5, order=2)
    d = layered_domain([(8.0, solid)], 8.0, "absorbing", "absorbing", spec, "harmonic", 1.0)
    out = {}
    for mode in (0, 1):
        sol = solve_mode(d, mode, axis_point_force(d, mode, 1.0), omega=1.0)
        nodes = d.surface_nodes()
        out[mode] = (d.mesh.nodes[nodes, 0], sol.nodal()[nodes])
    return out


@pytest.mark.parametrize(("mode", "component", "entry"), [
    (0, UR, "Ur_vertical"), (0, UZ, "Uz_vertical"),
    (1, UR, "Ur_horizontal"), (1, 2, "Ut_horizontal"),
])
def test_harmonic_point_load_matches_published_table(apsel_solutions, mode, component, entry):
    table = analytic.APSEL_TABLE
    r, U = apsel_solutions[mode]
    r0 = table.r0  # omega = c_S = 1, so r = r0
    value = np.interp(r0, r, U[:, component].real) + 1j * np.interp(r0, r, U[:, component].imag)
    assert np.abs(r0 * value - getattr(table, entry)).max() < table.accuracy


@pytest.mark.parametrize("direction", ["tangential", "normal"])
def test_moving_the_absorbing_boundary_does_not_move_the_answer(direction):
    base = scene_to_dict(load_scene(EXAMPLE))
    base["load"]["direction"] = direction
    base["output"]["radii_mm"] = list(np.arange(0.0, 20.5, 2.0))
    amps = []
    for radius in (50.0, 80.0):
        d = {**base, "tissue": {**base["tissue"], "radius_mm": radius}}
        res = simulate(scene_from_dict(d))
        amps.append(np.sqrt(np.sum(np.abs(res.U) ** 2, axis=1)))
    assert np.max(np.abs(amps[0] / amps[1] - 1)) < 0.02


def test_harmonic_at_low_frequency_tends_to_static():
    """At 1 Hz the wavelength is metres: the harmonic answer must approach the static one,
    which checks the quasi-static far-field extension in front of the PML."""
    base = scene_to_dict(load_scene(EXAMPLE))
    base["load"]["direction"] = "normal"
    res = {}
    for kind in ("static", "harmonic"):
        d = {**base, "analysis": {"kind": kind, "frequency_hz": 1.0}}
        res[kind] = simulate(scene_from_dict(d))
    s, h = (np.abs(res[k].U[:, 1]) for k in ("static", "harmonic"))
    assert np.allclose(h, s, rtol=0.01)
