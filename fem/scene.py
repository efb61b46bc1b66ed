"""Scene schema: a TOML file describing one FE problem, validated into frozen dataclasses.

Layout (the public contract; see ``examples/forearm.toml`` for a commented file)::

    [tissue]            radius_mm, side, base, and [[tissue.layer]] (top to bottom):
                        name, material, thickness_mm, E_kPa, density_kg_m3, nu, loss_factor
    [load]              kind, direction, radius_mm, amplitude_Pa, force_N
    [analysis]          kind, frequency_hz
    [mesh]              near_size_mm, near_radius_mm, far_size_mm, order
    [output]            radii_mm

Values are stored in the user units named in each field (mm, kPa); SI properties (``E_Pa``,
``thickness_m``, ...) convert at the edge. Every table is described by a small spec (key ->
:class:`Spec`: type, default, interval or choices), so adding a table (``[unit]``,
``[effects]``) or an analysis kind is a matter of adding a spec entry and a dataclass.

Every error is a :class:`SceneError` whose ``.field`` is the dotted path of the offending
value (``tissue.layer[1].nu``) and whose message names the allowed range or choices.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import math
import numbers
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fem.materials import UnknownMaterialError, get_material

__all__ = [
    "DEFAULT_FOREARM_LAYERS",
    "Analysis",
    "Layer",
    "Load",
    "MeshSettings",
    "Output",
    "Scene",
    "SceneError",
    "Tissue",
    "dump_scene_toml",
    "load_scene",
    "scene_from_dict",
    "scene_hash",
    "scene_to_dict",
]

MAX_LAYERS = 50


class SceneError(ValueError):
    """Invalid scene input. ``field`` is the dotted path of the bad value, e.g.
    ``tissue.layer[1].nu``, or ``"<file>"`` for a TOML syntax error."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


# --------------------------------------------------------------------------- dataclasses


@dataclass(frozen=True)
class Layer:
    """One tissue or encapsulation layer: thickness [mm], Young's modulus [kPa], density
    [kg/m3], Poisson's ratio [-], hysteretic loss factor eta [-] (E* = E (1 + i eta)).
    ``material`` is the canonical library name the values started from, if any."""

    name: str
    thickness_mm: float
    E_kPa: float
    density_kg_m3: float
    nu: float
    loss_factor: float = 0.0
    material: str | None = None

    @property
    def thickness_m(self) -> float:
        return self.thickness_mm * 1e-3

    @property
    def E_Pa(self) -> float:
        return self.E_kPa * 1e3


@dataclass(frozen=True)
class Tissue:
    """Layered cylinder of radius ``radius_mm`` [mm]; ``layers`` top (skin) to bottom."""

    layers: tuple[Layer, ...]
    radius_mm: float = 50.0
    side: str = "absorbing"
    base: str = "fixed"

    def __post_init__(self) -> None:
        object.__setattr__(self, "layers", tuple(self.layers))  # a list would be unhashable

    @property
    def radius_m(self) -> float:
        return self.radius_mm * 1e-3

    @property
    def depth_mm(self) -> float:
        """Total thickness of all layers [mm]."""
        return sum(layer.thickness_mm for layer in self.layers)


@dataclass(frozen=True)
class Load:
    """Surface load at the axis: a pressure patch of ``radius_mm`` [mm] and ``amplitude_Pa``
    [Pa], or a point force ``force_N`` [N]; "normal" is Fourier mode 0, "tangential" mode 1."""

    kind: str = "pressure_patch"
    direction: str = "normal"
    radius_mm: float = 2.0
    amplitude_Pa: float = 1000.0
    force_N: float = 1.0

    @property
    def radius_m(self) -> float:
        return self.radius_mm * 1e-3


@dataclass(frozen=True)
class Analysis:
    """Analysis kind and, for "harmonic", the drive frequency [Hz]."""

    kind: str = "static"
    frequency_hz: float = 120.0


