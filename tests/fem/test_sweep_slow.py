"""The sweep's verification at full size (``make test-slow``): every example scene and 40
designs of the default space, 10 of them pogo units with three lightly damped rings (loss
factor 0.02-0.03), against one direct solve per frequency at 1 Hz steps over 100-250 Hz on the
same mesh. Tolerances: magnitudes 0.1 % (relative), phases 1e-3 rad where a component exceeds
1 % of its quantity's largest."""

from __future__ import annotations

import pytest
from sweep_cases import EXAMPLES, MAGNITUDE_TOL, PHASE_TOL, example, space_designs

from fem.sweep import direct_sweep, sweep, sweep_errors

pytestmark = pytest.mark.slow


def _check(scene) -> dict[str, float]:
    rom = sweep(scene)
    err = sweep_errors(rom, direct_sweep(scene))
    assert max(v for k, v in err.items() if k.endswith("magnitude")) <= MAGNITUDE_TOL, err
    assert max(v for k, v in err.items() if k.endswith("phase_rad")) <= PHASE_TOL, err
    assert rom.error_estimate <= rom.tolerance
    return err


@pytest.mark.parametrize("name", EXAMPLES)
def test_every_example_scene(name):
    _check(example(name))


DESIGNS = space_designs(40, n_light_pogo=10)


@pytest.mark.parametrize("label, scene", DESIGNS, ids=[f"design{i}" for i in range(40)])
def test_designs_of_the_default_space(label, scene):
    _check(scene)


def test_the_design_set_holds_ten_lightly_damped_pogo_units():
    light = [s for _, s in DESIGNS if s.unit.attachment == "pogo"
             and len(s.unit.encapsulation) == 3
             and max(r.loss_factor for r in s.unit.encapsulation) <= 0.03]
    assert len(light) >= 10
