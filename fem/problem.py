"""From a validated scene to a discretised problem: which Fourier mode, which operators, which
load, and which physical effects are in or out.

Effects are switched on by what the scene contains ("auto") and can be switched off in the
scene's ``[effects]`` table; asking for an effect the scene cannot have is an error. Nothing an
effect needs is built when it is off: no mass without inertia, no complex moduli without
hysteretic damping, no ring cells without encapsulation, no pin operator without pogo pins.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from . import haptic_unit
from .absorbers import ELEMENTS_PER_WAVELENGTH
from .assembly import UR
from .domain import CellPlanError, Domain, MeshSpec, layered_domain
from .scene import LoadKind, Scene, SceneError, Unit


@dataclass(frozen=True)
class Problem:
    """A discretised scene.

    Attributes:
        domain: mesh, materials, absorbers, constraints.
        mode: the one Fourier mode the load excites.
        omega: drive angular frequency (rad/s) of a steady solve; 0 for static or quasi-static.
        load: full nodal load vector (N) at the drive amplitude.
        extra: (name, dofs, matrices) operators beyond the continuum (pin springs).
        edge: radius of the load footprint's edge (m), None for a point force.
        effects: resolved effect switches.
        unit: the scene's unit, or None; layout: where its parts are.
    """

    domain: Domain
    mode: int
    omega: float
    load: NDArray
    extra: tuple
    edge: float | None
    effects: dict[str, bool]
    unit: Unit | None = None
    layout: haptic_unit.UnitLayout | None = None

    def effect_lists(self) -> tuple[list[str], list[str]]:
        """(included, skipped) effect names for the summary, with the domain's own."""
        inc = [*self.domain.effects, *(k.replace("_", " ") for k, v in self.effects.items() if v)]
        skip = [*self.domain.skipped,
                *(k.replace("_", " ") for k, v in self.effects.items() if not v),
                f"Fourier mode {1 - self.mode}"]
        return inc, skip


def _has_loss(scene: Scene) -> bool:
    rings = scene.unit.encapsulation if scene.unit is not None else ()
    return any(x.loss_factor > 0 for x in (*scene.tissue.layers, *rings))


def resolve_effects(scene: Scene) -> dict[str, bool]:
    """Effect switches: the scene's explicit choices over what it contains. Every effect the
    scene can have is on by default, except the pin preload check (on request only)."""
    u = scene.unit
    act = scene.load.kind.actuator
    rocks = [f"'{k}'" for k in LoadKind if k.actuator.parallel_force]
    spins = [f"'{k}'" for k in LoadKind if k.actuator.spins_up]
    available = {
        "inertia": (scene.analysis.kind != "static",
                    "analysis.kind = 'harmonic', 'sweep' or 'transient'"),
        "hysteretic_damping": (_has_loss(scene), "a layer or ring with loss_factor > 0"),
        "encapsulation": (u is not None and len(u.encapsulation) > 0, "unit.encapsulation rings"),
        "pogo": (u is not None and u.attachment == "pogo", "unit.attachment = 'pogo'"),
        "unit_mass": (u is not None, "a [unit]"),
        "rocking": (act.parallel_force, f"load.kind = {' or '.join(rocks)} (an ERM)"),
        "spin_up": (act.spins_up and scene.analysis.kind == "transient",
                    f"load.kind = {' or '.join(spins)} with analysis.kind = 'transient'"),
        "preload": (u is not None and u.attachment == "pogo", "unit.attachment = 'pogo'"),
    }
    chosen = {}
    for name, (possible, needs) in available.items():
        asked = getattr(scene.effects, name)
        if asked and not possible:
            raise SceneError(f"effects.{name}", f"effects.{name} = true needs {needs}")
        auto = possible and name != "preload"
        chosen[name] = auto if asked is None else bool(asked)
    if scene.analysis.kind == "transient" and not chosen["inertia"]:
        raise SceneError("effects.inertia", "a transient analysis needs inertia = true")
    if u is not None and u.attachment == "pogo" and not chosen["pogo"]:
        raise SceneError("effects.pogo", "effects.pogo = false conflicts with unit.attachment = "
                         "'pogo'; set attachment = 'glued' to drop the pins")
    _check_unit_restrained(scene, chosen)
    return chosen


