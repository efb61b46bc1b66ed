"""Sample identity portable across machines: sampled continuous values are rounded to the
space's significant digits before they are hashed and stored (issue: last-bit differences of
``np.exp`` between platforms changed scene hashes)."""

from __future__ import annotations

import numpy as np

from surrogate.data.parameters import Parameter, round_significant
from surrogate.data.space import SIGNIFICANT_DIGITS, space_from_dict

SPACE = {
    "space": {"name": "p", "seed": 3},
    "base": {"load": {"kind": "patch"}, "analysis": {"kind": "static"},
             "mesh": {"near_size_mm": 2.0, "far_size_mm": 4.0, "order": 1},
             "tissue": {"radius_mm": 20.0}},
    "parameter": [{"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
                   "low": 20.0, "high": 120.0, "scale": "log"}],
}


def test_last_bit_differences_round_to_the_same_value():
    x = np.exp(np.linspace(np.log(20.0), np.log(120.0), 257))
    nudged = np.nextafter(x, np.inf)
    assert np.any(nudged != x)
    assert np.array_equal(round_significant(x, 12), round_significant(nudged, 12))
    assert np.array_equal(round_significant(x, 0), x)


def test_sampled_values_carry_the_stated_digits_and_stay_in_range():
    p = Parameter("e", "continuous", ("tissue.layer[0].E_kPa",), low=20.0, high=120.0,
                  scale="log")
    v = p.from_unit(np.array([0.0, 0.123456789123, 0.999999]), SIGNIFICANT_DIGITS)
    assert all(float(f"{x:.{SIGNIFICANT_DIGITS}g}") == x for x in v)
    assert v[0] == 20.0 and np.all(v <= 120.0)


def test_space_records_digits_and_legacy_spaces_hash_as_before():
    space = space_from_dict(SPACE, check_scenes=False)
    assert space.significant_digits == SIGNIFICANT_DIGITS
    assert space.to_dict()["space"]["significant_digits"] == SIGNIFICANT_DIGITS
    legacy = {**SPACE, "space": {**SPACE["space"], "significant_digits": 0}}
    old = space_from_dict(legacy, check_scenes=False)
    assert "significant_digits" not in old.to_dict()["space"]  # the hash of older datasets
    assert old.space_hash() != space.space_hash()
    a, b = space.points(0, 8)["skin_E_kPa"], old.points(0, 8)["skin_E_kPa"]
    assert np.allclose(a, b, rtol=1e-11) and all(float(f"{x:.12g}") == x for x in a)
