"""The scene schema as data: one spec table per TOML table (key -> ``fieldspec.Spec``: type,
allowed range or choices). Defaults are those of the dataclass fields (``MODEL``), written once
with their sources in ``fem.scene.model`` / ``unit_model``; the default forearm is here. Adding
a key or a table is adding an entry here and a dataclass field.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from fieldspec import REQUIRED, Spec
from motorlaw.lra import RANGES as LRA_RANGES

from ..materials import get_material
from .frequencies import Frequencies, read_frequencies
from .model import (
    EFFECT_NAMES,
    Analysis,
    Effects,
    Layer,
    Load,
    LoadKind,
    MeshSettings,
    Output,
    Tissue,
)
from .schedule import Schedule, read_schedule
from .unit_model import Actuator, Board, LraPart, Motor, Pogo, Unit

MAX_LAYERS = 50
MAX_RINGS = 5
FROM_MATERIAL = " or a library material (material = ...)"

MODEL: Any = object()
"""Spec default sentinel: the default of the dataclass field of the same name (the defaults and
their sources are written once, in ``fem.scene.model`` and ``fem.scene.unit_model``)."""


def _from_model(cls: type, specs: dict[str, Spec]) -> dict[str, Spec]:
    """``specs`` with every :data:`MODEL` default replaced by the default of ``cls``'s field."""
    defaults = {f.name: f.default for f in dataclasses.fields(cls)
                if f.default is not dataclasses.MISSING}
    return {key: dataclasses.replace(spec, default=defaults[key]) if spec.default is MODEL
            else spec for key, spec in specs.items()}


# The forearm of Guo et al. 2025 (Biomimetics 10:597), Table 1. The paper states a 31.9 mm
# block, which fits none of the ways to split Table 1's digits; this reading
# (1.9 + 14 + 21 + 5 = 41.9 mm) keeps the plausible layer thicknesses and is a documented choice.
# The moduli, densities and Poisson's ratios are the library's (``fem.materials``, same source).
DEFAULT_FOREARM_THICKNESS_MM = (("skin", 1.9), ("subcutaneous", 14.0), ("muscle", 21.0),
                                ("bone", 5.0))
DEFAULT_FOREARM_LAYERS: tuple[Layer, ...] = tuple(
    Layer(m.name, thickness, m.E_Pa / 1e3, m.density_kg_m3, m.nu, m.loss_factor, m.name)
    for m, thickness in ((get_material(name), t) for name, t in DEFAULT_FOREARM_THICKNESS_MM))

LAYER = _from_model(Layer, {
    "name": Spec(str, None),  # default: the material name, else "layer<i>"
    "material": Spec(str, None),  # library name; explicit fields below override it
    "thickness_mm": Spec(float, REQUIRED, "[0.001, 10000]"),  # 1 um: below, cells are slivers
    "E_kPa": Spec(float, REQUIRED, "[0.001, 1e9]", missing_hint=FROM_MATERIAL),
    "density_kg_m3": Spec(float, REQUIRED, "(0, 1e5]", missing_hint=FROM_MATERIAL),
    "nu": Spec(float, REQUIRED, "[0, 0.5)", missing_hint=FROM_MATERIAL),
    "loss_factor": Spec(float, MODEL, "[0, 2]"),
})
RING = {key: spec for key, spec in LAYER.items() if key != "thickness_mm"}  # name: "ring<i>"

MOTOR = _from_model(Motor, {
    "diameter_mm": Spec(float, MODEL, "[0.001, 100]"),  # lengths >= 1 um: no sliver cells
    "height_mm": Spec(float, MODEL, "[0.001, 50]"),
    "mass_g": Spec(float, MODEL, "(0, 1000]"),
    "unbalance_g_mm": Spec(float, MODEL, "(0, 1000]"),
    "force_N": Spec(float, None, "(0, 1e3]", input_only=True),  # -> unbalance_g_mm
    "force_at_hz": Spec(float, None, "(0, 1e5]", input_only=True),
    "rotor_height_mm": Spec(float, MODEL, "[0, unit.motor.height_mm]"),
    "E_kPa": Spec(float, MODEL, "[0.001, 1e9]"),
    "nu": Spec(float, MODEL, "[0, 0.5)"),
    "rated_voltage_V": Spec(float, MODEL, "(0, 50]"),
    "rated_frequency_hz": Spec(float, MODEL, "(0, 1e4]"),
    "start_voltage_V": Spec(float, MODEL, "[0, unit.motor.rated_voltage_V)"),
    "tau_spinup_ms": Spec(float, MODEL, "(0, 1e4]"),
    "tau_spindown_ms": Spec(float, MODEL, "(0, 1e4]"),
})
BOARD = _from_model(Board, {
    "thickness_mm": Spec(float, MODEL, "[0, 10]"),  # 0: no board; else >= 1 um (unit checks)
    "diameter_mm": Spec(float, MODEL, "[0.001, 100]"),
    "material": Spec(str, MODEL),  # library name; the three keys below default to its values
    "E_kPa": Spec(float, REQUIRED, "[0.001, 1e9]", missing_hint=FROM_MATERIAL),
    "density_kg_m3": Spec(float, REQUIRED, "(0, 1e5]", missing_hint=FROM_MATERIAL),
    "nu": Spec(float, REQUIRED, "[0, 0.5)", missing_hint=FROM_MATERIAL),
})
POGO = _from_model(Pogo, {
    "count": Spec(int, MODEL, "[1, 64]"),
    "radius_mm": Spec(float, MODEL, "[0.001, 50]"),
    "stiffness_N_m": Spec(float, MODEL, "(0, 1e9]"),
    "length_mm": Spec(float, MODEL, "[0.001, 50]"),
    "travel_mm": Spec(float, MODEL, "[0, unit.pogo.length_mm)"),
    "tip_diameter_mm": Spec(float, MODEL, "[0.001, 5]"),
})
ACTUATOR = _from_model(Actuator, {"force_N": Spec(float, MODEL, "[-1e3, 1e3]", nonzero=True)})
# [unit.lra]: the ranges of the LRA's drive law (motorlaw.lra.RANGES), the mass in g
LRA = _from_model(LraPart, {
    "resonance_hz": Spec(float, MODEL, "[{:g}, {:g}]".format(*LRA_RANGES["resonance_hz"])),
    "quality_factor": Spec(float, MODEL, "[{:g}, {:g}]".format(*LRA_RANGES["quality_factor"])),
    "moving_mass_g": Spec(float, MODEL, "[{:g}, {:g}]".format(
        *(1e3 * m for m in LRA_RANGES["moving_mass_kg"]))),
    "rated_voltage_V": Spec(float, MODEL, "[{:g}, {:g}]".format(*LRA_RANGES["rated_voltage_V"])),
    "max_voltage_V": Spec(float, MODEL, "[unit.lra.rated_voltage_V, {:g}]".format(
        LRA_RANGES["max_voltage_V"][1])),
})

