"""Measurement files: measured skin-surface vibration around one haptic unit (docs/calibration.md).

A CSV file, optionally preceded by ``# key = value`` lines (the unit design, known tissue
inputs, the subject, the source)::

    # format = hapticrom-measurement 1
    # subject = forearm, volar, 60 mm below the elbow
    # design.orientation = forward
    # design.attachment = glued
    # design.n_rings = 0
    reference,distance_mm,frequency_hz,quantity,unit,statistic,component,value,uncertainty
    centre,0,150,acceleration,g,rms,normal,1.21,5%
    edge,4,150,velocity,mm/s,peak,normal,4.5,0.3

Each row is converted once, here, into the model's quantity: the peak displacement amplitude
[m] (the modulus of the complex Fourier amplitude of the harmonic steady state) of the
component named, with its standard uncertainty [m]. Every bad row is named (row number as
counted in the file, column, allowed values) in one :class:`MeasurementError`.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fieldspec import FieldError

__all__ = ["COLUMNS", "COMPONENTS", "FORMAT", "QUANTITY_UNITS", "REFERENCES", "STATISTICS",
           "MeasuredPoint", "Measurement", "MeasurementError", "measurement_from_rows",
           "read_measurement", "write_measurement"]

FORMAT = "hapticrom-measurement 1"
G_M_S2 = 9.80665  # standard gravity [m/s^2]
COLUMNS = ("reference", "distance_mm", "frequency_hz", "quantity", "unit", "statistic",
           "component", "value", "uncertainty")
REFERENCES = ("centre", "edge")
COMPONENTS = ("normal", "magnitude")
#: quantity -> unit -> (factor to SI, time derivative order)
QUANTITY_UNITS: dict[str, dict[str, tuple[float, int]]] = {
    "displacement": {"um": (1e-6, 0), "mm": (1e-3, 0)},
    "velocity": {"mm/s": (1e-3, 1), "m/s": (1.0, 1)},
    "acceleration": {"m/s^2": (1.0, 2), "g": (G_M_S2, 2)},
}
#: statistic -> factor from it to the peak amplitude of a sinusoid
STATISTICS = {"peak": 1.0, "rms": math.sqrt(2.0), "peak-to-peak": 0.5}
MAX_ERRORS = 25  # rows listed in one error message
META_PREFIXES = ("design.", "site.")
META_KEYS = ("format", "subject", "source", "note")


class MeasurementError(FieldError):
    """A bad measurement file or row; ``.field`` names the first offending value
    (``row 5: unit``) and the message lists every bad row."""


@dataclass(frozen=True)
class MeasuredPoint:
    """One measured value, as given and converted (SI: m, Hz)."""

    row: int  # line number in the file (1 = first line), or the index given in Python
    reference: str  # "centre" | "edge"
    distance_m: float  # from the unit's centre or edge [m]
    frequency_hz: float
    quantity: str
    unit: str
    statistic: str
    component: str  # "normal" | "magnitude"
    value: float  # as given, in ``unit``
    uncertainty: float  # as given, in ``unit`` (one standard deviation)
    amplitude_m: float  # converted: peak displacement amplitude [m]
    sigma_m: float  # its standard uncertainty [m]

    @property
    def relative_sigma(self) -> float:
        """Standard uncertainty over the value (the same in every unit)."""
        return self.sigma_m / self.amplitude_m


@dataclass(frozen=True)
class Measurement:
    """A validated measurement: its points, the unit design (model inputs by name) and known
    tissue inputs (``site``), and free-text metadata."""

    points: tuple[MeasuredPoint, ...]
    design: dict[str, Any] = field(default_factory=dict)
    site: dict[str, Any] = field(default_factory=dict)
    meta: dict[str, str] = field(default_factory=dict)
    source: str = ""  # the file read, if any

    @property
    def frequencies_hz(self) -> tuple[float, ...]:
        """The distinct measured frequencies, ascending."""
        return tuple(sorted({p.frequency_hz for p in self.points}))


def to_amplitude_m(value: float, quantity: str, unit: str, statistic: str,
                   frequency_hz: float) -> float:
    """``value`` (quantity, unit, statistic) as a peak displacement amplitude [m] of a sinusoid
    at ``frequency_hz``: divided by (2 pi f)^order for velocity (1) and acceleration (2)."""
    factor, order = QUANTITY_UNITS[quantity][unit]
    return value * factor * STATISTICS[statistic] / (2.0 * math.pi * frequency_hz) ** order


def from_amplitude_m(amplitude_m: float, quantity: str, unit: str, statistic: str,
                     frequency_hz: float) -> float:
    """The inverse of :func:`to_amplitude_m` (for writing synthetic measurements)."""
    return amplitude_m / to_amplitude_m(1.0, quantity, unit, statistic, frequency_hz)


def _number(text: Any) -> float | None:
    try:
        x = float(str(text).strip())
    except ValueError:
        return None
    return x if math.isfinite(x) else None


def _point(rec: Mapping[str, Any], row: int, errors: list[tuple[str, str]]) -> MeasuredPoint | None:
    """One row's point, or None with its problems appended as (field, message)."""
    n0 = len(errors)

    def bad(col: str, msg: str) -> None:
        errors.append((f"row {row}: {col}", f"row {row}, column {col}: {msg}"))

    vals = {c: str(rec.get(c, "") if rec.get(c) is not None else "").strip() for c in COLUMNS}
    choices = {"reference": REFERENCES, "component": COMPONENTS,
               "statistic": tuple(STATISTICS), "quantity": tuple(QUANTITY_UNITS)}
    for col, allowed in choices.items():
        if vals[col] not in allowed:
            bad(col, f"{vals[col]!r} is not one of {', '.join(allowed)}")
    q = vals["quantity"]
    if q in QUANTITY_UNITS and vals["unit"] not in QUANTITY_UNITS[q]:
        bad("unit", f"{vals['unit']!r} is not a unit of {q} (allowed: "
            f"{', '.join(QUANTITY_UNITS[q])})")
    dist, freq, value = (_number(vals[c]) for c in ("distance_mm", "frequency_hz", "value"))
    if dist is None or not 0.0 <= dist <= 1000.0:
        bad("distance_mm", f"{vals['distance_mm']!r}: expected a number in [0, 1000] mm")
    if freq is None or not 0.0 < freq <= 1e4:
        bad("frequency_hz", f"{vals['frequency_hz']!r}: expected a number in (0, 1e4] Hz")
    if value is None or value <= 0.0:
        bad("value", f"{vals['value']!r}: expected a number > 0 (an amplitude in the row's "
            "unit)")
    unc_text = vals["uncertainty"]
    relative = unc_text.endswith("%")
    unc = _number(unc_text[:-1] if relative else unc_text)
    if unc is not None and value is not None and value > 0:
        unc = unc / 100.0 * value if relative else unc
        if not 0.0 < unc < value:
            unc = None
    if unc is None:
        bad("uncertainty", f"{unc_text!r}: expected one standard deviation in the row's unit, "
            "or a percentage of the value ('5%'), > 0 and below the value")
    if len(errors) > n0:
        return None
    assert dist is not None and freq is not None and value is not None and unc is not None
    conv = to_amplitude_m(1.0, q, vals["unit"], vals["statistic"], freq)
    return MeasuredPoint(row, vals["reference"], dist * 1e-3, freq, q, vals["unit"],
                         vals["statistic"], vals["component"], value, unc, value * conv,
                         unc * conv)


