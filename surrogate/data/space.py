"""Parameter spaces: a TOML file that says which scene fields vary, over which range, and how.

Layout (``datasets/spaces/default.toml`` is a commented example)::

    [space]
    name = "default"                 # required
    description = "..."
    sampler = "sobol"                # sobol | halton | lhs | random   (surrogate.sampling)
    seed = 2025                      # integer >= 0
    lhs_batch = 256                  # batch size of the extendable LHS / random designs
    significant_digits = 12          # continuous values rounded to this many digits (0: not)
    mesh_topology = "per_sample"     # per_sample | per_design  (surrogate.data.mesh_plan)
    base_scene = "scene.toml"        # optional scene file, relative to this file

    [base]                           # scene overrides (TOML-shaped, fem.scene schema),
    analysis.kind = "harmonic"       # merged over base_scene

    [[parameter]]
    name = "skin_E_kPa"              # column name in the dataset
    type = "continuous"              # continuous | integer | categorical | fixed
    path = "tissue.layer[0].E_kPa"   # dotted scene path with [i] list indices (or a list)
    low = 20.0                       # continuous / integer: low <= value <= high
    high = 120.0
    scale = "log"                    # continuous only: linear | log
    # categorical: choices = ["forward", "reverse"]; fixed: value = 1.0
    # map = "list_length"            # integer: truncate the list at `path` to `value` entries

    [[constraint]]
    name = "thin_layers"
    expr = "skin_thickness_mm + fat_thickness_mm <= 15"   # rejected points are skipped

    [band]                           # optional: every row is a sweep over the band
    start = 100.0                    # Hz (surrogate.data.band)
    stop = 250.0
    step = 2.0

Paths: a parameter writes its value at every path in ``path``. Tables or lists missing on the
way are first taken from the base scene's fully resolved defaults (so ``tissue.layer[1]...``
edits the default fat layer), otherwise created; lists grow as needed. Filled-in default
layers carry explicit E_kPa/density/nu, which override a layer's ``material``: to vary a
tissue layer's material, list the layers in ``[base]`` with ``material`` only.
``map = "list_length"`` mappings apply after all value mappings: ``n_rings`` with path
``unit.encapsulation`` keeps the first ``n_rings`` entries written by ``ring_1 .. ring_3``.

Constraints are expressions over parameter names with numbers, strings, ``+ - * / ** %``,
comparisons, ``and or not`` and the functions ``abs min max log log10 exp sqrt``. They are
parsed into a small interpreter (never ``eval``).

Checks at load time (:class:`SpaceError`, naming the field and the allowed range): the TOML
layout, every range and choice, unique names, the constraints' names, and the scene schema -
the space's center point and a set of probe points are resolved into scenes with
``fem.scene.scene_from_dict``, a path unknown to the schema is reported with the parameter
that uses it, and a parameter that never changes the scene (its path is ignored or
overridden) is an error.
"""

from __future__ import annotations

import copy
import functools
import hashlib
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fem.scene import SceneError, effective_scene_dict, scene_from_dict, scene_to_dict
from fieldspec import REQUIRED, Context, Spec, read_array, read_table, require_table
from fieldspec.documents import read_toml_file
from surrogate.data.band import Band, check_band_parameters, read_band
from surrogate.data.constraints import Constraint, read_constraint
from surrogate.data.errors import SpaceError
from surrogate.data.mesh_plan import MESH_TOPOLOGIES, MeshPlan
from surrogate.data.parameters import Parameter, read_parameter
from surrogate.data.sampling import LHS_BATCH_DEFAULT, SAMPLERS, unit_points
from surrogate.data.scene_paths import deep_merge, format_path, parse_path, set_path, truncate_path

__all__ = ["Space", "SpaceError", "check_space", "load_space", "space_from_dict"]

_PROBE_POINTS = 32  # points used to check that every parameter reaches the scene
#: Continuous sampled values are stored and hashed rounded to this many significant digits:
#: far below any physical tolerance, far above the last-bit differences between machines.
SIGNIFICANT_DIGITS = 12

