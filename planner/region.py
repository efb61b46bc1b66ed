"""``objective = "max_sites"``: the largest grid of identical units that fits in a region.

A ``rows x cols`` grid at pitch ``p`` covers, with each unit's edge radius ``a``:

* square: ``(cols - 1) p + 2a`` by ``(rows - 1) p + 2a``;
* hex: ``(cols - 1) p + p/2 + 2a`` (odd rows shifted, when rows > 1) by
  ``(rows - 1) p sqrt(3)/2 + 2a``.

So the region ``w x h`` bounds the pitch from above (:func:`largest_pitch`). Leakage never
falls with a shorter pitch (the envelope profile) and never falls with more sites (a grid
holds every smaller grid), so a shape fits when the criterion holds at that largest pitch,
and the fitting shapes form a staircase: :func:`largest_array` walks it (rows up, cols down)
in at most ``2 * MAX_SITES_PER_SIDE`` checks instead of trying every shape.
"""

from __future__ import annotations

import math
from collections.abc import Callable

__all__ = ["largest_array", "largest_pitch"]


def largest_pitch(rows: int, cols: int, grid: str, region_mm: tuple[float, float],
                  edge_radius_mm: float) -> float:
    """Largest pitch [mm] at which the grid fits in ``region_mm`` = (w, h) (inf for a single
    site that fits, -inf when even touching units do not fit)."""
    w, h = region_mm[0] - 2 * edge_radius_mm, region_mm[1] - 2 * edge_radius_mm
    if w < 0 or h < 0:
        return -math.inf
    spans = []
    x_units = (cols - 1) + (0.5 if grid == "hex" and rows > 1 else 0.0)
    y_units = (rows - 1) * (math.sqrt(3.0) / 2.0 if grid == "hex" else 1.0)
    for units, room in ((x_units, w), (y_units, h)):
        if units > 0:
            spans.append(room / units)
    return min(spans) if spans else math.inf


def largest_array(fits: Callable[[int, int], bool], max_side: int) -> tuple[int, int] | None:
    """The (rows, cols) with the most sites for which ``fits(rows, cols)`` holds, with
    ``fits`` monotone (a shape that fits makes every smaller one fit); ties: the squarer
    shape, then fewer rows. None if not even 1 x 1."""
    best: tuple[int, int] | None = None
    rows, cols = 1, max_side
    while rows <= max_side and cols >= 1:
        if fits(rows, cols):
            if best is None or (-rows * cols, abs(rows - cols)) < (-best[0] * best[1],
                                                                    abs(best[0] - best[1])):
                best = (rows, cols)
            rows += 1
        else:
            cols -= 1
    return best
