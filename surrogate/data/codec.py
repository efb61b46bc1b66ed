"""The compact stored form of sweep datasets: integer codes on a per-location step, an error
bound proved by the part itself, and Parquet's own compression.

A sweep row (:mod:`surrogate.data.columns`) holds 18 float32 lists: the complex response
(components r, z, t; re, im) at the centre and the edge over the band's n_f frequencies, and on
the n_p profile distances (frequency-major). Stored, each value becomes an integer code on a
step chosen per row and location (location: the centre, the edge, each profile distance):

* ``M``: the band maximum of the displacement magnitude at the location,
  max over frequencies of sqrt(sum over r, z, t of re^2 + im^2) [um];
* ``step = 2 * tolerance * M`` (float32), so rounding to the nearest code errs by at most
  ``tolerance * M`` (default 2.5e-4 M; the bound is 3e-4 M, which leaves room for float32);
* codes ``q = round(u / step)`` (|q| <= 1 / (2 tolerance)), stored as their differences of
  order ``order`` (default 3) along frequency: the response is smooth in frequency, so these
  are small integers (order-0 entropy 4.2 bits on the first real designs) that Parquet's zstd
  packs into about 5.5 bits each (``bench/datasets/codec.py`` compares the orders).

Stored columns (everything else in the row is stored as written):

* ``sweep_{where}_u{c}_{part}_q`` (list<int16>): the differences along frequency, as many as
  the float list they replace: n_f for the centre and the edge, n_p * n_f for the profile,
  distance-major (entry j * n_f + i is distance j at frequency i: each distance's band is
  contiguous, which compresses better than the float lists' frequency-major order);
* ``sweep_step_um`` (list<float32>, 2 + n_p): the steps of the centre, the edge, then the
  profile distances [um].

Decoding (what :meth:`SweepCodec.decode` does, and all a reader needs with pandas + numpy)::

    q = q.reshape(-1, n_f)                    # (locations, n_f) integer differences
    for _ in range(order):                    # undo the differences along frequency
        q = np.cumsum(q, axis=1, dtype=np.int64)
    u = q * step[location][:, None]           # um (location: 0 centre, 1 edge, 2 + j)

The error is measured at encode time on the float32 values a reader gets back (per column: the
largest |decoded - original| / M over rows, frequencies, locations) and recorded by the store
in the manifest; it is also provable from the stored part alone (:meth:`SweepCodec.proven`):
the codes' rounding error is at most step / 2, and M is at least the decoded band maximum less
the decoded values' possible error, so ``dataset validate`` checks every part against the
bound without the original values.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from fieldspec import FieldError
from surrogate.data.columns import COMPONENTS
from surrogate.data.errors import DatasetError

__all__ = ["ARRAY_COLUMNS", "BOUND", "CODEC_NAME", "STEP_COLUMN", "CodecError", "SweepCodec",
           "code_column", "location_scales", "worst_errors"]

CODEC_NAME = "sweep-step-codes"
CODEC_VERSION = 1
#: The largest codec error allowed, relative to the band maximum magnitude at the location.
BOUND = 3e-4
#: The quantiser's target error, relative to the same maximum (below BOUND: float32 rounding
#: of the decoded values adds at most 2**-24 of M).
TOLERANCE = 2.5e-4
WHERE = ("center", "edge", "profile")
PARTS = ("re", "im")
#: The 18 float32 list columns of a sweep row, in (where, component, part) order.
ARRAY_COLUMNS = tuple(f"sweep_{w}_u{c}_{p}_um" for w in WHERE for c in COMPONENTS for p in PARTS)
STEP_COLUMN = "sweep_step_um"
#: Order of the differences along frequency (whole rows of the first 32 designs of the sweep
#: test set at zstd 19: order 2 8.07, 3 7.38, 4 7.67 kB a design; ``bench/datasets/codec.py``).
ORDER = 3
#: zstd level of the parts.
ZSTD_LEVEL = 19
_F32_EPS = 2.0 ** -24
_INT16 = np.iinfo(np.int16).max


class CodecError(FieldError):
    """Values the codec cannot store (non-finite, ragged, or a damaged stored part), or codec
    parameters out of range; ``field`` names the column or the parameter."""


def worst_errors(*errors: Mapping[str, float]) -> dict[str, float]:
    """The largest error per column over several records (column -> error)."""
    out: dict[str, float] = {}
    for record in errors:
        for name, err in record.items():
            out[name] = max(out.get(name, 0.0), float(err))
    return out


def code_column(name: str) -> str:
    """The stored code column of a float list column (``..._um`` -> ``..._q``)."""
    return name.removesuffix("_um") + "_q"


def location_scales(u: np.ndarray) -> np.ndarray:
    """M (n, L): the band maximum magnitude per row and location of ``u`` (n, n_f, L, 6)
    [um] (last axis r re, r im, z re, z im, t re, t im)."""
    return np.sqrt(np.max(np.sum(np.square(u, dtype=float), axis=-1), axis=1))


@dataclass(frozen=True)
class SweepCodec:
    """The codec and its parameters (recorded in the manifest: :meth:`to_dict`)."""

    tolerance: float = TOLERANCE
    bound: float = BOUND
    order: int = ORDER

    def __post_init__(self) -> None:
        for name in ("tolerance", "bound"):
            v = getattr(self, name)
            if not (isinstance(v, float | int) and math.isfinite(v) and 0 < v <= 0.01):
                raise CodecError(f"codec.{name}",
                                 f"codec.{name} = {v!r}: allowed 0 < {name} <= 0.01")
        if self.tolerance >= self.bound:
            raise CodecError("codec.tolerance", f"codec.tolerance = {self.tolerance!r}: "
                             f"allowed below the bound {self.bound!r} (float32 rounding adds "
                             "to it)")
        if isinstance(self.order, bool) or self.order not in range(0, 5):
            raise CodecError("codec.order", f"codec.order = {self.order!r}: allowed 0, 1, 2, 3, 4")
        lowest = 2 ** self.order / (2.0 * (_INT16 - 2 ** self.order))
        if self.tolerance < lowest:  # |difference| <= 2**order * (1 / (2 tolerance) + 1)
            raise CodecError("codec.tolerance", f"codec.tolerance = {self.tolerance!r}: "
                             f"codes of order {self.order} would not fit int16 (allowed >= "
                             f"{lowest:.3g})")

    # ---- description

    @classmethod
    def from_record(cls, recorded: Any, where: str | Path) -> SweepCodec:
        """The codec of a manifest's ``codec`` entry; :class:`DatasetError` naming ``where``
        (the manifest) for a record that is not one this version reads."""
        try:
            if not isinstance(recorded, Mapping):
                raise CodecError("codec", f"{recorded!r} is not a codec record")
            return cls.from_dict(recorded)
        except (ValueError, KeyError, TypeError) as err:  # CodecError is a ValueError
            raise DatasetError(str(where), f"{where}: codec: {err}") from None

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> SweepCodec:
        """The codec a manifest records; :class:`CodecError` for another codec or version."""
        if d.get("name") != CODEC_NAME or d.get("version") != CODEC_VERSION:
            raise CodecError("codec", f"codec {d.get('name')!r} version {d.get('version')!r} "
                             f"is not known (this version reads {CODEC_NAME!r} "
                             f"{CODEC_VERSION})")
        return cls(tolerance=float(d["tolerance"]), bound=float(d["bound"]),
                   order=d["order"])

    def to_dict(self) -> dict[str, Any]:
        """The manifest's ``codec`` entry (the store adds the measured errors)."""
        return {"name": CODEC_NAME, "version": CODEC_VERSION, "tolerance": self.tolerance,
                "bound": self.bound, "order": self.order, "columns": list(ARRAY_COLUMNS),
                "stored_as": "COLUMN_q: int16 differences of the given order along frequency "
                "of round(u / step), profile distance-major (entry j * n_f + i); step = 2 * "
                "tolerance * (band maximum magnitude at the location); "
                f"{STEP_COLUMN}: the steps of the centre, the edge, the profile distances [um]",
                "error": "largest |decoded - original| / (band maximum magnitude at the "
                "location), per column"}

    def describe(self) -> str:
        """One line for reports."""
        return (f"{CODEC_NAME} v{CODEC_VERSION}: int16 order-{self.order} frequency "
                f"differences on step 2*{self.tolerance:g}*M, zstd {ZSTD_LEVEL}")

    # ---- schemas

    def stored_schema(self, logical: pa.Schema) -> pa.Schema:
        """The parts' schema: ``logical`` with the float lists replaced, where the first of
        them was, by the code columns and the step column."""
        fields: list[pa.Field] = []
        for f in logical:
            if f.name == ARRAY_COLUMNS[0]:
                fields += [pa.field(code_column(n), pa.list_(pa.int16())) for n in ARRAY_COLUMNS]
                fields.append(pa.field(STEP_COLUMN, pa.list_(pa.float32())))
            elif f.name not in ARRAY_COLUMNS:
                fields.append(f)
        return pa.schema(fields)

    def stored_columns(self, columns: Sequence[str]) -> list[str]:
        """The stored columns needed to decode the logical ``columns``."""
        out: list[str] = []
        for name in columns:
            need = [code_column(name), STEP_COLUMN] if name in ARRAY_COLUMNS else [name]
            out += [n for n in need if n not in out]
        return out

    @staticmethod
    def parquet_options(schema: pa.Schema) -> dict[str, Any]:
        """Options of ``pyarrow.parquet.write_table`` for a stored part: zstd at
        :data:`ZSTD_LEVEL`; dictionaries for the columns that repeat (not for the codes:
        distinct small integers); no column statistics (never filtered on, and those of
        ``scene_json`` alone would add 5 kB to every part's footer)."""
        codes = {code_column(n) for n in ARRAY_COLUMNS} | {STEP_COLUMN}
        return {"compression": "zstd", "compression_level": ZSTD_LEVEL,
                "use_dictionary": [f.name for f in schema if f.name not in codes],
                "write_statistics": False}

    def part_record(self) -> dict[str, Any]:
        """What a part's own metadata records of the codec (its parameters)."""
        return {"name": CODEC_NAME, "version": CODEC_VERSION, "tolerance": self.tolerance,
                "bound": self.bound, "order": self.order}

    # ---- encoding

    def encode(self, table: pa.Table) -> tuple[pa.Table, dict[str, float]]:
        """(stored table, largest error per column) of a logical table (the float lists
        as the dataset schema types them; rows whose lists are null stay null)."""
        u, valid, n_f = _gather(table)
        L = u.shape[2]
        step = (2.0 * self.tolerance * location_scales(u)).astype(np.float32)  # (n, L)
        safe = np.where(step > 0, step, 1.0).astype(float)[:, None, :, None]
        q = np.rint(u / safe).astype(np.int64)
        diff = q
        for _ in range(self.order):
            diff = np.diff(diff, axis=1, prepend=0)
        if np.abs(diff).max(initial=0) > _INT16:  # cannot happen (checked in __post_init__)
            raise CodecError("codec", "codes do not fit int16")
        decoded = _decode_codes(diff, step, self.order)
        errors = _errors(decoded, u)
        columns = _code_arrays(diff, step, valid, n_f, L)
        return _assemble(table, self.stored_schema(table.schema), columns), errors

    # ---- decoding

    def decode(self, stored: pa.Table, logical: pa.Schema | None = None) -> pa.Table:
        """The logical table of a stored one (float32 lists; only the array columns whose
        codes ``stored`` holds); :class:`CodecError` when the stored lists do not fit
        together (a damaged or edited part)."""
        present = [n for n in ARRAY_COLUMNS if code_column(n) in stored.column_names]
        if not present:
            return stored
        if STEP_COLUMN not in stored.column_names:
            raise CodecError(STEP_COLUMN, f"{STEP_COLUMN} missing: the codes cannot be decoded")
        step, valid = _steps(stored)
        n, L = step.shape
        arrays: dict[str, pa.Array] = {}
        bands: set[int] = set()
        for name in present:
            where = name.split("_")[1]
            q = _codes(stored, code_column(name), valid, where, L)
            bands.add(q.shape[2])
            if len(bands) > 1:
                raise CodecError(code_column(name), f"{code_column(name)}: list lengths give "
                                 f"{q.shape[2]} frequencies, other code columns "
                                 f"{min(bands - {q.shape[2]})}")
            for _ in range(self.order):
                q = np.cumsum(q, axis=2)
            u = q * _where_steps(step, where).astype(float)[:, :, None]   # (n, locs, n_f)
            arrays[name] = _lists(u.astype(np.float32).transpose(0, 2, 1).reshape(n, -1),
                                  valid)
        fields: list[pa.Field] = []
        stored_only = {code_column(c) for c in ARRAY_COLUMNS} | {STEP_COLUMN}
        for f in stored.schema:  # the float lists where the codes were
            if f.name not in stored_only:
                fields.append(f)
            elif not any(g.name in arrays for g in fields):
                fields += [pa.field(n, pa.list_(pa.float32())) for n in present]
        cols = {**{n: stored.column(n) for n in stored.column_names}, **arrays}
        schema = pa.schema(fields)
        out = pa.table([cols[f.name] for f in schema], schema=schema)
        return out if logical is None else out.select([n for n in logical.names
                                                        if n in out.column_names])

    def proven(self, stored: pa.Table) -> dict[str, float]:
        """An upper bound of each array column's codec error provable from the stored part
        alone: rounding errs by at most step / 2 and float32 by 2**-24 of a value, and the
        band maximum M is at least the decoded maximum less sqrt(6) step / 2."""
        step, valid = _steps(stored)
        L = step.shape[1]
        decoded = self.decode(stored.select([*(code_column(c) for c in ARRAY_COLUMNS),
                                             STEP_COLUMN]))
        u, _, _ = _gather(decoded)
        m_dec = location_scales(u)                                  # (n, L)
        half = step.astype(float) / 2.0
        m_low = m_dec - math.sqrt(6.0) * (half + _F32_EPS * m_dec)
        bound = np.where(m_low > 0, (half + _F32_EPS * m_dec) / np.where(m_low > 0, m_low, 1),
                         np.where(half > 0, np.inf, 0.0))
        out = {}
        for name in ARRAY_COLUMNS:
            b = bound[:, _where_slice(name.split("_")[1], L)]
            out[name] = float(b[valid].max(initial=0.0))
        return out


