"""The layout request: where the array goes, which unit designs may be used, what counts as
crosstalk. A TOML file validated by the project's field-spec engine, like scenes and spaces.

    [model]
    path = "models/nn-default"      # a registered harmonic surrogate (predictor run time only;
                                    # left out: the default one, surrogate.runtime.defaults)

    [array]
    rows = 4                        # sites per column
    cols = 4                        # sites per row
    grid = "square"                 # "square" | "hex" (rows offset by half a pitch) | "free"
    # positions_mm = [[0, 0], [18, 0], ...]  # grid = "free" only (no rows/cols): 2-256 sites
    # objective = "max_sites"       # instead of rows/cols: the most sites that fit in
    # region_mm = [60, 120]         #   the region [width, height] [mm] (planner.region)
    min_pitch_mm = 5.0              # centre-to-centre pitch searched in [min, max] [mm]
    max_pitch_mm = 60.0

    [site]                          # the skin under the array: model inputs shared by all
    skin_E_kPa = 49.0
    fat_thickness_mm = 14.0
    tissue_loss_factor = 0.3

    [drive]
    frequencies_hz = [120.0]        # drive frequencies tried (the best one is kept per design)

    [criterion]
    kind = "ratio"                  # "ratio" | "perceptual" (leakage below the detection
                                    # threshold at the drive frequency, planner.threshold)
    max_ratio = 0.1                 # ratio: leakage at a site / its own amplitude, at most
    superposition = "incoherent"    # "incoherent" (independent ERMs: powers add) | "worst"
    drive_level = 1.0               # perceptual: running amplitude / the surrogate's (nominal)
    holds_at = "bounds_95"          # rank on the pitch at which the criterion holds with the
                                    # model's 95 % bounds (default) | "nominal": the prediction
    # threshold_hz, threshold_um, threshold_source: perceptual: a threshold table of one's own
    # contactor_area_cm2: perceptual: rescale the curve to this contact area (3 dB / doubling)
    # body_site = "thigh"           # where the array is worn: a warning when the threshold
                                    # curve is for another site (the default: volar forearm)

    [timing]                        # the envelope timing of the chosen unit (planner.timing)
    model = "models/rom-default"    # the transient ROM; enabled = false skips the timing;
                                    # "": the actuator's drive law alone (tissue quasi-static)
    actuator = "unit"               # whose drive law (motorlaw.DRIVES): "unit" (coin ERM), "lra"
    tau_spinup_ms = 20.0            # motor time constants (fem.motor estimates)
    tau_spindown_ms = 35.0
    isi_fraction = 0.1              # ratio criterion: residual below this of steady for the ISI

    [[design]]                      # candidate unit designs: model inputs by name
    name = "optimised"
    orientation = "reverse"
    ...

    [[design]]                      # or: designs drawn from the model's trained range
    name = "any"
    any = true                      # inputs given here stay fixed, the others are drawn
    n_candidates = 64               # [8, 1024] (planner.candidates)
    seed = 0

Every value is checked here for its type and range; the design inputs are checked against
the model's own inputs (names, units, trained ranges) when the plan is made.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fieldspec import (
    Context,
    FieldError,
    Spec,
    read_array,
    read_fields,
    read_table,
    read_value,
    require_table,
)
from fieldspec.toml import read_toml_file
from motorlaw import DEFAULTS as MOTOR_LAW
from motorlaw import DRIVES, SpeedLaw
from planner.threshold import VERRILLO_1966_FOREARM, ThresholdCurve
from surrogate.runtime.card import ModelFileError
from surrogate.runtime.defaults import default_model

__all__ = ["CriterionSpec", "LayoutError", "LayoutRequest", "TimingSpec", "layout_from_dict",
           "load_layout", "short_repr"]

GRIDS = ("square", "hex", "free")
SUPERPOSITIONS = ("incoherent", "worst")
OBJECTIVES = ("min_pitch", "max_sites")
KINDS = ("ratio", "perceptual")
HOLDS_AT = ("bounds_95", "nominal")
MAX_SITES_PER_SIDE = 32
MAX_FREQUENCIES = 64  # drive.frequencies_hz: values at most
MAX_NAME = 64  # design.name: characters at most
FREE_SITES = (2, 256)  # grid = "free": number of given positions
POSITION_LIMIT_MM = 1000.0  # |x|, |y| of a free position: the pitch bound's 1 m


class LayoutError(FieldError):
    """A bad layout request (``.field`` names the offending value)."""


@dataclass(frozen=True)
class CriterionSpec:
    """Crosstalk criterion. ``ratio``: leakage at a site at most ``max_ratio`` of its own
    amplitude. ``perceptual``: leakage (at ``drive_level`` times the surrogate's amplitude)
    below the detection threshold at the drive frequency, and the site's own amplitude above
    it."""

    max_ratio: float
    superposition: str
    kind: str = "ratio"
    drive_level: float = 1.0
    threshold: ThresholdCurve | None = None  # perceptual only
    holds_at: str = "bounds_95"  # the pitch ranked and laid out: at the 95 % bounds | nominal
    body_site: str | None = None  # where the array is worn (checked against the curve's site)

    def warnings(self) -> list[str]:
        """Perceptual criterion: a warning when the threshold curve is not for the body site
        of the array (or no site is named), naming the curve used."""
        t = self.threshold
        if self.kind != "perceptual" or t is None or not t.site:
            return []
        if self.body_site is None:
            return [f"no criterion.body_site given: the detection threshold is the {t.site} "
                    f"curve ({t.source}); name the site, or give a threshold table for it"]
        if self.body_site.strip().lower() in t.site.lower():
            return []
        return [f"criterion.body_site = {self.body_site!r} has no threshold data of its own: "
                f"the {t.site} curve is used ({t.source}); give threshold_hz, threshold_um "
                "and threshold_source measured at that site"]


@dataclass(frozen=True)
class TimingSpec:
    """Envelope timing request (see :mod:`planner.timing`); times in ms as in the file."""

    enabled: bool = True
    model: str = "models/rom-default"  # "": no envelope model, the drive law's own envelope
    actuator: str = SpeedLaw.kind  # the actuator's drive law (motorlaw.DRIVES): the coin ERM
    tau_spinup_ms: float = 1e3 * MOTOR_LAW["tau_spinup_s"]
    tau_spindown_ms: float = 1e3 * MOTOR_LAW["tau_spindown_s"]
    isi_fraction: float = 0.1


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
    timing: TimingSpec = TimingSpec()
    positions_mm: tuple[tuple[float, float], ...] | None = None  # grid = "free" only
    objective: str = "min_pitch"  # "max_sites": rows x cols chosen to fill region_mm
    region_mm: tuple[float, float] | None = None  # (width, height) [mm], max_sites only


# path: None -> the default harmonic model (surrogate.runtime.defaults, resolved when read)
_MODEL = {"path": Spec(str, None),
          "allow_extrapolation": Spec(bool, False)}


def short_repr(value: Any, limit: int = 80) -> str:
    """``repr(value)`` cut to ``limit`` characters (long inputs are summarised, not echoed)."""
    text = repr(value)
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def _read_positions(value: Any, spec: Spec, path: str, ctx: Context) -> tuple:
    """``[[x, y], ...]`` [mm]: FREE_SITES sites, each two finite numbers within the limit."""
    lo, hi = FREE_SITES
    if not isinstance(value, list | tuple) or not lo <= len(value) <= hi:
        got = (f"a list of {len(value)} positions" if isinstance(value, list | tuple) else
               short_repr(value))
        raise ctx.error(path, f"{path}: expected a list of {lo} to {hi} [x, y] positions [mm], "
                        f"got {got}")
    xy = Spec(tuple, None, f"[-{POSITION_LIMIT_MM:g}, {POSITION_LIMIT_MM:g}]")
    out = []
    for i, item in enumerate(value):
        where = f"{path}[{i}]"
        pair = read_value(item, xy, "positions_mm", where, ctx)
        if len(pair) != 2:
            raise ctx.error(where, f"{where} = {short_repr(item)}: expected two numbers [x, y] "
                            "[mm]")
        out.append((pair[0], pair[1]))
    return tuple(out)


_ARRAY = {"grid": Spec(str, "square", choices=GRIDS),
          "rows": Spec(int, None, f"[1, {MAX_SITES_PER_SIDE}]"),
          "cols": Spec(int, None, f"[1, {MAX_SITES_PER_SIDE}]"),
          "positions_mm": Spec(object, None, reader=_read_positions),
          "objective": Spec(str, "min_pitch", choices=OBJECTIVES),
          "region_mm": Spec(tuple, None, f"(0, {POSITION_LIMIT_MM:g}]"),
          "min_pitch_mm": Spec(float, 2.0, "(0, 500]"),
          "max_pitch_mm": Spec(float, 100.0, "[array.min_pitch_mm, 1000]")}
_DRIVE = {"frequencies_hz": Spec(tuple, (120.0,), "(0, 1e4]")}
_CRITERION = {"kind": Spec(str, "ratio", choices=KINDS),
              "max_ratio": Spec(float, 0.1, "(0, 1]"),
              "superposition": Spec(str, "incoherent", choices=SUPERPOSITIONS),
              "drive_level": Spec(float, 1.0, "(0, 10]"),
              "holds_at": Spec(str, "bounds_95", choices=HOLDS_AT),
              "body_site": Spec(str, None),
              "threshold_hz": Spec(tuple, None, "(0, 1e4]"),
              "threshold_um": Spec(tuple, None, "(0, 1e4]"),
              "threshold_source": Spec(str, None),
              "contactor_area_cm2": Spec(float, None, "(0, 100]")}
# motor time constants: the motorlaw estimates (coin ERMs lag 10-20 ms, stop in 50-150 ms);
# isi_fraction 0.1: the 10 % level that also ends the 90-10 % decay time
_TIMING = {"enabled": Spec(bool, True),
           "model": Spec(str, "models/rom-default"),
           "actuator": Spec(str, TimingSpec.actuator, choices=tuple(DRIVES)),
           "tau_spinup_ms": Spec(float, TimingSpec.tau_spinup_ms, "(0, 1000]"),
           "tau_spindown_ms": Spec(float, TimingSpec.tau_spindown_ms, "(0, 1000]"),
           "isi_fraction": Spec(float, 0.1, "(0, 1)")}
_TABLES = ("model", "array", "site", "drive", "criterion", "timing", "design")


def _inputs(raw: Any, path: str, ctx: Context) -> dict[str, Any]:
    """A table of model inputs: numbers or text only (the model checks names and ranges)."""
    table = require_table(raw, path, list(raw) if isinstance(raw, dict) else [], ctx)
    for key, value in table.items():
        if isinstance(value, bool) or not isinstance(value, int | float | str):
            raise LayoutError(f"{path}.{key}", f"{path}.{key} = {short_repr(value)}: expected a "
                              "number or a choice (text)")
    return dict(table)


# any = true: candidates drawn from the model's trained range (planner.candidates)
_ANY = {"any": Spec(bool, False),
        "n_candidates": Spec(int, 64, "[8, 1024]"),
        "seed": Spec(int, 0, "[0, 4294967295]")}


def _design(raw: Any, path: str, i: int, ctx: Context) -> dict[str, Any]:
    table = dict(raw) if isinstance(raw, dict) else raw
    sampling = {k: table.pop(k) for k in _ANY if isinstance(table, dict) and k in table}
    opts = read_fields(sampling, _ANY, path, ctx)
    if not opts["any"]:
        extra = [k for k in ("n_candidates", "seed") if k in sampling]
        if extra:
            raise LayoutError(f"{path}.{extra[0]}", f"{path}.{extra[0]}: only with "
                              f"{path}.any = true")
    d = _inputs(table, path, ctx)
    name = d.pop("name", f"design{i}")
    if not isinstance(name, str) or not 0 < len(name) <= MAX_NAME:
        raise LayoutError(f"{path}.name", f"{path}.name = {short_repr(name)}: expected a "
                          f"non-empty text of at most {MAX_NAME} characters")
    return {"name": name, "inputs": d, **opts}


def _criterion(c: dict[str, Any], freqs: tuple[float, ...]) -> CriterionSpec:
    """The criterion table's values as a :class:`CriterionSpec` (the threshold curve checked
    against the drive frequencies)."""
    table = [c["threshold_hz"], c["threshold_um"], c["threshold_source"]]
    given = [x is not None for x in table]
    names = ("threshold_hz", "threshold_um", "threshold_source")
    if any(given) and not all(given):
        missing = names[given.index(False)]
        raise LayoutError(f"criterion.{missing}", f"criterion.{missing} is missing: a threshold "
                          "table needs threshold_hz, threshold_um and threshold_source")
    if c["kind"] == "ratio":
        extra = [k for k in (*names, "contactor_area_cm2") if c[k] is not None]
        if extra:
            raise LayoutError(f"criterion.{extra[0]}", f"criterion.{extra[0]}: only for "
                              'criterion.kind = "perceptual"')
        return CriterionSpec(c["max_ratio"], c["superposition"], "ratio", c["drive_level"],
                             holds_at=c["holds_at"], body_site=c["body_site"])
    curve = VERRILLO_1966_FOREARM
    if all(given):
        try:
            curve = ThresholdCurve(table[0], table[1], table[2], contactor_area_cm2=None)
        except ValueError as err:
            raise LayoutError("criterion.threshold_hz", f"criterion: {err}") from None
    if c["contactor_area_cm2"] is not None:
        if curve.contactor_area_cm2 is None:
            raise LayoutError("criterion.contactor_area_cm2", "criterion.contactor_area_cm2: "
                              "a threshold table of one's own has no reference area to rescale")
        curve = curve.at_area(c["contactor_area_cm2"])
    lo, hi = curve.range_hz
    bad = [f for f in freqs if not lo <= f <= hi]
    if bad:
        raise LayoutError("drive.frequencies_hz", f"drive.frequencies_hz: {bad[0]:g} Hz is "
                          f"outside the threshold curve's range [{lo:g}, {hi:g}] Hz")
    return CriterionSpec(c["max_ratio"], c["superposition"], "perceptual", c["drive_level"],
                         curve, c["holds_at"], c["body_site"])


def _sites(array: dict[str, Any]) -> tuple[int, int, tuple | None]:
    """(rows, cols, positions): a grid needs rows and cols, free positions exclude them (a
    free layout is one row of its sites)."""
    given = [k for k in ("rows", "cols") if array[k] is not None]
    region = array["region_mm"]
    if region is not None and len(region) != 2:
        raise LayoutError("array.region_mm", f"array.region_mm = {list(region)}: expected "
                          "[width, height] [mm]")
    if array["objective"] == "max_sites":
        if region is None:
            raise LayoutError("array.region_mm", 'array.region_mm is missing: objective = '
                              '"max_sites" needs the region [width, height] [mm]')
        if array["grid"] == "free":
            raise LayoutError("array.objective", 'array.objective = "max_sites" needs grid = '
                              '"square" or "hex"')
        if given:
            raise LayoutError(f"array.{given[0]}", f"array.{given[0]}: not with objective = "
                              '"max_sites" (the plan chooses rows and cols)')
        return 1, 1, None
    if region is not None:
        raise LayoutError("array.region_mm", 'array.region_mm: only with objective = '
                          '"max_sites"')
    if array["grid"] == "free":
        if array["positions_mm"] is None:
            raise LayoutError("array.positions_mm", 'array.positions_mm is missing: grid = '
                              '"free" needs the site centres [[x, y], ...] [mm]')
        if given:
            raise LayoutError(f"array.{given[0]}", f"array.{given[0]}: not with grid = "
                              '"free" (the sites are array.positions_mm)')
        return 1, len(array["positions_mm"]), array["positions_mm"]
    if array["positions_mm"] is not None:
        raise LayoutError("array.positions_mm", 'array.positions_mm: only for grid = "free"')
    for k in ("rows", "cols"):
        if array[k] is None:
            raise LayoutError(f"array.{k}", f"array.{k} is missing: give {k} "
                              f"([1, {MAX_SITES_PER_SIDE}]) or grid = \"free\" with positions_mm")
    return array["rows"], array["cols"], None


def _default_model() -> str:
    """The default harmonic model's directory (``[model] path`` not given)."""
    try:
        return default_model("harmonic")
    except ModelFileError as err:
        raise LayoutError("model.path", f"model.path is not given and {err}") from None


