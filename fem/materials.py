"""Material library: linear isotropic (visco)elastic solids for the forearm and the haptic unit.

Every value is SI (Pa, kg/m3) and carries a ``source`` string that says where the number comes
from. Look materials up with :func:`get_material` (case-insensitive, aliases allowed); build
custom ones with :func:`material_from_fields`.

Silicones (Smooth-On): the datasheets give specific gravity, Shore hardness and the 100 %
tensile modulus, not the small-strain Young's modulus, and published estimates differ 2-4x
(datasheet-derived values against the tensile fits of Marechal et al., Soft Robotics Materials
Database). The library default is the neo-Hookean value implied by the datasheet
100 % modulus, E = 3 sigma_100 / (2 - 1/4) (incompressible uniaxial nominal stress
mu (lambda - lambda^-2) at stretch 2, E = 3 mu); the alternate set fitted to public tensile data
is :data:`SILICONE_E_TENSILE_FIT_Pa`. Silicone ``loss_factor`` is 0.1, an estimate for soft
platinum-cure silicones at 100-250 Hz (order 0.05-0.3, not a datasheet number); set it per
ring when damping matters. The silicones' numbers and sources live in one file,
``silicones/catalogue.toml`` (the :mod:`silicones` package), which the unit designer reads too.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from fieldspec import FieldError
from silicones import Silicone, read_catalogue

__all__ = [
    "ALIASES",
    "BONE_LOSS_FACTOR",
    "MATERIALS",
    "SOFT_TISSUE_LOSS_FACTOR",
    "Material",
    "SILICONE_E_NEO_HOOKEAN_Pa",
    "SILICONE_E_TENSILE_FIT_Pa",
    "SILICONE_MODULUS_100_Pa",
    "UnknownMaterialError",
    "get_material",
    "material_from_fields",
]


@dataclass(frozen=True)
class Material:
    """A linear isotropic solid in SI units: the one solid type of the solver. The library
    holds named ones, a scene's layers, rings and board give theirs through ``solid()``, and
    the domain paints them onto the mesh.

    ``E_Pa`` Young's modulus [Pa], ``density_kg_m3`` [kg/m3], ``nu`` Poisson's ratio [-],
    ``loss_factor`` hysteretic damping eta [-] (complex modulus E* = E (1 + i eta)).
    """

    name: str
    E_Pa: float
    density_kg_m3: float
    nu: float
    loss_factor: float = 0.0
    source: str = ""

    def __post_init__(self) -> None:
        # Thermodynamic admissibility: positive E, -1 < nu < 0.5, eta >= 0.
        checks = (
            ("E_Pa", self.E_Pa > 0, "E_Pa > 0"),
            # 0 is a massless solid: a part whose inertia is switched off (effects.unit_mass)
            ("density_kg_m3", self.density_kg_m3 >= 0, "density_kg_m3 >= 0"),
            ("nu", -1.0 < self.nu < 0.5, "-1 < nu < 0.5"),
            ("loss_factor", self.loss_factor >= 0, "loss_factor >= 0"),
        )
        for field, ok, allowed in checks:
            if not ok:
                value = getattr(self, field)
                raise ValueError(f"material {self.name!r}: {field} = {value!r}; allowed {allowed}")

    @property
    def mu_Pa(self) -> float:
        """Shear modulus mu = E / (2 (1 + nu)) [Pa]."""
        return self.E_Pa / (2.0 * (1.0 + self.nu))

    @property
    def lambda_Pa(self) -> float:
        """First Lame parameter lambda = E nu / ((1 + nu)(1 - 2 nu)) [Pa]."""
        return self.E_Pa * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu))

    @property
    def bulk_Pa(self) -> float:
        """Bulk modulus K = E / (3 (1 - 2 nu)) [Pa]."""
        return self.E_Pa / (3.0 * (1.0 - 2.0 * self.nu))

    @property
    def shear_speed_m_s(self) -> float:
        """Shear (S) wave speed sqrt(mu / rho) [m/s]."""
        return math.sqrt(self.mu_Pa / self.density_kg_m3)

    @property
    def pressure_speed_m_s(self) -> float:
        """Pressure (P) wave speed sqrt((lambda + 2 mu) / rho) [m/s]."""
        return math.sqrt((self.lambda_Pa + 2.0 * self.mu_Pa) / self.density_kg_m3)


class UnknownMaterialError(FieldError, KeyError):
    """Raised by :func:`get_material` for a name that is neither a material nor an alias
    (``field`` is ``material``; a ``KeyError`` too, as a failed lookup)."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.message = (
            f"unknown material {name!r}; known materials: {', '.join(sorted(MATERIALS))} "
            f"(aliases: {', '.join(sorted(ALIASES))})"
        )
        super().__init__("material", self.message)

    def __str__(self) -> str:  # KeyError would repr-quote the message
        return self.message


_TISSUE_SRC = "Guo et al. 2025 (Biomimetics 10:597) Table 1"

#: Hysteretic loss factor of living soft tissue (skin, fat, muscle) at 50-250 Hz. In vivo MR
#: and ultrasound elastography report loss tangents G''/G' of roughly 0.1-0.5 in this band
#: (e.g. Klatt et al. 2007, Phys. Med. Biol. 52:7281, multifrequency MRE, 25-62.5 Hz: 0.3-0.5
#: for soft organs); the Voigt fit of human skin surface impedance of von Gierke et al. 1952
#: (J. Acoust. Soc. Am. 24:490) implies more (about 3.8 at 100 Hz). 0.3 is a mid value of the
#: elastography range and the conservative side of the impedance data: less damping, more
#: crosstalk predicted. Guo et al. 2025 give none (their model is undamped).
SOFT_TISSUE_LOSS_FACTOR = 0.3
#: Cortical bone: loss tangent about 0.01-0.03 from 1 to 100 Hz (Lakes, Katz and Sternstein
#: 1979, J. Biomech. 12:657).
BONE_LOSS_FACTOR = 0.02


