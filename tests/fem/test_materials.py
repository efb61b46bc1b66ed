"""Material library: lookup, provenance, and elastic identities."""

from __future__ import annotations

import dataclasses
import math

import pytest

from fem.materials import (
    MATERIALS,
    Material,
    SILICONE_E_TENSILE_FIT_Pa,
    SILICONE_MODULUS_100_Pa,
    UnknownMaterialError,
    get_material,
    material_from_fields,
)

# Guo et al. 2025 (Biomimetics 10:597) Table 1: E [kPa], density [kg/m3], nu.
PAPER_TISSUE = {
    "skin": (49.0, 1116.0, 0.47),
    "subcutaneous": (10.0, 1116.0, 0.47),
    "muscle": (53.0, 1116.0, 0.47),
    "bone": (2.94e6, 2000.0, 0.32),
}
# Smooth-On datasheets: specific gravity, 100 % modulus [kPa],
# and the two published small-strain E estimates [kPa].
DATASHEET = {
    "ecoflex-00-10": (1.04, 55.0, 95.0, 21.0),
    "ecoflex-00-50": (1.07, 83.0, 142.0, 59.0),
    "dragon-skin-10-medium": (1.07, 152.0, 260.0, 129.0),
    "dragon-skin-30": (1.08, 593.0, 1016.0, 538.0),
}


@pytest.mark.parametrize("name", sorted(PAPER_TISSUE))
def test_tissue_values_match_paper(name: str) -> None:
    E_kPa, rho, nu = PAPER_TISSUE[name]
    m = get_material(name)
    assert m.E_Pa == pytest.approx(E_kPa * 1e3)
    assert (m.density_kg_m3, m.nu) == (rho, nu)
    assert "Guo" in m.source and "Table 1" in m.source


@pytest.mark.parametrize("name", sorted(DATASHEET))
def test_silicones_follow_datasheet(name: str) -> None:
    sg, s100_kPa, e_nh_kPa, e_fit_kPa = DATASHEET[name]
    m = get_material(name)
    assert m.density_kg_m3 == pytest.approx(sg * 1000.0)
    assert m.E_Pa == pytest.approx(e_nh_kPa * 1e3)  # default: neo-Hookean estimate
    assert SILICONE_E_TENSILE_FIT_Pa[name] == pytest.approx(e_fit_kPa * 1e3)
    assert SILICONE_MODULUS_100_Pa[name] == pytest.approx(s100_kPa * 1e3)
    # Independent check of the neo-Hookean reading: incompressible uniaxial nominal stress at
    # stretch 2 is mu (2 - 1/4), and E = 3 mu; the published values are rounded.
    assert m.E_Pa == pytest.approx(3.0 * s100_kPa * 1e3 / 1.75, rel=0.015)
    assert m.nu == 0.49
    assert f"{e_nh_kPa:g} kPa" in m.source and f"{e_fit_kPa:g} kPa" in m.source


def test_every_material_cites_a_source() -> None:
    for key, m in MATERIALS.items():
        assert key == m.name == m.name.lower()
        assert len(m.source) > 10, key


@pytest.mark.parametrize(
    ("query", "canonical"),
    [
        ("skin", "skin"),
        ("SKIN", "skin"),
        ("  Muscle ", "muscle"),
        ("fat", "subcutaneous"),
        ("Fat", "subcutaneous"),
        ("A", "ecoflex-00-10"),
        ("a", "ecoflex-00-10"),
        ("ecoflex 00-10", "ecoflex-00-10"),
        ("Ecoflex-00-10", "ecoflex-00-10"),
        ("B", "ecoflex-00-50"),
        ("C", "dragon-skin-10-medium"),
        ("dragon skin 10", "dragon-skin-10-medium"),
        ("Dragon Skin 10 Medium", "dragon-skin-10-medium"),
        ("D", "dragon-skin-30"),
        ("dragon_skin_30", "dragon-skin-30"),
        ("PCB", "pcb"),
        ("motor", "motor"),
    ],
)
def test_lookup_by_name_alias_and_case(query: str, canonical: str) -> None:
    assert get_material(query) is MATERIALS[canonical]


def test_unknown_material_lists_choices() -> None:
    with pytest.raises(UnknownMaterialError) as info:
        get_material("unobtainium")
    err = info.value
    assert isinstance(err, ValueError) and isinstance(err, KeyError)
    msg = str(err)
    assert "unobtainium" in msg
    for name in MATERIALS:
        assert name in msg
    assert not msg.startswith("'")  # not KeyError's repr-quoting


def test_pcb_and_motor_entries() -> None:
    pcb, motor = get_material("pcb"), get_material("motor")
    assert (pcb.E_Pa, pcb.density_kg_m3, pcb.nu) == (2.5e9, 1420.0, 0.34)
    assert "Kapton" in pcb.source
    assert (motor.E_Pa, motor.density_kg_m3, motor.nu) == (100e9, 7800.0, 0.3)
    assert "estimate" in motor.source


def test_elastic_identities() -> None:
    for m in MATERIALS.values():
        mu, lam, K = m.mu_Pa, m.lambda_Pa, m.bulk_Pa
        assert m.E_Pa == pytest.approx(9 * K * mu / (3 * K + mu))
        assert lam + 2 * mu == pytest.approx(K + 4 * mu / 3)
        ratio = m.pressure_speed_m_s / m.shear_speed_m_s
        assert ratio == pytest.approx(math.sqrt(2 * (1 - m.nu) / (1 - 2 * m.nu)))


def test_wave_speeds_match_design_notes() -> None:
    # skin (49 kPa, nu 0.47, 1116 kg/m3): c_S = sqrt(E / (2 (1 + nu) rho)), about 3.8 m/s.
    assert get_material("skin").shear_speed_m_s == pytest.approx(3.8, rel=0.03)
    # ... and c_P / c_S is about 7 at nu = 0.49.
    m = get_material("A")
    assert m.pressure_speed_m_s / m.shear_speed_m_s == pytest.approx(7.0, rel=0.03)


def test_material_from_fields_converts_kPa() -> None:
    m = material_from_fields(E_kPa=355.0, density_kg_m3=1000.0, nu=0.47, loss_factor=0.1,
                             name="table3")
    assert m == Material("table3", 355e3, 1000.0, 0.47, 0.1, "user-defined")


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"E_kPa": 0.0}, "E_Pa"),
        ({"density_kg_m3": -1.0}, "density_kg_m3"),
        ({"nu": 0.5}, "nu"),
        ({"nu": -1.0}, "nu"),
        ({"loss_factor": -0.1}, "loss_factor"),
    ],
)
def test_invalid_material_names_field(kwargs: dict, field: str) -> None:
    args = {"E_kPa": 10.0, "density_kg_m3": 1000.0, "nu": 0.4, **kwargs}
    with pytest.raises(ValueError, match=field):
        material_from_fields(**args)


def test_material_is_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        get_material("skin").E_Pa = 1.0  # type: ignore[misc]
