"""Where the 10-90 % rise of held-out transient runs differs between FE and envelope model.

For each run (dataset row ``sample_index``) over the first burst: the FE envelope (demodulated
as ``surrogate.rom`` does), the model's envelope (``models/rom-default``), the motor law's
speed^2 (the unbalance force, normalised by its level at switch-off) and the model's
quasi-static envelope (steady response at the instantaneous speed, no mode dynamics), each
as a fraction of its own level over the last 5 ms before switch-off; and their 10 % / 90 %
crossing times as ``surrogate.rom_metrics`` reads them.

    python bench/transient_rise_check.py --samples 175 219 75 95 247
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from surrogate import rom
from surrogate.data.store import Store
from surrogate.rom_metrics import STEADY_WINDOW_S, first_crossing
from surrogate.runtime.rom import STATES, continued_steady, gain_factor, load_envelope_model

ROOT = Path(__file__).resolve().parents[1]
PROBE_MS = (5, 10, 15, 20, 25, 30, 40, 50, 60, 80, 100, 120, 140)


def crossings(t: np.ndarray, y: np.ndarray, on_s: float) -> tuple[float, float, float]:
    """(level, t10 ms, t90 ms) of ``y`` read as rom_metrics reads them."""
    level = float(np.mean(y[(t >= on_s - STEADY_WINDOW_S) & (t < on_s)]))
    up = t < on_s
    return (level, 1e3 * first_crossing(t[up], y[up], 0.1 * level, rising=True),
            1e3 * first_crossing(t[up], y[up], 0.9 * level, rising=True))


def check(row: dict, model, point: int = 0) -> dict[str, dict]:
    run, _ = rom.run_from_row(row, model.design_names)
    t, on = run.t, run.on_time_s
    sim = model.simulate(t, run.volts, run.design, extrapolate=True)
    par = model.parameters(run.design, extrapolate=True)[rom.POINTS[point]]
    amp = model.steady_amplitudes(run.design, extrapolate=True)[rom.POINTS[point]]
    sig, fn = np.array([par["sigma_1_s"]]), np.array([par["fn_hz"]])
    quasi = (gain_factor(run.omega, np.array([par["gain"]]), np.array([par["gain_slope"]]))
             * continued_steady(run.omega, model.grid_hz, amp[None, :], sig, fn))[0]
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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT / "datasets" / "transient"))
    ap.add_argument("--model", default=str(ROOT / "models" / "rom-default"))
    ap.add_argument("--samples", type=int, nargs="+", default=[175, 219, 75, 95, 247])
    ap.add_argument("--point", choices=rom.POINTS, default="center")
    args = ap.parse_args(argv)
    model = load_envelope_model(args.model)
    df = Store.open(args.data).read()
    for si in args.samples:
        row = df[df["sample_index"] == si].iloc[0].to_dict()
        scene = json.loads(row["scene_json"])
        m = scene["unit"]["motor"]
        res = check(row, model, rom.POINTS.index(args.point))
        r = res.pop("_run")
        print(f"run {si} ({row.get('attachment')}, {args.point}): tau_up {m['tau_spinup_ms']:.1f} ms, "
              f"schedule {scene['analysis']['voltage_schedule'][:3]}; off at {r['on_ms']:.1f} ms, "
              f"speed there {r['f_end_hz']:.1f} Hz; mode sigma {r['sigma']:.0f} 1/s "
              f"f_n {r['fn_hz']:.0f} Hz")
        print(f"  {'curve':13s} {'level':>8s} {'t10':>6s} {'t90':>6s} {'rise':>6s}  "
              + " ".join(f"{ms:>5d}" for ms in PROBE_MS) + "  (ms: fraction of level)")
        for name, c in res.items():
            print(f"  {name:13s} {c['level']:8.3g} {c['t10_ms']:6.1f} {c['t90_ms']:6.1f} "
                  f"{c['rise_ms']:6.1f}  " + " ".join(f"{x:5.2f}" for x in c["frac"]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
