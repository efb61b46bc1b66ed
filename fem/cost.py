"""What a scene will cost before anything is allocated: cells, unknowns, memory and time.

The mesher grades element sizes along r and z (``fem.mesh.graded_lines``: the number of cells
of a segment is the integral of 1/h over it) and appends the absorbers (a PML or damping layer
one or three reference wavelengths thick, meshed at the wave size, or a graded static far
field). Those counts have closed forms, so the size of a scene is known from its numbers alone,
even for inputs (a 1e-30 kPa layer, 0.1 Hz, a 100 m radius) whose mesh could never be built.

:func:`check_cost` turns an estimate above the limit into a :class:`fem.scene.SceneError`
naming the scene fields that drive the size, with values that would fit. Memory and time are
rough models calibrated on this solver (sparse LU of a 2-D grid: fill ~ N log N, time ~ N^1.5);
the unknown count is the reliable part and the limit is stated in it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

from . import haptic_unit
from .absorbers import (
    DAMPING_LAYER_WAVELENGTHS,
    ELEMENTS_PER_WAVELENGTH,
    STATIC_EXTENSION_FACTOR,
    reference_speed,
)
from .domain import MeshSpec
from .problem import (
    absorber_omega,
    mesh_spec,
    resolve_effects,
    shortest_shear_wavelength,
)
from .scene import Scene, SceneError

__all__ = ["DEFAULT_MAX_UNKNOWNS", "CostEstimate", "check_cost", "estimate_cost"]

#: Largest problem solved without ``force``: about 12 GB of sparse LU by the model below,
#: sized for a 24 GB, 2-core machine (the rest for Python, the mesh and the OS).
DEFAULT_MAX_UNKNOWNS = 1_000_000
#: A transient may take this many steps of a problem at the unknown limit (work = unknowns x
#: steps is what its time grows with, the factorisation being reused across steps).
STEPS_AT_LIMIT = 2000
#: Calibration of the time model on the default forearm (quadratic, mode 1): its estimated
#: unknowns (the mesh has 16,432) and its measured solve time.
_REF_UNKNOWNS, _REF_SECONDS = 18_619, 0.35
_LU_BYTES_PER_UNKNOWN_LOG2 = 440.0  # complex LU fill ~ N log2 N


@dataclass(frozen=True)
class CostEstimate:
    """Cells along r and z (absorbers included), unknowns, memory [GB] and time [s]."""

    cells_r: float
    cells_z: float
    unknowns: float
    memory_gb: float
    seconds: float
    absorber_r: float = 0.0  # of cells_r: beyond the tissue radius (PML, far field)
    absorber_z: float = 0.0  # of cells_z: below the tissue
    near_r: float = 0.0  # of cells_r: inside mesh.near_radius_mm at the near size


def _graded_cells(length: float, x0: float, h0: float, h1: float, growth: float) -> float:
    """Integral of 1/h over [0, length] for h = min(h1, h0 + growth (x - x0)+) (see
    ``fem.mesh.growing_size``)."""
    flat = min(length, x0) / h0
    rest = max(0.0, length - x0)
    if rest == 0.0 or h1 <= h0:
        return flat + rest / h0
    ramp = (h1 - h0) / growth  # length over which h grows from h0 to h1
    if rest <= ramp:
        return flat + math.log((h0 + growth * rest) / h0) / growth
    return flat + math.log(h1 / h0) / growth + (rest - ramp) / h1


def _absorber_cells(kind: str, end: float, size: float, model_size: float, lam_ref: float,
                    h_wave: float) -> float:
    """Cells of the region beyond ``end`` (see ``fem.domain.layered_domain``)."""
    if kind == "static":
        return 4.0 * math.log(STATIC_EXTENSION_FACTOR * size / max(end * 1e-3, 1e-12))
    wavelengths = 1.0 if kind in ("harmonic", "sweep") else DAMPING_LAYER_WAVELENGTHS
    start = max(end, min(lam_ref, 20.0 * model_size))
    extension = 0.0
    if start > end:  # graded from the last cell up to h_wave, then at h_wave
        extension = (start - end) / h_wave + math.log(max(h_wave / 1e-4, 1.0)) / math.log(1.25)
    return extension + max(6.0, wavelengths * lam_ref / h_wave)


def _segment_slack(spec: MeshSpec) -> float:
    """Upper bound of the cells a segment adds beyond the integral of 1/h over it: its count
    is rounded up, and at least ``min_cells`` (see ``fem.domain.layered_domain``)."""
    return 2.0 if spec.order == 1 else 1.0


def _unit_cells(scene: Scene, spec: MeshSpec) -> tuple[float, float, float]:
    """(extra r segments, cells along r under the unit, cell rows above the skin) of the
    unit's parts, from its layout (geometry only, nothing allocated)."""
    effects = resolve_effects(scene)
    lay = haptic_unit.layout(scene.unit, effects["encapsulation"], effects["unit_mass"],
                             effects["rocking"], effects["hysteretic_damping"])
    slack = _segment_slack(spec)
    r_pts = {0.0, *lay.r_breaks, *(x for b in lay.blocks for x in (b.r0, b.r1))}
    r_pts = {r for r in r_pts if 0.0 <= r <= scene.tissue.radius_m}
    z_pts = {0.0, *lay.z_breaks, *(z for b in lay.blocks for z in (b.z0, b.z1) if z <= 0.0)}
    height = -min(z_pts)
    under = max(r_pts) / spec.near_size + slack * (len(r_pts) - 1)
    rows = height / spec.near_size + slack * (len(z_pts) - 1)
    return float(len(r_pts)), under, rows


