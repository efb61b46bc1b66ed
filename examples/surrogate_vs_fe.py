"""The shipped surrogates beside the finite-element solver on the paper's three prototypes.

    .venv/bin/python examples/surrogate_vs_fe.py [--models models/nn-default models/gp-default]
    (default: the shipped network and GP of surrogate.runtime.defaults)

Each prototype scene (``examples/unit-*.toml``: forearm with the sourced tissue damping, 120 Hz)
is solved by ``fem.simulate`` and predicted by every model from the matching design point of
``examples/designs.csv`` (the scene's values written as the model's inputs; the model's one
ring density and Poisson's ratio stand for the rings' library values, 1040-1080 kg/m3 and 0.49).
Prints the center and edge amplitudes [um], the normalized edge and the relative differences.
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import numpy as np

from fem import load_scene, simulate
from surrogate.runtime import load_predictor
from surrogate.runtime.defaults import default_model_path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SCENES = ("unit-bare-forward.toml", "unit-double-forward.toml", "unit-triple-reverse-pogo.toml")


def design_points(path: Path) -> dict[str, np.ndarray]:
    """The CSV's columns as arrays (numbers as float, categories as text)."""
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))

    def value(text: str) -> float | str:
        try:
            return float(text)
        except ValueError:
            return text

    return {k: np.array([value(r[k]) for r in rows]) for k in rows[0]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", default=None,
                        help="model directories (default: the shipped network and GP, "
                        "surrogate.runtime.defaults)")
    args = parser.parse_args()
    if args.models is None:
        args.models = [str(default_model_path(role))
                       for role in ("harmonic", "gaussian_process")]
    points = design_points(HERE / "designs.csv")

    fe = []
    t0 = time.perf_counter()
    for name in SCENES:
        fe.append(simulate(load_scene(HERE / name)))
    fe_ms = (time.perf_counter() - t0) / len(SCENES) * 1e3
    print(f"{'design':28s} {'source':12s} {'center um':>10s} {'edge um':>9s} {'norm edge':>9s}"
          f" {'d center':>9s} {'d edge':>8s}")
    preds = {}
    for model in args.models:
        p = load_predictor(model)
        p.predict(points)  # warm-up: the session's first run allocates
        t0 = time.perf_counter()
        preds[Path(model).name] = p.predict(points)
        preds[Path(model).name]["ms"] = (time.perf_counter() - t0) * 1e3
    for i, (name, res) in enumerate(zip(SCENES, fe, strict=True)):
        label = name.removesuffix(".toml")
        print(f"{label:28s} {'FE':12s} {res.center_amplitude_um:10.3f} "
              f"{res.edge_amplitude_um:9.3f} {res.normalized_edge:9.3f}")
        for model, out in preds.items():
            c, e = out["center_amplitude_um"][i], out["edge_amplitude_um"][i]
            print(f"{'':28s} {model:12s} {c:10.3f} {e:9.3f} {out['normalized_edge'][i]:9.3f}"
                  f" {c / res.center_amplitude_um - 1:+9.1%} {e / res.edge_amplitude_um - 1:+8.1%}")
    print(f"\nFE {fe_ms:.0f} ms per design; " + "; ".join(
        f"{m} {out['ms']:.2f} ms for all {len(SCENES)}" for m, out in preds.items()))


if __name__ == "__main__":
    main()
