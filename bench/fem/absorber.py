"""How well the outer boundary absorbs: move it and watch the answer.

For the PML (harmonic) and the graded damping layer (the time-domain absorber, here solved in
the frequency domain on the transient's own domain), the optimised unit is solved with the
tissue truncated at 50 mm and at 80 mm; an absorber that reflects nothing gives the same surface
amplitudes within 20 mm. Also prints each against the 80 mm PML answer.

    .venv/bin/python bench/fem/absorber.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fem import results
from fem.problem import build_problem
from fem.scene import load_scene, scene_from_dict, scene_to_dict
from fem.solve import solve_mode

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "unit-transient.toml"
RADII_MM = np.arange(0.0, 20.5, 2.0)


def surface_amplitude(kind: str, radius_mm: float) -> tuple[np.ndarray, int]:
    d = scene_to_dict(load_scene(EXAMPLE))
    d["tissue"]["radius_mm"] = radius_mm
    d["analysis"]["kind"] = kind
    scene = scene_from_dict(d)
    p = build_problem(scene)
    w = 2 * np.pi * scene.unit.motor.rated_frequency_hz
    # the transient problem carries a unit force pattern; scale to the steady unbalance force
    force = scene.unit.motor.unbalance_kg_m * w**2 if kind == "transient" else 1.0
    sol = solve_mode(p.domain, 1, p.load * force, w, extra=p.extra)
    stencil = results.surface_stencil(p.domain, RADII_MM * 1e-3)
    return np.linalg.norm(results.interpolate(stencil, sol.nodal()), axis=1), sol.n_dofs


def main() -> None:
    ref, _ = surface_amplitude("harmonic", 80.0)
    print("max relative change of surface amplitude within 20 mm, triple-ring pogo unit, 120 Hz")
    print(f"{'absorber':<34} {'dofs (50 mm)':>12} {'50 vs 80 mm':>12} {'vs PML 80 mm':>13}")
    for kind, name in (("harmonic", "PML (frequency domain)"),
                       ("transient", "graded damping layer (time domain)")):
        a50, n50 = surface_amplitude(kind, 50.0)
        a80, _ = surface_amplitude(kind, 80.0)
        print(f"{name:<34} {n50:>12} {np.max(np.abs(a50 / a80 - 1)):>12.2e} "
              f"{np.max(np.abs(a50 / ref - 1)):>13.2e}")


if __name__ == "__main__":
    main()