def estimate_cost(scene: Scene) -> CostEstimate:
    """The size of ``scene``'s discretisation, from its numbers alone (nothing allocated).

    The unknown count is an upper bound of the mesh's (each graded segment is counted with its
    rounding up, every cell line with its nodes); memory and time are rough models."""
    spec: MeshSpec = mesh_spec(scene)
    kind = scene.analysis.kind
    radius, depth = scene.tissue.radius_m, sum(ly.thickness_m for ly in scene.tissue.layers)
    slack = _segment_slack(spec)
    cells_r = _graded_cells(radius, spec.near_radius, spec.near_size, spec.far_size, spec.growth)
    cells_r += slack * (2 if spec.near_radius < radius else 1)
    cells_z = _graded_cells(depth, 0.0, spec.near_size, spec.far_size, spec.growth)
    cells_z += slack * len(scene.tissue.layers)  # every interface is a line
    if kind != "static":
        omega = absorber_omega(scene)
        speeds = [ly.solid().shear_speed_m_s for ly in scene.tissue.layers]
        lam_ref = 2 * math.pi * reference_speed(speeds) / omega
        lam_min, _ = shortest_shear_wavelength(scene)
        h_wave = min(lam_min * spec.order / ELEMENTS_PER_WAVELENGTH, 4 * spec.far_size)
    else:
        lam_ref = h_wave = 0.0
    absorber_r = absorber_z = 0.0
    if scene.tissue.side == "absorbing":
        absorber_r = _absorber_cells(kind, radius, radius, radius, lam_ref, h_wave)
    if scene.tissue.base == "absorbing":
        absorber_z = _absorber_cells(kind, depth, max(depth, radius), max(depth, radius),
                                     lam_ref, h_wave)
    cells_r, cells_z = cells_r + absorber_r, cells_z + absorber_z
    o = spec.order
    nodes = (o * cells_r + 1) * (o * cells_z + 1)
    rows = 0.0
    if scene.unit is not None:  # the unit's parts above the skin, out to its outer radius
        segments, under, rows = _unit_cells(scene, spec)
        cells_r += slack * segments  # its radii are cell lines through the whole grid
        nodes += o * slack * segments * (o * cells_z + 1) + (o * under + 1) * o * rows
    if spec.cells_r is not None or spec.cells_z is not None:
        # fixed counts (at least what the sizes need, else the build refuses them): the full
        # grid of the cells along each axis bounds the mesh (void cells only remove nodes)
        grid_r = sum(spec.cells_r) if spec.cells_r is not None else cells_r
        grid_z = sum(spec.cells_z) if spec.cells_z is not None else cells_z + rows
        nodes = max(nodes, (o * grid_r + 1) * (o * grid_z + 1))
        cells_r, cells_z = max(cells_r, grid_r), max(cells_z, grid_z)
    dofs_per_node = 2 if scene.load.fourier_mode == 0 else 3
    n = nodes * dofs_per_node
    memory = _LU_BYTES_PER_UNKNOWN_LOG2 * n * math.log2(max(n, 2.0)) / 1e9
    seconds = _REF_SECONDS * (n / _REF_UNKNOWNS) ** 1.5
    near_r = min(spec.near_radius, radius) / spec.near_size
    return CostEstimate(cells_r, cells_z, n, memory, seconds, absorber_r, absorber_z, near_r)


