"""The design request: the array and its site (as a layout request has them), and the space of
units to search. A TOML file validated by the project's field-spec engine.

    [model], [array], [site], [drive], [criterion], [timing]   # as in a layout request
                                    # (planner.layout); no [[design]] tables: the designer
                                    # finds the design. grid "square" or "hex" only.
    [drive]
    frequencies_hz = [100.0, 120.0, 150.0]   # the drive frequencies tried, or instead:
    # band_step_hz = 10.0           # every step of the model's frequency range the motor
                                    # reaches (unreachable ones are dropped and listed)

    [space]                         # the units searched
    orientations = ["forward", "reverse"]
    attachments = ["glued", "pogo"]
    n_rings = [0, 1, 2, 3]
    materials = "catalogue"         # each ring one silicone of the catalogue, or
                                    # "continuous": Young's modulus per ring, and one density,
                                    # Poisson's ratio and loss factor, within the catalogue's
                                    # range (the model's inputs)
    catalogue = []                  # names of the catalogue to use (default: all of it)
    grid_levels = 5                 # continuous: levels per dimension of the exhaustive grid

    [search]
    optimiser = "de"                # "de" (scipy) | "tpe" (Optuna) | "cmaes" (cma) | "grid"
    budget = 200                    # distinct designs evaluated, at most (grid: all of it)
    batch = 16                      # designs per batched prediction
    seed = 0                        # the optimiser's seed (--seed overrides it)
    perceptible = true              # the unit's own amplitude must be felt (below)

    [verify]
    top = 3                         # designs re-solved with the FE over their drive band

    [reference]
    scenes = ["unit-bare-forward.toml"]   # unit scenes compared with (relative to this file)

*Perceptible*: at the chosen frequency (one the motor reaches) the unit's own centre
amplitude at the model's lower 95 % bound, times ``criterion.drive_level``, reaches the
detection threshold (the criterion's curve, or the default Verrillo 1966 forearm curve)
rescaled to the unit's own contact area (3 dB per doubling, ``planner.threshold``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from fieldspec import Context, Spec, read_table, require_table
from fieldspec.toml import read_toml_file
from planner.design.catalogue import Catalogue, load_catalogue
from planner.design.prototypes import Prototype, read_prototype
from planner.layout import LayoutError, LayoutRequest, layout_from_dict, short_repr

__all__ = ["OPTIMISERS", "DesignRequest", "DesignRequestError", "SearchSpec", "SpaceSpec",
           "design_request_from_dict", "load_design_request"]

OPTIMISERS = ("tpe", "cmaes", "de", "grid")
MATERIALS = ("catalogue", "continuous")
LAYOUT_TABLES = ("model", "array", "site", "drive", "criterion", "timing")
_TABLES = (*LAYOUT_TABLES, "space", "search", "verify", "reference")
MAX_REFERENCES = 8


class DesignRequestError(LayoutError):
    """A bad design request (``.field`` names the offending value)."""


@dataclass(frozen=True)
class SpaceSpec:
    """The units searched: every combination of the discrete choices, ring materials from the
    catalogue or continuous within its range."""

    orientations: tuple[str, ...] = ("forward", "reverse")
    attachments: tuple[str, ...] = ("glued", "pogo")
    n_rings: tuple[int, ...] = (0, 1, 2, 3)
    materials: str = "catalogue"
    catalogue: Catalogue | None = None
    grid_levels: int = 5


@dataclass(frozen=True)
class SearchSpec:
    """How the space is searched (planner.design.search)."""

    optimiser: str = "de"
    budget: int = 200
    batch: int = 16
    seed: int = 0
    perceptible: bool = True


@dataclass(frozen=True)
class DesignRequest:
    """A validated design request; ``layout`` carries the array, site, drive and criterion
    (its designs are set per evaluated batch)."""

    layout: LayoutRequest
    space: SpaceSpec
    search: SearchSpec
    verify_top: int = 3
    band_step_hz: float | None = None
    references: tuple[Prototype, ...] = ()
    raw_layout: dict[str, Any] | None = None  # the layout tables as given (written back)

    def with_seed(self, seed: int | None) -> DesignRequest:
        """The request with the optimiser's seed replaced (None: as it is)."""
        return self if seed is None else replace(self, search=replace(self.search, seed=seed))


def _strings(choices: tuple[str, ...] | None = None
             ) -> Callable[[Any, Spec, str, Context], tuple[str, ...]]:
    """A reader of a non-empty list of distinct texts (each one of ``choices`` if given)."""
    def read(value: Any, spec: Spec, path: str, ctx: Context) -> tuple[str, ...]:
        if not isinstance(value, list | tuple) or not all(isinstance(v, str) for v in value):
            raise ctx.error(path, f"{path} = {short_repr(value)}: expected a list of texts")
        if choices is not None:
            for i, v in enumerate(value):
                if v not in choices:
                    raise ctx.error(f"{path}[{i}]", f"{path}[{i}] = {v!r}: expected one of "
                                    + ", ".join(repr(c) for c in choices))
            if not value:
                raise ctx.error(path, f"{path} is empty: give at least one of "
                                + ", ".join(repr(c) for c in choices))
        if len(set(value)) != len(value):
            raise ctx.error(path, f"{path} = {short_repr(value)}: a value is listed twice")
        return tuple(value)
    return read


