"""The pattern file: a sequence of steps of site intensities (TOML, validated by ``fieldspec``).

    [pattern]
    name = "sweep"                  # optional label

    [[step]]
    sites = [0, 1]                  # sites driven in this step (0-based, row by row) ...
    intensity = 1.0                 # ... at this intensity (0-1; default 1)
    duration_ms = 150.0             # how long the step is felt [ms]
    gap_ms = 100.0                  # pause after it [ms]

    [[step]]
    intensities = [0.5, 0.0, 1.0]   # or one intensity (0-1) per site of the plan
    duration_ms = 200.0

An intensity is the fraction of the site's own amplitude at the nominal level (the plan's
crosstalk matrix diagonal). Site numbers and the length of ``intensities`` are checked against
the plan when the pattern is bound to it (:func:`hardware.schedule.build_schedule`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fieldspec import (
    REQUIRED,
    Context,
    FieldError,
    Spec,
    read_array,
    read_fields,
    read_table,
    require_table,
)
from fieldspec.toml import read_toml_file

__all__ = ["MAX_STEPS", "Pattern", "PatternError", "Step", "load_pattern", "pattern_from_dict"]

MAX_STEPS = 10_000
MAX_DURATION_MS = 60_000.0


class PatternError(FieldError):
    """A bad pattern file (``.field`` names the offending value)."""


@dataclass(frozen=True)
class Step:
    """One step: either ``intensities`` (one per site) or ``sites`` at ``intensity``."""

    duration_ms: float
    gap_ms: float
    intensities: tuple[float, ...] | None = None
    sites: tuple[int, ...] | None = None
    intensity: float = 1.0


@dataclass(frozen=True)
class Pattern:
    name: str
    steps: tuple[Step, ...]


_PATTERN = {"name": Spec(str, "pattern")}
_STEP = {"duration_ms": Spec(float, REQUIRED, f"(0, {MAX_DURATION_MS:g}]"),
         "gap_ms": Spec(float, 0.0, f"[0, {MAX_DURATION_MS:g}]"),
         "intensity": Spec(float, 1.0, "[0, 1]"),
         "intensities": Spec(tuple, None, "[0, 1]")}


def _sites(raw: Any, path: str, ctx: Context) -> tuple[int, ...]:
    if not isinstance(raw, list) or not raw:
        raise PatternError(path, f"{path} = {raw!r}: expected a non-empty list of site "
                           "numbers (0-based integers)")
    out = []
    for i, v in enumerate(raw):
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise PatternError(f"{path}[{i}]", f"{path}[{i}] = {v!r}: expected a site number "
                               "(an integer >= 0)")
        out.append(v)
    if len(set(out)) != len(out):
        raise PatternError(path, f"{path} = {raw!r}: a site is listed twice")
    return tuple(out)


def _step(raw: Any, path: str, ctx: Context) -> Step:
    table = require_table(raw, path, [*_STEP, "sites"], ctx)
    has_i, has_s = "intensities" in table, "sites" in table
    if has_i == has_s:
        raise PatternError(path, f"{path}: give either sites (with intensity) or intensities "
                           "(one per site), not " + ("both" if has_i else "neither"))
    if has_i and "intensity" in table:
        raise PatternError(f"{path}.intensity", f"{path}.intensity goes with sites; with "
                           "intensities give each site's value in the list")
    f = read_fields(table, _STEP, path, ctx)
    sites = _sites(table["sites"], f"{path}.sites", ctx) if has_s else None
    return Step(f["duration_ms"], f["gap_ms"], f["intensities"], sites, f["intensity"])


def pattern_from_dict(d: Any) -> Pattern:
    """Validate a TOML-shaped mapping; raises :class:`PatternError` naming the field."""
    ctx = Context(PatternError)
    require_table(d, "", ("pattern", "step"), ctx, what="the pattern")
    head = read_table(d.get("pattern", {}), _PATTERN, "pattern", ctx)
    if "step" not in d:
        raise PatternError("step", "step is missing: give at least one [[step]] table")
    steps = read_array(d["step"], "step", ctx, lambda raw, p, i: _step(raw, p, ctx),
                       count=(1, MAX_STEPS), noun="steps")
    return Pattern(head["name"], tuple(steps))


def load_pattern(path: str | Path) -> Pattern:
    """Read and validate a pattern TOML file."""
    return pattern_from_dict(read_toml_file(path, PatternError, "pattern file"))