def _work_limit(scene: Scene, est: CostEstimate, max_unknowns: float) -> float | None:
    """Largest number of time steps a transient of ``est`` may take (None: within limits)."""
    a = scene.analysis
    if a.kind != "transient" or est.unknowns > max_unknowns:
        return None
    steps = a.duration_ms / a.time_step_ms
    if est.unknowns * steps > max_unknowns * STEPS_AT_LIMIT:
        return max_unknowns * STEPS_AT_LIMIT / est.unknowns
    return None


def _fits(scene: Scene, max_unknowns: float) -> bool:
    """True when ``scene`` passes :func:`check_cost` (no advice is built)."""
    try:
        est = estimate_cost(scene)
    except (ValueError, ArithmeticError):
        return False
    return est.unknowns <= max_unknowns and _work_limit(scene, est, max_unknowns) is None


def check_cost(scene: Scene, max_unknowns: float = DEFAULT_MAX_UNKNOWNS) -> CostEstimate:
    """The estimate, or a SceneError naming what drives a size above ``max_unknowns`` and a
    value of that field that passes (checked on the changed scene) when one exists."""
    est = estimate_cost(scene)
    a = scene.analysis
    most = _work_limit(scene, est, max_unknowns)
    if most is not None:
        steps = a.duration_ms / a.time_step_ms
        raise SceneError("analysis.duration_ms", f"analysis.duration_ms: {steps:.3g} time "
                         f"steps of {est.unknowns:.3g} unknowns exceed the work limit "
                         f"({max_unknowns:.3g} unknowns x {STEPS_AT_LIMIT} steps): use at "
                         f"most {most:.3g} steps (analysis.duration_ms <= "
                         f"{most * a.time_step_ms:.3g} at this analysis.time_step_ms), a "
                         "coarser mesh, or raise the limit")
    if est.unknowns <= max_unknowns:
        return est
    field, advice = _driver(scene, est, max_unknowns)
    raise SceneError(field, f"{field}: this scene needs about {est.unknowns:.3g} unknowns "
                     f"({est.cells_r:.3g} x {est.cells_z:.3g} cells, ~{est.memory_gb:.3g} GB, "
                     f"~{_duration(est.seconds)}), above the limit of {max_unknowns:.3g}: "
                     f"{advice}. To run it anyway raise the limit (hapticrom simulate "
                     "--max-unknowns N, or fem.simulate(scene, max_unknowns=N))")


def _frequency_field(scene: Scene) -> tuple[str, float]:
    """The scene field the absorbers and wavelengths follow (:func:`fem.problem.drive_omega`):
    the motor's rated speed for a transient ERM unit, else the analysis frequency."""
    if scene.analysis.kind == "transient":
        act = scene.load.kind.actuator
        return act.transient_frequency_field, act.transient_frequency_hz(scene)
    return "analysis.frequency_hz", scene.analysis.frequency_hz


