"""What a sweep writes: the JSON document ``hapticrom.simulate.sweep`` (schema version 1,
docs/output-schema.md), the terminal summary, and the figure of magnitude and phase against
frequency with resonances and antiresonances marked.

The document follows the harmonic one (``fem.output``): the resolved scene and its digest, the
definitions of centre, edge and magnitude, and the values with the unit in every key; every
value is a list over ``analysis.frequency_hz`` (the profile: frequency-major lists of lists).
``reduced_model`` says how the answer was obtained: the error estimate, the tolerance, the
full solves (factorisations) and back-substitutions it took, the expansion frequencies.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

import figstyle

from . import SOLVER_VERSION, results
from .output import (
    MAGNITUDE,
    PHASE_REFERENCE,
    SCHEMA_VERSION,
    SurfaceSamples,
    describe_design,
)
from .scene import scene_hash, scene_to_dict

__all__ = ["KIND", "extrema", "plot_sweep", "sweep_document", "sweep_summary"]

KIND = "hapticrom.simulate.sweep"


class SweepResult(SurfaceSamples, Protocol):
    """What a sweep document is made of (:class:`fem.sweep.SweepResult` is one; it writes
    itself with :func:`sweep_document`, so this module names what it reads rather than
    importing it). Every sampled value has a leading axis over ``frequency_hz`` (Hz)."""

    frequency_hz: NDArray
    error_estimate: float
    tolerance: float
    full_solves: int

    @property
    def center_amplitude_um(self) -> NDArray | None: ...

    @property
    def edge_amplitude_um(self) -> NDArray | None: ...
_COMPONENTS = ("ur", "uz", "ut")
#: A local extremum of a magnitude curve is marked when it stands out from its surroundings
#: by this share of the curve's range (scipy.signal.find_peaks prominence).
PROMINENCE = 0.02


def _series(U: NDArray) -> dict[str, Any]:
    """Per-component complex values and magnitudes (um) of (..., 3) amplitudes in m."""
    out: dict[str, Any] = {"magnitude_um": (results.magnitude(U) * 1e6).tolist()}
    for k, c in enumerate(_COMPONENTS):
        out[f"{c}_complex_um"] = results.complex_um(U[..., k])
    return out


def extrema(frequency_hz: NDArray, magnitude: NDArray) -> tuple[NDArray, NDArray]:
    """(resonances, antiresonances): frequencies (Hz) of the interior local maxima and minima
    of a magnitude curve that stand out by :data:`PROMINENCE` of its range."""
    # Lazy: scipy.signal costs 0.55 s to import (measured beside scipy.sparse), which every
    # solve would pay through fem.simulation; only a sweep's document needs it.
    from scipy.signal import find_peaks

    m = np.asarray(magnitude, dtype=float)
    span = float(m.max() - m.min()) if m.size else 0.0
    if m.size < 3 or span <= 0.0:
        return np.empty(0), np.empty(0)
    peaks, _ = find_peaks(m, prominence=PROMINENCE * span)
    dips, _ = find_peaks(-m, prominence=PROMINENCE * span)
    return frequency_hz[peaks], frequency_hz[dips]


def sweep_document(res: SweepResult, scene_name: str | None = None) -> dict[str, Any]:
    """The version-1 JSON document of a sweep (see the module docstring)."""
    m = res.meta
    has_edge = res.edge_mm is not None
    doc: dict[str, Any] = {
        "schema_version": SCHEMA_VERSION,
        "kind": KIND,
        "solver_version": SOLVER_VERSION,
        "scene": {"name": scene_name, "digest": scene_hash(res.scene),
                  "resolved": scene_to_dict(res.scene)},
        "analysis": {
            "kind": "sweep", "frequency_hz": res.frequency_hz.tolist(),
            "fourier_mode": int(m["modes"][0]), "mesh_frequency_hz": m["mesh_frequency_hz"],
            "time_convention": "exp(+i omega t)", "phase_reference": PHASE_REFERENCE,
        },
        "definitions": {
            "centre": {"radius_mm": 0.0, "z_mm": float(res.centre_z_mm),
                       "text": "the unit's skin-side face at r = 0 (the skin when glued)"},
            "edge": {"radius_mm": res.edge_mm,
                     "text": "the skin surface at the outer radius of the load footprint"},
            "profile": {"text": "skin-surface samples at distances from the edge"},
            "magnitude": MAGNITUDE,
            "amplitude": "modulus of the complex Fourier amplitude of each component (um), "
                         "at each frequency of analysis.frequency_hz",
        },
        "reduced_model": {
            "error_estimate": res.error_estimate, "tolerance": res.tolerance,
            "full_solves": res.full_solves, "back_solves": m.get("back_solves"),
            "basis_size": m.get("basis_size"), "expansions_hz": m.get("expansions_hz"),
            "chebyshev_nodes": m.get("chebyshev_nodes"),
            "residual": m.get("residual"), "residual_hz": m.get("residual_hz"),
            "text": "Galerkin projection onto shift-and-invert Krylov vectors at the "
                    "expansion frequencies (docs/model.md); error_estimate bounds the relative "
                    "error of every component of centre, edge and profile above 1 % of its "
                    "quantity's largest",
        },
        "surface": {"r_mm": res.r_mm.tolist(), **_series(res.U)},
        "centre": {"radius_mm": 0.0, **_series(res.center)} if has_edge else None,
        "edge": {"radius_mm": res.edge_mm, **_series(res.edge)} if has_edge else None,
        "profile": {"distance_from_edge_mm": res.profile_mm.tolist(), **_series(res.profile)},
        "meta": dict(m),
    }
    return doc


def sweep_summary(res: SweepResult, scene_name: str | None = None) -> str:
    """A short report: mesh, model cost and error, and centre/edge over the band."""
    m = res.meta
    f = res.frequency_hz
    lines = [
        f"hapticrom {SOLVER_VERSION}: sweep of {f.size} frequencies, {f[0]:g}-{f[-1]:g} Hz"
        + (f" of {scene_name}" if scene_name else ""),
        f"  design: {describe_design(res.scene)}",
        f"  elements {m['elements']}, dofs {m['dofs']} (mesh sized for {m['mesh_frequency_hz']:g}"
        f" Hz), Fourier mode {m['modes'][0]}, wall time {m['wall_s'] * 1e3:.0f} ms",
        f"  reduced model: {res.full_solves} full solves (factorisations) at "
        + ", ".join(f"{x:g}" for x in m.get("expansions_hz", [])) + " Hz, "
        f"{m.get('back_solves', 0)} back-solves, basis {m.get('basis_size', 0)}; "
        f"error estimate {res.error_estimate:.2g} (tolerance {res.tolerance:g})",
    ]
    if res.edge_mm is not None:
        c, e = res.center_amplitude_um, res.edge_amplitude_um
        lines.append(f"  centre magn. (unit face, z = {res.centre_z_mm:g} mm) {c.min():.4g}-"
                     f"{c.max():.4g} um; edge magn. (r = {res.edge_mm:g} mm) {e.min():.4g}-"
                     f"{e.max():.4g} um; magn. = sqrt(|u_r|^2 + |u_z|^2 + |u_t|^2)")
        for name, curve in (("centre", c), ("edge", e)):
            peaks, dips = extrema(f, curve)
            if peaks.size or dips.size:
                lines.append(f"  {name}: resonances at {_hz(peaks)}, antiresonances at "
                             f"{_hz(dips)}")
        lines.append(f"  {'f (Hz)':>8} {'centre um':>11} {'edge um':>11}")
        for i in np.unique(np.linspace(0, f.size - 1, min(f.size, 11)).round().astype(int)):
            lines.append(f"  {f[i]:8g} {c[i]:11.4g} {e[i]:11.4g}")
    lines += [f"  warning: {w}" for w in m.get("warnings", [])]
    return "\n".join(lines)


def _hz(values: NDArray) -> str:
    return ", ".join(f"{v:g}" for v in values) + " Hz" if values.size else "none"


def plot_sweep(path: str, res: SweepResult, scene_name: str | None = None) -> None:
    """Magnitude (log) and phase of the centre and the edge against frequency, resonances
    (triangles up) and antiresonances (down) marked, in the shared figure style."""
    f = res.frequency_hz
    fig, (ax, bx) = figstyle.figure(2, 1, width_in=6.4, height_in=6.0)
    curves = [("centre", res.center)] if res.edge_mm is not None else []
    if res.edge_mm is not None:
        curves.append((f"edge (r = {res.edge_mm:g} mm)", res.edge))
    for i, (label, U) in enumerate(curves):
        colour = figstyle.OKABE_ITO[i]
        mag = results.magnitude(U) * 1e6
        k = int(np.argmax(np.abs(U).max(axis=0)))  # the component that moves most
        ax.semilogy(f, mag, color=colour, label=f"{label} magnitude")
        peaks, dips = extrema(f, mag)
        for marks, symbol, kind in ((peaks, "^", "resonance"), (dips, "v", "antiresonance")):
            if marks.size:
                at = np.searchsorted(f, marks)
                ax.plot(marks, mag[at], symbol, color=colour, ms=7,
                        label=f"{label} {kind}{'s' if marks.size > 1 else ''}")
        bx.plot(f, np.degrees(np.unwrap(np.angle(U[:, k]))), color=colour,
                label=f"{label} phase of {('u_r', 'u_z', 'u_t')[k]}")
    ax.set_ylabel("amplitude (um)")
    ax.legend(fontsize=7)
    figstyle.plain_log_ticks(ax)
    bx.set_xlabel("drive frequency (Hz)")
    bx.set_ylabel("phase (degrees)")
    bx.legend(fontsize=7)
    figstyle.annotate(
        fig, f"{scene_name or 'scene'}: frequency sweep", design=describe_design(res.scene),
        frequency=f"{f[0]:g}-{f[-1]:g} Hz, {f.size} frequencies",
        plotted="top: magnitude sqrt(|u_r|^2+|u_z|^2+|u_t|^2) in um, log scale, at the centre "
        f"(the unit's face at r = 0, z = {res.centre_z_mm:g} mm) and the edge (skin); bottom: "
        "phase of the component that moves most, relative to the drive force (exp(+i omega "
        f"t)); reduced-order model, {res.full_solves} full solves, estimated error "
        f"{res.error_estimate:.1g}")
    figstyle.save(fig, path)
