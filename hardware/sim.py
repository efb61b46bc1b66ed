"""The ``sim`` back end: a virtual array that renders the skin amplitude field over time.

The unit's amplitude field is the plan's: the run-time surrogate's prediction for the chosen
design at the chosen frequency (:func:`unit_field`, the same :class:`planner.UnitField` the
planner used; checked against the plan's crosstalk diagonal), one copy centred on each site.
Each channel's vibration envelope e(t) (1 = the nominal steady amplitude) is the plan's
transient model (``surrogate.runtime.rom``, :func:`model_envelopes`) driven by the channel's
voltage, so what is shown is what the model predicts. A plan that does not name its model's
design (made before it was recorded) falls back to a first-order system following the segment
levels with the plan's timing: time constant rise_ms / ln 9 while
rising and decay_ms / ln 9 while falling (a 10-90 % time of a first-order response is
tau ln 9); an overdrive kick drives towards its higher level but ends at the nominal amplitude
(the kick of ERM practice stops when the motor reaches its nominal speed, which is how the
plan's overdrive_ms is defined), a brake pulse drives towards a negative level, and the
envelope never goes below 0 (the rotor stops). The skin field is the incoherent
sum over units, A(x, t) = sqrt(sum_j e_j(t)^2 a_j(x)^2) (independent ERMs, as in the plan).

``play`` writes ``field-peak.png`` (the field at its peak, and every site's amplitude against
time) and ``field.gif`` (the animation, matplotlib's PillowWriter) into ``out_dir``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

import figstyle
from hardware.device import Device
from hardware.protocol import Segment, Status
from hardware.safety import ExposureMeter, SafetyLimits
from hardware.schedule import PlanFile, PlanFileError, Schedule
from planner.crosstalk import UnitField, crosstalk_matrix
from planner.timing import rom_response
from surrogate.runtime import load_predictor
from surrogate.runtime.rom import load_envelope_model

__all__ = ["SimDevice", "envelopes", "field_maps", "model_envelopes", "unit_field"]

DT_MS = 1.0  # envelope time step [ms]
MAX_FRAMES = 80  # animation frames at most (the frame interval grows for long patterns)
GRID_POINTS = 72  # field map resolution per side
GIF_DPI = 60  # animation resolution (a 252 x 228 pixel GIF)


def unit_field(plan: PlanFile) -> UnitField:
    """The chosen design's amplitude field from the plan's model (run-time predictor)."""
    d = plan.data
    cand = next((c for c in d["candidates"] if c["name"] == d["best"]
                 and c["frequency_hz"] == d["best_frequency_hz"]), None)
    if cand is None:
        raise PlanFileError("best", f"plan.best = {d['best']!r} is not among its candidates")
    predictor = load_predictor(d["model"])
    row = {**d["site"], **cand["inputs"], "frequency_hz": plan.frequency_hz}
    X = {n: np.array([row[n]]) for n in predictor.input_names}
    out = predictor.predict(X, extrapolate=bool(cand.get("extrapolated")))
    f = UnitField(float(out["center_amplitude_um"][0]), float(out["edge_radius_mm"][0]),
                  predictor.profile_distance_mm, out["profile_um"][0])
    own = float(np.diag(plan.crosstalk_um).mean())
    if not math.isclose(f.center_um, own, rel_tol=1e-3):
        raise PlanFileError("model", f"the model {d['model']} now predicts {f.center_um:.4g} um "
                            f"at the centre, the plan says {own:.4g} um: re-plan")
    return f


def envelopes(segments: list[Segment], n_channels: int, timing: dict[str, float],
              total_ms: float) -> tuple[NDArray, NDArray]:
    """(t_ms, e): each channel's envelope (n_channels, len(t)) on a DT_MS grid.

    First order towards the segment level (rise and decay time constants from the timing).
    When the plan has an overdrive kick, the first segment of each run of positive segments
    on a channel is that kick: the envelope rises towards the kick level but stops at the
    kick level / overdrive_level (the nominal amplitude), as the kick of ERM practice ends
    when the motor reaches its nominal speed. Reverse drive pulls it to 0, not below."""
    t = np.arange(0.0, total_ms + 5 * timing["decay_ms"] + DT_MS, DT_MS)
    target = np.zeros((n_channels, len(t)))
    cap = np.full((n_channels, len(t)), np.inf)
    kick = timing["overdrive_ms"] > 0 and timing["overdrive_level"] > 1
    last: dict[int, tuple[int, float]] = {}  # channel -> (end [ms], level) of its last segment
    for s in sorted(segments, key=lambda s: (s.channel, s.t_ms)):
        span = (t >= s.t_ms) & (t < s.t_ms + s.duration_ms)
        target[s.channel, span] = s.level
        end, level = last.get(s.channel, (-1, 0.0))
        if kick and s.level > 0 and not (end == s.t_ms and level > 0):
            cap[s.channel, span] = s.level / timing["overdrive_level"]
        last[s.channel] = (s.t_ms + s.duration_ms, s.level)
    tau_up = max(timing["rise_ms"], DT_MS) / math.log(9)
    tau_down = max(timing["decay_ms"], DT_MS) / math.log(9)
    k_up, k_down = 1 - math.exp(-DT_MS / tau_up), 1 - math.exp(-DT_MS / tau_down)
    e = np.zeros_like(target)
    for i in range(1, len(t)):
        goal = target[:, i - 1]
        prev = e[:, i - 1]
        k = np.where(goal > prev, k_up, k_down)
        nxt = prev + k * (goal - prev)
        e[:, i] = np.clip(nxt, 0.0, np.maximum(cap[:, i - 1], np.minimum(prev, nxt)))
    return t, e


def model_envelopes(segments: list[Segment], n_channels: int, timing: dict[str, Any],
                    total_ms: float) -> tuple[NDArray, NDArray] | None:
    """(t_ms, e) like :func:`envelopes`, rendered by the plan's transient model itself
    (``timing.model`` driven by each channel's voltage, level x ``nominal_voltage_V``, for the
    plan's unit ``timing.design``), normalised by the model's steady envelope; None when the
    plan does not name the model and design (a plan made before they were recorded)."""
    design, path = timing.get("design"), timing.get("model")
    if not isinstance(design, dict) or not path:
        return None
    model = load_envelope_model(path)
    respond = rom_response(model, design, extrapolate=True)
    limit = model.motor.max_voltage_V
    t = np.arange(0.0, total_ms + 5 * timing["decay_ms"] + DT_MS, DT_MS)
    volts = np.zeros((n_channels, len(t)))
    for s in segments:
        span = (t >= s.t_ms) & (t < s.t_ms + s.duration_ms)
        volts[s.channel, span] = np.clip(s.level * timing["nominal_voltage_V"], -limit, limit)
    e = np.zeros_like(volts)
    for ch in np.flatnonzero(np.any(volts != 0.0, axis=1)):
        env, _ = respond(1e-3 * t, volts[ch])
        e[ch] = env / timing["steady_envelope_um"]
    return t, e


def field_maps(unit: UnitField, positions_mm: NDArray,
               n: int = GRID_POINTS) -> tuple[NDArray, NDArray, NDArray]:
    """(x_mm, y_mm, a): each unit's amplitude [um] on an n x n grid, a[j] for unit j (its
    centre amplitude inside its edge radius)."""
    pad = 2 * unit.edge_radius_mm + 2.0
    lo, hi = positions_mm.min(axis=0) - pad, positions_mm.max(axis=0) + pad
    x, y = np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n)
    X, Y = np.meshgrid(x, y)
    a = np.empty((len(positions_mm), n, n))
    for j, (px, py) in enumerate(positions_mm):
        r = np.hypot(X - px, Y - py)
        a[j] = np.where(r <= unit.edge_radius_mm, unit.center_um,
                        unit.amplitude(np.maximum(r, unit.edge_radius_mm)))
    return x, y, a


class SimDevice(Device):
    """A virtual array rendering the skin field of whatever it plays into ``out_dir``."""

    def __init__(self, out_dir: str | Path, unit: UnitField, positions_mm: NDArray,
                 limits: SafetyLimits | None = None, exposure: ExposureMeter | None = None,
                 frequency_hz: float | None = None) -> None:
        super().__init__(len(positions_mm), limits, exposure)
        self.out_dir = Path(out_dir)
        self.unit = unit
        self.positions_mm = np.asarray(positions_mm, dtype=float)
        self.frequency_hz = frequency_hz
        self.levels = np.zeros(self.n_channels)
        self.written: list[Path] = []
        self.peak_um = 0.0

    def _set_levels(self, levels: NDArray) -> None:
        self.levels = levels.copy()

    def _play(self, schedule: Schedule, segments: list[Segment]) -> None:
        rendered = model_envelopes(segments, self.n_channels, schedule.timing,
                                   schedule.total_ms)
        t, e = rendered or envelopes(segments, self.n_channels, schedule.timing,
                                     schedule.total_ms)
        x, y, a = field_maps(self.unit, self.positions_mm)
        C = crosstalk_matrix(self.unit, self.positions_mm)
        sites = np.sqrt((C**2) @ e**2)  # amplitude at every site over time [um]
        k = int(sites.max(axis=0).argmax())
        self.peak_um = float(sites[:, k].max())
        step = max(1, math.ceil(len(t) / MAX_FRAMES))
        frames = range(0, len(t), step)
        self.written = _write_figures(self.out_dir, schedule.frequency_hz, t, e, sites, k,
                                      frames, x, y, a, self.unit, self.positions_mm)
        self.levels = np.zeros(self.n_channels)

    def _stop_all(self) -> None:
        self.levels = np.zeros(self.n_channels)

    def _heartbeat(self) -> None:
        pass  # a virtual array has no link to lose

    def _status(self) -> Status:
        return Status(0, round(self.limits.watchdog_s * 1e3), tuple(map(float, self.levels)))

    def _close(self) -> None:
        pass


def _write_figures(out: Path, freq: float, t: NDArray, e: NDArray, sites: NDArray, k: int,
                   frames: range, x: NDArray, y: NDArray, a: NDArray, unit: UnitField,
                   pos: NDArray) -> list[Path]:
    # lazy: matplotlib takes 1.9 s to import, and only a figure needs it
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    def field(i: int) -> NDArray:
        return np.sqrt(np.tensordot(e[:, i] ** 2, a**2, axes=1))

    vmax = float(field(k).max()) or 1.0
    ext = (x[0], x[-1], y[0], y[-1])

    def draw_map(ax, i):
        im = ax.imshow(field(i), origin="lower", extent=ext, cmap="magma", vmin=0, vmax=vmax)
        for px, py in pos:
            ax.add_patch(plt.Circle((px, py), unit.edge_radius_mm, fill=False, color="0.7",
                                    lw=0.6))
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        return im

    fig, (ax, bx) = figstyle.figure(1, 2, width_in=11, height_in=5.4)
    im = draw_map(ax, k)
    fig.colorbar(im, ax=ax, label="skin amplitude [um]")
    ax.set_title(f"skin amplitude at t = {t[k]:.0f} ms (the pattern's peak)")
    for i in range(len(sites)):
        bx.plot(t, sites[i], lw=0.8)
    bx.axvline(t[k], color="k", ls="--", lw=0.8)
    bx.set_xlabel("time [ms]")
    bx.set_ylabel("amplitude at each site [um]")
    bx.set_title("site amplitudes (own unit and crosstalk)")
    figstyle.annotate(
        fig, "Simulated array playing a pattern", design=f"{len(pos)} units, the plan's design",
        frequency=f"{freq:g} Hz",
        plotted="left: skin displacement amplitude (um) over the array at the moment of the "
        "largest site amplitude, units' outlines in grey, neighbours added in power "
        "(independent ERMs); right: the amplitude at every site against time (its own unit "
        "plus crosstalk), with the left panel's moment dashed")
    png = out / "field-peak.png"
    figstyle.save(fig, png)

    # the animation: no axes or colour bar (drawing ticks dominates the cost of a frame); the
    # scale is in the title, the axes are the PNG's
    fig, ax = figstyle.figure(width_in=4.2, height_in=4.2)
    im = draw_map(ax, 0)
    ax.set_axis_off()
    fig.subplots_adjust(0.02, 0.02, 0.98, 0.9)
    title = ax.set_title("", fontsize=9)

    def update(i: int):
        im.set_data(field(i))
        title.set_text(f"t = {t[i]:4.0f} ms   (black 0, white {vmax:.1f} um)")
        return im, title

    fps = max(1, round(1e3 / (t[frames.step] - t[0]))) if len(t) > 1 else 1
    gif = out / "field.gif"
    FuncAnimation(fig, update, frames=list(frames), blit=False).save(
        gif, writer=PillowWriter(fps=min(fps, 50)), dpi=GIF_DPI)
    plt.close(fig)
    return [png, gif]