# --------------------------------------------------------------------------- helpers


def _where_slice(where: str, L: int) -> slice:
    return {"center": slice(0, 1), "edge": slice(1, 2), "profile": slice(2, L)}[where]


def _where_steps(step: np.ndarray, where: str) -> np.ndarray:
    return step[:, _where_slice(where, step.shape[1])]


def _list_values(col: pa.ChunkedArray | pa.Array) -> tuple[pa.Array, np.ndarray]:
    arr = col.combine_chunks() if isinstance(col, pa.ChunkedArray) else col
    lengths = np.asarray(arr.value_lengths().fill_null(0), dtype=np.int64)
    return arr, lengths


def _gather(table: pa.Table) -> tuple[np.ndarray, np.ndarray, int]:
    """(u (n, n_f, L, 6) float64 [um], valid rows (n,), n_f) of a logical table; rows whose
    lists are all null are zero and not valid."""
    n = table.num_rows
    nulls = np.stack([np.asarray(table.column(c).is_null(), dtype=bool) for c in ARRAY_COLUMNS])
    valid = ~nulls.any(axis=0)
    if np.any(nulls.any(axis=0) & ~nulls.all(axis=0)):
        raise CodecError("rows", "a row has some sweep lists and not others")
    sizes = {}
    for where in WHERE:
        lengths = {int(v) for c in ARRAY_COLUMNS if c.split("_")[1] == where
                   for v in _list_values(table.column(c))[1][valid]}
        if len(lengths) > 1:
            raise CodecError(f"sweep_{where}", f"sweep_{where}_* lists of different lengths "
                             f"{sorted(lengths)}")
        sizes[where] = lengths.pop() if lengths else 0
    n_f = sizes["center"]
    if sizes["edge"] != n_f or (n_f and sizes["profile"] % n_f):
        raise CodecError("sweep_profile", f"sweep list lengths centre {n_f}, edge "
                         f"{sizes['edge']}, profile {sizes['profile']} do not fit one band")
    n_p = sizes["profile"] // n_f if n_f else 0
    u = np.zeros((n, n_f, 2 + n_p, 6))
    k = 0
    for where in WHERE:
        for _ in range(6):
            name = ARRAY_COLUMNS[k]
            arr, _ = _list_values(table.column(name))
            vals = np.asarray(arr.filter(pa.array(valid)).flatten().to_numpy(
                zero_copy_only=False), dtype=float)
            u[valid, :, _where_slice(where, 2 + n_p), k % 6] = vals.reshape(
                int(valid.sum()), n_f, -1)
            k += 1
    if not np.all(np.isfinite(u)):
        bad = [c for i, c in enumerate(ARRAY_COLUMNS) if not np.all(np.isfinite(
            u[:, :, _where_slice(c.split('_')[1], 2 + n_p), i % 6]))]
        raise CodecError(bad[0], f"non-finite values in {', '.join(bad)}")
    return u, valid, n_f