def _check_unit_restrained(scene: Scene, effects: dict[str, bool]) -> None:
    """A unit on frictionless pins whose rings do not touch it (ring_contact = "none", or no
    rings) is held sideways only by its own inertia: without inertia or mass it is a mechanism,
    and a transient spin-up makes it drift away."""
    u = scene.unit
    if u is None or u.attachment != "pogo":
        return
    if u.encapsulation and effects["encapsulation"] and u.ring_contact != "none":
        return
    why = ("leaves the unit on frictionless pogo pins with nothing holding it sideways (no "
           "rings touch it); give it rings with unit.ring_contact = 'frictionless' or 'bonded'")
    for name in ("inertia", "unit_mass"):
        if not effects[name]:
            if getattr(scene.effects, name) is None and name == "inertia":  # the default
                raise SceneError("analysis.kind", f"analysis.kind = '{scene.analysis.kind}' "
                                 "has no inertia (effects.inertia defaults to false for a "
                                 f"static analysis), which {why}; or solve it with "
                                 "analysis.kind = 'harmonic'")
            raise SceneError(f"effects.{name}", f"effects.{name} = false {why}")
    if scene.analysis.kind == "transient":
        raise SceneError("unit.ring_contact", f"a transient spin-up {why}: it would drift away")


def shortest_shear_wavelength(scene: Scene) -> tuple[float, str]:
    """(wavelength [m], part name): the shortest elastic shear wavelength at the drive
    frequency among the tissue layers and the rings; (inf, "") for a static analysis."""
    if scene.analysis.kind == "static":
        return np.inf, ""
    parts = [(ly.name, ly.solid()) for ly in scene.tissue.layers]
    if scene.unit is not None:
        parts += [(ring.name, ring.solid()) for ring in scene.unit.encapsulation]
    name, solid = min(parts, key=lambda p: p[1].shear_speed_m_s)
    return 2 * np.pi * solid.shear_speed_m_s / drive_omega(scene), name


def wave_element_size(scene: Scene) -> float:
    """Largest element size [m] with ``absorbers.ELEMENTS_PER_WAVELENGTH / order`` elements
    per shortest shear wavelength (inf for a static analysis)."""
    lam, _ = shortest_shear_wavelength(scene)
    return lam * scene.mesh.order / ELEMENTS_PER_WAVELENGTH


def mesh_spec(scene: Scene) -> MeshSpec:
    """The element sizes [m] the scene is meshed with: its own, capped by the wavelength rule
    when ``mesh.follow_wavelength``."""
    m = scene.mesh
    near, far = m.near_size_mm * 1e-3, m.far_size_mm * 1e-3
    if m.follow_wavelength:
        h = wave_element_size(scene)
        near, far = min(near, h), min(far, h)
    return MeshSpec(near, m.near_radius_mm * 1e-3, far, m.order, cells_r=m.cells_r,
                    cells_z=m.cells_z)


def drive_omega(scene: Scene) -> float:
    """Angular frequency (rad/s) the mesh is sized for and the absorbers are tuned for: the
    analysis frequency (a sweep's highest), or for a transient ERM the motor's rated speed."""
    if scene.analysis.kind == "transient":
        return 2 * np.pi * scene.load.kind.actuator.transient_frequency_hz(scene)
    return 2 * np.pi * scene.analysis.frequency_hz


def absorber_omega(scene: Scene) -> float:
    """Angular frequency (rad/s) whose wavelength sets the absorbers' extent: a sweep's
    lowest frequency (the longest wave of its band), else :func:`drive_omega`."""
    if scene.analysis.kind == "sweep":
        return 2 * np.pi * min(scene.analysis.frequencies_hz)
    return drive_omega(scene)