# [unit]: its own keys, the rings list, then its part tables (in this order when written).
UNIT = _from_model(Unit, {
    "orientation": Spec(str, MODEL, choices=("forward", "reverse")),
    "attachment": Spec(str, MODEL, choices=("glued", "pogo")),
    "ring_thickness_mm": Spec(float, MODEL, "[0.001, 20]"),
    "ring_contact": Spec(str, MODEL, choices=("frictionless", "bonded", "none")),
})
UNIT_PARTS: dict[str, tuple[type, dict[str, Spec]]] = {
    "motor": (Motor, MOTOR),
    "board": (Board, BOARD),
    "pogo": (Pogo, POGO),
    "actuator": (Actuator, ACTUATOR),
    "lra": (LraPart, LRA),  # optional: an actuator's own table (Actuator.own_part)
}
UNIT_KEYS = ["orientation", "attachment", "encapsulation", "ring_thickness_mm", "ring_contact",
             *UNIT_PARTS]

# Table name -> (dataclass, specs). Order matters: intervals may refer to earlier values, and
# the [unit] checks need tissue.radius_mm and load.kind.
_TABLE_SPECS: dict[str, tuple[type, dict[str, Spec]]] = {
    "tissue": (Tissue, {
        "radius_mm": Spec(float, MODEL, "[0.001, 1e5]"),
        "side": Spec(str, MODEL, choices=("absorbing", "fixed", "free")),
        "base": Spec(str, MODEL, choices=("fixed", "absorbing")),
    }),
    "load": (Load, {
        "kind": Spec(str, MODEL, choices=tuple(kind.value for kind in LoadKind)),
        "direction": Spec(str, MODEL, choices=("normal", "tangential")),
        "radius_mm": Spec(float, MODEL, "[0.001, tissue.radius_mm)"),
        "amplitude_Pa": Spec(float, MODEL, "[-1e9, 1e9]", nonzero=True),
        "force_N": Spec(float, MODEL, "[-1e9, 1e9]", nonzero=True),
    }),
    "unit": (Unit, UNIT),
    "analysis": (Analysis, {
        "kind": Spec(str, MODEL, choices=("static", "harmonic", "transient", "sweep")),
        "frequency_hz": Spec(Frequencies, MODEL, "(0, 1e5]", reader=read_frequencies),
        "time_step_ms": Spec(float, MODEL, "(0, 100]"),
        "duration_ms": Spec(float, MODEL, "[analysis.time_step_ms, 1e5]"),
        "rho_inf": Spec(float, MODEL, "[0, 1]"),
        "voltage_schedule": Spec(Schedule, MODEL, "[-50, 50]", reader=read_schedule),
        "damping": Spec(str, MODEL, choices=("viscous_at_drive", "hysteretic_band")),
        "tolerance": Spec(float, MODEL, "[1e-6, 0.1]"),
    }),
    "mesh": (MeshSettings, {
        "near_size_mm": Spec(float, MODEL, "(0, 100]"),
        "near_radius_mm": Spec(float, MODEL, "(0, tissue.radius_mm]"),
        "far_size_mm": Spec(float, MODEL, "[mesh.near_size_mm, 1000]"),
        "order": Spec(int, MODEL, choices=(1, 2)),
        "follow_wavelength": Spec(bool, MODEL),
        "cells_r": Spec(list, None, "[1, 100000]"),  # cells per mesh segment
        "cells_z": Spec(list, None, "[1, 100000]"),
    }),
    "output": (Output, {
        "radii_mm": Spec(tuple, MODEL, "[0, tissue.radius_mm]"),
        "profile_step_mm": Spec(float, MODEL, "(0, 100]"),
        "profile_length_mm": Spec(float, MODEL, "(0, 1000]"),
        "history_every": Spec(int, MODEL, "[1, 1e6]"),
    }),
    "effects": (Effects, {name: Spec(bool, MODEL) for name in EFFECT_NAMES}),
}
TABLES = {name: (cls, _from_model(cls, specs)) for name, (cls, specs) in _TABLE_SPECS.items()}
SUBARRAYS = {"tissue": "layer"}  # array-of-tables keys inside a table