def _with_frequency(scene: Scene, field: str, value: float) -> Scene:
    if field == "unit.motor.rated_frequency_hz":
        motor = replace(scene.unit.motor, rated_frequency_hz=value)
        return replace(scene, unit=replace(scene.unit, motor=motor))
    return replace(scene, analysis=replace(scene.analysis, frequency_hz=value))


def _passing_frequency(scene: Scene, limit: float, field: str, value: float,
                       factor: float) -> float | None:
    """The first of value * factor^k (k = 1..60) within the field's range that fits (none
    for a sweep: its band is the question asked, not a knob to turn)."""
    if scene.analysis.kind == "sweep":
        return None
    top = 1e4 if field == "unit.motor.rated_frequency_hz" else 1e5
    for k in range(1, 61):
        f = float(f"{value * factor**k:.3g}")
        if not 1e-3 <= f <= top:
            return None
        try:
            if _fits(_with_frequency(scene, field, f), limit):
                return f
        except (ValueError, TypeError):
            return None
    return None


def _passing_cells(scene: Scene, limit: float, axis: str) -> list[int] | None:
    """Counts of ``mesh.cells_<axis>`` scaled down (each at least 1) until the scene fits."""
    counts = getattr(scene.mesh, f"cells_{axis}")
    for k in range(1, 200):
        scale = 0.9**k
        trial = [max(1, math.floor(c * scale)) for c in counts]
        if _fits(replace(scene, mesh=replace(scene.mesh, **{f"cells_{axis}": tuple(trial)})),
                 limit):
            return trial
        if all(c == 1 for c in trial):
            return None
    return None


def _fixed_cells_driver(scene: Scene, est: CostEstimate, limit: float
                        ) -> tuple[str, str] | None:
    """``mesh.cells_r`` / ``mesh.cells_z`` when their fixed counts, not the sizes, make the
    scene too large."""
    m = scene.mesh
    if m.cells_r is None and m.cells_z is None:
        return None
    free = estimate_cost(replace(scene, mesh=replace(m, cells_r=None, cells_z=None)))
    over = [(sum(c) / max(n, 1.0), axis) for c, n, axis in
            ((m.cells_r, free.cells_r, "r"), (m.cells_z, free.cells_z, "z")) if c is not None]
    ratio, axis = max(over)
    if ratio <= 1.0:
        return None
    field = f"mesh.cells_{axis}"
    given = list(getattr(m, f"cells_{axis}"))
    trial = _passing_cells(scene, limit, axis)
    shown = f"{given}" if len(given) <= 6 else f"[{given[0]}, ... {len(given)} counts]"
    advice = (f"{field} = {shown} fixes {sum(given)} cells along {axis} where the element "
              f"sizes need about {free.cells_r if axis == 'r' else free.cells_z:.0f}")
    if trial is not None:
        advice += (f"; use {field} = {trial} or fewer (each segment keeping at least the cells "
                   "its element sizes need)")
    return field, advice + f", or leave {field} out to let the sizes choose the counts"


