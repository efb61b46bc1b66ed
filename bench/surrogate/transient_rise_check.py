"""Where the 10-90 % rise of held-out transient runs differs between FE and envelope model.

For each run (dataset row ``sample_index``) over the first burst: the FE envelope (demodulated
as ``surrogate.envelope.fit`` does), the model's envelope (``models/rom-default``), the motor law's
speed^2 (the unbalance force, normalised by its level at switch-off) and the model's
quasi-static envelope (steady response at the instantaneous speed, no mode dynamics), each
as a fraction of its own level over the last 5 ms before switch-off; and their 10 % / 90 %
crossing times as ``surrogate.envelope.metrics`` reads them. With ``--harmonic`` also the steady
response along the spin-up: the FE harmonic solve of the row's own scene (same mesh, hysteretic
loss) at the speeds the motor passes, against the model's steady part A(f) (harmonic NN times
the learned gain, continued below 100 Hz through the mode), each over its value at the speed
reached at switch-off: the 10-90 % rise of a slow spin-up is where A(f(t)) crosses 0.9.

    python bench/surrogate/transient_rise_check.py --samples 175 219 75 95 247 --harmonic

``--quasi-static`` does it for every held-out run (``sample_index % 4 == 3``; about 25 fast
harmonic solves per run): the rise of the quasi-static FE envelope A_FE(f(t)) (harmonic solves
every 5 Hz, interpolated on the run's speed curve) against the FE's and the model's rises,
and the correlation of the model's rise error with its quasi-static part.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from surrogate.data.store import Store
from surrogate.envelope import fit as rom
from surrogate.envelope.metrics import STEADY_WINDOW_S, first_crossing
from surrogate.runtime.rom import STATES, load_envelope_model

ROOT = Path(__file__).resolve().parents[2]
PROBE_MS = (5, 10, 15, 20, 25, 30, 40, 50, 60, 80, 100, 120, 140)


def crossings(t: np.ndarray, y: np.ndarray, on_s: float) -> tuple[float, float, float]:
    """(level, t10 ms, t90 ms) of ``y`` read as surrogate.envelope.metrics reads them."""
    level = float(np.mean(y[(t >= on_s - STEADY_WINDOW_S) & (t < on_s)]))
    up = t < on_s
    return (level, 1e3 * first_crossing(t[up], y[up], 0.1 * level, rising=True),
            1e3 * first_crossing(t[up], y[up], 0.9 * level, rising=True))


def check(row: dict, model, point: int = 0) -> dict[str, dict]:
    run, _ = rom.run_from_row(row, model.design_names)
    t, on = run.t, run.on_time_s
    sim = model.simulate(t, run.volts, run.design, extrapolate=True)
    par = model.parameters(run.design, extrapolate=True)[rom.POINTS[point]]
    quasi = model.steady_levels(run.omega, run.design, extrapolate=True)[rom.POINTS[point]]
    curves = {"fe": run.env[point], "model": sim[STATES[point]],
              "speed^2": run.omega ** 2, "quasi-static": quasi}
    out = {}
    for name, y in curves.items():
        level, t10, t90 = crossings(t, y, on)
        frac = [float(np.interp(ms * 1e-3, t, y)) / level for ms in PROBE_MS]
        out[name] = {"level": level, "t10_ms": t10, "t90_ms": t90, "rise_ms": t90 - t10,
                     "frac": frac}
    out["_run"] = {"on_ms": 1e3 * on, "sigma": par["sigma_1_s"], "fn_hz": par["fn_hz"],
                   "f_end_hz": float(np.interp(on, t, run.omega)) / (2 * math.pi)}
    return out


def steady_along_spin_up(row: dict, model, point: int = 0) -> dict[str, np.ndarray]:
    """FE harmonic amplitudes (um) of the row's scene and the model's A(f) at the speeds
    40, 60, ... Hz up to the speed at switch-off (last entry)."""

    run, _ = rom.run_from_row(row, model.design_names)
    f_end = float(np.interp(run.on_time_s - 0.5 * STEADY_WINDOW_S, run.t, run.omega)) / (
        2 * math.pi)
    freqs = np.append(np.arange(40.0, f_end - 2.0, 10.0), f_end)
    a_model = model.steady_levels(2 * math.pi * freqs, run.design,
                                  extrapolate=True)[rom.POINTS[point]]
    a_fe = harmonic_amplitudes(row, freqs, point)
    return {"f_hz": freqs, "fe_harmonic_um": a_fe, "model_um": a_model}


def harmonic_amplitudes(row: dict, freqs_hz, point: int = 0) -> np.ndarray:
    """Steady amplitudes (um) of the row's scene solved harmonically (hysteretic loss: the
    transient's schedule and damping keys dropped) at ``freqs_hz``; centre (0) or edge (1)."""
    from fem.scene.io import scene_from_dict
    from fem.simulation import simulate

    scene = json.loads(row["scene_json"])
    for key in ("time_step_ms", "duration_ms", "rho_inf", "voltage_schedule", "damping"):
        scene["analysis"].pop(key, None)
    out = []
    for f in freqs_hz:
        scene["analysis"].update(kind="harmonic", frequency_hz=float(f))
        res = simulate(scene_from_dict(scene))
        out.append(res.center_amplitude_um if point == 0 else res.edge_amplitude_um)
    return np.array(out)


