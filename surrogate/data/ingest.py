"""Import results of external simulations (ABAQUS, COMSOL, other codes) into a dataset.

Two inputs:

*Table* (one sample per row), a CSV with a header row::

    skin_E_kPa,fat_thickness_mm,...,center_amplitude_um,edge_amplitude_um,profile_file
    49,14,...,3.1,1.6,runs/job1_profile.csv

Columns: every free parameter of the space (a parameter missing from the file may be given
once for all rows with ``values``/``--set NAME=VALUE``; fixed parameters are optional and
must equal their value), and any of ``center_amplitude_um``, ``edge_amplitude_um``,
``normalized_edge`` (checked against edge/center when all three are given), ``profile_file``
(a profile CSV, path relative to the table), ``wall_s`` [s] and ``dofs``. Each row needs an
amplitude or a profile. Lines starting with ``#`` are comments. Unknown columns are an error.

*Profile* (one sample): a ``hapticrom simulate --json`` result (``.json``, schema version 1
or the unversioned layout before it; its centre magnitude is taken too), or amplitude versus
distance from the unit edge, as exported by ABAQUS
(Report > XY data, ``.rpt`` or ``.csv``) or COMSOL (Export > Plot/Table, ``%`` comment
header). Delimiters ``,`` ``;`` tab or blanks; non-numeric lines before the data are
headers, the last one names the columns. Units come from the header (``(mm)``, ``[m]``,
``(um)``/``(µm)``) or from ``distance_unit``/``amplitude_unit`` (ABAQUS writes none: give
them). The parameter values of the run are given with ``values``. The edge amplitude is the
profile interpolated at distance 0 (None if 0 lies outside the data); the center amplitude
can be given separately.

Every value is checked against the space (ranges, choices, constraints) and every row's
scene is resolved and validated like a generated one; its ``sample_id`` is the scene hash,
so ingested and generated rows for the same design point can be compared. Rows are marked
``source = "ingest:FILENAME"``; ingesting the same file again adds nothing. Everything is
validated before anything is written.
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fem.scene import SceneError, scene_hash, scene_to_dict
from surrogate.data.errors import DatasetError
from surrogate.data.provenance import solver_info
from surrogate.data.simulate_json import read_simulate_json
from surrogate.data.space import Space, SpaceError, load_space
from surrogate.data.store import Store, new_manifest

__all__ = [
    "AMPLITUDE_UNITS",
    "DISTANCE_UNITS",
    "IngestReport",
    "ingest_profile",
    "ingest_table",
    "read_profile_csv",
]

DISTANCE_UNITS = {"mm": 1.0, "m": 1e3, "cm": 10.0, "um": 1e-3, "µm": 1e-3, "in": 25.4}
AMPLITUDE_UNITS = {"um": 1.0, "µm": 1.0, "nm": 1e-3, "mm": 1e3, "m": 1e6}
_UNIT_RE = re.compile(r"[\(\[]\s*(µm|um|nm|mm|cm|m|in)\s*[\)\]]")
_OUTPUT_COLUMNS = ("center_amplitude_um", "edge_amplitude_um", "normalized_edge",
                   "profile_file", "wall_s", "dofs")


@dataclass
class IngestReport:
    """Outcome of an ingest: rows read, rows added, rows already present (skipped)."""

    path: Path
    source: str
    rows_read: int
    added: int
    skipped_existing: int


# --------------------------------------------------------------------------- profile files


def _split(line: str) -> list[str]:
    for delim in (",", ";", "\t"):
        if delim in line:  # csv honours quoted fields such as "U:Magnitude, PI: PART-1"
            return [f.strip() for f in next(csv.reader([line], delimiter=delim))]
    return line.split()


def _unit(header_field: str | None, given: str | None, table: Mapping[str, float],
          what: str, path: Path) -> float:
    if given is not None:
        if given not in table:
            raise DatasetError(f"{what}_unit", f"{what}_unit = {given!r}: allowed "
                               f"{', '.join(table)}")
        return table[given]
    m = _UNIT_RE.search(header_field or "")
    if m and m.group(1) in table:
        return table[m.group(1)]
    raise DatasetError(f"{what}_unit", f"{path}: the unit of the {what} column is not in "
                       f"the header ({header_field!r}); give {what}_unit "
                       f"({', '.join(table)})")


def read_profile_csv(path: str | Path, distance_unit: str | None = None,
                     amplitude_unit: str | None = None,
                     columns: tuple[int, int] = (0, 1)) -> tuple[np.ndarray, np.ndarray]:
    """Read an amplitude-versus-distance export; return (distance [mm], amplitude [um]) sorted
    by distance. Raises :class:`DatasetError` naming the file and line for bad input."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as err:
        raise DatasetError(str(path), f"cannot read profile {path}: {err}") from None
    header: list[str] | None = None
    last_comment: list[str] | None = None
    rows: list[list[float]] = []
    for ln, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s:
            continue
        if s[0] in "%#":
            body = s.lstrip("%#").strip()
            if body and not rows:
                last_comment = _split(body)
            continue
        fields = _split(s)
        try:
            rows.append([float(f) for f in fields])
        except ValueError:
            if rows:
                raise DatasetError(str(path), f"{path}:{ln}: non-numeric value in the data "
                                   f"({s!r})") from None
            header = fields
    if len(rows) < 2:
        raise DatasetError(str(path), f"{path}: need at least 2 data lines (distance, "
                           f"amplitude), found {len(rows)}")
    width = {len(r) for r in rows}
    if len(width) != 1:
        raise DatasetError(str(path), f"{path}: data lines have different numbers of columns "
                           f"({sorted(width)})")
    ncol = width.pop()
    if max(columns) >= ncol or min(columns) < 0:
        raise DatasetError("columns", f"{path}: columns = {columns[0]},{columns[1]} but the "
                           f"data has {ncol} columns (0..{ncol - 1})")
    header = header or last_comment
    names = header if header and len(header) == ncol else [None] * ncol
    data = np.asarray(rows, dtype=float)
    dist = data[:, columns[0]] * _unit(names[columns[0]], distance_unit, DISTANCE_UNITS,
                                       "distance", path)
    amp = data[:, columns[1]] * _unit(names[columns[1]], amplitude_unit, AMPLITUDE_UNITS,
                                      "amplitude", path)
    if not (np.all(np.isfinite(dist)) and np.all(np.isfinite(amp))):
        raise DatasetError(str(path), f"{path}: NaN or inf in the data")
    if np.any(amp < 0):
        raise DatasetError(str(path), f"{path}: negative amplitude {amp.min():g}; the column "
                           "must be an amplitude (>= 0), not a signed displacement")
    order = np.argsort(dist, kind="stable")
    dist, amp = dist[order], amp[order]
    if np.any(np.diff(dist) == 0):
        raise DatasetError(str(path), f"{path}: repeated distance values")
    return dist, amp


