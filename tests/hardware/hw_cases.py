"""Plan fixtures for the hardware tests: a hand-made plan (three sites in a row, a crosstalk
matrix written out) and a real one from the shipped surrogate (a 2 x 2 forearm array). Both
carry a ``timing`` object with the keys ``planner.timing`` writes. Both drive at 100 Hz, where
the shipped ERM's level limit (4.5 V maximum / 2.82 V nominal = 1.598) allows the 1.5 kick;
``sealed`` adds the plan record (``planner.plan_record``) as ``hapticrom plan`` writes it."""

from __future__ import annotations

import copy
from typing import Any

TIMING = {"rise_ms": 30.0, "decay_ms": 40.0, "overdrive_ms": 10.0, "overdrive_level": 1.5,
          "brake_ms": 8.0, "min_isi_ms": 45.0}


def line_plan() -> dict[str, Any]:
    """Three sites 20 mm apart: own amplitude 10 um, 1 um at one pitch, 0.1 um at two."""
    C = [[10.0, 1.0, 0.1], [1.0, 10.0, 1.0], [0.1, 1.0, 10.0]]
    return {"format": "hapticrom-plan", "version": 1, "model": "models/nn-default",
            "array": {"rows": 1, "cols": 3, "grid": "square"}, "site": {}, "candidates": [],
            "best": "hand-made", "best_frequency_hz": 100.0, "pitch_mm": 20.0,
            "positions_mm": [[0.0, 0.0], [20.0, 0.0], [40.0, 0.0]], "crosstalk_um": C,
            "timing": dict(TIMING)}


_REAL: dict[str, Any] = {}


def real_plan() -> dict[str, Any]:
    """The example forearm layout cut to 2 x 2, planned on the shipped surrogate (cached)."""
    if not _REAL:
        import tomllib

        from planner import layout_from_dict, plan_layout, plan_to_dict

        with open("examples/forearm-layout.toml", "rb") as f:
            d = tomllib.load(f)
        d["array"].update(rows=2, cols=2)
        d["drive"]["frequencies_hz"] = [100.0]
        _REAL.update(plan_to_dict(plan_layout(layout_from_dict(d))), timing=dict(TIMING))
    return copy.deepcopy(_REAL)


def sealed(d: dict[str, Any]) -> dict[str, Any]:
    """``d`` as ``hapticrom plan`` writes it: schema version, kind and digest."""
    from planner.plan_record import seal_plan

    return seal_plan(d)
