"""Validation of a TOML-shaped scene mapping against the spec tables, and building the frozen
dataclasses from the resolved result. Every error is a :class:`SceneError` naming the field
(dotted path) and the allowed range or choices.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

from fieldspec import (
    Context,
    Spec,
    allowed_text,
    read_array,
    read_fields,
    read_table,
    read_value,
    require_table,
)

from ..materials import Material, UnknownMaterialError, get_material
from ..viscoelastic import default_fit
from .model import UNIT_LOAD_KINDS, Layer, LoadKind, Scene, SceneError, Tissue
from .tables import (
    ACTUATOR,
    BOARD,
    DEFAULT_FOREARM_LAYERS,
    LAYER,
    MAX_LAYERS,
    MAX_RINGS,
    MOTOR,
    POGO,
    RING,
    SUBARRAYS,
    TABLES,
    UNIT,
    UNIT_KEYS,
    UNIT_PARTS,
)
from .unit_model import Ring, Unit

__all__ = ["build_scene", "read_solid", "validate"]

def _material(name: str, path: str) -> Material:
    try:
        return get_material(name)
    except UnknownMaterialError as err:
        raise SceneError(path, f"{path}: {err}") from None


def read_solid(raw: Any, path: str, specs: Mapping[str, Spec], ctx: Context,
               default_name: str | None = None) -> dict[str, Any]:
    """A table of solid properties whose E, density, nu (and loss factor, name) default to
    those of its library ``material``; the canonical material name is stored."""
    raw = require_table(raw, path, list(specs), ctx)
    defaults: dict[str, Any] = {"name": default_name}
    material = raw.get("material", specs["material"].default)
    if material is not None:
        name = read_value(material, specs["material"], "material", f"{path}.material", ctx)
        mat = _material(name, f"{path}.material")
        defaults = {"name": mat.name, "material": mat.name, "E_kPa": mat.E_Pa / 1e3,
                    "density_kg_m3": mat.density_kg_m3, "nu": mat.nu,
                    "loss_factor": mat.loss_factor}
        raw = {**raw, "material": mat.name}  # store the canonical name, not the alias
    return read_fields(raw, specs, path, ctx, {k: v for k, v in defaults.items() if k in specs})


def _read_layers(raw: Any, ctx: Context) -> list[dict[str, Any]]:
    if raw is None:  # the default forearm
        return [{key: getattr(layer, key) for key in LAYER} for layer in DEFAULT_FOREARM_LAYERS]
    return read_array(raw, "tissue.layer", ctx,
                      lambda item, where, i: read_solid(item, where, LAYER, ctx, f"layer{i}"),
                      count=(1, MAX_LAYERS), noun="layers",
                      expected="an array of tables ([[tissue.layer]])")


def _read_ring(item: Any, where: str, i: int, ctx: Context) -> dict[str, Any]:
    if isinstance(item, str):  # a bare name: exactly the library material
        item = {"material": _material(item, where).name}
    elif not isinstance(item, Mapping):
        raise SceneError(where, f"{where} = {item!r} has the wrong type: expected a "
                         "material name or an inline table {material = ..., E_kPa = ...}")
    return read_solid(item, where, RING, ctx, f"ring{i}")


def _read_rings(raw: Any, ctx: Context) -> list[dict[str, Any]]:
    """``unit.encapsulation``: library names (aliases allowed) or inline layer-like tables."""
    return read_array(raw, "unit.encapsulation", ctx,
                      lambda item, where, i: _read_ring(item, where, i, ctx),
                      count=(0, MAX_RINGS), noun="rings",
                      expected="a list of ring materials (library names or inline tables), "
                      "inner to outer")


def _read_motor(raw: Any, ctx: Context) -> dict[str, Any]:
    """[unit.motor]; an unbalance given as force_N at force_at_hz is resolved to g mm."""
    path = "unit.motor"
    raw = require_table(raw, path, list(MOTOR), ctx)
    out = read_fields(raw, MOTOR, path, ctx)
    force, hz = out.pop("force_N"), out.pop("force_at_hz")
    if force is not None and "unbalance_g_mm" in raw:
        raise SceneError(f"{path}.force_N", f"{path}: give either unbalance_g_mm or force_N "
                         "(with force_at_hz), not both")
    if (force is None) != (hz is None):
        key = "force_at_hz" if force is not None else "force_N"
        other = "force_N" if force is not None else "force_at_hz"
        raise SceneError(f"{path}.{key}", f"{path}.{key} is missing: {other} needs it "
                         f"({allowed_text(MOTOR[key], key, ctx)})")
    if force is not None:
        unbalance = force / (2.0 * math.pi * hz) ** 2 * 1e6  # kg m -> g mm
        if not 0 < unbalance <= 1000:
            allowed = allowed_text(MOTOR["unbalance_g_mm"], "unbalance_g_mm", ctx)
            raise SceneError(f"{path}.force_N", f"{path}.force_N = {force!r} at force_at_hz = "
                             f"{hz!r} gives unbalance_g_mm = {unbalance:g}, out of range: "
                             f"allowed {allowed}")
        out["unbalance_g_mm"] = unbalance
    return out


def _read_unit(raw: Any, ctx: Context) -> dict[str, Any]:
    kind = ctx["load.kind"]
    if kind not in UNIT_LOAD_KINDS:
        units = " or ".join(f'"{k}"' for k in UNIT_LOAD_KINDS)
        raise SceneError("unit", f"the [unit] table needs load.kind = {units} (load.kind is "
                         f"{str(kind)!r}); remove [unit] otherwise")
    raw = require_table(raw, "unit", UNIT_KEYS, ctx)
    out = read_fields(raw, UNIT, "unit", ctx)
    out["encapsulation"] = _read_rings(raw.get("encapsulation", []), ctx)
    out["motor"] = _read_motor(raw.get("motor", {}), ctx)
    out["board"] = read_solid(raw.get("board", {}), "unit.board", BOARD, ctx)
    out["pogo"] = read_table(raw.get("pogo", {}), POGO, "unit.pogo", ctx)
    if LoadKind(kind).actuator.unit_part == "actuator":
        out["actuator"] = read_table(raw.get("actuator", {}), ACTUATOR, "unit.actuator", ctx)
    elif "actuator" in raw:
        users = " or ".join(f'"{k}"' for k in LoadKind if k.actuator.unit_part == "actuator")
        raise SceneError("unit.actuator", f"unit.actuator is only used with load.kind = "
                         f"{users} (load.kind is {str(kind)!r}); remove it")
    own = LoadKind(kind).actuator.own_part
    for part in sorted({k.actuator.own_part for k in LoadKind} - {None}):
        if part in raw and part != own:
            users = " or ".join(f'"{k}"' for k in LoadKind if k.actuator.own_part == part)
            raise SceneError(f"unit.{part}", f"unit.{part} is only used with load.kind = "
                             f"{users} (load.kind is {str(kind)!r}); remove it")
    if own is not None and own in raw:
        out[own] = read_table(raw[own], UNIT_PARTS[own][1], f"unit.{own}", ctx)
    _check_unit_geometry(build_unit(out), ctx)
    return {key: out[key] for key in UNIT_KEYS if key in out}


def _check_unit_geometry(unit: Unit, ctx: Context) -> None:
    """Cross-field checks: pins under the board, and the unit inside the tissue cylinder."""
    board, pogo = unit.board, unit.pogo
    if 0 < board.thickness_mm < 0.001:
        raise SceneError("unit.board.thickness_mm", f"unit.board.thickness_mm = "
                         f"{board.thickness_mm!r} is out of range: allowed 0 (no board) or "
                         "0.001 <= thickness_mm <= 10")
    if unit.attachment == "pogo":
        if not board.present:
            raise SceneError("unit.board.thickness_mm", 'unit.board.thickness_mm = 0.0 is out '
                             'of range for unit.attachment = "pogo": allowed 0.001 <= thickness_mm '
                             "<= 10 (the pins are soldered under the board)")
        r_board = 0.5 * board.diameter_mm
        if pogo.radius_mm + 0.5 * pogo.tip_diameter_mm > r_board:
            raise SceneError("unit.pogo.radius_mm", f"unit.pogo.radius_mm = "
                             f"{pogo.radius_mm!r} is out of range: the pin tips must sit under "
                             "the board, allowed radius_mm + tip_diameter_mm / 2 <= "
                             f"unit.board.diameter_mm / 2 (= {r_board:g}), i.e. radius_mm <= "
                             f"{r_board - 0.5 * pogo.tip_diameter_mm:g}")
    core, outer, n = unit.core_radius_mm, unit.outer_radius_mm, len(unit.encapsulation)
    tissue = ctx["tissue.radius_mm"]
    if not outer < tissue:
        # blame the part that sets the size: the rings, else the motor or the board
        if n:
            where = "unit.encapsulation"
        elif unit.core_radius_m == unit.motor.radius_m:
            where = "unit.motor.diameter_mm"
        else:
            where = "unit.board.diameter_mm"
        gap = f" + {unit.ring_gap_mm:g} mm slit" if unit.ring_gap_mm else ""
        raise SceneError(where, f"the unit's outer radius {outer:g} mm (core {core:g} mm{gap} + "
                         f"{n} ring(s) x {unit.ring_thickness_mm:g} mm), set by {where}, is out "
                         f"of range: allowed outer radius < tissue.radius_mm (= {tissue:g})")


def _read_table(name: str, raw: Any, ctx: Context) -> dict[str, Any]:
    specs = TABLES[name][1]
    sub = SUBARRAYS.get(name)
    out = read_table(raw, specs, name, ctx, [sub] if sub else [])
    if name == "tissue":
        out["layer"] = _read_layers(raw.get("layer"), ctx)
    if name == "effects":  # auto (None) is the absence of a key
        out = {key: value for key, value in out.items() if value is not None}
    return out


def validate(d: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """Check ``d`` against the specs; return it fully resolved (defaults filled, ints -> float,
    material names canonical, rings as full tables), TOML-shaped. ``unit`` is present only for
    the unit load kinds, ``effects`` only when some effect is set."""
    ctx = Context(SceneError)
    require_table(d, "", list(TABLES), ctx, what="the scene")
    out: dict[str, dict[str, Any]] = {}
    for name in TABLES:
        if name == "unit":
            if "unit" in d:
                out[name] = _read_unit(d["unit"], ctx)
            elif ctx["load.kind"] in UNIT_LOAD_KINDS:
                raise SceneError("unit", f"load.kind = {str(ctx['load.kind'])!r} needs a [unit] "
                                 "table (an empty one takes every default)")
            continue
        table = _read_table(name, d.get(name, {}), ctx)
        if table or name != "effects":
            out[name] = table
    _check_counts(out)
    _check_band(out["analysis"])
    _check_motor_drive(out, ctx["load.kind"])
    _check_band_damping(out)
    if out["analysis"]["kind"] == "transient" and "unit" not in out:
        units = " or ".join(f'"{k}"' for k in UNIT_LOAD_KINDS)
        raise SceneError("analysis.kind", 'analysis.kind = "transient" drives a haptic unit '
                         f"through analysis.voltage_schedule: it needs load.kind = {units} "
                         f"and a [unit] table (load.kind is {str(ctx['load.kind'])!r}); use "
                         "\"static\" or \"harmonic\" for a patch or point load")
    return out


#: Most profile points and time steps a scene may ask for (each is a row of the results).
MAX_PROFILE_POINTS = 100_000
MAX_TIME_STEPS = 1_000_000


def _check_band(a: Mapping[str, Any]) -> None:
    """A sweep needs a band of frequencies, every other analysis one frequency."""
    band = isinstance(a["frequency_hz"], tuple)
    if a["kind"] == "sweep" and not band:
        raise SceneError("analysis.frequency_hz", f"analysis.frequency_hz = "
                         f"{a['frequency_hz']!r}: a sweep needs a band, e.g. frequency_hz = "
                         "{ start = 100, stop = 250, step = 1 } or a list of frequencies in Hz")
    if a["kind"] != "sweep" and band:
        raise SceneError("analysis.frequency_hz", "analysis.frequency_hz is a band of "
                         f"{len(a['frequency_hz'])} frequencies, allowed only with "
                         f"analysis.kind = 'sweep' (kind is {a['kind']!r}); give one number")


def _check_counts(out: Mapping[str, Mapping[str, Any]]) -> None:
    """Cross-field limits on the sizes of the requested results."""
    o, a = out["output"], out["analysis"]
    n = o["profile_length_mm"] / o["profile_step_mm"]
    if n > MAX_PROFILE_POINTS:
        raise SceneError("output.profile_step_mm", f"output.profile_step_mm = "
                         f"{o['profile_step_mm']!r} gives {n:.3g} profile points over "
                         f"output.profile_length_mm = {o['profile_length_mm']!r}: allowed "
                         f"profile_step_mm >= {o['profile_length_mm'] / MAX_PROFILE_POINTS:g} "
                         f"(at most {MAX_PROFILE_POINTS} points)")
    steps = a["duration_ms"] / a["time_step_ms"]
    if a["kind"] == "transient" and steps > MAX_TIME_STEPS:
        raise SceneError("analysis.time_step_ms", f"analysis.time_step_ms = "
                         f"{a['time_step_ms']!r} gives {steps:.3g} steps over "
                         f"analysis.duration_ms = {a['duration_ms']!r}: allowed time_step_ms >= "
                         f"{a['duration_ms'] / MAX_TIME_STEPS:g} (at most {MAX_TIME_STEPS} "
                         "steps)")


#: Largest drive voltage of an ERM transient unless the schedule goes higher [V] (the
#: simulator's guard, fem.transient_analysis.load_history).
ERM_MAX_VOLTAGE_V = 4.5


def _check_motor_drive(out: Mapping[str, Mapping[str, Any]], load_kind: Any) -> None:
    """An ERM transient spins the motor up to its rated speed within the largest drive voltage
    (4.5 V, or the schedule's peak when higher): a rated voltage above it is refused here, at
    load, naming the scene field (the solver's motor model would refuse it at solve)."""
    a = out["analysis"]
    spins_up = LoadKind(load_kind).actuator.spins_up  # the ERM (a kind read and checked)
    if a["kind"] != "transient" or not spins_up or "unit" not in out:
        return
    motor = out["unit"].get("motor") or {}
    rated = motor.get("rated_voltage_V")
    peak = max((abs(float(v)) for _, v in a.get("voltage_schedule") or ()), default=0.0)
    top = max(ERM_MAX_VOLTAGE_V, peak)
    if rated is not None and float(rated) > top:
        raise SceneError("unit.motor.rated_voltage_V", f"unit.motor.rated_voltage_V = "
                         f"{rated!r} is out of range for a transient: allowed "
                         f"unit.motor.start_voltage_V < rated_voltage_V <= {top:g} V (the "
                         f"largest drive voltage: {ERM_MAX_VOLTAGE_V:g} V, or the peak of "
                         "analysis.voltage_schedule when higher)")


def _check_band_damping(out: Mapping[str, Mapping[str, Any]]) -> None:
    """The band model's relaxed modulus E (1 - c eta) must keep a tenth of E
    (``fem.viscoelastic.BandFit.max_loss_factor``): every loss factor is checked, naming the
    first one above the limit."""
    a = out["analysis"]
    if a["kind"] != "transient" or a.get("damping") != "hysteretic_band":
        return
    limit = default_fit().max_loss_factor()
    solids = [(f"tissue.layer[{i}]", layer) for i, layer in enumerate(out["tissue"]["layer"])]
    unit = out.get("unit") or {}
    solids += [(f"unit.encapsulation[{i}]", ring) for i, ring in
               enumerate(unit.get("encapsulation") or ()) if isinstance(ring, Mapping)]
    if isinstance(unit.get("board"), Mapping):
        solids.append(("unit.board", unit["board"]))
    for where, solid in solids:
        eta = solid.get("loss_factor")
        if eta is not None and float(eta) > limit:
            raise SceneError(f"{where}.loss_factor", f"{where}.loss_factor = {eta!r} is out "
                             f"of range for analysis.damping = 'hysteretic_band': allowed "
                             f"loss_factor <= {limit:.3g} (the band model's static modulus "
                             "E (1 - c eta) keeps a tenth of E); use damping = "
                             "'viscous_at_drive' for a larger loss")


def make(cls: type, table: Mapping[str, Any]) -> Any:
    """``cls`` from the keys of ``table`` that are its fields."""
    names = {f.name for f in dataclasses.fields(cls)}
    return cls(**{key: value for key, value in table.items() if key in names})


def build_unit(u: Mapping[str, Any]) -> Unit:
    """A :class:`Unit` from its resolved table."""
    parts = {name: make(cls, u[name]) for name, (cls, _) in UNIT_PARTS.items() if name in u}
    return Unit(u["orientation"], u["attachment"],
                tuple(make(Ring, ring) for ring in u["encapsulation"]), u["ring_thickness_mm"],
                u["ring_contact"], **parts)


def build_scene(resolved: Mapping[str, Mapping[str, Any]]) -> Scene:
    """A :class:`Scene` from the output of :func:`validate`."""
    parts: dict[str, Any] = {}
    for name, (cls, _) in TABLES.items():
        if name == "unit":
            if name in resolved:
                parts[name] = build_unit(resolved[name])
        elif name == "tissue":
            layers = tuple(make(Layer, layer) for layer in resolved[name]["layer"])
            parts[name] = make(Tissue, {**resolved[name], "layers": layers})
        else:
            parts[name] = make(cls, resolved.get(name, {}))
    return Scene(**parts)