def build_problem(scene: Scene) -> Problem:
    """Discretise a scene with only the effects it asks for."""
    effects = resolve_effects(scene)
    hyst = effects["hysteretic_damping"]
    layers = [(ly.thickness_m, ly.solid(hyst)) for ly in scene.tissue.layers]
    dynamic = effects["inertia"]
    analysis = {"sweep": "harmonic"}.get(scene.analysis.kind, scene.analysis.kind)
    analysis = analysis if dynamic else "static"
    omega = drive_omega(scene) if dynamic else 0.0
    lay = None
    act = scene.load.kind.actuator
    r_breaks, blocks, z_breaks = act.r_breaks(scene), (), ()
    if act.is_unit:
        lay = haptic_unit.layout(scene.unit, effects["encapsulation"], effects["unit_mass"],
                                 effects["rocking"], hyst)
        r_breaks, blocks, z_breaks = lay.r_breaks, lay.blocks, lay.z_breaks
    try:
        domain = layered_domain(layers, scene.tissue.radius_m, scene.tissue.side,
                                scene.tissue.base, mesh_spec(scene), analysis, omega, r_breaks,
                                blocks, z_breaks=z_breaks,
                                absorber_omega=absorber_omega(scene) if dynamic else None)
    except CellPlanError as err:
        raise SceneError(f"mesh.cells_{err.axis}", f"mesh.cells_{err.axis}: {err}") from None
    if lay is not None and lay.contact_ties is not None:
        domain = replace(domain, ties=(ring_contact_ties(domain, *lay.contact_ties),))
    mode = scene.load.fourier_mode
    extra = ()
    if lay is not None and lay.pins is not None:
        extra = (("pogo pins", *haptic_unit.pin_spring(domain, mode, lay.pins)),)
    steady_omega = omega if scene.analysis.kind in ("harmonic", "sweep") else 0.0
    return Problem(domain, mode, steady_omega, act.nodal_load(scene, domain, mode, lay), extra,
                   act.edge(scene, lay), effects, scene.unit, lay)


def ring_contact_ties(domain: Domain, r_core: float, r_ring: float, z_top: float,
                      z_bottom: float) -> tuple[NDArray, NDArray, int]:
    """Frictionless contact across the slit between the core and the inner ring: the ring's
    radial displacement follows the core's at every node height where the core has a face.

    When the motor and the board differ in diameter the core's outer face at ``r_core`` covers
    only the wider part's height; the ring's inner face spans the whole unit height, so only
    its nodes level with a core node are tied (the rest face a gap and move freely)."""
    nodes = domain.mesh.nodes
    tol = 1e-9

    def face(r: float) -> NDArray:
        on = (np.abs(nodes[:, 0] - r) < tol) & (nodes[:, 1] >= z_top - tol) & (
            nodes[:, 1] <= z_bottom + tol)
        idx = np.flatnonzero(on)
        return idx[np.argsort(nodes[idx, 1])]

    core, ring = face(r_core), face(r_ring)
    z_ring = nodes[ring, 1]
    at = np.clip(np.searchsorted(z_ring, nodes[core, 1] - tol), 0, max(ring.size - 1, 0))
    if ring.size == 0 or not np.allclose(z_ring[at], nodes[core, 1], rtol=0.0, atol=tol):
        # the mesher puts the ring's and the core's grid lines at the same heights
        raise AssertionError("ring contact: a core face node has no ring node level with it")
    return ring[at], core, UR


def resolution_warning(scene: Scene, problem: Problem) -> str | None:
    """A message when the largest elements hold fewer than ``ELEMENTS_PER_WAVELENGTH / order``
    elements per shortest shear wavelength (10 linear or 5 quadratic keep the phase error near
    1 %). Only possible with ``mesh.follow_wavelength = false``: otherwise the mesh obeys the
    rule by construction."""
    lam, part = shortest_shear_wavelength(scene)
    h = mesh_spec(scene).far_size
    if not np.isfinite(lam) or h <= wave_element_size(scene) * (1 + 1e-9):
        return None
    f = drive_omega(scene) / (2 * np.pi)
    per_wave = lam / h
    advice = f"use far_size_mm <= {np.floor(wave_element_size(scene) * 1e6) / 1e3:g}"
    if scene.mesh.order == 1:
        advice += " or mesh.order = 2"
    return (f"under-resolved: {per_wave:.2f} elements per shear wavelength ({lam * 1e3:.2f} mm) "
            f"in '{part}' at {f:g} Hz with far_size_mm = {h * 1e3:g} and order "
            f"{scene.mesh.order}; {advice}, or mesh.follow_wavelength = true (about 1 % error)")
