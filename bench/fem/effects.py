"""What each physical effect costs: a glued two-ring unit solved with everything on, then with
one effect switched off at a time, plus model choices that are not effects (pogo pins, absorbing
vs fixed side, element order). Glued, because a unit on frictionless pins with unbonded rings has
nothing but its inertia holding it sideways, so inertia and mass cannot be dropped there.

Prints median wall time over repeats, the ratio to the full model, and how much the answer moves
(normalized edge and edge amplitude), so the saving can be weighed against the error.

    .venv/bin/python bench/fem/effects.py [--repeat 5]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from fem import simulate
from fem.scene import load_scene, scene_from_dict, scene_to_dict
from studies.accuracy import effects
from studies.accuracy.timing import timed

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
EXAMPLE = EXAMPLES / "unit-double-forward.toml"


def variants() -> dict[str, dict]:
    """The study's variants (:func:`studies.accuracy.effects.variants`) of the example, with a
    tissue loss factor so that hysteresis has something to skip, plus the pogo-pin unit."""
    base = scene_to_dict(load_scene(EXAMPLE))
    for layer in base["tissue"]["layer"]:
        layer["loss_factor"] = 0.1  # so that switching hysteretic damping off has an effect
    out = {k: v for k, v in effects.variants(base).items() if v is not None}
    pogo = scene_to_dict(load_scene(EXAMPLES / "unit-triple-reverse-pogo.toml"))
    out["pogo unit (pin springs)"] = {**base, "unit": {**base["unit"], "attachment": "pogo",
                                                       "pogo": pogo["unit"]["pogo"]}}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    rows = []
    for name, d in variants().items():
        scene = scene_from_dict(d)
        res, t = timed(lambda scene=scene: simulate(scene), args.repeat)
        rows.append((name, t, res))
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
