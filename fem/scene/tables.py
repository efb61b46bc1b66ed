"""The scene schema as data: one spec table per TOML table (key -> Spec), with the defaults and
where each comes from. Adding a key or a table is adding an entry here and a dataclass field.
"""

from __future__ import annotations

from fieldspec import REQUIRED, Spec

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
from .unit_model import Actuator, Board, Motor, Pogo, Unit

MAX_LAYERS = 50
MAX_RINGS = 5
FROM_MATERIAL = " or a library material (material = ...)"

# The forearm of Guo et al. 2025 (Biomimetics 10:597), Table 1. The paper states a 31.9 mm
# block, which fits none of the ways to split Table 1's digits; this reading
# (1.9 + 14 + 21 + 5 = 41.9 mm) keeps the plausible layer thicknesses and is a documented choice.
DEFAULT_FOREARM_LAYERS: tuple[Layer, ...] = (
    Layer("skin", 1.9, 49.0, 1116.0, 0.47, 0.0, "skin"),
    Layer("subcutaneous", 14.0, 10.0, 1116.0, 0.47, 0.0, "subcutaneous"),
    Layer("muscle", 21.0, 53.0, 1116.0, 0.47, 0.0, "muscle"),
    Layer("bone", 5.0, 2.94e6, 2000.0, 0.32, 0.0, "bone"),
)

LAYER = {
    "name": Spec(str, None),  # default: the material name, else "layer<i>"
    "material": Spec(str, None),  # library name; explicit fields below override it
    "thickness_mm": Spec(float, REQUIRED, "(0, 10000]"),
    "E_kPa": Spec(float, REQUIRED, "(0, 1e9]", missing_hint=FROM_MATERIAL),
    "density_kg_m3": Spec(float, REQUIRED, "(0, 1e5]", missing_hint=FROM_MATERIAL),
    "nu": Spec(float, REQUIRED, "[0, 0.5)", missing_hint=FROM_MATERIAL),
    "loss_factor": Spec(float, 0.0, "[0, 2]"),
}
RING = {key: spec for key, spec in LAYER.items() if key != "thickness_mm"}  # name: "ring<i>"

MOTOR = {
    "diameter_mm": Spec(float, 7.0, "(0, 100]"),
    "height_mm": Spec(float, 2.0, "(0, 50]"),
    "mass_g": Spec(float, 0.6, "(0, 1000]"),
    "unbalance_g_mm": Spec(float, 0.006, "(0, 1000]"),
    "force_N": Spec(float, None, "(0, 1e3]", input_only=True),  # -> unbalance_g_mm
    "force_at_hz": Spec(float, None, "(0, 1e5]", input_only=True),
    "rotor_height_mm": Spec(float, 1.4, "[0, unit.motor.height_mm]"),
    "E_kPa": Spec(float, 5.0e6, "(0, 1e9]"),
    "nu": Spec(float, 0.3, "[0, 0.5)"),
    "rated_voltage_V": Spec(float, 3.3, "(0, 50]"),
    "rated_frequency_hz": Spec(float, 120.0, "(0, 1e4]"),
    "start_voltage_V": Spec(float, 0.4, "[0, unit.motor.rated_voltage_V)"),
    "tau_spinup_ms": Spec(float, 20.0, "(0, 1e4]"),
    "tau_spindown_ms": Spec(float, 35.0, "(0, 1e4]"),
}
BOARD = {
    "thickness_mm": Spec(float, 0.1, "[0, 10]"),
    "diameter_mm": Spec(float, 7.0, "(0, 100]"),
    "material": Spec(str, "pcb"),  # library name; the three keys below default to its values
    "E_kPa": Spec(float, REQUIRED, "(0, 1e9]", missing_hint=FROM_MATERIAL),
    "density_kg_m3": Spec(float, REQUIRED, "(0, 1e5]", missing_hint=FROM_MATERIAL),
    "nu": Spec(float, REQUIRED, "[0, 0.5)", missing_hint=FROM_MATERIAL),
}
POGO = {
    "count": Spec(int, 3, "[1, 64]"),
    "radius_mm": Spec(float, 2.25, "(0, 50]"),
    "stiffness_N_m": Spec(float, 2942.0, "(0, 1e9]"),
    "length_mm": Spec(float, 2.4, "(0, 50]"),
    "travel_mm": Spec(float, 0.3, "[0, unit.pogo.length_mm)"),
    "tip_diameter_mm": Spec(float, 0.5, "(0, 5]"),
}
ACTUATOR = {"force_N": Spec(float, 0.1, "[-1e3, 1e3]", nonzero=True)}

