"""What accuracy costs in time: the default forearm scene at several mesh levels and orders.

For each (order, level) the scene is solved harmonically `--repeat` times; the table prints DOFs,
the median wall time (mesh, assembly, factorisation and solve included) and the relative error
of the surface amplitude at the probe radii (0-20 mm) against the finest quadratic level.
Level 1 is the paper's resolution (0.5 mm near field, 2 mm far field); level f scales both
(wavelength-following off, as in ``hapticrom bench accuracy``, which runs the same ladder on
the study's unit designs).

    .venv/bin/python bench/fem/accuracy.py            # full table (about a minute)
    .venv/bin/python bench/fem/accuracy.py --quick    # two levels only
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from fem import simulate
from fem.scene import load_scene, scene_from_dict, scene_to_dict
from studies.accuracy import fe_ladder
from studies.accuracy.timing import timed

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "forearm.toml"


def scene_at(level: float, order: int, direction: str):
    """The forearm example at a mesh level (study's :func:`fe_ladder.scene_at`) and load
    direction, probed every 1 mm over 0-20 mm."""
    d = fe_ladder.scene_at(scene_to_dict(load_scene(EXAMPLE)), level, order)
    d["load"]["direction"] = direction
    d["output"]["radii_mm"] = list(np.arange(0.0, 20.5, 1.0))
    return scene_from_dict(d)


def amplitude(res) -> np.ndarray:
    return np.sqrt(np.sum(np.abs(res.U) ** 2, axis=1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="levels 2 and 1 only")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--direction", default="tangential", choices=["tangential", "normal"])
    args = ap.parse_args()
    levels = [2.0, 1.0] if args.quick else [2.0, 1.0, 0.7, 0.5]
    ref_level = 0.5 if args.quick else 0.25
    ref_scene = scene_at(ref_level, 2, args.direction)
    ref, _ = timed(lambda: simulate(ref_scene), 1)
    a_ref = amplitude(ref)
    print(f"forearm, {args.direction} load, 120 Hz; reference: order 2 at level {ref_level} "
          f"({ref.meta['dofs']} dofs)")
    print(f"{'order':>5} {'level':>6} {'near mm':>8} {'far mm':>7} {'dofs':>8} "
          f"{'median s':>9} {'max rel err':>12} {'normalized edge':>16}")
    for order in (1, 2):
        for level in levels:
            scene = scene_at(level, order, args.direction)
            res, t = timed(lambda scene=scene: simulate(scene), args.repeat)
            err = np.max(np.abs(amplitude(res) / a_ref - 1))
            print(f"{order:>5} {level:>6.2f} {0.5 * level:>8.3f} {2 * level:>7.2f} "
                  f"{res.meta['dofs']:>8} {t:>9.3f} {err:>12.2e} {res.normalized_edge:>16.4f}")


if __name__ == "__main__":
    main()
