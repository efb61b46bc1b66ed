"""Drive inversion: levels that render a pattern within the bounds, with least leakage."""

from __future__ import annotations

import numpy as np
import pytest

from planner.drive import drive_levels, rendered


def test_without_crosstalk_levels_are_target_over_own_amplitude():
    C = np.diag([10.0, 8.0, 12.0])
    sol = drive_levels(C, np.array([5.0, 8.0, 0.0]))
    np.testing.assert_allclose(sol.levels, [0.5, 1.0, 0.0], atol=1e-9)
    assert sol.max_error_um == pytest.approx(0.0, abs=1e-9)


def test_a_reachable_pattern_is_rendered_exactly_despite_crosstalk():
    C = np.array([[10.0, 3.0], [3.0, 10.0]])
    levels = np.array([0.6, 0.2])
    target = rendered(C, levels)
    sol = drive_levels(C, target)
    np.testing.assert_allclose(sol.levels, levels, atol=1e-9)
    naive = target / np.diag(C)  # ignoring the neighbour overshoots both sites
    assert np.all(rendered(C, naive) > target)


def test_one_site_alone_trades_its_own_level_against_the_leakage():
    C = np.array([[10.0, 4.0, 1.0], [4.0, 10.0, 4.0], [1.0, 4.0, 10.0]])
    sol = drive_levels(C, np.array([0.0, 10.0, 0.0]))
    # By hand: the outer channels stay off (bound); v = u1^2 minimises
    # 2 (16 v / 100)^2 + (v - 1)^2  ->  v = 1 / (1 + 0.0512), the rows scaled by 1 / C_ii^2.
    np.testing.assert_allclose(sol.levels, [0.0, np.sqrt(1 / 1.0512), 0.0], atol=1e-7)
    assert np.all((sol.levels >= 0) & (sol.levels <= 1))


def test_a_pattern_beyond_the_drive_limit_saturates():
    sol = drive_levels(np.diag([10.0, 10.0]), np.array([20.0, 5.0]), max_level=0.8)
    np.testing.assert_allclose(sol.levels, [0.8, 0.5], atol=1e-9)


@pytest.mark.parametrize("target, message", [
    (np.array([1.0]), "one amplitude per site"),
    (np.array([1.0, -1.0]), "finite and >= 0"),
    (np.array([1.0, np.nan]), "finite and >= 0"),
])
def test_bad_patterns_are_refused(target, message):
    with pytest.raises(ValueError, match=message):
        drive_levels(np.eye(2), target)