def _scalar(text: str) -> Any:
    """A metadata value: an integer, a number, or text."""
    t = text.strip()
    for kind in (int, float):
        try:
            return kind(t)
        except ValueError:
            pass
    return t


def _raise(errors: list[tuple[str, str]], where: str) -> None:
    if not errors:
        return
    lines = [m for _, m in errors[:MAX_ERRORS]]
    more = len(errors) - MAX_ERRORS
    if more > 0:
        lines.append(f"... and {more} more")
    raise MeasurementError(errors[0][0], f"{where}: {len(errors)} bad value(s):\n  "
                           + "\n  ".join(lines))


def measurement_from_rows(rows: Iterable[Mapping[str, Any]], *, design: Mapping[str, Any]
                          | None = None, site: Mapping[str, Any] | None = None,
                          meta: Mapping[str, str] | None = None, first_row: int = 1,
                          source: str = "") -> Measurement:
    """Validate rows (mappings of :data:`COLUMNS`; numbers may be numbers or text) into a
    :class:`Measurement`. Rows are numbered from ``first_row``; every problem is collected
    and raised together as :class:`MeasurementError`."""
    errors: list[tuple[str, str]] = []
    points = []
    for i, rec in enumerate(rows):
        p = _point(rec, first_row + i, errors)
        if p is not None:
            points.append(p)
    if not points and not errors:
        errors.append(("rows", "no measurement rows (give at least one row under the header)"))
    _raise(errors, source or "measurement")
    return Measurement(tuple(points), dict(design or {}), dict(site or {}), dict(meta or {}),
                       source)


