"""Model inputs derived from a space: conditional inputs (ring properties used only when the
ring exists) encode the same wherever they do not change the design."""

from __future__ import annotations

import numpy as np

from surrogate.features import input_specs, used_when
from surrogate.runtime.encoding import InputSpec, encode

PARAMS = [
    {"name": "n_rings", "type": "integer", "path": "unit.encapsulation", "map": "list_length",
     "low": 0, "high": 3},
    {"name": "ring_2_E_kPa", "type": "continuous", "path": "unit.encapsulation[1].E_kPa",
     "low": 15.0, "high": 1500.0, "scale": "log"},
    {"name": "ring_nu", "type": "continuous",
     "path": ["unit.encapsulation[0].nu", "unit.encapsulation[2].nu"], "low": 0.45,
     "high": 0.49},
    {"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
     "low": 20.0, "high": 120.0, "scale": "log"},
    {"name": "ring_thickness_mm", "type": "fixed", "path": "unit.ring_thickness_mm",
     "value": 1.0},
]


def test_used_when_follows_the_list_length_parameter():
    assert used_when(PARAMS[1], PARAMS) == ("n_rings", 2.0)
    assert used_when(PARAMS[2], PARAMS) == ("n_rings", 1.0)  # the first ring it writes
    assert used_when(PARAMS[3], PARAMS) is None
    specs = input_specs(PARAMS)
    assert [s.name for s in specs] == ["n_rings", "ring_2_E_kPa", "ring_nu", "skin_E_kPa"]
    assert InputSpec.from_dict(specs[1].to_dict()) == specs[1]


def test_unused_inputs_encode_to_zero_and_used_ones_to_their_scaled_value():
    specs = input_specs(PARAMS)
    codes = np.array([[1, 1500.0, 0.47, 49.0], [1, 15.0, 0.45, 49.0], [2, 1500.0, 0.47, 49.0]])
    feats = encode(codes, specs)
    assert feats[0, 1] == 0.0 and feats[1, 1] == 0.0  # ring 2 absent: same feature
    assert feats[2, 1] == 1.0  # ring 2 present at the top of its range
    assert np.isclose(feats[0, 2], 0.5) and np.isclose(feats[1, 2], 0.0)  # ring 1 exists
