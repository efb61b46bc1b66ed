"""Which fields of a scene the solver reads, given the scene's other fields.

A scene file may hold fields that change nothing for that scene: the pogo pins of a glued
unit, the drive frequency of a static analysis, the time step of a harmonic one. They stay in
the scene (and in its hash: a sample's id is its full resolved scene), but a parameter space
that only ever varies such a field varies nothing, and :func:`effective_scene_dict` lets its
check say so.
"""

from __future__ import annotations

import copy
from typing import Any

from .io import scene_to_dict
from .model import LoadKind, Scene

__all__ = ["effective_scene_dict", "unused_fields"]

_LOAD_FIELDS = {kind: kind.actuator.load_fields for kind in LoadKind
                if kind.actuator.load_fields}
_TRANSIENT_FIELDS = ("time_step_ms", "duration_ms", "rho_inf", "voltage_schedule", "damping")


def unused_fields(scene: Scene) -> list[str]:
    """Dotted paths (``table.key`` or ``table``) the solver does not read for ``scene``."""
    unused = []
    kind = scene.load.kind
    used = _LOAD_FIELDS.get(kind, ())
    unused += [f"load.{k}" for keys in _LOAD_FIELDS.values() for k in keys if k not in used]
    a = scene.analysis.kind
    transient_field = LoadKind(kind).actuator.transient_frequency_field
    if a not in ("harmonic", "sweep") and not (
            a == "transient" and transient_field == "analysis.frequency_hz"):
        unused.append("analysis.frequency_hz")  # a transient ERM runs at its motor's speed
    if a != "transient":
        unused += [f"analysis.{k}" for k in _TRANSIENT_FIELDS] + ["output.history_every"]
    if a == "static":
        unused.append("mesh.follow_wavelength")
    unit = scene.unit
    if unit is not None:
        if unit.attachment != "pogo":
            unused.append("unit.pogo")
        if not unit.encapsulation:
            unused += ["unit.ring_thickness_mm", "unit.ring_contact"]
    return unused


def effective_scene_dict(scene: Scene) -> dict[str, Any]:
    """:func:`scene_to_dict` without the fields the solver does not read for it."""
    d = copy.deepcopy(scene_to_dict(scene))
    for path in unused_fields(scene):
        table, _, key = path.partition(".")
        if table not in d:
            continue
        if key:
            d[table].pop(key, None)
        else:
            d.pop(table)
    return d