def _edge_from_profile(dist: np.ndarray, amp: np.ndarray) -> float | None:
    if dist[0] <= 0.0 <= dist[-1]:
        return float(np.interp(0.0, dist, amp))
    return None


# --------------------------------------------------------------------------- shared


def _open_target(out: str | Path, space: Space | str | Path | None) -> tuple[Store | None,
                                                                              Space]:
    """The existing store (or None) and the space to validate against; writes nothing."""
    out = Path(out)
    if isinstance(space, str | Path):
        space = load_space(space)
    if Store.exists(out):
        store = Store.open(out, deep=True)
        if space is not None and space.space_hash() != store.manifest.get("space_hash"):
            raise DatasetError("space", f"space {space.name!r} differs from the space of {out}; "
                               "give no space to use the dataset's own")
        if store.space.band is not None:
            raise DatasetError("out", f"{out} is a sweep dataset (its space has a [band]); "
                               "ingest writes single-frequency rows: give another --out")
        return store, space or store.space
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise DatasetError("out", f"{out} exists and is not a hapticrom dataset")
    if space is None:
        raise DatasetError("space", f"{out} does not exist yet: give a space to create it")
    if space.band is not None:
        raise DatasetError("space", f"space {space.name!r} has a [band] (rows are sweeps); "
                           "ingest writes single-frequency rows: give a space without a band")
    return None, space