def _decode_codes(diff: np.ndarray, step: np.ndarray, order: int) -> np.ndarray:
    """The float32 values a reader gets back from differences (n, n_f, L, 6)."""
    q = diff
    for _ in range(order):
        q = np.cumsum(q, axis=1)
    return (q * step.astype(float)[:, None, :, None]).astype(np.float32)


def _errors(decoded: np.ndarray, u: np.ndarray) -> dict[str, float]:
    """Largest |decoded - u| / M per column (absolute where M = 0: all values zero)."""
    m = location_scales(u)
    err = np.abs(decoded.astype(float) - u).max(axis=1)            # (n, L, 6)
    rel = np.where(m[..., None] > 0, err / np.where(m > 0, m, 1.0)[..., None], err)
    L = u.shape[2]
    return {name: float(rel[:, _where_slice(name.split("_")[1], L), i % 6].max(initial=0.0))
            for i, name in enumerate(ARRAY_COLUMNS)}


def _lists(values: np.ndarray, valid: np.ndarray) -> pa.Array:
    """A list array of the rows of ``values`` (n, k), null where not ``valid``."""
    n, k = values.shape
    offsets = pa.array(np.arange(n + 1, dtype=np.int32) * k)
    arr = pa.ListArray.from_arrays(offsets, pa.array(values.reshape(-1)))
    if valid.all():
        return arr
    return pa.ListArray.from_arrays(offsets, arr.values, mask=pa.array(~valid))


