"""Steady amplitude of FE transients with either loss model against the hysteretic harmonic.

    nice -n 5 python bench/fem/transient_damping.py                  # 3 designs x 4 speeds
    python bench/fem/transient_damping.py --samples 43 --freqs 80 --json out.json

For each design (a ``sample_index`` of ``datasets/transient``) and motor speed f, the design's
scene is run as a transient at the constant voltage that spins the motor at f (spin-up time
constant 2 ms, so the load is at speed within a few ms), time step 0.1 ms, until
``--duration-ms``; once with ``[analysis] damping = "viscous_at_drive"`` (C = K_eta /
omega_rated) and once with ``"hysteretic_band"`` (``fem.viscoelastic``). The settled
centre and edge amplitudes (the complex amplitude of each component fitted at f over the last
two periods, combined as sqrt(|u_r|^2 + |u_z|^2 + |u_theta|^2)) are compared with harmonic
solves on the transient's own matrices (``bench.surrogate.rom_steady_levels.steady_solves``):
``hyst`` (K (1 + i eta), the harmonic solver's damping: the reference), and each model's own
frequency response (``rayleigh``, ``band``: what the transient should settle to; the
difference is time-stepping error and what has not settled). ``drift`` is the change of the
fitted amplitude between the last two periods and the two before (how settled the run is).

``--harmonic-only`` skips the transients and compares the two models' own frequency responses
(the steady states their transients settle to) with the hysteretic one, on the same matrices,
in seconds per design; ``--re-weight`` then fits the band model with another weight of the
real part (``fem.viscoelastic.fit_band``), as the choice of the default was measured:

    python bench/fem/transient_damping.py --harmonic-only --samples 43 53 124 213 \
        --re-weight 0.5 1 2 4
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

MODELS = ("viscous_at_drive", "hysteretic_band")


def transient_scene(scene_json: str, f_hz: float, model: str, duration_ms: float,
                    dt_ms: float = 0.1) -> dict[str, Any]:
    """The design's scene as a constant-speed transient at ``f_hz`` with loss model
    ``model``."""
    from fem.scene.io import scene_from_dict
    from motorlaw.erm import voltage_for_frequency

    d = json.loads(scene_json)
    motor = scene_from_dict(d).unit.motor
    d["unit"]["motor"]["tau_spinup_ms"] = 2.0
    d["analysis"].update(kind="transient", time_step_ms=dt_ms, duration_ms=duration_ms,
                         voltage_schedule=[[0.0, voltage_for_frequency(motor, f_hz)]],
                         damping=model)
    d["output"]["history_every"] = 1
    return d


def settled(t: np.ndarray, u: np.ndarray, omega: float, periods: float = 2.0,
            shift: float = 0.0) -> np.ndarray:
    """(n_points,) magnitude sqrt(sum_c |U_c|^2) of the complex amplitudes at ``omega``
    fitted over ``periods`` periods ending ``shift`` periods before the end."""
    T = 2 * math.pi / omega
    end = t[-1] - shift * T
    sel = (t > end - periods * T) & (t <= end)
    basis = np.column_stack([np.cos(omega * t[sel]), np.sin(omega * t[sel]), np.ones(sel.sum())])
    coef = np.linalg.lstsq(basis, u[sel].reshape(sel.sum(), -1), rcond=None)[0]
    amp = np.hypot(coef[0], coef[1]).reshape(u.shape[1:])
    return np.sqrt(np.sum(amp**2, axis=-1))


@functools.cache
def _dataset() -> Any:
    from surrogate.data.store import Store

    df = Store.open(ROOT / "datasets" / "transient").read()
    return df[df["status"] == "ok"]


def measure(sample: int, f_hz: float, duration_ms: float) -> dict[str, Any]:
    """One design at one speed: settled FE amplitudes of both models and the harmonic ones."""
    from bench.surrogate.rom_steady_levels import steady_solves
    from fem import probes, transient_analysis
    from fem.problem import build_problem
    from fem.scene.io import scene_from_dict
    from fem.solve import OperatorLog

    df = _dataset()
    row = df[df["sample_index"] == sample].iloc[0]
    omega = 2 * math.pi * f_hz
    rec: dict[str, Any] = {"sample_index": sample, "f_hz": f_hz,
                           "attachment": row["attachment"], "n_rings": int(row["n_rings"]),
                           "tissue_eta": float(row["tissue_loss_factor"]),
                           "ring_eta": float(row["ring_loss_factor"])}
    harm = steady_solves(row["scene_json"], omega, band=True)
    for model in MODELS:
        scene = scene_from_dict(transient_scene(row["scene_json"], f_hz, model, duration_ms))
        problem = build_problem(scene)
        pts = probes.output_points(scene, problem)
        h = transient_analysis.run(scene, problem, pts.stencil, pts.radii, OperatorLog())
        n = pts.r_probe.size
        u = h.u[:, [n, n + 1]]
        amp = settled(h.t, u, omega) * 1e6
        before = settled(h.t, u, omega, shift=2.0) * 1e6
        own = harm["rayleigh" if model == MODELS[0] else "band"]
        rec[model] = {"fe_um": amp.tolist(), "vs_hyst": (amp / harm["hyst"] - 1).tolist(),
                      "vs_own_harmonic": (amp / own - 1).tolist(),
                      "drift": (amp / before - 1).tolist()}
    rec["hyst_um"] = harm["hyst"].tolist()
    return rec


def harmonic_only(sample: int, f_hz: float, weights: list[float],
                  anchored: bool = False) -> dict[str, Any]:
    """Each model's steady response vs the hysteretic one at ``f_hz``: ``viscous_at_drive``
    and ``band_w<weight>`` for each real-part weight (and ``band_w<weight>_at_rated``, held
    to 1 + i eta at the rated speed, with ``anchored``)."""
    from bench.surrogate.rom_steady_levels import steady_solves
    from fem.viscoelastic import fit_band

    row = _dataset()[_dataset()["sample_index"] == sample].iloc[0]
    omega = 2 * math.pi * f_hz
    rec: dict[str, Any] = {"sample_index": sample, "f_hz": f_hz,
                           "attachment": row["attachment"], "n_rings": int(row["n_rings"]),
                           "tissue_eta": float(row["tissue_loss_factor"])}
    fits = {f"band_w{w:g}": fit_band(re_weight=w) for w in weights}
    if anchored:
        from fem.problem import drive_omega
        from fem.scene.io import scene_from_dict

        rated = drive_omega(scene_from_dict(json.loads(row["scene_json"]))) / (2 * math.pi)
        fits.update({f"band_w{w:g}_at_rated": fit_band(re_weight=w, anchor_hz=rated)
                     for w in weights})
    harm = steady_solves(row["scene_json"], omega, band=True, fits=fits)
    rec["viscous_at_drive"] = {"vs_hyst": (harm["rayleigh"] / harm["hyst"] - 1).tolist()}
    for name in fits:
        rec[name] = {"vs_hyst": (harm[name] / harm["hyst"] - 1).tolist()}
    return rec


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--samples", type=int, nargs="+", default=[43, 124, 213],
                    help="sample_index values of datasets/transient")
    ap.add_argument("--freqs", type=float, nargs="+", default=[40.0, 80.0, 130.0, 200.0],
                    help="motor speeds, Hz")
    ap.add_argument("--duration-ms", type=float, default=120.0)
    ap.add_argument("--json", help="write the rows to this file")
    ap.add_argument("--harmonic-only", action="store_true",
                    help="compare the models' harmonic responses only (no transients)")
    ap.add_argument("--re-weight", type=float, nargs="+", default=None,
                    help="with --harmonic-only: band-model fits with these real-part weights")
    ap.add_argument("--anchored", action="store_true",
                    help="with --harmonic-only: also each fit held exact at the rated speed")
    args = ap.parse_args(argv)
    if args.harmonic_only:
        from fem.viscoelastic import RE_WEIGHT

        return _harmonic_table(args.samples, args.freqs, args.re_weight or [RE_WEIGHT],
                               args.json, args.anchored)
    rows = []
    for s in args.samples:
        for f in args.freqs:
            r = measure(s, f, args.duration_ms)
            rows.append(r)
            print(f"{s:4d} {r['attachment']:5s} rings {r['n_rings']} eta {r['tissue_eta']:.2f}"
                  f" f {f:5.0f}  " + "  ".join(
                      f"{m}: vs hyst {r[m]['vs_hyst'][0]:+.3f}/{r[m]['vs_hyst'][1]:+.3f} "
                      f"(own {r[m]['vs_own_harmonic'][0]:+.3f}/{r[m]['vs_own_harmonic'][1]:+.3f},"
                      f" drift {r[m]['drift'][0]:+.3f}/{r[m]['drift'][1]:+.3f})"
                      for m in MODELS), flush=True)
            if args.json:
                Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")
    for m in MODELS:
        e = np.abs(np.array([r[m]["vs_hyst"] for r in rows]))
        print(f"{m}: median |FE / hyst - 1| centre/edge {np.median(e[:, 0]):.3f}/"
              f"{np.median(e[:, 1]):.3f}, max {e[:, 0].max():.3f}/{e[:, 1].max():.3f}")
    return 0


def _harmonic_table(samples: list[int], freqs: list[float], weights: list[float],
                    out: str | None, anchored: bool = False) -> int:
    rows = []
    for s in samples:
        for f in freqs:
            r = harmonic_only(s, f, weights, anchored)
            rows.append(r)
            models = [k for k in r if isinstance(r[k], dict)]
            print(f"{s:4d} {r['attachment']:5s} rings {r['n_rings']} eta {r['tissue_eta']:.2f}"
                  f" f {f:5.0f}  " + "  ".join(f"{m} {r[m]['vs_hyst'][0]:+.3f}/"
                                              f"{r[m]['vs_hyst'][1]:+.3f}" for m in models),
                  flush=True)
            if out:
                Path(out).write_text(json.dumps(rows, indent=1) + "\n")
    for m in models:
        e = np.abs(np.array([r[m]["vs_hyst"] for r in rows]))
        print(f"{m}: |steady / hyst - 1| median centre/edge {np.median(e[:, 0]):.3f}/"
              f"{np.median(e[:, 1]):.3f} (all {np.median(e):.3f}), max {e[:, 0].max():.3f}/"
              f"{e[:, 1].max():.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