def _rings(value: Any, spec: Spec, path: str, ctx: Context) -> tuple[int, ...]:
    if not isinstance(value, list | tuple) or not value:
        raise ctx.error(path, f"{path} = {short_repr(value)}: expected a non-empty list of "
                        "integers in [0, 3]")
    for i, v in enumerate(value):
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= 3:
            raise ctx.error(f"{path}[{i}]", f"{path}[{i}] = {short_repr(v)}: expected an "
                            "integer in [0, 3]")
    if len(set(value)) != len(value):
        raise ctx.error(path, f"{path} = {list(value)}: a value is listed twice")
    return tuple(sorted(value))


_SPACE = {"orientations": Spec(object, ("forward", "reverse"),
                               reader=_strings(("forward", "reverse"))),
          "attachments": Spec(object, ("glued", "pogo"), reader=_strings(("glued", "pogo"))),
          "n_rings": Spec(object, (0, 1, 2, 3), reader=_rings),
          "materials": Spec(str, "catalogue", choices=MATERIALS),
          "catalogue": Spec(object, (), reader=_strings()),
          "grid_levels": Spec(int, 5, "[2, 12]")}
_SEARCH = {"optimiser": Spec(str, "de", choices=OPTIMISERS),
           "budget": Spec(int, 200, "[8, 20000]"),
           "batch": Spec(int, 16, "[1, 1024]"),
           "seed": Spec(int, 0, "[0, 4294967295]"),
           "perceptible": Spec(bool, True)}
_VERIFY = {"top": Spec(int, 3, "[1, 8]")}
_REFERENCE = {"scenes": Spec(object, (), reader=_strings())}
_BAND = {"band_step_hz": Spec(float, None, "[1, 150]")}


def _layout(d: dict[str, Any]) -> tuple[LayoutRequest, float | None, dict[str, Any]]:
    """The layout part (a placeholder design: the designer sets them), the band step."""
    ctx = Context(DesignRequestError)
    raw = {k: dict(d[k]) for k in LAYOUT_TABLES if k in d and isinstance(d[k], dict)}
    drive = raw.get("drive", {})
    band = read_table({k: drive.pop(k) for k in list(drive) if k in _BAND}, _BAND, "drive",
                      ctx)["band_step_hz"]
    if band is not None and "frequencies_hz" in drive:
        raise DesignRequestError("drive.band_step_hz", "drive.band_step_hz: give either "
                                 "frequencies_hz or band_step_hz, not both")
    if band is not None:
        drive["frequencies_hz"] = [120.0]  # replaced by the band once the model is known
    layout = layout_from_dict({**{k: d[k] for k in LAYOUT_TABLES if k in d}, **raw,
                               "design": [{"name": "search"}]})
    if layout.grid == "free" or layout.objective != "min_pitch":
        field = "array.grid" if layout.grid == "free" else "array.objective"
        raise DesignRequestError(field, f"{field}: the designer minimises the pitch of a "
                                 'square or hex grid (grid = "square" or "hex", objective = '
                                 '"min_pitch")')
    return layout, band, raw


def design_request_from_dict(d: Any, base_dir: str | Path = ".") -> DesignRequest:
    """Validate a TOML-shaped mapping (reference scenes relative to ``base_dir``); raises
    :class:`DesignRequestError` (a LayoutError) naming the field."""
    try:
        return _read(d, base_dir)
    except DesignRequestError:
        raise
    except LayoutError as err:  # the layout's tables, the catalogue, a reference scene
        raise DesignRequestError(err.field, str(err)) from None


def _read(d: Any, base_dir: str | Path) -> DesignRequest:
    ctx = Context(DesignRequestError)
    require_table(d, "", _TABLES, ctx, what="the design request")
    layout, band, raw = _layout(d)
    space = read_table(d.get("space", {}), _SPACE, "space", ctx)
    search = read_table(d.get("search", {}), _SEARCH, "search", ctx)
    verify = read_table(d.get("verify", {}), _VERIFY, "verify", ctx)
    ref = read_table(d.get("reference", {}), _REFERENCE, "reference", ctx)
    catalogue = load_catalogue(space.pop("catalogue"), "space.catalogue")
    if len(ref["scenes"]) > MAX_REFERENCES:
        raise DesignRequestError("reference.scenes", f"reference.scenes: {len(ref['scenes'])} "
                                 f"scenes; give at most {MAX_REFERENCES}")
    refs = tuple(read_prototype(Path(base_dir) / p, f"reference.scenes[{i}]", catalogue.all)
                 for i, p in enumerate(ref["scenes"]))
    return DesignRequest(layout, SpaceSpec(**space, catalogue=catalogue), SearchSpec(**search),
                         verify["top"], band, refs, raw)


def load_design_request(path: str | Path) -> DesignRequest:
    """Read and validate a design request TOML file."""
    data = read_toml_file(path, DesignRequestError, "design request")
    return design_request_from_dict(data, Path(path).parent)