@dataclass(frozen=True)
class Space:
    """A validated parameter space. Build with :func:`load_space` or :func:`space_from_dict`.

    ``base`` is the scene override dict the parameters are written onto; ``defaults`` is its
    fully resolved scene (used to fill tables a path needs)."""

    name: str
    parameters: tuple[Parameter, ...]
    base: dict[str, Any]
    sampler: str = "sobol"
    seed: int = 0
    lhs_batch: int = LHS_BATCH_DEFAULT
    description: str = ""
    constraints: tuple[Constraint, ...] = ()
    significant_digits: int = SIGNIFICANT_DIGITS
    mesh_topology: str = "per_sample"
    band: Band | None = None

    @functools.cached_property
    def mesh_plan(self) -> MeshPlan:
        """The cells per segment of every discrete design, with ``mesh_topology =
        "per_design"``."""
        return MeshPlan(self)

    @functools.cached_property
    def defaults(self) -> dict[str, Any]:
        """The base scene with every default filled in (``fem.scene``), or the default scene
        when the base alone is incomplete (parameters may supply what it lacks)."""
        return _resolved_defaults(self.base)

    @property
    def free(self) -> tuple[Parameter, ...]:
        """The sampled parameters, in declaration order (one hypercube dimension each)."""
        return tuple(p for p in self.parameters if p.free)

    @property
    def dim(self) -> int:
        """Number of sampled dimensions."""
        return len(self.free)

    @property
    def names(self) -> tuple[str, ...]:
        """All parameter names (dataset columns), in declaration order."""
        return tuple(p.name for p in self.parameters)

    def parameter(self, name: str) -> Parameter:
        """The parameter called ``name`` (KeyError naming the known ones otherwise)."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(f"unknown parameter {name!r}; known: {', '.join(self.names)}")

    # ---- sampling

    def values_from_unit(self, u: np.ndarray) -> dict[str, np.ndarray]:
        """Columns of parameter values for unit-hypercube rows ``u`` of shape (n, dim)."""
        u = np.atleast_2d(np.asarray(u, dtype=float))
        cols: dict[str, np.ndarray] = {}
        free = iter(range(u.shape[1]))
        for p in self.parameters:
            cols[p.name] = p.from_unit(u[:, next(free)] if p.free else np.zeros(len(u)),
                                       self.significant_digits)
        return cols

    def points(self, start: int, n: int) -> dict[str, np.ndarray]:
        """Parameter values of design points ``start .. start + n - 1`` (before constraints)."""
        u = unit_points(self.sampler, self.dim, self.seed, start, n, self.lhs_batch)
        return self.values_from_unit(u)

    def feasible(self, values: Mapping[str, np.ndarray]) -> np.ndarray:
        """Mask of rows that satisfy every constraint."""
        n = len(next(iter(values.values())))
        mask = np.ones(n, dtype=bool)
        for c in self.constraints:
            mask &= c.evaluate(values)
        return mask

    # ---- scenes

    def resolve(self, row: Mapping[str, Any]) -> dict[str, Any]:
        """Scene dict for one point (parameter name -> value); not yet validated.

        Raises :class:`SpaceError` naming the parameter whose path cannot be written."""
        scene = copy.deepcopy(self.base)
        ordered = sorted(self.parameters, key=lambda p: p.mapping == "list_length")
        for p in ordered:
            value = _plain(row[p.name])
            for path in p.paths:
                tokens = parse_path(path)
                try:
                    if p.mapping == "list_length":
                        truncate_path(scene, self.defaults, tokens, int(value))
                    else:
                        set_path(scene, self.defaults, tokens, value)
                except (TypeError, IndexError) as err:
                    raise SpaceError(f"parameter {p.name}.path",
                                     f"parameter {p.name!r} (path {path!r}): {err}") from None
        _check_no_holes(scene, self)
        if self.band is not None:
            self.band.apply(scene)
        return scene

    def resolve_at(self, row: Mapping[str, Any], frequency_hz: float) -> dict[str, Any]:
        """Scene dict of one design at one frequency [Hz], what a model trained on this space
        predicts for ``row`` at ``frequency_hz``: a space with a ``frequency_hz`` parameter
        takes it as that value; a sweep space's band becomes one harmonic solve at it (its
        sweep tolerance left out: a direct solve has none)."""
        scene = self.resolve({**row, "frequency_hz": float(frequency_hz)})
        if self.band is not None:
            analysis = scene["analysis"]
            analysis.pop("tolerance", None)
            analysis.update(kind="harmonic", frequency_hz=float(frequency_hz))
        return scene

    def scene(self, row: Mapping[str, Any]) -> Any:
        """Validated ``fem.scene.Scene`` for one point. A scene schema error is re-raised as
        :class:`SpaceError` naming the parameter whose path it concerns."""
        resolved = self.resolve(row)
        if self.mesh_topology == "per_design":
            cells_r, cells_z = self.mesh_plan.cells(row)
            resolved.setdefault("mesh", {}).update(cells_r=list(cells_r), cells_z=list(cells_z))
        try:
            return scene_from_dict(resolved)
        except SceneError as err:
            raise self._scene_error(err, row) from None

    def _scene_error(self, err: Any, row: Mapping[str, Any]) -> SpaceError:
        fld = getattr(err, "field", "") or ""
        for p in self.parameters:
            for path in p.paths:
                if fld == path or fld.startswith(path + ".") or fld.startswith(path + "[") \
                        or path.startswith(fld + ".") or path.startswith(fld + "["):
                    value = _plain(row[p.name])
                    return SpaceError(f"parameter {p.name}.path",
                                      f"parameter {p.name!r} = {value!r} (path {path!r}) "
                                      f"is not valid for the scene schema: {err}")
        return SpaceError("base", f"space {self.name!r}: the resolved scene is invalid at "
                          f"{fld or '?'}: {err}")

    def center(self) -> dict[str, Any]:
        """The center point of the space (u = 0.5 in every dimension), as a row."""
        cols = self.values_from_unit(np.full((1, self.dim), 0.5))
        return {k: _plain(v[0]) for k, v in cols.items()}

    # ---- serialisation

    def to_dict(self) -> dict[str, Any]:
        """Self-contained TOML-shaped dict (``base_scene`` already merged into ``base``)."""
        head: dict[str, Any] = {"name": self.name, "sampler": self.sampler, "seed": self.seed,
                                "lhs_batch": self.lhs_batch}
        if self.significant_digits:  # 0 (no rounding) is how spaces were before the key existed
            head["significant_digits"] = self.significant_digits
        if self.mesh_topology != "per_sample":  # written only when set: older hashes hold
            head["mesh_topology"] = self.mesh_topology
        if self.description:
            head["description"] = self.description
        d: dict[str, Any] = {"space": head, "base": copy.deepcopy(self.base),
                             "parameter": [p.to_dict() for p in self.parameters]}
        if self.constraints:
            d["constraint"] = [{"name": c.name, "expr": c.expr} for c in self.constraints]
        if self.band is not None:  # written only when set: older hashes hold
            d["band"] = self.band.to_dict()
        return d

    def space_hash(self) -> str:
        """sha256 of the canonical JSON of :meth:`to_dict`: equal spaces hash equally."""
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


def _plain(value: Any) -> Any:
    return value.item() if isinstance(value, np.generic) else value


def _check_no_holes(tree: Any, space: Space, where: str = "") -> None:
    """A list entry a parameter skipped (e.g. encapsulation[2] without [1]) is an error."""
    if isinstance(tree, dict):
        for k, v in tree.items():
            _check_no_holes(v, space, f"{where}.{k}" if where else k)
    elif isinstance(tree, list):
        for i, v in enumerate(tree):
            if v is None:
                raise SpaceError("parameter", f"space {space.name!r}: {where}[{i}] is never "
                                 "set: parameters must fill list entries from index 0 up")
            _check_no_holes(v, space, f"{where}[{i}]")


_SPACE_HEAD = {
    "name": Spec(str, REQUIRED, missing_hint=" (a name for the space)"),
    "description": Spec(str, ""),
    "sampler": Spec(str, "sobol", choices=SAMPLERS),
    "seed": Spec(int, 0, "[0, 9.2e18]"),
    "lhs_batch": Spec(int, LHS_BATCH_DEFAULT, "[1, 1048576]"),
    "significant_digits": Spec(int, SIGNIFICANT_DIGITS, "[0, 17]"),
    "mesh_topology": Spec(str, "per_sample", choices=MESH_TOPOLOGIES),
    "base_scene": Spec(str, None),
}
_FILE_KEYS = ("space", "base", "parameter", "constraint", "band")


def space_from_dict(d: Mapping[str, Any], base_dir: str | Path | None = None,
                    check_scenes: bool = True) -> Space:
    """Validate a TOML-shaped space dict and build a :class:`Space`.

    ``base_dir`` resolves a relative ``space.base_scene``. With ``check_scenes`` (default) the
    center and probe points are resolved through ``fem.scene`` (see module docstring)."""
    ctx = Context(SpaceError)
    d = require_table(d, "", _FILE_KEYS, ctx, what="<space file>")
    head = read_table(d.get("space", {}), _SPACE_HEAD, "space", ctx)
    base = _read_base(d, head, base_dir)
    if not d.get("parameter"):
        raise SpaceError("parameter", "the space has no [[parameter]] entries: give at least one")
    params = tuple(read_array(d["parameter"], "parameter", ctx, lambda raw, _, i:
                              read_parameter(raw, i), noun="parameters"))
    _check_unique(params)
    band = read_band(d["band"]) if "band" in d else None
    if band is not None:
        check_band_parameters(params)
    if not any(p.free for p in params):
        raise SpaceError("parameter", "every parameter is fixed: give at least one continuous, "
                         "integer or categorical parameter")
    names = [p.name for p in params]
    constraints = tuple(read_array(d.get("constraint", []), "constraint", ctx, lambda raw, _, i:
                                   read_constraint(raw, i, names), noun="constraints"))
    space = Space(name=head["name"], parameters=params, base=base, sampler=head["sampler"],
                  seed=head["seed"], lhs_batch=head["lhs_batch"],
                  description=head["description"], constraints=constraints,
                  significant_digits=head["significant_digits"],
                  mesh_topology=head["mesh_topology"], band=band)
    if check_scenes:
        check_space(space)
    return space


def _read_base(d: Mapping[str, Any], head: Mapping[str, Any],
               base_dir: str | Path | None) -> dict[str, Any]:
    base = d.get("base", {})
    if not isinstance(base, Mapping):
        raise SpaceError("base", f"base must be a table of scene overrides, got "
                         f"{type(base).__name__}")
    if head["base_scene"] is None:
        return copy.deepcopy(dict(base))
    path = Path(head["base_scene"])
    if not path.is_absolute():
        path = Path(base_dir or ".") / path

    try:
        scene = read_toml_file(path, SpaceError, "base scene")
    except SpaceError as err:
        raise SpaceError("space.base_scene", f"space.base_scene = {str(path)!r}: cannot read "
                         f"it: {err}") from None
    return deep_merge(scene, base)


def _check_unique(params: Sequence[Parameter]) -> None:
    seen: dict[str, int] = {}
    written: dict[str, str] = {}
    for i, p in enumerate(params):
        if p.name in seen:
            raise SpaceError(f"parameter[{i}].name", f"parameter[{i}].name = {p.name!r} is "
                             f"already used by parameter[{seen[p.name]}]")
        seen[p.name] = i
        for path in p.paths:
            key = f"{p.mapping}:{format_path(parse_path(path))}"
            if key in written:
                raise SpaceError(f"parameter[{i}].path", f"parameter {p.name!r}: path {path!r} "
                                 f"is also written by parameter {written[key]!r}")
            written[key] = p.name


def _resolved_defaults(base: Mapping[str, Any]) -> dict[str, Any]:
    # The base alone may be incomplete (a parameter supplies the rest): then fill missing
    # tables from the schema's own defaults.
    for scene in (base, {}):
        try:
            return scene_to_dict(scene_from_dict(scene))
        except SceneError:
            continue
    return {}


def check_space(space: Space) -> None:
    """Resolve the center and probe points into scenes (raising :class:`SpaceError` for paths
    the schema rejects), check the constraints admit points, and check that every free
    parameter changes what the solver reads somewhere (a field the solver ignores for that
    scene, e.g. the pins of a glued unit, does not count: ``fem.scene.effective_scene_dict``)."""
    def scene_hash(scene: Any) -> str:
        text = json.dumps(effective_scene_dict(scene), sort_keys=True, allow_nan=False)
        return hashlib.sha256(text.encode()).hexdigest()

    center = space.center()
    space.scene(center)
    probe = space.points(0, _PROBE_POINTS)
    mask = space.feasible(probe)
    if not mask.any():
        cons = ", ".join(f"{c.name}: {c.expr}" for c in space.constraints)
        raise SpaceError("constraint", f"the constraints reject all of the first "
                         f"{_PROBE_POINTS} design points ({cons}); widen them or the ranges")
    rows = [{k: _plain(v[i]) for k, v in probe.items()} for i in np.flatnonzero(mask)]
    hashes = [scene_hash(space.scene(row)) for row in rows]
    for p in space.free:
        alt = p.from_unit(np.array([0.0, 0.999]))
        if not any(_changes(space, row, h, p, alt, scene_hash) for row, h in zip(rows, hashes,
                                                                                   strict=True)):
            raise SpaceError(f"parameter {p.name}.path",
                             f"parameter {p.name!r} (path {', '.join(p.paths)}) never changes "
                             "what the solver reads in the probe points: its list entry is "
                             "always truncated away, the field is overwritten, or the solver "
                             "ignores it there (e.g. pogo pins of a glued unit, the frequency "
                             "of a static analysis)")


def _changes(space: Space, row: Mapping[str, Any], h: str, p: Parameter, alt: np.ndarray,
             scene_hash: Any) -> bool:
    for value in alt:
        if value == row[p.name]:
            continue
        if scene_hash(space.scene({**row, p.name: value})) != h:
            return True
    return False


def load_space(path: str | Path, check_scenes: bool = True) -> Space:
    """Read a space TOML file (see module docstring). Raises :class:`SpaceError`."""
    path = Path(path)
    data = read_toml_file(path, SpaceError, "space file")
    return space_from_dict(data, base_dir=path.parent, check_scenes=check_scenes)