# [unit]: its own keys, the rings list, then its part tables (in this order when written).
UNIT = {
    "orientation": Spec(str, "forward", choices=("forward", "reverse")),
    "attachment": Spec(str, "glued", choices=("glued", "pogo")),
    "ring_thickness_mm": Spec(float, 1.0, "(0, 20]"),
    "ring_contact": Spec(str, "frictionless", choices=("frictionless", "bonded", "none")),
}
UNIT_PARTS: dict[str, tuple[type, dict[str, Spec]]] = {
    "motor": (Motor, MOTOR),
    "board": (Board, BOARD),
    "pogo": (Pogo, POGO),
    "actuator": (Actuator, ACTUATOR),
}
UNIT_KEYS = ["orientation", "attachment", "encapsulation", "ring_thickness_mm", "ring_contact",
             *UNIT_PARTS]

# Table name -> (dataclass, specs). Order matters: intervals may refer to earlier values, and
# the [unit] checks need tissue.radius_mm and load.kind.
TABLES: dict[str, tuple[type, dict[str, Spec]]] = {
    "tissue": (Tissue, {
        "radius_mm": Spec(float, 50.0, "(0, 1e5]"),
        "side": Spec(str, "absorbing", choices=("absorbing", "fixed", "free")),
        "base": Spec(str, "fixed", choices=("fixed", "absorbing")),
    }),
    "load": (Load, {
        "kind": Spec(str, LoadKind.PRESSURE_PATCH.value,
                     choices=tuple(kind.value for kind in LoadKind)),
        "direction": Spec(str, "normal", choices=("normal", "tangential")),
        "radius_mm": Spec(float, 2.0, "(0, tissue.radius_mm)"),
        "amplitude_Pa": Spec(float, 1000.0, "[-1e9, 1e9]", nonzero=True),
        "force_N": Spec(float, 1.0, "[-1e9, 1e9]", nonzero=True),
    }),
    "unit": (Unit, UNIT),
    "analysis": (Analysis, {
        "kind": Spec(str, "static", choices=("static", "harmonic", "transient")),
        "frequency_hz": Spec(float, 120.0, "(0, 1e5]"),
        "time_step_ms": Spec(float, 0.05, "(0, 100]"),
        "duration_ms": Spec(float, 200.0, "[analysis.time_step_ms, 1e5]"),
        "rho_inf": Spec(float, 0.9, "[0, 1]"),
        "voltage_schedule": Spec(Schedule, ((0.0, 3.3),), "[-50, 50]", reader=read_schedule),
    }),
    "mesh": (MeshSettings, {
        "near_size_mm": Spec(float, 0.5, "(0, 100]"),
        "near_radius_mm": Spec(float, 8.0, "(0, tissue.radius_mm]"),
        "far_size_mm": Spec(float, 2.0, "[mesh.near_size_mm, 1000]"),
        "order": Spec(int, 2, choices=(1, 2)),
    }),
    "output": (Output, {
        "radii_mm": Spec(tuple, (0.0, 2.0, 4.0, 8.0, 12.0, 16.0, 20.0), "[0, tissue.radius_mm]"),
        "profile_step_mm": Spec(float, 1.0, "(0, 100]"),
        "profile_length_mm": Spec(float, 20.0, "(0, 1000]"),
        "history_every": Spec(int, 1, "[1, 1e6]"),
    }),
    "effects": (Effects, {name: Spec(bool, None) for name in EFFECT_NAMES}),
}
SUBARRAYS = {"tissue": "layer"}  # array-of-tables keys inside a table