@dataclass(frozen=True)
class MeshSettings:
    """Element size [mm] within ``near_radius_mm`` of the axis and beyond; element order."""

    near_size_mm: float = 0.5
    near_radius_mm: float = 8.0
    far_size_mm: float = 2.0
    order: int = 2


@dataclass(frozen=True)
class Output:
    """Surface probe radii [mm], stored in the order given."""

    radii_mm: tuple[float, ...] = (0.0, 2.0, 4.0, 8.0, 12.0, 16.0, 20.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "radii_mm", tuple(self.radii_mm))

    @property
    def radii_m(self) -> tuple[float, ...]:
        return tuple(r * 1e-3 for r in self.radii_mm)


@dataclass(frozen=True)
class Scene:
    """A complete, validated FE scene. Construction validates (raises :class:`SceneError`)."""

    tissue: Tissue
    load: Load = field(default_factory=Load)
    analysis: Analysis = field(default_factory=Analysis)
    mesh: MeshSettings = field(default_factory=MeshSettings)
    output: Output = field(default_factory=Output)

    def __post_init__(self) -> None:
        _validate(scene_to_dict(self))  # direct construction gets the same checks as a file


# The paper's forearm (Guo et al. 2025, Table 1, as read in PAPER.md). The paper states a
# 31.9 mm block, which fits none of the ways to split Table 1's digits; this reading
# (1.9 + 14 + 21 + 5 = 41.9 mm) keeps the plausible layer thicknesses and is a documented choice.
DEFAULT_FOREARM_LAYERS: tuple[Layer, ...] = (
    Layer("skin", 1.9, 49.0, 1116.0, 0.47, 0.0, "skin"),
    Layer("subcutaneous", 14.0, 10.0, 1116.0, 0.47, 0.0, "subcutaneous"),
    Layer("muscle", 21.0, 53.0, 1116.0, 0.47, 0.0, "muscle"),
    Layer("bone", 5.0, 2.94e6, 2000.0, 0.32, 0.0, "bone"),
)

# --------------------------------------------------------------------------- table specs

REQUIRED: Any = object()  # sentinel: no default


@dataclass(frozen=True)
class Spec:
    """One key of a table: ``kind`` (float, int, str or tuple = list of floats), default,
    ``interval`` in math notation ("(0, 1e9]"; a bound may be a dotted path of an earlier
    resolved value, e.g. "tissue.radius_mm"), enum ``choices``, and ``nonzero``."""

    kind: type
    default: Any = REQUIRED
    interval: str = ""
    choices: tuple[Any, ...] = ()
    nonzero: bool = False


_LAYER = {
    "name": Spec(str, None),  # default: the material name, else "layer<i>"
    "material": Spec(str, None),  # library name; explicit fields below override it
    "thickness_mm": Spec(float, REQUIRED, "(0, 10000]"),
    "E_kPa": Spec(float, REQUIRED, "(0, 1e9]"),
    "density_kg_m3": Spec(float, REQUIRED, "(0, 1e5]"),
    "nu": Spec(float, REQUIRED, "[0, 0.5)"),
    "loss_factor": Spec(float, 0.0, "[0, 2]"),
}

# Table name -> (dataclass, specs). Order matters: intervals may refer to earlier values.
_TABLES: dict[str, tuple[type, dict[str, Spec]]] = {
    "tissue": (Tissue, {
        "radius_mm": Spec(float, 50.0, "(0, 1e5]"),
        "side": Spec(str, "absorbing", choices=("absorbing", "fixed", "free")),
        "base": Spec(str, "fixed", choices=("fixed", "absorbing")),
    }),
    "load": (Load, {
        "kind": Spec(str, "pressure_patch", choices=("pressure_patch", "point_force")),
        "direction": Spec(str, "normal", choices=("normal", "tangential")),
        "radius_mm": Spec(float, 2.0, "(0, tissue.radius_mm)"),
        "amplitude_Pa": Spec(float, 1000.0, "[-1e9, 1e9]", nonzero=True),
        "force_N": Spec(float, 1.0, "[-1e9, 1e9]", nonzero=True),
    }),
    "analysis": (Analysis, {
        "kind": Spec(str, "static", choices=("static", "harmonic")),
        "frequency_hz": Spec(float, 120.0, "(0, 1e5]"),
    }),
    "mesh": (MeshSettings, {
        "near_size_mm": Spec(float, 0.5, "(0, 100]"),
        "near_radius_mm": Spec(float, 8.0, "(0, tissue.radius_mm]"),
        "far_size_mm": Spec(float, 2.0, "[mesh.near_size_mm, 1000]"),
        "order": Spec(int, 2, choices=(1, 2)),
    }),
    "output": (Output, {
        "radii_mm": Spec(tuple, (0.0, 2.0, 4.0, 8.0, 12.0, 16.0, 20.0), "[0, tissue.radius_mm]"),
    }),
}
_SUBARRAYS = {"tissue": "layer"}  # array-of-tables keys inside a table

