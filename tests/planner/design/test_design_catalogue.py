"""One silicone catalogue: the solver's library and the designer read the same numbers."""

from __future__ import annotations

import pytest

from fem.materials import get_material
from planner.design.catalogue import load_catalogue, ring_inputs
from planner.layout import LayoutError
from silicones import read_catalogue


@pytest.mark.parametrize("s", read_catalogue(), ids=lambda s: s.name)
def test_fem_library_and_catalogue_agree(s):
    m = get_material(s.name)
    assert (m.E_Pa, m.density_kg_m3, m.nu, m.loss_factor) == (s.E_Pa, s.density_kg_m3, s.nu,
                                                              s.loss_factor)
    assert all(len(v) > 10 for v in s.sources.values())  # every number has its source
    # the neo-Hookean reading of the 100 % modulus, E = 3 sigma_100 / 1.75 (rounded)
    assert s.E_Pa == pytest.approx(3 * s.modulus_100_Pa / 1.75, rel=0.01)


def test_letters_and_aliases_resolve_as_in_fem():
    cat = load_catalogue(["A", "Dragon Skin 10", "d"])
    assert [s.name for s in cat.chosen] == ["ecoflex-00-10", "dragon-skin-10-medium",
                                            "dragon-skin-30"]  # by increasing modulus
    for key in ("A", "Dragon Skin 10", "d"):
        assert cat.lookup(key).name == get_material(key).name


def test_ring_inputs_mean_the_shared_properties():
    cat = load_catalogue()
    a, d = cat.lookup("A"), cat.lookup("D")
    x = ring_inputs([a, d], unused_E_kPa=50.0)
    assert (x["ring_1_E_kPa"], x["ring_2_E_kPa"], x["ring_3_E_kPa"]) == (95.0, 1016.0, 50.0)
    assert x["ring_density_kg_m3"] == pytest.approx(1060.0)


def test_unknown_silicone_is_refused_with_the_known_ones():
    with pytest.raises(LayoutError) as err:
        load_catalogue(["glass"], "space.catalogue")
    assert err.value.field == "space.catalogue[0]" and "ecoflex-00-30" in str(err.value)