def layout_from_dict(d: Any) -> LayoutRequest:
    """Validate a TOML-shaped mapping; raises :class:`LayoutError` naming the field."""
    ctx = Context(LayoutError)
    require_table(d, "", _TABLES, ctx, what="the layout")
    model = read_table(d.get("model", {}), _MODEL, "model", ctx)
    array = read_table(d.get("array", {}), _ARRAY, "array", ctx)
    drive = read_table(d.get("drive", {}), _DRIVE, "drive", ctx)
    criterion = read_table(d.get("criterion", {}), _CRITERION, "criterion", ctx)
    timing = read_table(d.get("timing", {}), _TIMING, "timing", ctx)
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
    if len(drive["frequencies_hz"]) > MAX_FREQUENCIES:
        n = len(drive["frequencies_hz"])
        raise LayoutError("drive.frequencies_hz", f"drive.frequencies_hz: {n} values; give at "
                          f"most {MAX_FREQUENCIES}")
    rows, cols, positions = _sites(array)
    return LayoutRequest(model["path"] or _default_model(), rows, cols, array["grid"],
                         array["min_pitch_mm"], array["max_pitch_mm"], site,
                         tuple(drive["frequencies_hz"]),
                         _criterion(criterion, tuple(drive["frequencies_hz"])),
                         tuple(designs), model["allow_extrapolation"], TimingSpec(**timing),
                         positions, array["objective"],
                         None if array["region_mm"] is None else tuple(array["region_mm"]))


def load_layout(path: str | Path) -> LayoutRequest:
    """Read and validate a layout TOML file."""
    return layout_from_dict(read_toml_file(path, LayoutError, "layout file"))
