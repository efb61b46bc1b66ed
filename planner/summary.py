"""What a plan's answer rests on: the validity domain, and every extrapolation summarised.

Three kinds of extrapolation are flagged where they happen and gathered here for the chosen
design (``plan.json`` ``validity``, and the terminal):

* ``inputs``: request values outside the domain (:mod:`planner.domain`; only with
  ``model.allow_extrapolation = true``), naming the field and the model(s) exceeded;
* ``profile``: the leakage at the chosen pitch read beyond the model's profile (its last
  point, 20 mm from the unit's edge for the shipped models), where the amplitude is the
  log-slope extension of :mod:`planner.crosstalk`, not a prediction. Flagged when at least
  ``PROFILE_SHARE_FLAG`` (1 %) of the worst site's leakage power comes from there;
* ``timing``: ROM inputs outside its trained range (``timing.extrapolated``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["PROFILE_SHARE_FLAG", "summary_lines", "validity"]

PROFILE_SHARE_FLAG = 0.01  # leakage power share from beyond the profile that is flagged


def validity(plan: Any) -> dict[str, Any]:
    """The ``validity`` object of plan.json (see the module docstring)."""
    best = plan.best
    doc: dict[str, Any] = {"domain": None if plan.domain is None else plan.domain.to_dict()}
    if best is None:
        return {**doc, "extrapolated": None}
    inputs = [x.to_dict() for x in best.extrapolations]
    pos = plan.positions_mm
    nearest = None
    if len(pos) > 1:
        r = np.linalg.norm(pos[:, None] - pos[None], axis=2)
        np.fill_diagonal(r, np.inf)
        nearest = round(float(r.min()) - best.edge_radius_mm, 3)
    share = round(best.beyond_profile, 4)
    profile = {"profile_end_from_edge_mm": plan.profile_end_mm,
               "nearest_neighbour_from_edge_mm": nearest,
               "leakage_share_beyond_profile": share,
               "extrapolated": share >= PROFILE_SHARE_FLAG}
    t = plan.timing or {}
    timing = {"extrapolated_inputs": list(t.get("extrapolated") or []),
              "extrapolated": bool(t.get("extrapolated"))}
    flagged = bool(inputs) or profile["extrapolated"] or timing["extrapolated"]
    return {**doc, "extrapolated": flagged, "inputs": inputs, "profile": profile,
            "timing": timing}


def summary_lines(v: dict[str, Any]) -> list[str]:
    """Human-readable lines of a ``validity`` object (empty when nothing is extrapolated)."""
    if not v.get("extrapolated"):
        return []
    lines = []
    for x in v["inputs"]:
        lo, hi = x["domain"]
        lines.append(f"input {x['field']} = {x['value']:g} outside the plan's domain "
                     f"[{lo:.4g}, {hi:.4g}] ({', '.join(x['models'])})")
    p = v["profile"]
    if p["extrapolated"]:
        lines.append(f"crosstalk beyond the model's profile: the nearest neighbour is "
                     f"{p['nearest_neighbour_from_edge_mm']:.2f} mm from a unit's edge, the "
                     f"profile ends at {p['profile_end_from_edge_mm']:g} mm; "
                     f"{p['leakage_share_beyond_profile']:.0%} of the worst site's leakage is "
                     "the log-slope extension")
    if v["timing"]["extrapolated"]:
        lines.append("timing: the envelope ROM extrapolates in "
                     + ", ".join(v["timing"]["extrapolated_inputs"]))
    return lines
