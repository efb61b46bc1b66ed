"""The layout request: where the array goes, which unit designs may be used, what counts as
crosstalk. A TOML file validated by the project's field-spec engine, like scenes and spaces.

    [model]
    path = "models/nn-default"      # a registered harmonic surrogate (predictor run time only)

    [array]
    rows = 4                        # sites per column
    cols = 4                        # sites per row
    grid = "square"                 # "square" | "hex" (rows offset by half a pitch)
    min_pitch_mm = 5.0              # centre-to-centre pitch searched in [min, max] [mm]
    max_pitch_mm = 60.0

    [site]                          # the skin under the array: model inputs shared by all
    skin_E_kPa = 49.0
    fat_thickness_mm = 14.0
    tissue_loss_factor = 0.3

    [drive]
    frequencies_hz = [120.0]        # drive frequencies tried (the best one is kept per design)

    [criterion]
    max_ratio = 0.1                 # leakage at a site / the site's own amplitude, at most
    superposition = "incoherent"    # "incoherent" (independent ERMs: powers add) | "worst"

    [[design]]                      # candidate unit designs: model inputs by name
    name = "optimised"
    orientation = "reverse"
    ...

Every value is checked here for its type and range; the design inputs are checked against
the model's own inputs (names, units, trained ranges) when the plan is made.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fieldspec import REQUIRED, Context, FieldError, Spec, read_array, read_table, require_table

__all__ = ["CriterionSpec", "LayoutError", "LayoutRequest", "layout_from_dict", "load_layout"]

GRIDS = ("square", "hex")
SUPERPOSITIONS = ("incoherent", "worst")
MAX_SITES_PER_SIDE = 32


class LayoutError(FieldError):
    """A bad layout request (``.field`` names the offending value)."""


@dataclass(frozen=True)
class CriterionSpec:
    """Crosstalk criterion: leakage at a site at most ``max_ratio`` of its own amplitude."""

    max_ratio: float
    superposition: str


@dataclass(frozen=True)
class LayoutRequest:
    """A validated layout request (lengths in mm, as in the file)."""

    model: str
    rows: int
    cols: int
    grid: str
    min_pitch_mm: float
    max_pitch_mm: float
    site: dict[str, Any]
    frequencies_hz: tuple[float, ...]
    criterion: CriterionSpec
    designs: tuple[dict[str, Any], ...]
    allow_extrapolation: bool = False


_MODEL = {"path": Spec(str, "models/nn-default"),
          "allow_extrapolation": Spec(bool, False)}
_ARRAY = {"rows": Spec(int, REQUIRED, f"[1, {MAX_SITES_PER_SIDE}]"),
          "cols": Spec(int, REQUIRED, f"[1, {MAX_SITES_PER_SIDE}]"),
          "grid": Spec(str, "square", choices=GRIDS),
          "min_pitch_mm": Spec(float, 2.0, "(0, 500]"),
          "max_pitch_mm": Spec(float, 100.0, "[array.min_pitch_mm, 1000]")}
_DRIVE = {"frequencies_hz": Spec(tuple, (120.0,), "(0, 1e4]")}
_CRITERION = {"max_ratio": Spec(float, 0.1, "(0, 1]"),
              "superposition": Spec(str, "incoherent", choices=SUPERPOSITIONS)}
_TABLES = ("model", "array", "site", "drive", "criterion", "design")


def _inputs(raw: Any, path: str, ctx: Context) -> dict[str, Any]:
    """A table of model inputs: numbers or text only (the model checks names and ranges)."""
    table = require_table(raw, path, list(raw) if isinstance(raw, dict) else [], ctx)
    for key, value in table.items():
        if isinstance(value, bool) or not isinstance(value, int | float | str):
            raise LayoutError(f"{path}.{key}", f"{path}.{key} = {value!r}: expected a number "
                              "or a choice (text)")
    return dict(table)


def _design(raw: Any, path: str, i: int, ctx: Context) -> dict[str, Any]:
    d = _inputs(raw, path, ctx)
    name = d.pop("name", f"design{i}")
    if not isinstance(name, str) or not name:
        raise LayoutError(f"{path}.name", f"{path}.name = {name!r}: expected a non-empty text")
    return {"name": name, "inputs": d}


def layout_from_dict(d: Any) -> LayoutRequest:
    """Validate a TOML-shaped mapping; raises :class:`LayoutError` naming the field."""
    ctx = Context(LayoutError)
    require_table(d, "", _TABLES, ctx, what="the layout")
    model = read_table(d.get("model", {}), _MODEL, "model", ctx)
    array = read_table(d.get("array", {}), _ARRAY, "array", ctx)
    drive = read_table(d.get("drive", {}), _DRIVE, "drive", ctx)
    criterion = read_table(d.get("criterion", {}), _CRITERION, "criterion", ctx)
    site = _inputs(d.get("site", {}), "site", ctx)
    if "design" not in d:
        raise LayoutError("design", "design is missing: give at least one [[design]] table "
                          "of model inputs (orientation, attachment, n_rings, ...)")
    designs = read_array(d["design"], "design", ctx, lambda raw, p, i: _design(raw, p, i, ctx),
                         count=(1, 64), noun="designs")
    names = [x["name"] for x in designs]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise LayoutError("design.name", f"design.name {dup!r} is used twice: names must be "
                          "unique")
    for i, x in enumerate(designs):
        clash = sorted(set(x["inputs"]) & set(site))
        if clash:
            raise LayoutError(f"design[{i}].{clash[0]}", f"design[{i}].{clash[0]} is also "
                              "given in [site]: give each input once")
        if "frequency_hz" in x["inputs"]:
            raise LayoutError(f"design[{i}].frequency_hz", f"design[{i}].frequency_hz: the "
                              "drive frequency goes in [drive] frequencies_hz")
    return LayoutRequest(model["path"], array["rows"], array["cols"], array["grid"],
                         array["min_pitch_mm"], array["max_pitch_mm"], site,
                         tuple(drive["frequencies_hz"]),
                         CriterionSpec(criterion["max_ratio"], criterion["superposition"]),
                         tuple(designs), model["allow_extrapolation"])


def load_layout(path: str | Path) -> LayoutRequest:
    """Read and validate a layout TOML file."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except OSError as err:
        raise LayoutError("<file>", f"cannot read layout file {str(path)!r}: {err}") from None
    except tomllib.TOMLDecodeError as err:
        raise LayoutError("<file>", f"{path}: invalid TOML: {err}") from None
    return layout_from_dict(data)
