"""The crosstalk model and the pitch search on profiles whose answer is known by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.crosstalk import UnitField, crosstalk_matrix, leakage_ratio, site_positions
from planner.layout import layout_from_dict
from planner.optimise import PITCH_TOL_MM, smallest_pitch

EDGE, L, C, R0 = 3.5, 4.0, 10.0, 0.8  # edge radius mm, decay length mm, center um, edge/center


def exponential_unit() -> UnitField:
    """A(d) = C R0 exp(-d / L) at distance d from the edge, sampled on 0-20 mm."""
    grid = np.linspace(0.0, 20.0, 21)
    return UnitField(C, EDGE, grid, C * R0 * np.exp(-grid / L))


def request(rows: int, cols: int, superposition: str, max_ratio: float, grid: str = "square"):
    return layout_from_dict({
        "array": {"rows": rows, "cols": cols, "grid": grid, "min_pitch_mm": 1.0,
                  "max_pitch_mm": 200.0},
        "criterion": {"max_ratio": max_ratio, "superposition": superposition},
        "design": [{"name": "x"}]})


def test_exponential_profile_is_exact_inside_and_beyond_the_grid():
    f = exponential_unit()
    r = np.array([EDGE, EDGE + 7.3, EDGE + 20.0, EDGE + 55.0])
    np.testing.assert_allclose(f.amplitude(r), C * R0 * np.exp(-(r - EDGE) / L), rtol=1e-9)


def test_two_units_one_neighbour_pitch_by_hand():
    # R0 exp(-(p - EDGE) / L) = 0.05  ->  p = EDGE + L ln(R0 / 0.05)
    p = smallest_pitch(exponential_unit(), request(1, 2, "worst", 0.05))
    assert p == pytest.approx(EDGE + L * math.log(R0 / 0.05), abs=PITCH_TOL_MM)


def test_a_row_of_three_powers_add_at_the_middle_site():
    # middle site: sqrt(2) A(p) dominates the ends' sqrt(A(p)^2 + A(2p)^2)
    p = smallest_pitch(exponential_unit(), request(1, 3, "incoherent", 0.05))
    assert p == pytest.approx(EDGE + L * math.log(math.sqrt(2) * R0 / 0.05), abs=PITCH_TOL_MM)


def test_units_never_overlap_and_infeasible_is_none():
    f = exponential_unit()
    assert smallest_pitch(f, request(1, 2, "worst", 0.9)) == pytest.approx(2 * EDGE)
    req = layout_from_dict({"array": {"rows": 1, "cols": 2, "min_pitch_mm": 1.0,
                                      "max_pitch_mm": 8.0},
                            "criterion": {"max_ratio": 0.01}, "design": [{"name": "x"}]})
    assert smallest_pitch(f, req) is None


def test_the_envelope_is_conservative_and_monotone():
    grid = np.linspace(0.0, 20.0, 21)
    rippled = 5.0 * np.exp(-grid / 6.0) * (1.0 + 0.5 * np.cos(grid))  # troughs and crests
    f = UnitField(10.0, 2.0, grid, rippled)
    r = np.linspace(2.0, 40.0, 400)
    a = f.amplitude(r)
    assert np.all(np.diff(a) <= 1e-12)  # never grows with distance
    inside = r <= 22.0  # on the grid: never below the raw profile (log-linear interpolation)
    raw = np.exp(np.interp(r[inside] - 2.0, grid, np.log(rippled)))
    assert np.all(a[inside] >= raw * (1 - 1e-12))
    assert a[inside][0] == pytest.approx(rippled.max())  # the crest ahead counts from the edge


def test_hex_neighbours_are_all_one_pitch_away():
    pos = site_positions(3, 3, 10.0, "hex")
    d = np.linalg.norm(pos[:, None] - pos[None], axis=2)
    nearest = np.sort(d, axis=1)[:, 1]
    np.testing.assert_allclose(nearest, 10.0)
    centre = 4  # row 1, col 1: six neighbours at one pitch
    assert np.sum(np.isclose(d[centre], 10.0)) == 6


def test_crosstalk_matrix_is_symmetric_with_own_amplitude_on_the_diagonal():
    f = exponential_unit()
    C_ = crosstalk_matrix(f, site_positions(2, 3, 12.0, "square"))
    np.testing.assert_allclose(C_, C_.T)
    np.testing.assert_allclose(np.diag(C_), C)
    ratios = leakage_ratio(C_, "incoherent")
    assert ratios.shape == (6,) and np.all(ratios > 0)