def _scene_row(space: Space, values: Mapping[str, Any], where: str) -> tuple[str, str]:
    cols = {k: np.asarray([v], dtype=object) for k, v in values.items()}
    for c in space.constraints:
        if not c.evaluate(cols)[0]:
            raise SpaceError(f"constraint {c.name}", f"{where}: violates constraint "
                             f"{c.name!r} ({c.expr})")
    try:
        scene = space.scene(values)
    except SpaceError as err:
        raise SpaceError(err.field, f"{where}: {err}") from None
    return scene_hash(scene), json.dumps(scene_to_dict(scene), sort_keys=True,
                                         separators=(",", ":"))


def _check_values(space: Space, raw: Mapping[str, Any], where: str) -> dict[str, Any]:
    values = {}
    for p in space.parameters:
        if p.name in raw:
            try:
                values[p.name] = p.check_value(_strip(raw[p.name]), f"{where}: {p.name}")
            except SpaceError:
                choice = _same_scene_choice(space, p.name, _strip(raw[p.name]))
                if choice is None:
                    raise
                values[p.name] = choice
        elif p.free:
            raise SpaceError(p.name, f"{where}: no value for parameter {p.name!r} "
                             f"({p.allowed()}); add the column or give --set {p.name}=VALUE")
        else:
            values[p.name] = p.value
    return values


def _choice_scenes(space: Space, name: str) -> dict[str, str]:
    """Scene hash of the space's center with each choice of categorical ``name``."""
    p = next(q for q in space.parameters if q.name == name)
    center = space.center()
    return {scene_hash(space.scene({**center, name: c})): c for c in p.choices}


def _same_scene_choice(space: Space, name: str, value: Any) -> Any:
    """The choice of categorical ``name`` that resolves to the same scene as ``value`` (a
    material alias such as "A" for "ecoflex-00-10", as scene files accept), else None."""
    p = next(q for q in space.parameters if q.name == name)
    if p.type != "categorical" or not p.free or not isinstance(value, str):
        return None
    try:
        h = scene_hash(space.scene({**space.center(), name: value}))
    except (SpaceError, SceneError, ValueError, KeyError):
        return None
    return _choice_scenes(space, name).get(h)


def _strip(value: Any) -> Any:
    return value.strip() if isinstance(value, str) else value


def _write(out: Path, store: Store | None, space: Space, rows: list[dict[str, Any]],
           source: str, n_read: int) -> IngestReport:
    if store is not None:
        keys, _ = store.keys()
        fresh = [r for r in rows if (source, r["sample_id"]) not in keys]
    else:
        fresh = rows
    if fresh:
        if store is None:
            store = Store.create(out, space, **new_manifest(space, solver_info()))
        with store.lock():
            store.remove_temp_files()
            store.write_part(fresh, {"source": source})
            store.manifest.setdefault("ingested", []).append({"source": source,
                                                              "rows": len(fresh)})
            store.save_manifest()
    return IngestReport(out, source, n_read, len(fresh), len(rows) - len(fresh))


def _float_or_none(raw: str | None, where: str, column: str, lo: float = 0.0,
                   low_open: bool = False) -> float | None:
    """The cell as a float >= lo (> lo with ``low_open``), None when empty."""
    if raw is None or raw.strip() == "":
        return None
    try:
        value = float(raw)
    except ValueError:
        raise DatasetError(column, f"{where}: {column} = {raw!r} is not a number") from None
    if not math.isfinite(value) or value < lo or (low_open and value == lo):
        need = f"> {lo:g}" if low_open else f">= {lo:g}"
        raise DatasetError(column, f"{where}: {column} = {raw!r}: need a finite value {need}")
    return value


