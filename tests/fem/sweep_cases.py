"""Scenes the frequency sweep is verified on: the example scenes and designs drawn from the
default dataset space, each turned into a 100-250 Hz sweep."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from fem.scene import Scene, load_scene
from fem.scene.frequencies import band_grid

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ["forearm.toml", "unit-bare-forward.toml", "unit-double-forward.toml",
            "unit-triple-reverse-pogo.toml", "unit-sweep.toml"]
BAND_HZ = band_grid(100.0, 250.0, 1.0)
#: The issue's tolerances: magnitudes relative, phases in rad where |u| > 1 % of the largest.
MAGNITUDE_TOL = 1e-3
PHASE_TOL = 1e-3


def as_sweep(scene: Scene, band: tuple[float, ...] = BAND_HZ) -> Scene:
    """``scene`` as a sweep over ``band`` (Hz), meshed for the band (fixed cell counts, which
    a dataset's mesh plan sets for one frequency, are dropped)."""
    return replace(scene, analysis=replace(scene.analysis, kind="sweep", frequency_hz=band,
                                           frequencies_hz=()),
                   mesh=replace(scene.mesh, cells_r=None, cells_z=None))


def example(name: str) -> Scene:
    return as_sweep(load_scene(ROOT / "examples" / name))


def space_designs(n: int, n_light_pogo: int, seed: int = 7) -> list[tuple[str, Scene]]:
    """``n`` designs of ``datasets/spaces/default.toml`` (its Sobol sequence from ``seed``
    x 64), the last ``n_light_pogo`` of them forced to pogo pins with three rings of loss
    factor 0.02-0.03: the lightly damped units whose centre has sharp antiresonances."""
    from surrogate.data.space import load_space

    space = load_space(ROOT / "datasets" / "spaces" / "default.toml")
    pts = space.points(seed * 64, n)
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        row = {k: v[i].item() if hasattr(v[i], "item") else v[i] for k, v in pts.items()}
        if i >= n - n_light_pogo:
            row.update(attachment="pogo", n_rings=3,
                       ring_loss_factor=float(rng.uniform(0.02, 0.03)))
        out.append((f"design {i}: " + ", ".join(f"{k}={v}" for k, v in row.items()),
                    as_sweep(space.scene(row))))
    return out
