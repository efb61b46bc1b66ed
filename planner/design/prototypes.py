"""Reference units read from scene files: the designs the search is compared with (the
paper's three prototypes: ``examples/unit-bare-forward.toml``, ``unit-double-forward.toml``,
``unit-triple-reverse-pogo.toml``).

Only the ``[unit]`` table of the scene is read (``orientation``, ``attachment``,
``encapsulation`` as catalogue names, ``ring_thickness_mm``), with the scene schema's defaults
(forward, glued, no rings, 1 mm): the model inputs of that unit follow
(:func:`planner.design.catalogue.ring_inputs`). The site, drive and criterion are the request's,
so every reference is judged exactly as the searched designs are.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fieldspec.toml import read_toml_file
from planner.design.catalogue import lookup, ring_inputs
from planner.layout import LayoutError
from silicones import Silicone

__all__ = ["Prototype", "read_prototype"]

RING_THICKNESS_MM = 1.0  # the models' training space fixes the ring width (1 mm, the paper's)


@dataclass(frozen=True)
class Prototype:
    """A reference unit: its name (the file's stem), model inputs and ring silicones."""

    name: str
    path: str
    inputs: dict[str, Any]
    materials: tuple[str, ...]


def read_prototype(path: Path, where: str, silicones: Sequence[Silicone]) -> Prototype:
    """The unit of the scene file ``path``; errors name ``where`` (a LayoutError)."""
    try:
        scene = read_toml_file(path, LayoutError, "reference scene")
    except LayoutError as err:
        raise LayoutError(where, f"{where} = {str(path)!r}: {err}") from None
    unit = scene.get("unit")
    if not isinstance(unit, dict):
        raise LayoutError(where, f"{where} = {str(path)!r}: the scene has no [unit] table")
    rings = unit.get("encapsulation", [])
    if not isinstance(rings, list) or len(rings) > 3:
        raise LayoutError(where, f"{where}: unit.encapsulation must list 0-3 rings")
    found = []
    for k, ring in enumerate(rings):
        s = lookup(silicones, ring) if isinstance(ring, str) else None
        if s is None:
            raise LayoutError(where, f"{where}: unit.encapsulation[{k}] = {ring!r} is not a "
                              "silicone of the catalogue (silicones/catalogue.toml)")
        found.append(s)
    thickness = unit.get("ring_thickness_mm", RING_THICKNESS_MM)
    if rings and thickness != RING_THICKNESS_MM:
        raise LayoutError(where, f"{where}: unit.ring_thickness_mm = {thickness!r}: the models "
                          f"know {RING_THICKNESS_MM:g} mm rings only")
    inputs = {"orientation": unit.get("orientation", "forward"),
              "attachment": unit.get("attachment", "glued"), "n_rings": len(found),
              **ring_inputs(found, found[0].E_kPa if found else silicones[0].E_kPa)}
    return Prototype(Path(path).stem, str(path), inputs, tuple(s.name for s in found))