def read_measurement(path: str | Path) -> Measurement:
    """Read and validate a measurement CSV (see the module docstring and docs/calibration.md)."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise MeasurementError("<file>", f"cannot read measurement file {str(path)!r}: "
                               f"{err}") from None
    design: dict[str, Any] = {}
    site: dict[str, Any] = {}
    meta: dict[str, str] = {}
    errors: list[tuple[str, str]] = []
    body: list[tuple[int, str]] = []
    for number, line in enumerate(lines, start=1):
        text = line.strip()
        if not text:
            continue
        if text.startswith("#"):
            if body or "=" not in text:
                continue  # a plain comment
            key, _, value = (s.strip() for s in text[1:].partition("="))
            prefix = next((p for p in META_PREFIXES if key.startswith(p)), None)
            if prefix is not None and len(key) > len(prefix):
                (design if prefix == "design." else site)[key[len(prefix):]] = _scalar(value)
            elif key in META_KEYS:
                meta[key] = value
            else:
                errors.append((f"line {number}: {key}", f"line {number}: unknown key {key!r} "
                               f"(allowed: {', '.join(META_KEYS)}, design.<model input>, "
                               "site.<model input>)"))
            continue
        body.append((number, line))
    if meta.get("format", FORMAT) != FORMAT:
        errors.append(("format", f"line: format = {meta['format']!r}: expected {FORMAT!r}"))
    if not body:
        errors.append(("header", f"no header line: expected {','.join(COLUMNS)}"))
    _raise(errors, str(path))
    header_line, header = body[0][0], next(csv.reader([body[0][1]]))
    header = [h.strip() for h in header]
    missing = [c for c in COLUMNS if c not in header]
    unknown = [c for c in header if c not in COLUMNS]
    if missing or unknown:
        col = (missing or unknown)[0]
        raise MeasurementError(f"header: {col}", f"{path}, line {header_line}: "
                               + (f"column {missing[0]!r} is missing" if missing else
                                  f"unknown column {unknown[0]!r}")
                               + f" (the columns are {', '.join(COLUMNS)})")
    pts: list[MeasuredPoint] = []
    for number, line in body[1:]:
        cells = next(csv.reader([line]))
        if len(cells) != len(header):
            errors.append((f"row {number}", f"row {number}: {len(cells)} cells, expected "
                           f"{len(header)} ({','.join(header)})"))
            continue
        p = _point(dict(zip(header, cells, strict=True)), number, errors)
        if p is not None:
            pts.append(p)
    if len(body) == 1 and not errors:
        errors.append(("rows", "no measurement rows under the header"))
    _raise(errors, str(path))
    return Measurement(tuple(pts), design, site, meta, str(path))


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def write_measurement(m: Measurement, path: str | Path) -> None:
    """Write ``m`` as a measurement CSV (values and uncertainties as given in each point)."""
    out = [f"# format = {FORMAT}"]
    out += [f"# {k} = {v}" for k, v in m.meta.items() if k != "format"]
    out += [f"# design.{k} = {v}" for k, v in m.design.items()]
    out += [f"# site.{k} = {v}" for k, v in m.site.items()]
    out.append(",".join(COLUMNS))
    for p in m.points:
        out.append(",".join([p.reference, _fmt(p.distance_m * 1e3), _fmt(p.frequency_hz),
                             p.quantity, p.unit, p.statistic, p.component, _fmt(p.value),
                             _fmt(p.uncertainty)]))
    Path(path).write_text("\n".join(out) + "\n")