def _code_arrays(diff: np.ndarray, step: np.ndarray, valid: np.ndarray, n_f: int,
                 L: int) -> dict[str, pa.Array]:
    n = diff.shape[0]
    out = {}
    for i, name in enumerate(ARRAY_COLUMNS):
        block = diff[:, :, _where_slice(name.split("_")[1], L), i % 6].transpose(0, 2, 1)
        out[code_column(name)] = _lists(np.ascontiguousarray(block, dtype=np.int16)
                                        .reshape(n, -1), valid)
    out[STEP_COLUMN] = _lists(step, valid)
    return out


def _assemble(table: pa.Table, schema: pa.Schema, columns: Mapping[str, pa.Array]) -> pa.Table:
    data = [columns[f.name] if f.name in columns else table.column(f.name) for f in schema]
    return pa.table(data, schema=schema)


def _steps(stored: pa.Table) -> tuple[np.ndarray, np.ndarray]:
    arr, lengths = _list_values(stored.column(STEP_COLUMN))
    valid = ~np.asarray(arr.is_null(), dtype=bool)
    L = {int(v) for v in lengths[valid]}
    if len(L) > 1 or (L and min(L) < 3):
        raise CodecError(STEP_COLUMN, f"{STEP_COLUMN}: lists of lengths {sorted(L)} (need "
                         "2 + n_p, equal)")
    width = L.pop() if L else 3
    step = np.zeros((stored.num_rows, width), dtype=np.float32)
    vals = np.asarray(arr.filter(pa.array(valid)).flatten().to_numpy(zero_copy_only=False),
                      dtype=np.float32)
    step[valid] = vals.reshape(-1, width)
    if not (np.all(np.isfinite(step)) and np.all(step >= 0)):
        raise CodecError(STEP_COLUMN, f"{STEP_COLUMN}: steps must be finite and >= 0")
    return step, valid


def _codes(stored: pa.Table, column: str, valid: np.ndarray, where: str,
           L: int) -> np.ndarray:
    """Differences (n, locations of ``where``, n_f) of one code column."""
    arr, lengths = _list_values(stored.column(column))
    if not np.array_equal(~np.asarray(arr.is_null(), dtype=bool), valid):
        raise CodecError(column, f"{column}: null where {STEP_COLUMN} is not (or the reverse)")
    width = 1 if where != "profile" else L - 2
    ok = lengths[valid]
    if ok.size and (np.any(ok != ok[0]) or ok[0] % width):
        raise CodecError(column, f"{column}: list lengths {sorted(set(ok.tolist()))[:4]} do not "
                         f"fit {width} location(s)")
    n_f = int(ok[0]) // width if ok.size else 0
    q = np.zeros((stored.num_rows, width, n_f), dtype=np.int64)
    vals = np.asarray(arr.filter(pa.array(valid)).flatten().to_numpy(zero_copy_only=False))
    q[valid] = vals.reshape(-1, width, n_f)
    return q
