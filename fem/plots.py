"""PNG of a solved scene in the project's figure style (:mod:`figstyle`).

Steady (harmonic, static): surface amplitude against radius, |u_z| and the magnitude, the
centre and the edge marked. Transient: left, the time histories of the displacement magnitude
at the centre and at the edge with their envelopes; right, the peak amplitude against radius
("peak": the largest |u| of the run at each radius).

The envelope joins the successive peaks of |u(t)| (:func:`envelope`): it follows the spin-up
and spin-down while ignoring the oscillation within a period, also while the motor's frequency
changes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

import figstyle

from .output import describe_design
from .results import magnitude

if TYPE_CHECKING:
    from .simulation import SimulationResult

__all__ = ["envelope", "plot_result"]


def envelope(t: NDArray, x: NDArray) -> NDArray:
    """The peak envelope of an oscillation ``x(t)``: straight lines through the successive
    local maxima of |x| (and its end values), never below |x| itself. Unlike a fixed window or
    the Hilbert transform it follows a frequency that drifts (spin-up) and has no end
    effects."""
    a = np.abs(np.asarray(x, dtype=float))
    if a.size < 3:
        return a
    inner = np.flatnonzero((a[1:-1] >= a[:-2]) & (a[1:-1] > a[2:])) + 1
    peaks = np.concatenate([[0], inner, [a.size - 1]])
    return np.maximum(np.interp(t, t[peaks], a[peaks]), a)


def _frequency_text(res: SimulationResult) -> str | None:
    f = res.meta.get("frequency_hz")
    if f is None:
        return None
    if res.scene.analysis.kind == "transient" and res.scene.load.kind.actuator.spins_up:
        return f"ERM spin-up to the rated {f:g} Hz (rev/s), schedule " + ", ".join(
            f"{v:g} V from {t:g} ms" for t, v in res.scene.analysis.voltage_schedule)
    return f"{f:g} Hz"


def plot_result(path: str, res: SimulationResult, scene_name: str | None = None) -> None:
    """Write the figure of ``res`` to ``path``."""
    name = scene_name or "scene"
    design = describe_design(res.scene)
    freq = _frequency_text(res)
    if res.histories is None:
        _steady(path, res, name, design, freq)
    else:
        _transient(path, res, name, design, freq)


def _steady(path: str, res: SimulationResult, name: str, design: str,
            freq: str | None) -> None:
    r_mm, U = res.surface_curve()
    harmonic = res.scene.analysis.kind == "harmonic"
    fig, ax = figstyle.figure()
    ax.semilogy(r_mm, np.abs(U[:, 1]) * 1e6, label="|u_z| (normal)")
    ax.semilogy(r_mm, magnitude(U) * 1e6, label="magnitude")
    if res.edge_mm is not None:
        ax.axvline(res.edge_mm, color="0.5", ls="--", lw=0.8,
                   label=f"edge, r = {res.edge_mm:g} mm")
        where = ("unit face, z = " f"{res.centre_z_mm:g} mm" if res.scene.unit is not None
                 else "skin, r = 0")
        ax.plot([0.0], [res.center_amplitude_um], "k^", ms=6, label=f"centre ({where})")
    ax.set_xlabel("radius r (mm)")
    ax.set_ylabel("amplitude (um)" if harmonic else "|displacement| (um)")
    ax.legend()
    what = ("modulus of the complex Fourier amplitude" if harmonic
            else "absolute static displacement")
    figstyle.annotate(fig, f"{name}: {res.scene.analysis.kind} surface response",
                      design=design, frequency=freq,
                      plotted=f"{what} on the skin surface (z = 0, theta = 0) against radius, "
                      "um, log scale; magnitude = sqrt(|u_r|^2+|u_z|^2+|u_t|^2)")
    figstyle.save(fig, path)


def _transient(path: str, res: SimulationResult, name: str, design: str,
               freq: str | None) -> None:
    h = res.histories
    n = res.r_mm.size
    t_ms = h.t * 1e3
    fig, (ax, bx) = figstyle.figure(1, 2, width_in=10.0, height_in=4.4)
    points = [("centre", n, figstyle.OKABE_ITO[0])]
    if res.edge_mm is not None:
        points.append((f"edge (r = {res.edge_mm:g} mm)", n + 1, figstyle.OKABE_ITO[1]))
    for label, i, colour in points:
        k = int(np.argmax(np.abs(h.u[:, i]).max(axis=0)))  # the component that moves most
        u = h.u[:, i, k] * 1e6
        env = envelope(t_ms, u)
        comp = ("u_r", "u_z", "u_t")[k]
        ax.plot(t_ms, u, color=colour, lw=0.6, alpha=0.6, label=f"{label} {comp}(t)")
        ax.plot(t_ms, env, color=colour, lw=1.6, label=f"{label} envelope of {comp}")
        ax.plot(t_ms, -env, color=colour, lw=1.6)
    ax.set_xlabel("time t (ms)")
    ax.set_ylabel("displacement (um)")
    ax.set_title("time histories and envelopes (theta = 0)")
    ax.legend(fontsize=7)
    r_mm, U = res.surface_curve()
    U = np.abs(U)  # peaks are real and >= 0; stored as complex for the steady layout
    bx.semilogy(r_mm, U[:, 1] * 1e6, label="peak |u_z|")
    bx.semilogy(r_mm, magnitude(U) * 1e6, label="magnitude of peaks")
    if res.edge_mm is not None:
        bx.axvline(res.edge_mm, color="0.5", ls="--", lw=0.8, label="edge")
    bx.set_xlabel("radius r (mm)")
    bx.set_ylabel("peak amplitude over the run (um)")
    bx.set_title("peak amplitude against radius")
    bx.legend()
    figstyle.plain_log_ticks(bx)
    figstyle.annotate(
        fig, f"{name}: transient", design=design, frequency=freq,
        plotted="left: displacement u(t) in um of the component that moves most, at the centre "
        f"(the unit's face at r = 0, z = {res.centre_z_mm:g} mm) and at the edge (skin), with "
        "envelopes through the successive peaks of |u|; right: "
        "peak over the run against radius on the skin surface, log scale")
    figstyle.save(fig, path)
