"""The silicone catalogue, defined once (the standard library only; imports nothing of the
project).

``silicones/catalogue.toml`` lists the platinum-cure silicones one can buy, each number with
its source. The solver's material library (``fem.materials``) builds its named silicones from
it, and the unit designer (``planner.design``) searches over it: the same numbers on both
sides of the data flow, without the planner importing the solver (as :mod:`motorlaw` does for
the motor's speed law). Values are SI here: E [Pa], density [kg/m^3].
"""

from __future__ import annotations

import functools
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

__all__ = ["CATALOGUE", "Silicone", "read_catalogue"]

CATALOGUE = "catalogue.toml"  # the shipped file, beside this module
_REQUIRED = ("name", "shore", "specific_gravity", "modulus_100_kPa", "E_kPa", "nu",
             "loss_factor", "source_E", "source_density", "source_nu", "source_loss_factor")


@dataclass(frozen=True)
class Silicone:
    """One silicone: small-strain Young's modulus ``E_Pa`` [Pa], ``density_kg_m3``, Poisson's
    ratio ``nu`` [-], hysteretic ``loss_factor`` [-], each with its source."""

    name: str
    E_Pa: float
    density_kg_m3: float
    nu: float
    loss_factor: float
    shore: str
    modulus_100_Pa: float  # the bulletin's 100 % tensile modulus [Pa]
    sources: dict[str, str]  # "E", "density", "nu", "loss_factor" -> where the number is from
    letter: str | None = None  # the paper's material letter (A-D), if it used it
    aliases: tuple[str, ...] = ()
    E_tensile_fit_Pa: float | None = None  # the tensile-data fit (an alternative E) [Pa]

    @property
    def E_kPa(self) -> float:
        return self.E_Pa / 1e3


def _entry(raw: dict, i: int, where: str) -> Silicone:
    missing = [k for k in _REQUIRED if k not in raw]
    if missing:
        raise ValueError(f"{where}: silicone[{i}].{missing[0]} is missing")
    fit = raw.get("E_tensile_fit_kPa")
    return Silicone(
        raw["name"], float(raw["E_kPa"]) * 1e3, float(raw["specific_gravity"]) * 1e3,
        float(raw["nu"]), float(raw["loss_factor"]), str(raw["shore"]),
        float(raw["modulus_100_kPa"]) * 1e3,
        {k: str(raw[f"source_{k}"]) for k in ("E", "density", "nu", "loss_factor")},
        raw.get("letter"), tuple(raw.get("aliases", ())),
        None if fit is None else float(fit) * 1e3)


def read_catalogue(path: str | Path | None = None) -> tuple[Silicone, ...]:
    """The silicones of ``path`` (default: the shipped catalogue), in the file's order."""
    if path is None:
        return _shipped()
    return _parse(Path(path).read_text(encoding="utf-8"), str(path))


@functools.cache
def _shipped() -> tuple[Silicone, ...]:
    text = resources.files(__package__).joinpath(CATALOGUE).read_text(encoding="utf-8")
    return _parse(text, CATALOGUE)


def _parse(text: str, where: str) -> tuple[Silicone, ...]:
    entries = tomllib.loads(text).get("silicone", [])
    out = tuple(_entry(raw, i, where) for i, raw in enumerate(entries))
    names = [s.name for s in out]
    if len(set(names)) != len(names):
        raise ValueError(f"{where}: a silicone name is listed twice")
    return out