def _amplitude(raw: str | None, where: str, column: str) -> float | None:
    """An amplitude or amplitude ratio: strictly positive (the models learn its logarithm, and
    a zero center amplitude has no normalized edge)."""
    return _float_or_none(raw, where, column, 0.0, low_open=True)


# --------------------------------------------------------------------------- public API


def ingest_profile(path: str | Path, out: str | Path, values: Mapping[str, Any],
                   space: Space | str | Path | None = None, *,
                   center_amplitude_um: float | None = None, source: str | None = None,
                   distance_unit: str | None = None, amplitude_unit: str | None = None,
                   columns: tuple[int, int] = (0, 1)) -> IngestReport:
    """Add one externally computed amplitude-vs-distance profile (see module docstring) for
    the design point ``values`` (parameter name -> value) to dataset ``out``."""
    path, out = Path(path), Path(out)
    store, space = _open_target(out, space)
    _unknown(values, space, "values")
    where = str(path)
    vals = _check_values(space, values, where)
    center = None
    if path.suffix.lower() == ".json":  # a `hapticrom simulate --json` result (old or new)

        dist, amp, center = read_simulate_json(path)
    else:
        dist, amp = read_profile_csv(path, distance_unit, amplitude_unit, columns)
    sid, scene_json = _scene_row(space, vals, where)
    if center_amplitude_um is not None:
        center = _amplitude(str(center_amplitude_um), where, "center_amplitude_um")
    edge = _edge_from_profile(dist, amp)
    src = f"ingest:{source or path.name}"
    row = {**vals, **_amplitudes(center, edge, None, where), "sample_id": sid,
           "sample_index": 0, "status": "ok", "source": src, "scene_json": scene_json,
           "profile_distance_mm": dist.tolist(), "profile_magnitude_um": amp.tolist()}
    return _write(out, store, space, [row], src, 1)


def _amplitudes(center: float | None, edge: float | None, norm: float | None,
                where: str) -> dict[str, Any]:
    if center is not None and edge is not None:
        ratio = edge / center
        if norm is not None and not math.isclose(norm, ratio, rel_tol=1e-3, abs_tol=1e-9):
            raise DatasetError("normalized_edge", f"{where}: normalized_edge = {norm!r} but "
                               f"edge/center = {ratio:.6g}")
        norm = ratio
    return {"center_amplitude_um": center, "edge_amplitude_um": edge, "normalized_edge": norm}


def _unknown(given: Mapping[str, Any], space: Space, what: str) -> None:
    for name in given:
        if name not in space.names:
            raise SpaceError(what, f"{what} {name}: unknown parameter; the space has "
                             f"{', '.join(space.names)}")


def ingest_table(path: str | Path, out: str | Path, space: Space | str | Path | None = None,
                 *, values: Mapping[str, Any] | None = None, source: str | None = None,
                 distance_unit: str | None = None, amplitude_unit: str | None = None,
                 columns: tuple[int, int] = (0, 1)) -> IngestReport:
    """Add every row of a parameters + amplitudes CSV (see module docstring) to ``out``.
    ``values`` gives parameters missing from the file; the unit options apply to the
    profile files the table points to."""
    path, out = Path(path), Path(out)
    store, space = _open_target(out, space)
    values = dict(values or {})
    _unknown(values, space, "values")
    header, records = _read_table(path)
    allowed = set(space.names) | set(_OUTPUT_COLUMNS)
    for col in header:
        if col not in allowed:
            raise DatasetError(col, f"{path}: unknown column {col!r}; allowed: parameters "
                               f"{', '.join(space.names)} and {', '.join(_OUTPUT_COLUMNS)}")
        if col in values:
            raise DatasetError(col, f"{path}: {col} is both a column and given with --set")
    src = f"ingest:{source or path.name}"
    rows: list[dict[str, Any]] = []
    seen: dict[str, int] = {}
    for i, (ln, rec) in enumerate(records):
        where = f"{path}:{ln}"
        row = _table_row(space, {**values, **rec}, path, where, (distance_unit,
                                                                 amplitude_unit, columns))
        if row["sample_id"] in seen:
            raise DatasetError(str(path), f"{where}: same design point as line "
                               f"{seen[row['sample_id']]}")
        seen[row["sample_id"]] = ln
        rows.append({**row, "sample_index": i, "status": "ok", "source": src})
    if not rows:
        raise DatasetError(str(path), f"{path}: no data rows")
    return _write(out, store, space, rows, src, len(rows))


