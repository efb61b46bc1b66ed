"""The columns of a dataset: provenance, parameters, and the outputs of the analysis.

Single-frequency datasets (harmonic and transient scenes): magnitudes at the centre and the
edge [um], their ratio, the unit's edge radius [mm], the profile (``profile_distance_mm`` [mm],
``profile_uz_um`` = abs(U_z) and ``profile_magnitude_um`` [um]), transient histories, and, from
this version on, the complex Fourier amplitudes of the harmonic steady state (the phase is what
a coherent crosstalk model needs), per component ``c`` in r (radial), z (normal, out of the
skin), t (tangential, theta), real and imaginary parts in um:

* ``center_u{c}_re_um``, ``center_u{c}_im_um``, ``edge_u{c}_re_um``, ``edge_u{c}_im_um``
  (float64; magnitude = sqrt of the sum of the six squares, ``center_amplitude_um``);
* ``profile_u{c}_re_um``, ``profile_u{c}_im_um`` (list<float64> on ``profile_distance_mm``).

Datasets written before the complex columns existed keep their columns (the manifest records
them; :meth:`surrogate.data.store.Store.schema`) and stay readable and extendable.

Sweep datasets (a space with a ``[band]``, :mod:`surrogate.data.band`): one row per design
with its complex response over the band, float32 lists (7 significant digits, far below the
solver's 1e-3 error tolerance), frequency-major:

* ``sweep_frequency_hz`` (list<float64>, n_f) and ``profile_distance_mm`` (list<float64>, n_p);
* ``sweep_center_u{c}_re_um`` / ``_im_um`` and ``sweep_edge_u{c}_...`` (list<float32>, n_f);
* ``sweep_profile_u{c}_re_um`` / ``_im_um`` (list<float32>, n_f * n_p: entry i * n_p + j is
  frequency i at distance j; ``numpy.reshape(n_f, n_p)``);
* ``sweep_error_estimate`` (the solver's relative error estimate) and ``sweep_full_solves``.

These are the columns every reader gets; a compact dataset stores the float lists as integer
codes (:mod:`surrogate.data.codec`, within 3e-4 of the band maximum at each location) and the
store decodes them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Protocol

import numpy as np
import pyarrow as pa

from surrogate.data.errors import DatasetError

__all__ = ["COMPLEX_FIELDS", "COMPONENTS", "OUTPUT_FIELDS", "PROFILE_OUTPUTS",
           "PROVENANCE_FIELDS", "SWEEP_FIELDS", "arrow_schema", "complex_columns", "profile_matrix",
           "recorded_schema", "rows_to_table", "sweep_arrays", "sweep_columns"]

#: Component names in the order of the solver's result arrays (U_r, U_z, U_t).
COMPONENTS = ("r", "z", "t")
_TYPES = {"float64": pa.float64(), "int64": pa.int64(), "string": pa.string(),
          "bool": pa.bool_()}
_F64_LIST = pa.list_(pa.float64())
_F32_LIST = pa.list_(pa.float32())

PROVENANCE_FIELDS = [
    pa.field("sample_id", pa.string(), nullable=False),
    pa.field("sample_index", pa.int64(), nullable=False),
    pa.field("status", pa.string(), nullable=False),
    pa.field("error", pa.string()),
    pa.field("source", pa.string(), nullable=False),
    pa.field("wall_s", pa.float64()),
    pa.field("dofs", pa.int64()),
    pa.field("elements", pa.int64()),
    pa.field("solver_version", pa.string()),
    pa.field("solver_hash", pa.string()),
    pa.field("scene_json", pa.string()),
    pa.field("warnings", pa.string()),
]
OUTPUT_FIELDS = [
    pa.field("center_amplitude_um", pa.float64()),
    pa.field("edge_amplitude_um", pa.float64()),
    pa.field("normalized_edge", pa.float64()),
    pa.field("edge_radius_mm", pa.float64()),
    pa.field("profile_distance_mm", _F64_LIST),
    pa.field("profile_uz_um", _F64_LIST),
    pa.field("profile_magnitude_um", _F64_LIST),
    pa.field("history_t_s", _F64_LIST),
    pa.field("history_r_mm", _F64_LIST),
    pa.field("history_uz_um", pa.list_(_F64_LIST)),
    pa.field("history_magnitude_um", pa.list_(_F64_LIST)),
    # transient unit runs: [u_r, u_z, u_theta] histories (um) at the center and edge points
    pa.field("history_center_um", pa.list_(_F64_LIST)),
    pa.field("history_edge_um", pa.list_(_F64_LIST)),
]
COMPLEX_FIELDS = (
    [pa.field(f"{where}_u{c}_{part}_um", pa.float64())
     for where in ("center", "edge") for c in COMPONENTS for part in ("re", "im")]
    + [pa.field(f"profile_u{c}_{part}_um", _F64_LIST) for c in COMPONENTS
       for part in ("re", "im")])
SWEEP_FIELDS = (
    [pa.field("edge_radius_mm", pa.float64()),
     pa.field("sweep_frequency_hz", _F64_LIST),
     pa.field("profile_distance_mm", _F64_LIST)]
    + [pa.field(f"sweep_{where}_u{c}_{part}_um", _F32_LIST)
       for where in ("center", "edge", "profile") for c in COMPONENTS for part in ("re", "im")]
    + [pa.field("sweep_error_estimate", pa.float64()),
       pa.field("sweep_full_solves", pa.int64())])

#: The profiles a steady-state surrogate can learn from single-frequency rows (``hapticrom
#: train --outputs``): model output name -> (the dataset column on ``profile_distance_mm``,
#: what it is). ``profile_um`` is always learned; the others are extra POD blocks
#: (:class:`surrogate.pod.ProfileTargets`). ``profile_uz_um`` is checked against the complex
#: columns by ``dataset validate`` (:mod:`surrogate.data.output_checks`).
PROFILE_OUTPUTS: dict[str, tuple[str, str]] = {
    "profile_um": ("profile_magnitude_um", "displacement magnitude |u| on the skin surface "
                   "[um] (a 3-axis sensor)"),
    "profile_normal_um": ("profile_uz_um", "normal component |u_z| on the skin surface [um] "
                          "(what an LDV or a glued single-axis accelerometer sees)"),
}


class Space(Protocol):
    """What the columns depend on of a space (:class:`surrogate.data.space.Space` is one;
    the space's parameters are made of these columns, so this module does not import it)."""

    parameters: tuple[Any, ...]
    band: Any


def arrow_schema(space: Space) -> pa.Schema:
    """The Arrow schema of a new dataset over ``space``: provenance, parameters, outputs
    (single-frequency with complex columns, or sweep columns for a space with a band)."""
    params = [pa.field(p.name, _TYPES[p.column_type]) for p in space.parameters]
    outputs = SWEEP_FIELDS if space.band is not None else OUTPUT_FIELDS + COMPLEX_FIELDS
    return pa.schema(PROVENANCE_FIELDS + params + outputs)


def recorded_schema(space: Space, manifest: Mapping[str, Any]) -> pa.Schema:
    """The schema of an existing dataset: the columns its manifest records (datasets written
    before a column existed do not have it), typed as :func:`arrow_schema` types them."""
    full = arrow_schema(space)
    recorded = manifest.get("columns")
    if not isinstance(recorded, list):
        return full
    names = {c.get("name") for c in recorded if isinstance(c, Mapping)}
    return pa.schema([f for f in full if f.name in names])


def _um(values: Any) -> list[float]:
    return (np.asarray(values) * 1e6).tolist()


def complex_columns(center: np.ndarray, edge: np.ndarray,
                    profile: np.ndarray) -> dict[str, Any]:
    """The complex output columns [um] of one single-frequency result: ``center`` and
    ``edge`` (3,) complex [m], ``profile`` (n_p, 3) complex [m]."""
    out: dict[str, Any] = {}
    for i, c in enumerate(COMPONENTS):
        for where, u in (("center", center), ("edge", edge)):
            out[f"{where}_u{c}_re_um"] = float(u[i].real * 1e6)
            out[f"{where}_u{c}_im_um"] = float(u[i].imag * 1e6)
        out[f"profile_u{c}_re_um"] = _um(profile[:, i].real)
        out[f"profile_u{c}_im_um"] = _um(profile[:, i].imag)
    return out


def sweep_columns(res: Any) -> dict[str, Any]:
    """The output columns of a sweep result (``fem.sweep.SweepResult`` or any object with
    its fields: frequency_hz (n_f,), center and edge (n_f, 3) complex [m], profile_mm (n_p,),
    profile (n_f, n_p, 3) complex [m], edge_mm, error_estimate, full_solves, meta)."""
    f = np.asarray(res.frequency_hz, dtype=float)
    center, edge = np.asarray(res.center), np.asarray(res.edge)
    profile = np.asarray(res.profile)
    n_f, n_p = f.size, len(res.profile_mm)
    if center.shape != (n_f, 3) or edge.shape != (n_f, 3) or profile.shape != (n_f, n_p, 3):
        raise ValueError(f"sweep result shapes: center {center.shape}, edge {edge.shape}, "
                         f"profile {profile.shape} do not fit {n_f} frequencies x {n_p} "
                         "profile points")
    out: dict[str, Any] = {
        "edge_radius_mm": None if res.edge_mm is None else float(res.edge_mm),
        "sweep_frequency_hz": f.tolist(),
        "profile_distance_mm": np.asarray(res.profile_mm, dtype=float).tolist(),
        "sweep_error_estimate": float(res.error_estimate),
        "sweep_full_solves": int(res.full_solves),
    }
    for i, c in enumerate(COMPONENTS):
        for where, u in (("center", center[:, i]), ("edge", edge[:, i]),
                         ("profile", profile[:, :, i].reshape(-1))):
            out[f"sweep_{where}_u{c}_re_um"] = _f32_um(u.real)
            out[f"sweep_{where}_u{c}_im_um"] = _f32_um(u.imag)
    meta = getattr(res, "meta", {}) or {}
    for key in ("dofs", "elements"):
        if key in meta:
            out[key] = int(meta[key])
    warnings = meta.get("warnings") or []
    out["warnings"] = "; ".join(str(w) for w in warnings) or None
    return out


def _f32_um(values: np.ndarray) -> list[float]:
    """Values [m] as um, rounded to float32 (what the column stores) for a stable JSON trip."""
    return (np.asarray(values, dtype=float) * 1e6).astype(np.float32).tolist()


def sweep_arrays(row: Mapping[str, Any], where: str) -> np.ndarray:
    """A stored row's complex sweep at ``where`` ("center", "edge": (n_f, 3); "profile":
    (n_f, n_p, 3)) in um."""
    n_f = len(row["sweep_frequency_hz"])
    parts = [np.asarray(row[f"sweep_{where}_u{c}_re_um"], dtype=float)
             + 1j * np.asarray(row[f"sweep_{where}_u{c}_im_um"], dtype=float)
             for c in COMPONENTS]
    out = np.stack(parts, axis=-1)
    if where == "profile":
        return out.reshape(n_f, -1, 3)
    return out


def profile_matrix(df: Any, grid_mm: Sequence[float],
                   column: str = "profile_magnitude_um") -> np.ndarray:
    """Profiles of every row linearly interpolated onto ``grid_mm`` [mm]: an array of shape
    (rows, len(grid)) in the column's unit, NaN where a row has no profile or the grid point
    lies outside that row's distance range (no extrapolation)."""
    grid = np.asarray(grid_mm, dtype=float)
    out = np.full((len(df), grid.size), np.nan)
    for i, (d, a) in enumerate(zip(df["profile_distance_mm"], df[column], strict=True)):
        if d is None or a is None or len(d) == 0:
            continue
        d, a = np.asarray(d, dtype=float), np.asarray(a, dtype=float)
        inside = (grid >= d.min()) & (grid <= d.max())
        out[i, inside] = np.interp(grid[inside], d, a)
    return out


def rows_to_table(rows: Sequence[Mapping[str, Any]], schema: pa.Schema) -> pa.Table:
    """Arrow table from row dicts, with exactly ``schema`` (unknown keys are an error)."""
    names = set(schema.names)
    for i, row in enumerate(rows):
        extra = set(row) - names
        if extra:
            raise DatasetError("row", f"row {i} has unknown columns {sorted(extra)}")
    cols = {name: [_py(row.get(name)) for row in rows] for name in schema.names}
    return pa.table(cols, schema=schema)


def _py(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value
