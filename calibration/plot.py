"""The calibration figure: the measured points (with their stated 95 % uncertainty) against
distance from the unit's centre, and the posterior predictive 95 % band of the surrogate
(posterior draws of the tissue and the surrogate's own widened predictive spread), one colour
per frequency and component."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import figstyle
from calibration.fit import Z95, Calibration
from calibration.forward import ForwardModel, output_for
from calibration.measurement import measurement_from_rows

__all__ = ["write_calibration_plot"]


def _dense(cal: Calibration, step_mm: float = 0.5) -> tuple[ForwardModel, list[tuple]]:
    """A forward model on a dense set of points: the face (where the model predicts the
    component there) and the profile grid, for each measured (frequency, component)."""
    predictor = cal.forward.predictor
    grid = np.asarray(predictor.profile_distance_mm, dtype=float)
    dist = np.arange(grid[0], grid[-1] + 1e-9, step_mm)
    keys = sorted({(p.frequency_hz, p.component) for p in cal.measurement.points})
    available = predictor.output_names
    rows, tags = [], []
    for f, comp in keys:
        face = [("centre", 0.0)] if output_for(comp, True, available) else []
        for ref, d in [*face, *[("edge", x) for x in dist]]:
            rows.append({"reference": ref, "distance_mm": d, "frequency_hz": f,
                         "quantity": "displacement", "unit": "um", "statistic": "peak",
                         "component": comp, "value": 1.0, "uncertainty": 0.1})
            tags.append((f, comp, ref, d))
    m = measurement_from_rows(rows, design=cal.measurement.design)
    return ForwardModel(cal.forward.predictor, m, cal.names, cal.forward.fixed), tags


def write_calibration_plot(cal: Calibration, path: str | Path, *, n_draws: int = 200,
                           seed: int = 0, interval: str = "hdi") -> None:
    """Write the figure (PNG) to ``path``."""
    fwd, tags = _dense(cal)
    rng = np.random.default_rng(seed)
    pick = rng.choice(len(cal.samples), size=min(n_draws, len(cal.samples)), replace=False)
    mean, std = fwd.predict(cal.samples[pick])
    draws = mean + cal.surrogate_error_draws(fwd, std, rng)
    lo, mid, hi = (np.exp(np.percentile(draws, q, axis=0)) * 1e6 for q in (2.5, 50, 97.5))
    r_edge_mm = cal.forward.edge_radius_m * 1e3
    radius = np.array([0.0 if t[2] == "centre" else r_edge_mm + t[3] for t in tags])
    fig, ax = figstyle.figure(width_in=6.4, height_in=4.6)
    with figstyle.style():
        keys = sorted({(t[0], t[1]) for t in tags})
        for i, (f, comp) in enumerate(keys):
            c = figstyle.color(i)
            sel = np.array([(t[0], t[1]) == (f, comp) and t[2] == "edge" for t in tags])
            face = np.array([(t[0], t[1]) == (f, comp) and t[2] == "centre" for t in tags])
            ax.fill_between(radius[sel], lo[sel], hi[sel], color=c, alpha=0.25, lw=0)
            ax.plot(radius[sel], mid[sel], color=c, lw=1.2,
                    label=f"{f:g} Hz {comp}: calibrated model, 95 % band")
            if face.any():
                ax.errorbar([0.0], mid[face], yerr=[mid[face] - lo[face],
                                                    hi[face] - mid[face]],
                            color=c, fmt="_", ms=14, capsize=0, lw=6, alpha=0.35)
            pts = [p for p in cal.measurement.points
                   if (p.frequency_hz, p.component) == (f, comp)]
            r = [p.distance_m * 1e3 + (r_edge_mm if p.reference == "edge" else 0.0) for p in pts]
            a = np.array([p.amplitude_m for p in pts]) * 1e6
            s = np.array([p.sigma_m for p in pts]) * 1e6
            ax.errorbar(r, a, yerr=Z95 * s, fmt="o", color=c, ms=4, capsize=2,
                        label=f"{f:g} Hz {comp}: measured, +-1.96 sigma")
        ax.axvspan(0.0, r_edge_mm, color="0.85", alpha=0.5, lw=0)
        ax.set_yscale("log")
        ax.set_xlabel("distance from the unit's centre [mm] (grey: under the unit; 0: its face)")
        ax.set_ylabel("peak displacement amplitude [um]")
        ax.legend(loc="upper right")
        figstyle.plain_log_ticks(ax)
    summary = cal.summary(seed, interval=interval)
    fitted = "; ".join(f"{n} {s['mean']:.3g} [{s['ci95'][0]:.3g}, {s['ci95'][1]:.3g}]"
                       + ("" if s["identifiable"] else " (not determined)")
                       for n, s in summary.items())
    c = cal.point_scale
    errors = ", ".join((f"Student-t nu {cal.error_model[g.output]['nu']:g}"
                        if cal.error_model[g.output]["nu"] is not None else "Gaussian")
                       + f", x{np.mean(c[g.index]):.2f}" for g in cal.forward.groups)
    design = ", ".join(f"{k} {v}" for k, v in cal.measurement.design.items()
                       if k in ("orientation", "attachment", "n_rings"))
    figstyle.annotate(
        fig, "Calibration: measured skin vibration and the calibrated surrogate",
        design=design or None,
        frequency=", ".join(f"{f:g} Hz" for f in cal.measurement.frequencies_hz),
        plotted="peak displacement amplitude [um] on the skin surface against distance from "
                "the unit's centre; band: posterior predictive 95 % (tissue posterior and the "
                f"surrogate's error: {errors})",
        note=f"Posterior mean [95 % {interval.replace('_', '-')} interval]: {fitted}. Model "
             f"{cal.forward.predictor.card.get('name')}.")
    figstyle.save(fig, path)