def _read_table(path: Path) -> tuple[list[str], list[tuple[int, dict[str, str]]]]:
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as err:
        raise DatasetError(str(path), f"cannot read table {path}: {err}") from None
    lines = [(ln, line) for ln, line in enumerate(text.splitlines(), 1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise DatasetError(str(path), f"{path}: empty file (need a header row)")
    reader = csv.reader(io.StringIO("\n".join(line for _, line in lines)))
    parsed = list(reader)
    header = [h.strip() for h in parsed[0]]
    if len(set(header)) != len(header):
        raise DatasetError(str(path), f"{path}: repeated column names in the header")
    records = []
    for (ln, _), fields in zip(lines[1:], parsed[1:], strict=True):
        if len(fields) != len(header):
            raise DatasetError(str(path), f"{path}:{ln}: {len(fields)} fields, the header "
                               f"has {len(header)}")
        records.append((ln, dict(zip(header, fields, strict=True))))
    return header, records


def _table_row(space: Space, rec: Mapping[str, Any], path: Path, where: str,
               profile_opts: tuple[Any, Any, tuple[int, int]]) -> dict[str, Any]:
    vals = _check_values(space, {k: v for k, v in rec.items() if k in space.names}, where)
    sid, scene_json = _scene_row(space, vals, where)
    center = _amplitude(rec.get("center_amplitude_um"), where, "center_amplitude_um")
    edge = _amplitude(rec.get("edge_amplitude_um"), where, "edge_amplitude_um")
    norm = _amplitude(rec.get("normalized_edge"), where, "normalized_edge")
    row: dict[str, Any] = {**vals, "sample_id": sid, "scene_json": scene_json,
                           "wall_s": _float_or_none(rec.get("wall_s"), where, "wall_s")}
    dofs = _float_or_none(rec.get("dofs"), where, "dofs", lo=1.0)
    row["dofs"] = int(dofs) if dofs is not None else None
    pfile = (rec.get("profile_file") or "").strip()
    if pfile:
        dist, amp = read_profile_csv(path.parent / pfile, *profile_opts)
        row["profile_distance_mm"], row["profile_magnitude_um"] = dist.tolist(), amp.tolist()
        edge = edge if edge is not None else _edge_from_profile(dist, amp)
    if center is None and edge is None and not pfile:
        raise DatasetError(str(path), f"{where}: no result: give center_amplitude_um, "
                           "edge_amplitude_um or profile_file")
    row.update(_amplitudes(center, edge, norm, where))
    return row


def parse_assignments(items: Sequence[str]) -> dict[str, str]:
    """``["a=1", "b=x"]`` -> ``{"a": "1", "b": "x"}`` (values stay strings: the space
    converts and checks them). Raises :class:`DatasetError` for malformed items."""
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise DatasetError("set", f"{item!r}: expected NAME=VALUE")
        if name.strip() in out:
            raise DatasetError("set", f"{name.strip()} given twice")
        out[name.strip()] = value.strip()
    return out


def looks_like_table(path: str | Path) -> bool:
    """True when the first non-comment line of ``path`` names an amplitude or profile column
    (a table); otherwise the file is read as a profile export."""
    try:
        with open(path, encoding="utf-8-sig") as fh:
            for line in fh:
                s = line.strip()
                if s and not s.startswith(("#", "%")):
                    return any(c in s for c in ("center_amplitude_um", "edge_amplitude_um",
                                                "profile_file"))
    except (OSError, UnicodeDecodeError) as err:
        raise DatasetError(str(path), f"cannot read {path}: {err}") from None
    return False