def _driver(scene: Scene, est: CostEstimate, limit: float) -> tuple[str, str]:
    """The field most responsible for the size, and what to change."""
    ratio = est.unknowns / limit  # one length scaled by this fits: unknowns ~ 1 / h (one axis)
    shrink = math.sqrt(ratio)  # both axes (far size, or a wavelength that caps every size)
    m, t = scene.mesh, scene.tissue
    fixed = _fixed_cells_driver(scene, est, limit)
    if fixed is not None:
        return fixed
    wave = scene.analysis.kind != "static"
    if wave:
        f_field, freq = _frequency_field(scene)
        lam_min, name = shortest_shear_wavelength(scene)
        h_wave = lam_min * m.order / ELEMENTS_PER_WAVELENGTH
        if m.follow_wavelength and h_wave * 1e3 < m.near_size_mm:
            field = _material_field(scene, name)
            lower = _passing_frequency(scene, limit, f_field, freq, 1 / 1.25)
            return field, (f"the shortest shear wavelength ({lam_min * 1e3:.3g} mm, in {name!r} "
                           f"at {f_field} = {freq:g} Hz) sets the element size "
                           f"{h_wave * 1e3:.3g} mm; a stiffer {field} (about {ratio:.3g}x)"
                           + (f" or {f_field} <= {lower:g} would fit" if lower else
                              " would fit")
                           + ", or set mesh.follow_wavelength = false to mesh at the given "
                           "sizes")
    tissue_r, tissue_z = est.cells_r - est.absorber_r, est.cells_z - est.absorber_z
    if wave and (est.absorber_r > tissue_r or est.absorber_z > tissue_z):
        higher = _passing_frequency(scene, limit, f_field, freq, 1.25)
        thick = ("one wavelength" if scene.analysis.kind == "harmonic" else
                 f"{DAMPING_LAYER_WAVELENGTHS:g} wavelengths")
        return f_field, (
            f"at {f_field} = {freq:g} Hz the absorbing layers ({thick} thick) reach far "
            "beyond the tissue; "
            + (f"use {f_field} >= {higher:g}, " if higher else "")
            + 'or make the absorbing boundaries fixed (tissue.side = "fixed", '
            'tissue.base = "fixed")')
    far = _walk(scene, limit, lambda v: replace(scene, mesh=replace(m, far_size_mm=v)),
                m.far_size_mm * shrink, 1.1)
    far_text = f"mesh.far_size_mm >= {far:.3g}" if far else "a coarser mesh.far_size_mm"
    if tissue_r >= tissue_z:
        if est.near_r > 0.5 * tissue_r:
            near = _walk(scene, limit, lambda v: replace(scene, mesh=replace(
                m, near_size_mm=v, far_size_mm=max(v, m.far_size_mm))),
                m.near_size_mm * ratio, 1.1)
            return "mesh.near_size_mm", (
                f"use mesh.near_size_mm >= {near or m.near_size_mm * ratio:.3g}"
                + (" (and mesh.far_size_mm at least as large)"
                   if near and near > m.far_size_mm else ""))
        radius = _walk(scene, limit, lambda v: replace(scene, tissue=replace(t, radius_mm=v)),
                       t.radius_mm / ratio, 0.9)
        return "tissue.radius_mm", (f"use tissue.radius_mm <= "
                                    f"{radius or t.radius_mm / ratio:.3g} or {far_text}")
    thickest = max(range(len(t.layers)), key=lambda i: t.layers[i].thickness_mm)
    return f"tissue.layer[{thickest}].thickness_mm", (
        f"the tissue is {t.depth_mm:g} mm deep; use a thinner "
        f"tissue.layer[{thickest}].thickness_mm (the total <= {t.depth_mm / ratio:.3g} mm) "
        f"or {far_text}")


def _walk(scene: Scene, limit: float, build: Callable[[float], Scene], start: float,
          factor: float) -> float | None:
    """The first of start * factor^k (k = 0..40, three significant digits) whose scene
    ``build(value)`` fits the limit; None when none does (or the scene cannot be built)."""
    for k in range(41):
        value = float(f"{start * factor**k:.3g}")
        try:
            if value > 0 and _fits(build(value), limit):
                return value
        except (ValueError, TypeError, ArithmeticError):
            return None
    return None


def _material_field(scene: Scene, name: str) -> str:
    for i, ly in enumerate(scene.tissue.layers):
        if ly.name == name:
            return f"tissue.layer[{i}].E_kPa"
    if scene.unit is not None:
        for i, ring in enumerate(scene.unit.encapsulation):
            if ring.name == name:
                return f"unit.encapsulation[{i}].E_kPa"
    return "tissue.layer.E_kPa"


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.3g} h"