# --------------------------------------------------------------------------- validation


def _fail_unknown(path: str, key: str, allowed: list[str]) -> None:
    where = f"{path}.{key}" if path else key
    close = difflib.get_close_matches(key, allowed, n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    raise SceneError(where, f"unknown key {where!r}: {hint}allowed keys: {', '.join(allowed)}")


def _as_table(raw: Any, path: str, allowed: list[str]) -> Mapping[str, Any]:
    if not isinstance(raw, Mapping):
        raise SceneError(path, f"{path or 'the scene'} must be a table, got {type(raw).__name__}")
    for key in raw:
        if key not in allowed:
            _fail_unknown(path, str(key), allowed)
    return raw


def _bound(token: str, ctx: Mapping[str, Any]) -> tuple[float, str]:
    try:
        return float(token), token
    except ValueError:  # a dotted path to an earlier value
        return ctx[token], f"{token} (= {ctx[token]:g})"


def _interval(spec: Spec, key: str, ctx: Mapping[str, Any]) -> tuple[float, float, str]:
    """Bounds of ``spec.interval`` and its readable form, e.g. ``0 <= nu < 0.5``."""
    lo_tok, hi_tok = (t.strip() for t in spec.interval[1:-1].split(","))
    (lo, lo_txt), (hi, hi_txt) = _bound(lo_tok, ctx), _bound(hi_tok, ctx)
    lo_op = "<" if spec.interval[0] == "(" else "<="
    hi_op = "<" if spec.interval[-1] == ")" else "<="
    text = f"{lo_txt} {lo_op} {key} {hi_op} {hi_txt}" + (", non-zero" if spec.nonzero else "")
    return lo, hi, text


def _check_interval(value: float, spec: Spec, key: str, path: str, ctx: Mapping[str, Any]):
    lo, hi, allowed = _interval(spec, key, ctx)
    lo_ok = lo < value if spec.interval[0] == "(" else lo <= value  # both False for NaN
    hi_ok = value < hi if spec.interval[-1] == ")" else value <= hi
    if not (lo_ok and hi_ok) or (spec.nonzero and value == 0):
        raise SceneError(path, f"{path} = {value!r} is out of range: allowed {allowed}")


def _number(value: Any, kind: type, path: str) -> float | int:
    # numbers.Real/Integral also admit numpy scalars from parameter sweeps; bool is excluded.
    abc = numbers.Integral if kind is int else numbers.Real
    if isinstance(value, bool | np.bool_) or not isinstance(value, abc):
        what = "an integer" if kind is int else "a number (float or int)"
        extra = " (true/false is not a number)" if isinstance(value, bool | np.bool_) else ""
        raise SceneError(path, f"{path} = {value!r} has the wrong type: expected {what}, "
                         f"got {type(value).__name__}{extra}")
    try:
        return kind(value)
    except OverflowError:  # an integer too large for a float
        raise SceneError(path, f"{path} = {value!r} is out of range: not a finite float") from None


def _read_value(value: Any, spec: Spec, key: str, path: str, ctx: Mapping[str, Any]) -> Any:
    """Type-check, convert (int -> float) and range-check one value."""
    if spec.kind is str:
        if not isinstance(value, str):
            raise SceneError(path, f"{path} = {value!r} has the wrong type: expected a string, "
                             f"got {type(value).__name__}")
        value = str(value)
    elif spec.kind is tuple:
        if not isinstance(value, list | tuple) or not value:
            raise SceneError(path, f"{path} = {value!r} has the wrong type: expected a "
                             f"non-empty list of numbers ({_interval(spec, key, ctx)[2]})")
        items = tuple(_number(item, float, f"{path}[{i}]") for i, item in enumerate(value))
        for i, item in enumerate(items):
            _check_interval(item, spec, key, f"{path}[{i}]", ctx)
        return items
    else:
        value = _number(value, spec.kind, path)
    if spec.choices and value not in spec.choices:
        choices = ", ".join(repr(c) for c in spec.choices)
        raise SceneError(path, f"{path} = {value!r} is not allowed: choose one of {choices}")
    if spec.interval:
        _check_interval(value, spec, key, path, ctx)
    return value


_FROM_MATERIAL = ("E_kPa", "density_kg_m3", "nu", "loss_factor")


def _read_fields(raw: Mapping[str, Any], specs: Mapping[str, Spec], path: str,
                 ctx: dict[str, Any], defaults: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Resolve every key of ``specs`` from ``raw`` (else its default); record it in ``ctx``."""
    out: dict[str, Any] = {}
    for key, spec in specs.items():
        where = f"{path}.{key}"
        default = (defaults or {}).get(key, spec.default)
        if key in raw:
            out[key] = _read_value(raw[key], spec, key, where, ctx)
        elif default is REQUIRED:
            alt = " or a library material (material = ...)" if key in _FROM_MATERIAL else ""
            raise SceneError(where, f"{where} is missing: give {key} "
                             f"({_interval(spec, key, ctx)[2]}){alt}")
        else:
            out[key] = default
        ctx[where] = out[key]
    return out


def _read_layer(raw: Any, i: int, ctx: dict[str, Any]) -> dict[str, Any]:
    path = f"tissue.layer[{i}]"
    raw = _as_table(raw, path, list(_LAYER))
    defaults: dict[str, Any] = {"name": f"layer{i}"}
    if raw.get("material") is not None:
        name = _read_value(raw["material"], _LAYER["material"], "material", path + ".material",
                           ctx)
        try:
            mat = get_material(name)
        except UnknownMaterialError as err:
            raise SceneError(f"{path}.material", f"{path}.material: {err}") from None
        defaults = {"name": mat.name, "material": mat.name, "E_kPa": mat.E_Pa / 1e3,
                    "density_kg_m3": mat.density_kg_m3, "nu": mat.nu,
                    "loss_factor": mat.loss_factor}
        raw = {**raw, "material": mat.name}  # store the canonical name, not the alias
    return _read_fields(raw, _LAYER, path, ctx, defaults)


def _read_layers(raw: Any, ctx: dict[str, Any]) -> list[dict[str, Any]]:
    if raw is None:
        return [_layer_to_dict(layer) for layer in DEFAULT_FOREARM_LAYERS]
    if not isinstance(raw, list | tuple):
        raise SceneError("tissue.layer", "tissue.layer must be an array of tables "
                         f"([[tissue.layer]]), got {type(raw).__name__}")
    if not 1 <= len(raw) <= MAX_LAYERS:
        raise SceneError("tissue.layer", f"tissue.layer has {len(raw)} layers: "
                         f"allowed 1 <= number of layers <= {MAX_LAYERS}")
    return [_read_layer(item, i, ctx) for i, item in enumerate(raw)]


def _validate(d: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """Check ``d`` against the specs; return it fully resolved (defaults filled, ints -> float,
    material names canonical), TOML-shaped."""
    _as_table(d, "", list(_TABLES))
    ctx: dict[str, Any] = {}
    out: dict[str, dict[str, Any]] = {}
    for name, (_, specs) in _TABLES.items():
        sub = _SUBARRAYS.get(name)
        raw = _as_table(d.get(name, {}), name, list(specs) + ([sub] if sub else []))
        out[name] = _read_fields(raw, specs, name, ctx)
        if name == "tissue":
            out[name]["layer"] = _read_layers(raw.get("layer"), ctx)
    return out


def _build(resolved: Mapping[str, Mapping[str, Any]]) -> Scene:
    parts: dict[str, Any] = {}
    for name, (cls, specs) in _TABLES.items():
        kwargs = {key: resolved[name][key] for key in specs}
        if name == "tissue":
            kwargs["layers"] = tuple(Layer(**layer) for layer in resolved[name]["layer"])
        parts[name] = cls(**kwargs)
    return Scene(**parts)


# --------------------------------------------------------------------------- public API


def scene_from_dict(d: Mapping[str, Any]) -> Scene:
    """Validate a TOML-shaped mapping (as from ``tomllib``) and build a :class:`Scene`.
    Missing tables and keys take their documented defaults; no ``[[tissue.layer]]`` means the
    paper's forearm (:data:`DEFAULT_FOREARM_LAYERS`)."""
    return _build(_validate(d))


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene TOML file. Syntax errors raise :class:`SceneError` with
    ``field == "<file>"`` and the line in the message."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as err:
        raise SceneError("<file>", f"{path}: invalid TOML: {err}") from None
    return scene_from_dict(data)


def _plain(value: Any, kind: type) -> Any:
    # ints given directly to the dataclasses become floats, so equal scenes hash equally.
    if kind is float and isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    if kind is tuple and isinstance(value, list | tuple):
        return [_plain(v, float) for v in value]
    return value


def _layer_to_dict(layer: Layer) -> dict[str, Any]:
    """One layer as a TOML-shaped dict (``material`` omitted when None: TOML has no null)."""
    out = {key: _plain(getattr(layer, key), spec.kind) for key, spec in _LAYER.items()}
    if out["material"] is None:
        del out["material"]
    return out


def scene_to_dict(scene: Scene) -> dict[str, dict[str, Any]]:
    """Fully resolved TOML-shaped dict; ``scene_from_dict(scene_to_dict(s)) == s``."""
    out: dict[str, dict[str, Any]] = {}
    for name, (_, specs) in _TABLES.items():
        obj = getattr(scene, name)
        out[name] = {key: _plain(getattr(obj, key), spec.kind) for key, spec in specs.items()}
    out["tissue"]["layer"] = [_layer_to_dict(layer) for layer in scene.tissue.layers]
    return out


def scene_hash(scene: Scene) -> str:
    """sha256 hex digest of the canonical JSON of :func:`scene_to_dict` (sorted keys, floats
    written with ``repr`` so they round-trip exactly)."""
    text = json.dumps(scene_to_dict(scene), sort_keys=True, separators=(",", ":"),
                      allow_nan=False, ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


_TOML_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n",
                 "\f": "\\f", "\r": "\\r"}


def _toml_value(value: Any) -> str:
    if isinstance(value, str):
        # TOML basic strings forbid raw control characters (U+0000-U+001F, U+007F).
        return '"' + re.sub(
            r'["\\\x00-\x1f\x7f]',
            lambda m: _TOML_ESCAPES.get(m.group(), f"\\u{ord(m.group()):04X}"), value) + '"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"cannot write non-finite float {value!r}")
        return repr(value)  # shortest exact repr, always a valid TOML float ("1e-05", "2.0")
    if isinstance(value, int):
        return str(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__} to TOML")


def dump_scene_toml(scene: Scene) -> str:
    """Write ``scene`` as TOML text in the schema layout (all values explicit)."""
    d = scene_to_dict(scene)
    lines = ["# hapticrom scene (written by fem.scene.dump_scene_toml); units in key names", ""]
    for name, table in d.items():
        sub = _SUBARRAYS.get(name)
        lines += [f"[{name}]"] + [f"{k} = {_toml_value(v)}" for k, v in table.items() if k != sub]
        for item in table[sub] if sub else ():
            lines += ["", f"[[{name}.{sub}]]"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in item.items()]
        lines.append("")
    return "\n".join(lines)
