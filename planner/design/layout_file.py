"""The found unit as a layout request for ``hapticrom plan``: the design request's array,
site, drive, criterion and timing, and ``[[design]]`` tables for the winner and the reference
units (so the plan ranks them side by side). The site is the one searched (with ``--tissue``,
the calibration's point estimate), the drive frequencies the ones searched (a band resolved
to its frequencies)."""

from __future__ import annotations

from typing import Any

from fieldspec.toml import dumps, toml_value
from planner.design.run import DesignOutcome

__all__ = ["layout_toml"]


def _design_table(name: str, inputs: dict[str, Any], note: str) -> list[str]:
    lines = ["", f"# {note}", "[[design]]", f"name = {toml_value(name)}"]
    lines += [f"{k} = {toml_value(v)}" for k, v in inputs.items()]
    return lines


def layout_toml(outcome: DesignOutcome) -> str:
    """The layout request text (module docstring); the winner must exist."""
    w = outcome.winner
    if w is None:
        raise ValueError("layout_toml: no design was found")
    lay = outcome.layout
    raw = outcome.request.raw_layout or {}
    tables: dict[str, dict[str, Any]] = {k: dict(raw[k]) for k in ("model", "array", "criterion",
                                                                  "timing") if k in raw}
    tables.setdefault("model", {})["path"] = lay.model
    tables["site"] = dict(lay.site)
    tables["drive"] = {"frequencies_hz": [float(f) for f in lay.frequencies_hz]}
    order = ["model", "array", "site", "drive", "criterion", "timing"]
    text = dumps({k: tables[k] for k in order if k in tables},
                 header="hapticrom layout request written by `hapticrom design`: the found "
                        "unit and the\nreference units, ready for `hapticrom plan`.")
    lines = _design_table(w.name, w.inputs, "the unit found by the search"
                          + (f" (rings: {', '.join(w.materials)})" if w.materials else ""))
    for r in outcome.references:
        lines += _design_table(r.name, r.inputs, "reference unit")
    return text.rstrip("\n") + "\n" + "\n".join(lines) + "\n"
