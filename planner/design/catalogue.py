"""The silicones a unit's rings may be cast from, and the model inputs of a set of rings.

The catalogue is the shipped one (``silicones/catalogue.toml``, read through the
:mod:`silicones` package; the solver's material library reads the same file), optionally
narrowed to named entries. Names are matched as the solver's library matches them: case,
spaces and underscores do not matter, and a paper letter (A-D) or an alias is accepted.

The harmonic model takes a Young's modulus per ring and one density, Poisson's ratio and loss
factor shared by the rings (``ring_density_kg_m3``, ``ring_nu``, ``ring_loss_factor``). A unit
of different silicones gets their means (:func:`ring_inputs`): the catalogue's densities differ
by under 4 %, its Poisson's ratios and loss factors not at all, so the mean stands for the
set; the FE check solves the named silicones themselves.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

from planner.layout import LayoutError
from silicones import Silicone, read_catalogue

__all__ = ["Catalogue", "load_catalogue", "normalise", "ring_inputs"]

RING_SLOTS = 3  # ring_1 .. ring_3 of the model


def normalise(name: str) -> str:
    """"Dragon Skin 10", "dragon_skin_10" and "dragon-skin-10" all mean the same thing."""
    return re.sub(r"[\s_\-]+", "-", name.strip().lower())


@dataclass(frozen=True)
class Catalogue:
    """The shipped silicones (``all``) and those the search may use (``chosen``, by
    increasing Young's modulus)."""

    all: tuple[Silicone, ...]
    chosen: tuple[Silicone, ...]

    def lookup(self, name: str) -> Silicone | None:
        """The silicone called ``name`` (aliases and letters accepted), or None."""
        return lookup(self.all, name)


def lookup(silicones: Sequence[Silicone], name: str) -> Silicone | None:
    key = normalise(name)
    for s in silicones:
        names = {s.name, *s.aliases} | ({s.letter.lower()} if s.letter else set())
        if key in names:
            return s
    return None


def load_catalogue(names: Sequence[str] = (), where: str = "catalogue") -> Catalogue:
    """The shipped catalogue with ``names`` chosen (empty: all); an unknown name raises
    :class:`LayoutError` naming ``where[i]`` and listing the known ones."""
    every = read_catalogue()
    chosen = []
    for i, name in enumerate(names):
        s = lookup(every, name)
        if s is None:
            raise LayoutError(f"{where}[{i}]", f"{where}[{i}] = {name!r}: not in the silicone "
                              "catalogue (silicones/catalogue.toml); known: "
                              + ", ".join(x.name for x in every))
        if s in chosen:
            raise LayoutError(f"{where}[{i}]", f"{where}[{i}] = {name!r}: {s.name} is listed "
                              "twice")
        chosen.append(s)
    pick = tuple(chosen) if chosen else every
    return Catalogue(every, tuple(sorted(pick, key=lambda s: s.E_Pa)))


def ring_inputs(rings: Sequence[Silicone], unused_E_kPa: float) -> dict[str, float]:
    """Model inputs of rings cast from ``rings`` (inner to outer): a modulus per ring [kPa],
    the slots beyond them at ``unused_E_kPa`` (the model ignores them), and the rings' mean
    density, Poisson's ratio and loss factor (module docstring); a bare unit takes the
    catalogue's first silicone's (ignored too)."""
    if len(rings) > RING_SLOTS:
        raise ValueError(f"{len(rings)} rings: the model has {RING_SLOTS} ring slots")
    shared = rings or read_catalogue()[:1]
    out = {f"ring_{k + 1}_E_kPa": (rings[k].E_kPa if k < len(rings) else unused_E_kPa)
           for k in range(RING_SLOTS)}
    for name, attr in (("ring_density_kg_m3", "density_kg_m3"), ("ring_nu", "nu"),
                       ("ring_loss_factor", "loss_factor")):
        out[name] = round(sum(getattr(s, attr) for s in shared) / len(shared), 6)
    return out
