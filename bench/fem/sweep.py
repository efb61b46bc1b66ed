"""What a frequency sweep costs against direct solves on the same mesh, side by side in one run.

    python bench/fem/sweep.py                      # the default forearm unit, 100-250 Hz
    python bench/fem/sweep.py --scene examples/unit-sweep.toml --repeat 5

For the scene (a harmonic or sweep scene, turned into a sweep of ``--start``-``--stop`` Hz at
``--step`` Hz on one mesh sized for the band):

1. one direct solve (``fem.sweep.direct_sweep`` at single frequencies: element matrices with
   the exact PML of that frequency, assembly, factorisation, back-solve, sampling), warm
   (the topology's scatter map cached, as in a sweep of direct solves), median of
   ``--repeat`` solves at frequencies across the band;
2. the reduced-order sweep (``fem.sweep.sweep``), median of ``--repeat`` runs, with its split:
   setup (element matrices of the band: outside the PML once, the PML at the Chebyshev nodes),
   factorisations, basis (back-solves and orthogonalisation), projections, evaluations (the
   reduced solves at every frequency and the error estimate), output;
3. the ratio sweep / direct solve (the issue's target: at most 3), the solve count, the
   estimate, and the largest error against the direct solves at ``--check`` frequencies.

Ratios are the reliable part on a shared machine; BLAS runs on one thread throughout.
No assertions: the numbers go into the README and docs/model.md.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from fem.scene import load_scene, scene_from_dict  # noqa: E402
from fem.scene.frequencies import band_grid  # noqa: E402
from fem.sweep import direct_sweep, sweep, sweep_errors  # noqa: E402

DEFAULT_UNIT = {"load": {"kind": "unit"}, "unit": {}}


def _scene(args: argparse.Namespace):
    base = load_scene(args.scene) if args.scene else scene_from_dict(
        DEFAULT_UNIT | {"analysis": {"kind": "harmonic"}})
    band = band_grid(args.start, args.stop, args.step)
    return replace(base, analysis=replace(base.analysis, kind="sweep", frequency_hz=band,
                                          frequencies_hz=()))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", help="scene TOML (default: the default unit on the forearm)")
    ap.add_argument("--start", type=float, default=100.0)
    ap.add_argument("--stop", type=float, default=250.0)
    ap.add_argument("--step", type=float, default=1.0)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--check", type=int, default=16, help="direct solves to check against")
    args = ap.parse_args()
    scene = _scene(args)
    freqs = np.asarray(scene.analysis.frequencies_hz)
    name = args.scene or "default unit (forearm, bare glued ERM)"
    print(f"scene: {name}; sweep {freqs[0]:g}-{freqs[-1]:g} Hz, {freqs.size} frequencies")

    direct_sweep(scene, freqs[:1])  # warm: imports, the topology's scatter map
    picks = freqs[np.linspace(0, freqs.size - 1, args.repeat).round().astype(int)]
    direct = []
    for f in picks:
        t = time.perf_counter()
        direct_sweep(scene, [f])
        direct.append(time.perf_counter() - t)
    t_direct = statistics.median(direct)

    runs, results = [], []
    for _ in range(args.repeat):
        t = time.perf_counter()
        res = sweep(scene)
        runs.append(time.perf_counter() - t)
        results.append(res)
    t_sweep = statistics.median(runs)
    res = results[int(np.argsort(runs)[len(runs) // 2])]
    stages = res.meta["stages_s"]
    check = freqs[np.linspace(0, freqs.size - 1, args.check).round().astype(int)]
    err = sweep_errors(res, direct_sweep(scene, check))

    print(f"mesh: {res.meta['elements']} elements, {res.meta['dofs']} unknowns (uncondensed), "
          f"sized for {res.meta['mesh_frequency_hz']:g} Hz")
    print(f"direct solve (warm), median of {len(direct)}: {t_direct * 1e3:.0f} ms "
          f"-> {freqs.size} direct solves ~ {t_direct * freqs.size:.1f} s")
    print(f"reduced-order sweep, median of {len(runs)}: {t_sweep * 1e3:.0f} ms "
          f"= {t_sweep / t_direct:.2f} direct solves "
          f"({t_direct * freqs.size / t_sweep:.0f}x faster than {freqs.size} direct solves)")
    print(f"  full solves (factorisations) {res.full_solves} at "
          + ", ".join(f"{f:g}" for f in res.meta["expansions_hz"])
          + f" Hz; back-solves {res.meta['back_solves']}; basis {res.meta['basis_size']}; "
          f"Chebyshev nodes {res.meta['chebyshev_nodes']}")
    print("  split (ms): " + ", ".join(f"{k} {v * 1e3:.0f}" for k, v in stages.items()))
    print(f"  error estimate {res.error_estimate:.2g}; largest error against {check.size} "
          "direct solves: " + ", ".join(f"{k} {v:.2g}" for k, v in err.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