def _tissue(name: str, E_kPa: float, density: float, nu: float, layer: str,
            loss_factor: float = SOFT_TISSUE_LOSS_FACTOR) -> Material:
    damping = ("loss factor: cortical bone, Lakes et al. 1979" if layer == "skeleton"
               else "loss factor: soft-tissue elastography range 0.1-0.5, mid value "
               "(see SOFT_TISSUE_LOSS_FACTOR)")
    return Material(name, E_kPa * 1e3, density, nu, loss_factor,
                    f"{_TISSUE_SRC}: {layer}; {damping}")


#: The silicones, from the shared catalogue (``silicones/catalogue.toml``: each number with its
#: source); the unit designer (``planner.design``) reads the same file.
_CATALOGUE = read_catalogue()
#: Smooth-On datasheet 100 % tensile modulus [Pa].
SILICONE_MODULUS_100_Pa: dict[str, float] = {s.name: s.modulus_100_Pa for s in _CATALOGUE}
#: Small-strain E [Pa], neo-Hookean from the datasheet 100 % modulus (library default).
SILICONE_E_NEO_HOOKEAN_Pa: dict[str, float] = {s.name: s.E_Pa for s in _CATALOGUE}
#: Small-strain E [Pa] fitted to public tensile data (Marechal et al., Soft Robotics Materials
#: Database), where the catalogue has one. An alternative to the default, 2-4x softer.
SILICONE_E_TENSILE_FIT_Pa: dict[str, float] = {
    s.name: s.E_tensile_fit_Pa for s in _CATALOGUE if s.E_tensile_fit_Pa is not None}


def _silicone(s: Silicone) -> Material:
    letter = f" (material {s.letter} of Guo et al. 2025)" if s.letter else ""
    fit = ("" if s.E_tensile_fit_Pa is None else
           f"; a tensile-data fit (Marechal et al., Soft Robotics Materials Database) gives "
           f"{s.E_tensile_fit_Pa / 1e3:g} kPa (SILICONE_E_TENSILE_FIT_Pa)")
    source = (
        f"Smooth-On datasheet: specific gravity {s.density_kg_m3 / 1e3:g}, Shore {s.shore}, "
        f"100 % modulus {s.modulus_100_Pa / 1e3:g} kPa{letter}. "
        f"E = {s.E_Pa / 1e3:g} kPa: neo-Hookean small-strain modulus from the 100 % modulus "
        f"(default){fit}. nu {s.nu:g}: {s.sources['nu']}. Loss factor {s.loss_factor:g}: "
        f"{s.sources['loss_factor']}."
    )
    return Material(s.name, s.E_Pa, s.density_kg_m3, s.nu, s.loss_factor, source)


_ALL = (
    _tissue("skin", 49.0, 1116.0, 0.47, "epidermis and dermis"),
    _tissue("subcutaneous", 10.0, 1116.0, 0.47, "subcutaneous tissue"),
    _tissue("muscle", 53.0, 1116.0, 0.47, "muscle"),
    _tissue("bone", 2.94e6, 2000.0, 0.32, "skeleton", BONE_LOSS_FACTOR),
    *(_silicone(s) for s in _CATALOGUE),
    Material("pcb", 2.5e9, 1420.0, 0.34, 0.0, "DuPont Kapton HN polyimide film datasheet"),
    Material(
        "motor", 100e9, 7800.0, 0.3, 0.0,
        "estimate: homogenised coin ERM motor (steel/brass housing); the effective density "
        "of the real motor is computed from its mass elsewhere",
    ),
)

#: Library keyed by canonical lower-case name.
MATERIALS: dict[str, Material] = {m.name: m for m in _ALL}

#: Alternative names (already normalised, see :func:`_normalise`) -> canonical name.
ALIASES: dict[str, str] = {
    "fat": "subcutaneous",
    "epidermis-and-dermis": "skin",
    "skeleton": "bone",
    **{s.letter.lower(): s.name for s in _CATALOGUE if s.letter},
    **{alias: s.name for s in _CATALOGUE for alias in s.aliases},
    "fpcb": "pcb",
    "kapton": "pcb",
}


def _normalise(name: str) -> str:
    # "Dragon Skin 10", "dragon_skin_10" and "dragon-skin-10" all mean the same thing.
    return re.sub(r"[\s_\-]+", "-", name.strip().lower())


def get_material(name: str) -> Material:
    """Return the library material called ``name`` (case-insensitive; aliases such as "fat",
    "A"-"D", "ecoflex 00-10" accepted). Raises :class:`UnknownMaterialError` listing the known
    names otherwise."""
    key = _normalise(name)
    key = ALIASES.get(key, key)
    if key not in MATERIALS:
        raise UnknownMaterialError(name)
    return MATERIALS[key]


def material_from_fields(
    E_kPa: float,
    density_kg_m3: float,
    nu: float,
    loss_factor: float = 0.0,
    name: str = "custom",
    source: str = "user-defined",
) -> Material:
    """Build a custom :class:`Material` from user units (E in kPa, density in kg/m3)."""
    return Material(name, E_kPa * 1e3, density_kg_m3, nu, loss_factor, source)
