"""How long the first burst of a transient-space schedule must last for its FE window to be steady.

    nice -n 5 python bench/fem/transient_settling.py                      # 6 designs, 300 ms each
    python bench/fem/transient_settling.py --samples 211 --duration-ms 250 --ends-ms 60 150 200

For each design (a ``sample_index`` of ``--data``, default ``datasets/transient``) the run's own
first burst (its kick, then its drive voltage) is held for ``--duration-ms`` with the loss model
``--damping`` (default ``hysteretic_band``, as the transient space now uses) and demodulated as
in training (``surrogate.envelope.fit.run_from_row``). For each candidate switch-off time T
(``--ends-ms``) the card's "steady" level (mean envelope over [T - 5 ms, T),
``surrogate.envelope.metrics``) is compared with the steady state the transient tends to at the
window's mean speed: a harmonic solve with the same loss model on the transient's own matrices
(``bench.surrogate.rom_steady_levels.steady_solves``). Prints per design and T the relative
difference (center / edge) and the card's ``settled`` flag, the medians and maxima over designs,
and the wall time of each solve (the cost per simulated millisecond).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

# worst cases of the old dataset: pogo beats (211, 124, 236), a slow soft start (153),
# a low tissue loss (14), a pogo unit driven at 53 Hz (199)
SAMPLES = (211, 124, 236, 153, 14, 199)


def window_levels(t: np.ndarray, env: np.ndarray, omega: np.ndarray, end_s: float,
                  width_s: float = 5e-3) -> tuple[np.ndarray, float, np.ndarray]:
    """(center, edge) mean envelope over [end_s - width_s, end_s), the mean speed there
    (rad/s), and the card's settled flag per point (``surrogate.envelope.metrics``)."""
    from surrogate.envelope.metrics import SETTLED_PTP, SETTLED_WINDOW_S

    win = (t >= end_s - width_s) & (t < end_s)
    late = (t >= end_s - SETTLED_WINDOW_S) & (t < end_s)
    flags = np.array([np.ptp(e[late]) / np.mean(e[late]) < SETTLED_PTP for e in env])
    return env[:, win].mean(axis=1), float(omega[win].mean()), flags


def measure(row: dict[str, Any], duration_ms: float, ends_ms: list[float], damping: str
            ) -> dict[str, Any]:
    """One design: its first burst held for ``duration_ms``; per end time the window's level
    against the loss model's own steady state."""
    from bench.surrogate.rom_steady_levels import steady_solver
    from surrogate.data.worker import run_sample
    from surrogate.envelope.fit import run_from_row

    scene = json.loads(row["scene_json"])
    sched = scene["analysis"]["voltage_schedule"]
    scene["analysis"].update(voltage_schedule=[list(sched[0]), list(sched[1])],
                             duration_ms=duration_ms, damping=damping)
    t0 = time.perf_counter()
    out = run_sample(scene)
    wall = time.perf_counter() - t0
    if out["status"] != "ok":
        raise RuntimeError(f"sample {row['sample_index']}: {out['error']}")
    run, _ = run_from_row({**row, **out, "scene_json": json.dumps(scene)}, [])
    own = "band" if damping == "hysteretic_band" else "rayleigh"
    solve = steady_solver(json.dumps(scene))
    rec: dict[str, Any] = {"sample_index": int(row["sample_index"]),
                           "attachment": row["attachment"], "n_rings": int(row["n_rings"]),
                           "tissue_eta": float(row["tissue_loss_factor"]),
                           "tau_spinup_ms": float(row["tau_spinup_ms"]), "wall_s": wall,
                           "ends": []}
    for end in ends_ms:
        fe, omega, flags = window_levels(run.t, run.env, run.omega, end * 1e-3)
        ref = solve(omega, band=damping == "hysteretic_band")[own]
        rec["ends"].append({"end_ms": end, "f_hz": omega / (2 * math.pi),
                            "rel": (fe / ref - 1).tolist(), "settled": flags.tolist()})
    return rec


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=str(ROOT / "datasets" / "transient"))
    ap.add_argument("--samples", type=int, nargs="+", default=list(SAMPLES))
    ap.add_argument("--duration-ms", type=float, default=300.0)
    ap.add_argument("--ends-ms", type=float, nargs="+",
                    default=[60.0, 100.0, 130.0, 160.0, 200.0, 250.0, 295.0])
    ap.add_argument("--damping", default="hysteretic_band",
                    choices=("hysteretic_band", "viscous_at_drive"))
    ap.add_argument("--json", help="write the rows to this file")
    args = ap.parse_args(argv)
    from surrogate.data.store import Store

    df = Store.open(args.data).read()
    df = df[df["status"] == "ok"]
    rows = []
    for s in args.samples:
        row = df[df["sample_index"] == s].to_dict("records")[0]
        r = measure(row, args.duration_ms, args.ends_ms, args.damping)
        rows.append(r)
        print(f"{s:4d} {r['attachment']:5s} rings {r['n_rings']} eta {r['tissue_eta']:.2f} "
              f"tau_up {r['tau_spinup_ms']:4.1f} ms  solve {r['wall_s']:.1f} s  " + "  ".join(
                  f"{e['end_ms']:.0f} ms ({e['f_hz']:.0f} Hz): {e['rel'][0]:+.3f}/"
                  f"{e['rel'][1]:+.3f}{'' if all(e['settled']) else '*'}" for e in r["ends"]),
              flush=True)
        if args.json:
            Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")
    print("(*: the card's settled flag is off for a point)")
    for k, end in enumerate(args.ends_ms):
        a = np.abs(np.array([r["ends"][k]["rel"] for r in rows]))
        n_set = sum(all(r["ends"][k]["settled"]) for r in rows)
        print(f"switch-off at {end:.0f} ms: |window / own steady - 1| median center/edge "
              f"{np.median(a[:, 0]):.3f}/{np.median(a[:, 1]):.3f}, max {a[:, 0].max():.3f}/"
              f"{a[:, 1].max():.3f}; settled {n_set}/{len(rows)}")
    wall = np.array([r["wall_s"] for r in rows])
    print(f"solve wall time {np.median(wall):.1f} s median for {args.duration_ms:.0f} ms "
          f"({1e3 * np.median(wall) / args.duration_ms:.1f} s per simulated second)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
