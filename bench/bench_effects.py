"""What each physical effect costs: a glued two-ring unit solved with everything on, then with
one effect switched off at a time, plus model choices that are not effects (pogo pins, absorbing
vs fixed side, element order). Glued, because a unit on frictionless pins with unbonded rings has
nothing but its inertia holding it sideways, so inertia and mass cannot be dropped there.

Prints median wall time over repeats, the ratio to the full model, and how much the answer moves
(normalized edge and edge amplitude), so the saving can be weighed against the error.

    .venv/bin/python bench/bench_effects.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from fem import simulate
from fem.scene import load_scene, scene_from_dict, scene_to_dict

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
EXAMPLE = EXAMPLES / "unit-double-forward.toml"


def variants() -> dict[str, dict]:
    base = scene_to_dict(load_scene(EXAMPLE))
    for layer in base["tissue"]["layer"]:
        layer["loss_factor"] = 0.1  # so that switching hysteresis off has something to skip
    out = {"all effects": base}
    for effect in ("hysteretic_damping", "inertia", "encapsulation", "unit_mass", "rocking"):
        out[f"no {effect}"] = {**base, "effects": {effect: False}}
    pogo = scene_to_dict(load_scene(EXAMPLES / "unit-triple-reverse-pogo.toml"))
    out["pogo unit (pin springs)"] = {**base, "unit": {**base["unit"], "attachment": "pogo",
                                                       "pogo": pogo["unit"]["pogo"]}}
    out["fixed side (no PML)"] = {**base, "tissue": {**base["tissue"], "side": "fixed"}}
    out["order 1 elements"] = {**base, "mesh": {**base["mesh"], "order": 1}}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    rows = []
    for name, d in variants().items():
        scene = scene_from_dict(d)
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            res = simulate(scene)
            times.append(time.perf_counter() - t0)
        rows.append((name, statistics.median(times), res))
    t_ref, ref = rows[0][1], rows[0][2]
    print(f"{EXAMPLE.name} at 120 Hz, median of {args.repeat}")
    print(f"{'variant':<24} {'dofs':>7} {'median s':>9} {'x full':>7} {'norm. edge':>11} "
          f"{'edge um':>9} {'edge change':>12}")
    for name, t, res in rows:
        change = res.edge_amplitude_um / ref.edge_amplitude_um - 1
        print(f"{name:<24} {res.meta['dofs']:>7} {t:>9.3f} {t / t_ref:>7.2f} "
              f"{res.normalized_edge:>11.3f} {res.edge_amplitude_um:>9.3f} {change:>+12.1%}")


if __name__ == "__main__":
    main()
