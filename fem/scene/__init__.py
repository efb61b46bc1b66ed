"""Scene schema: a TOML file describing one FE problem, validated into frozen dataclasses.

Layout (the public contract; ``examples/forearm.toml`` and ``examples/unit-*.toml`` are
commented files)::

    [tissue]            radius_mm, side, base, and [[tissue.layer]] (top to bottom):
                        name, material, thickness_mm, E_kPa, density_kg_m3, nu, loss_factor
    [load]              kind, direction, radius_mm, amplitude_Pa, force_N
    [unit]              orientation, attachment, encapsulation, ring_thickness_mm
      [unit.motor]      diameter_mm, height_mm, mass_g, unbalance_g_mm (or force_N and
                        force_at_hz), rotor_height_mm, E_kPa, nu, rated_voltage_V,
                        rated_frequency_hz, start_voltage_V, tau_spinup_ms, tau_spindown_ms
      [unit.board]      thickness_mm, diameter_mm, material, E_kPa, density_kg_m3, nu
      [unit.pogo]       count, radius_mm, stiffness_N_m, length_mm, travel_mm, tip_diameter_mm
      [unit.actuator]   force_N
    [analysis]          kind, frequency_hz, time_step_ms, duration_ms, rho_inf, voltage_schedule,
                        damping
    [mesh]              near_size_mm, near_radius_mm, far_size_mm, order, follow_wavelength,
                        cells_r, cells_z (optional fixed cells per segment)
    [output]            radii_mm, profile_step_mm, profile_length_mm, history_every
    [effects]           inertia, hysteretic_damping, encapsulation, pogo, unit_mass, rocking,
                        spin_up, preload (booleans; a missing key means "auto")

Values are stored in the user units named in each field (mm, kPa, g, ms); SI properties
(``E_Pa``, ``thickness_m``, ``unbalance_kg_m``, ``solid()``, ...) convert at the edge. Every
table is described by a spec table (``fem.scene.tables``: key -> ``fieldspec.Spec``), so adding
a table or an analysis kind is a matter of adding a spec entry and a dataclass.

Modules: ``model`` and ``unit_model`` (frozen dataclasses), ``tables`` (spec tables and
defaults with their sources), ``validate`` (checks and building), ``io`` (TOML load/dump,
``scene_from_dict``, ``scene_to_dict``, ``scene_hash``).

The haptic unit. ``load.kind = "unit"`` is a coin ERM motor (an unbalance force rotating
parallel to the skin, Fourier mode 1), ``"normal_actuator"`` a voice coil (a vertical force on
the housing, mode 0, amplitude ``[unit.actuator] force_N``) and ``"lra"`` a coin LRA (the same
force at its resonance, a resonator's force elsewhere). Each kind is an actuator class of
``fem.actuators``. The unit kinds need a ``[unit]`` table, and a ``[unit]`` table needs one;
``load.direction``, ``radius_mm``, ``amplitude_Pa`` and ``force_N`` are then not used.
``encapsulation`` lists the silicone rings inner to outer, each a library material name
(aliases "A".."D" allowed) or an inline table with the keys of a tissue layer except
``thickness_mm`` (every ring is ``ring_thickness_mm`` wide).
``[unit.pogo]`` is validated even when ``attachment = "glued"`` leaves it unused.
``[unit.actuator]`` is only allowed with the kinds that read it (``"normal_actuator"``, ``"lra"``).

What :func:`scene_to_dict` writes back is described in ``fem.scene.io``.

Every error is a :class:`SceneError` (a ``fieldspec.FieldError``) whose ``.field`` is the
dotted path of the offending value (``tissue.layer[1].nu``, ``unit.encapsulation[2].E_kPa``)
and whose message names the allowed range or choices.
"""

from .io import dump_scene_toml, load_scene, scene_from_dict, scene_hash, scene_to_dict
from .model import (
    EFFECT_NAMES,
    UNIT_LOAD_KINDS,
    Analysis,
    Effects,
    Layer,
    Load,
    LoadKind,
    MeshSettings,
    Output,
    Scene,
    SceneError,
    Tissue,
)
from .tables import DEFAULT_FOREARM_LAYERS, MAX_LAYERS, MAX_RINGS
from .unit_model import RING_GAP_MM, Actuator, Board, LraPart, Motor, Pogo, Ring, Unit
from .usage import effective_scene_dict, unused_fields

__all__ = [
    "DEFAULT_FOREARM_LAYERS",
    "EFFECT_NAMES",
    "MAX_LAYERS",
    "MAX_RINGS",
    "RING_GAP_MM",
    "UNIT_LOAD_KINDS",
    "Actuator",
    "Analysis",
    "Board",
    "Effects",
    "Layer",
    "Load",
    "LoadKind",
    "LraPart",
    "MeshSettings",
    "Motor",
    "Output",
    "Pogo",
    "Ring",
    "Scene",
    "SceneError",
    "Tissue",
    "Unit",
    "dump_scene_toml",
    "effective_scene_dict",
    "load_scene",
    "scene_from_dict",
    "scene_hash",
    "scene_to_dict",
    "unused_fields",
]