def _rise_ms(t: np.ndarray, y: np.ndarray, on_s: float) -> float:
    _, t10, t90 = crossings(t, y, on_s)
    return t90 - t10


def quasi_static_rises(row: dict, model, step_hz: float = 5.0) -> dict[str, float]:
    """Centre rise (ms) of the FE envelope, the model's, and of the quasi-static envelopes
    A(f(t)) of the FE (harmonic solves every ``step_hz`` of the row's scene) and the model."""

    run, _ = rom.run_from_row(row, model.design_names)
    t, on, w = run.t, run.on_time_s, run.omega
    f = w / (2 * math.pi)
    f_max = float(f[t < on].max())
    grid = np.append(np.arange(step_hz, f_max, step_hz), f_max)
    a_fe = harmonic_amplitudes(row, grid)
    q_fe = np.interp(f, np.append(0.0, grid), np.append(0.0, a_fe))
    q_model = model.steady_levels(w, run.design, extrapolate=True)["center"]
    sim = model.simulate(t, run.volts, run.design, extrapolate=True)[STATES[0]]
    return {"fe": _rise_ms(t, run.env[0], on), "model": _rise_ms(t, sim, on),
            "fe_quasi": _rise_ms(t, q_fe, on), "model_quasi": _rise_ms(t, q_model, on)}


def held_out_quasi_static(df, model) -> None:
    """Print :func:`quasi_static_rises` of every held-out run and the summary."""
    rows = df[(df["status"] == "ok") & df["history_center_um"].notna()
              & (df["sample_index"] % 4 == 3)]
    out = []
    for row in rows.to_dict("records"):
        r = quasi_static_rises(row, model)
        out.append(r)
        print(f"run {int(row['sample_index'])} ({row['attachment']}): rise ms FE {r['fe']:.1f} "
              f"model {r['model']:.1f} | quasi-static FE {r['fe_quasi']:.1f} "
              f"model {r['model_quasi']:.1f}", flush=True)
    a = {k: np.array([r[k] for r in out]) for k in out[0]}
    err, qerr = a["model"] - a["fe"], a["model_quasi"] - a["fe_quasi"]
    big = np.abs(err) > 10.0
    print(f"{len(out)} held-out runs, centre: |model - FE| rise median {np.median(np.abs(err)):.2f}"
          f" max {np.max(np.abs(err)):.1f} ms; |quasi-static model - quasi-static FE| median "
          f"{np.median(np.abs(qerr)):.2f} max {np.max(np.abs(qerr)):.1f} ms; |quasi-static FE - "
          f"FE| median {np.median(np.abs(a['fe_quasi'] - a['fe'])):.2f} ms")
    print(f"correlation of the rise error with its quasi-static part: "
          f"{np.corrcoef(err, qerr)[0, 1]:.2f} (all), {np.corrcoef(err[big], qerr[big])[0, 1]:.2f}"
          f" ({int(big.sum())} runs with |error| > 10 ms)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT / "datasets" / "transient"))
    ap.add_argument("--model", default=str(ROOT / "models" / "rom-default"))
    ap.add_argument("--samples", type=int, nargs="+", default=[175, 219, 75, 95, 247])
    ap.add_argument("--point", choices=rom.POINTS, default="center")
    ap.add_argument("--harmonic", action="store_true",
                    help="also solve the FE steady response along the spin-up (fast solves)")
    ap.add_argument("--quasi-static", action="store_true",
                    help="quasi-static rise check of every held-out run (centre)")
    args = ap.parse_args(argv)
    model = load_envelope_model(args.model)
    df = Store.open(args.data).read()
    if args.quasi_static:
        held_out_quasi_static(df, model)
        return 0
    for si in args.samples:
        row = df[df["sample_index"] == si].iloc[0].to_dict()
        scene = json.loads(row["scene_json"])
        m = scene["unit"]["motor"]
        res = check(row, model, rom.POINTS.index(args.point))
        r = res.pop("_run")
        print(f"run {si} ({row.get('attachment')}, {args.point}): "
              f"tau_up {m['tau_spinup_ms']:.1f} ms, "
              f"schedule {scene['analysis']['voltage_schedule'][:3]}; "
              f"off at {r['on_ms']:.1f} ms, "
              f"speed there {r['f_end_hz']:.1f} Hz; mode sigma {r['sigma']:.0f} 1/s "
              f"f_n {r['fn_hz']:.0f} Hz")
        print(f"  {'curve':13s} {'level':>8s} {'t10':>6s} {'t90':>6s} {'rise':>6s}  "
              + " ".join(f"{ms:>5d}" for ms in PROBE_MS) + "  (ms: fraction of level)")
        for name, c in res.items():
            print(f"  {name:13s} {c['level']:8.3g} {c['t10_ms']:6.1f} {c['t90_ms']:6.1f} "
                  f"{c['rise_ms']:6.1f}  " + " ".join(f"{x:5.2f}" for x in c["frac"]))
        if args.harmonic:
            s = steady_along_spin_up(row, model, rom.POINTS.index(args.point))
            print("  steady response along the spin-up (over its value at the last speed):")
            print("    f Hz        " + " ".join(f"{x:6.1f}" for x in s["f_hz"]))
            for name in ("fe_harmonic_um", "model_um"):
                y = s[name]
                print(f"    {name[:-3]:11s} " + " ".join(f"{x:6.2f}" for x in y / y[-1])
                      + f"   (last {y[-1]:.2f} um)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
