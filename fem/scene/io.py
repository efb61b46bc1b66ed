"""Scene files: TOML load, TOML-shaped dicts both ways, canonical hash, and the TOML writer.

Resolution (what :func:`scene_to_dict` writes back, so that round trips are exact): a motor
given by ``force_N`` at ``force_at_hz`` is stored as ``unbalance_g_mm = force_N / (2 pi
force_at_hz)^2`` (converted to g mm); the force keys are input only and are not written back.
A ring equal to its library material is written as the canonical name, any other ring as a
full inline table. ``[effects]`` keeps only the keys set to true or false (None = auto) and is
left out when all are auto; ``[unit]`` is left out when the scene has no unit, and
``[unit.actuator]`` unless the load is a normal actuator (or the actuator is not the default);
an actuator's own optional table (``[unit.lra]``) only when it was given, so scenes without it
keep their hashes; for the same reason ``analysis.damping`` is written only when it is not
the default.
"""

from __future__ import annotations

import hashlib
import json
import numbers
from collections.abc import Mapping
from enum import Enum
from pathlib import Path
from typing import Any

from fieldspec import Context, Spec, is_bool
from fieldspec.toml import dumps, read_toml_file

from ..actuators import ACTUATORS
from .model import SCENE_CHECKS, Analysis, Scene, SceneError
from .schedule import Schedule
from .tables import LAYER, RING, SUBARRAYS, TABLES, UNIT, UNIT_KEYS, UNIT_PARTS
from .unit_model import Ring, Unit
from .validate import build_scene, make, read_solid, validate

__all__ = ["dump_scene_toml", "load_scene", "scene_from_dict", "scene_hash", "scene_to_dict"]


def scene_from_dict(d: Mapping[str, Any]) -> Scene:
    """Validate a TOML-shaped mapping (as from ``tomllib``) and build a :class:`Scene`.
    Missing tables and keys take their documented defaults; no ``[[tissue.layer]]`` means the
    forearm of Guo et al. 2025 (``fem.scene.DEFAULT_FOREARM_LAYERS``)."""
    return build_scene(validate(d))


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene TOML file. Syntax errors raise :class:`SceneError` with
    ``field == "<file>"`` and the line in the message."""
    return scene_from_dict(read_toml_file(path, SceneError, "scene file"))


def _plain(value: Any, kind: type) -> Any:
    # ints given directly to the dataclasses become floats, so equal scenes hash equally;
    # numpy scalars become Python ones (JSON and TOML know only those); enums their strings.
    if isinstance(value, Enum):
        return value.value
    if kind is float and isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    if kind is int and isinstance(value, numbers.Integral) and not isinstance(value, bool):
        return int(value)
    if kind is bool and is_bool(value):
        return bool(value)
    if kind is tuple and isinstance(value, list | tuple):
        return [_plain(v, float) for v in value]
    if kind is list and isinstance(value, list | tuple):
        return [_plain(v, int) for v in value]
    if kind is Schedule and isinstance(value, list | tuple):
        return [[_plain(v, float) for v in pair] if isinstance(pair, list | tuple) else pair
                for pair in value]
    return value


def _table_to_dict(obj: Any, specs: Mapping[str, Spec]) -> dict[str, Any]:
    return {key: _plain(getattr(obj, key), spec.kind) for key, spec in specs.items()
            if not spec.input_only}


def _solid_to_dict(solid: Any, specs: Mapping[str, Spec]) -> dict[str, Any]:
    """A layer or ring as a TOML-shaped dict (``material`` omitted when None: TOML has no
    null)."""
    out = _table_to_dict(solid, specs)
    if out["material"] is None:
        del out["material"]
    return out


def _ring_to_toml(ring: Ring) -> str | dict[str, Any]:
    """A ring equal to its library material as the canonical name, else a full inline table."""
    if isinstance(ring.material, str):
        try:
            library = make(Ring, read_solid({"material": ring.material}, "", RING,
                                            Context(SceneError)))
        except SceneError:  # not a library material: written inline, validation reports it
            library = None
        if ring == library:
            return library.material
    return _solid_to_dict(ring, RING)


def _unit_to_dict(unit: Unit, load_kind: str) -> dict[str, Any]:
    out = {**_table_to_dict(unit, UNIT),
           "encapsulation": [_ring_to_toml(ring) for ring in unit.encapsulation]}
    for name, (cls, specs) in UNIT_PARTS.items():
        part = getattr(unit, name)
        if part is None:  # an optional table not given (``[unit.lra]``): not written
            continue
        # the actuator table only matters to the kinds that read it (elsewhere a non-default
        # one is written so that validation rejects it instead of dropping it)
        reader = ACTUATORS.get(str(load_kind))  # None: an unknown kind, validation reports it
        if name != "actuator" or (reader and reader.unit_part == name) or part != cls():
            out[name] = _table_to_dict(part, specs)
    return {key: out[key] for key in UNIT_KEYS if key in out}


def scene_to_dict(scene: Scene) -> dict[str, dict[str, Any]]:
    """Fully resolved TOML-shaped dict; ``scene_from_dict(scene_to_dict(s)) == s``.
    ``unit`` appears only when the scene has one, ``effects`` only with some effect set (see
    the module docstring for how motors and rings are written)."""
    out: dict[str, dict[str, Any]] = {}
    for name, (_, specs) in TABLES.items():
        obj = getattr(scene, name)
        if name == "unit":
            if obj is not None:
                out[name] = _unit_to_dict(obj, scene.load.kind)
            continue
        table = _table_to_dict(obj, specs)
        if name == "analysis" and obj.kind == "sweep":  # the band, as read
            table["frequency_hz"] = [float(f) for f in obj.frequencies_hz]
        if name == "analysis":  # defaults not written: scenes from before keep their hash
            for key in ("damping", "tolerance"):
                if getattr(obj, key) == getattr(Analysis, key):
                    del table[key]
        if name in ("effects", "mesh"):  # auto effects, absent cell counts: TOML has no null
            table = {key: value for key, value in table.items() if value is not None}
            if not table:
                continue
        out[name] = table
    out["tissue"]["layer"] = [_solid_to_dict(layer, LAYER) for layer in scene.tissue.layers]
    return out


def scene_hash(scene: Scene) -> str:
    """sha256 hex digest of the canonical JSON of :func:`scene_to_dict` (sorted keys, floats
    written with ``repr`` so they round-trip exactly)."""
    text = json.dumps(scene_to_dict(scene), sort_keys=True, separators=(",", ":"),
                      allow_nan=False, ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def dump_scene_toml(scene: Scene) -> str:
    """Write ``scene`` as TOML text in the schema layout (all values explicit)."""
    return dumps(scene_to_dict(scene), SUBARRAYS,
                 "hapticrom scene (written by fem.scene.dump_scene_toml); units in key names")


def _check_scene(scene: Scene) -> None:
    validate(scene_to_dict(scene))


SCENE_CHECKS.append(_check_scene)  # every Scene(...) is validated as its file would be
