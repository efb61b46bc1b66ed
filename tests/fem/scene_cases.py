"""Scene builders and assertions shared by the scene tests."""

from __future__ import annotations

import copy
import tomllib
from typing import Any

from fem.materials import get_material
from fem.scene import Ring, Scene, dump_scene_toml, scene_from_dict, scene_hash, scene_to_dict

SILICONES = ["ecoflex-00-10", "ecoflex-00-50", "dragon-skin-10-medium", "dragon-skin-30"]


def assert_round_trips(scene: Scene) -> None:
    """Dict and TOML round trips give the same scene and the same hash."""
    assert scene_from_dict(scene_to_dict(scene)) == scene
    back = scene_from_dict(tomllib.loads(dump_scene_toml(scene)))
    assert back == scene
    assert scene_hash(back) == scene_hash(scene)


def unit_scene(kind: str = "unit", **unit: Any) -> dict[str, Any]:
    """A scene dict with a haptic unit load and the ``[unit]`` keys given."""
    return {"load": {"kind": kind}, "unit": copy.deepcopy(unit)}


def with_value(path: str, value: Any, base: dict[str, Any] | None = None) -> dict[str, Any]:
    """``base`` (default: an ERM unit scene) with ``value`` at the dotted ``path``."""
    d = copy.deepcopy(base) if base is not None else unit_scene()
    *tables, key = path.split(".")
    node = d
    for t in tables:
        node = node.setdefault(t, {})
    node[key] = value
    return d


def library_ring(name: str) -> Ring:
    """The ring a bare library name resolves to."""
    m = get_material(name)
    return Ring(m.name, m.E_Pa / 1e3, m.density_kg_m3, m.nu, m.loss_factor, m.name)
