"""The plan record: ``plan.json`` as a versioned, sealed document, and its check as untrusted
input.

A plan is a file a user edits, copies and receives from others; nothing in it may raise a drive
limit (those come from the device, the actuator and the user: :mod:`hardware.limits`), and an
edited plan must be recognisable as edited. So ``hapticrom plan`` writes

* ``schema_version`` (:data:`SCHEMA_VERSION`) and ``kind`` (:data:`KIND`);
* ``plan_sha256``: the sha256 hex digest of the canonical JSON of the plan without that key,
  ``json.dumps(plan, sort_keys=True, separators=(",", ":"), ensure_ascii=False)`` in UTF-8
  (the form of the model card's ``card_sha256``).

:func:`check_plan` validates every number a player uses against its type and its physical
range (levels, times [ms], voltages [V], frequencies [Hz], positions [mm], amplitudes [um]),
optionally against the JSON Schema ``hapticrom/schemas/plan.json`` too (:func:`schema_problems`,
the subset of JSON Schema that file uses), and recomputes the digest: the answer says whether
the plan is ``sealed`` (digest matches), ``edited`` (it does not) or ``unsealed`` (a plan of
the layout before schema version 1: ``format = "hapticrom-plan"``, ``version = 1``, no
digest; still read). A digest only detects edits; it is not a signature: anyone can re-seal
an edited plan, which is why the limits never come from the plan.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from dataclasses import dataclass, field, fields
from typing import Any

from fieldspec import FieldError

__all__ = ["DIGEST_KEY", "KIND", "LEGACY_FORMAT", "SCHEMA_VERSION", "PlanCheck", "PlanRecord",
           "PlanRecordError", "canonical_digest", "check_plan", "plan_digest", "schema_problems",
           "seal_plan"]

SCHEMA_VERSION = 1
KIND = "hapticrom.plan"
LEGACY_FORMAT = "hapticrom-plan"  # the layout before schema_version 1 (format/version keys)
DIGEST_KEY = "plan_sha256"

MAX_SITES = 256  # the planner's largest array (free sites); the protocol addresses 255
POSITION_MM = 1000.0  # |x|, |y| of a site [mm] (the layout's bound)
FREQUENCY_HZ = (0.0, 1e4)  # drive frequency (the layout's bound) [Hz]
AMPLITUDE_UM = 1e4  # any skin amplitude [um] (1 cm: far beyond any ERM)
TIME_MS = 1e4  # any timing entry [ms] (an ERM settles in tens of ms)
VOLTAGE_V = 50.0  # any drive voltage [V] (the scene's rated-voltage bound)
MAX_VERIFY_TOP = 32  # verify.top_k: candidates re-solved with the FE, at most
LEVEL = (1.0, 8.0)  # overdrive_level: a multiple of the nominal drive (the protocol's range)

#: timing key -> (low, high, low inclusive); a number or null (timing unavailable)
TIMING_RANGES: dict[str, tuple[float, float, bool]] = {
    "rise_ms": (0, TIME_MS, True), "decay_ms": (0, TIME_MS, True),
    "overdrive_ms": (0, TIME_MS, True), "overdrive_level": (*LEVEL, True),
    "brake_ms": (0, TIME_MS, True), "min_isi_ms": (0, TIME_MS, True),
    "nominal_voltage_V": (0, VOLTAGE_V, False), "overdrive_voltage_V": (0, VOLTAGE_V, False),
    "brake_voltage_V": (-VOLTAGE_V, 0, True), "steady_envelope_um": (0, AMPLITUDE_UM, True),
    "t90_ms": (0, TIME_MS, True), "rise_overdrive_ms": (0, TIME_MS, True),
    "settle_ms": (0, TIME_MS, True), "min_isi_unbraked_ms": (0, TIME_MS, True),
    "isi_level_fraction": (0, 1, False), "tau_spinup_ms": (0, 1000, False),
    "tau_spindown_ms": (0, 1000, False)}


class PlanRecordError(FieldError):
    """A plan that breaks its schema or a physical range (``.field`` names the key)."""


def _canonical(d: dict[str, Any]) -> bytes:
    return json.dumps(d, sort_keys=True, separators=(",", ":"), ensure_ascii=False).encode(
        "utf-8")


def canonical_digest(document: dict[str, Any], key: str) -> str:
    """sha256 hex of the canonical JSON of ``document`` without its digest ``key`` (the form of
    every sealed record: plan.json, the design record)."""
    return hashlib.sha256(_canonical({k: v for k, v in document.items() if k != key}))\
        .hexdigest()


def plan_digest(plan: dict[str, Any]) -> str:
    """sha256 hex of the canonical JSON of ``plan`` without ``plan_sha256``."""
    return canonical_digest(plan, DIGEST_KEY)


def seal_plan(plan: dict[str, Any]) -> dict[str, Any]:
    """A copy of ``plan`` with ``schema_version``, ``kind`` and ``plan_sha256`` (a plan of the
    old layout loses its ``format``/``version`` keys: migrated)."""
    out = {"schema_version": SCHEMA_VERSION, "kind": KIND,
           **{k: v for k, v in plan.items() if k not in ("format", "version", DIGEST_KEY,
                                                         "schema_version", "kind")}}
    out[DIGEST_KEY] = plan_digest(out)
    return out


@dataclass(frozen=True)
class PlanCheck:
    """The integrity of a plan that passed the checks: ``status`` is ``sealed``, ``edited``
    or ``unsealed``; ``recorded`` the digest the file carries, ``actual`` its recomputation."""

    status: str
    recorded: str | None
    actual: str

    @property
    def trusted(self) -> bool:
        return self.status == "sealed"

    def describe(self) -> str:
        if self.status == "sealed":
            return f"sealed (plan_sha256 {self.actual[:12]}...)"
        if self.status == "edited":
            return (f"edited after `hapticrom plan` wrote it: plan_sha256 records "
                    f"{self.recorded[:12]}..., the content hashes to {self.actual[:12]}...")
        return "unsealed (a plan written before plan records: no plan_sha256)"


def _num(v: Any, path: str, lo: float, hi: float, lo_incl: bool = True,
         hi_incl: bool = True) -> float:
    ok = isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) and (
        (v >= lo) if lo_incl else (v > lo)) and ((v <= hi) if hi_incl else (v < hi))
    if not ok:
        allowed = f"{lo:g} {'<=' if lo_incl else '<'} {path} {'<=' if hi_incl else '<'} {hi:g}"
        raise PlanRecordError(path, f"plan.{path} = {v!r}: expected a number, allowed "
                              f"{allowed}")
    return float(v)


def _list(v: Any, path: str, n: int | None = None) -> list[Any]:
    if not isinstance(v, list) or (n is not None and len(v) != n):
        want = "a list" if n is None else f"a list of {n}"
        raise PlanRecordError(path, f"plan.{path}: expected {want}, got "
                              f"{type(v).__name__}{'' if not isinstance(v, list) else len(v)}")
    return v


def _header(d: Any) -> str | None:
    """The recorded digest (None for a plan of the old layout or one never sealed); raises on
    a non-plan."""
    if not isinstance(d, dict):
        raise PlanRecordError("<file>", "not a hapticrom plan: expected a JSON object")
    if d.get("format") == LEGACY_FORMAT and "kind" not in d:
        if d.get("version") != 1:
            raise PlanRecordError("version", f"plan.version = {d.get('version')!r}: this "
                                  "hapticrom reads version 1 of the old plan layout")
        return None
    if d.get("kind") != KIND:
        raise PlanRecordError("kind", f"plan.kind = {d.get('kind')!r}: not a hapticrom plan "
                              f"(expected {KIND!r})")
    if d.get("schema_version") != SCHEMA_VERSION:
        raise PlanRecordError("schema_version", f"plan.schema_version = "
                              f"{d.get('schema_version')!r}: this hapticrom reads version "
                              f"{SCHEMA_VERSION}")
    digest = d.get(DIGEST_KEY)
    if digest is None:
        return None  # written by plan_to_dict, never sealed
    if not isinstance(digest, str) or not re.fullmatch(r"[0-9a-f]{64}", digest):
        raise PlanRecordError(DIGEST_KEY, f"plan.{DIGEST_KEY} = {digest!r}: expected 64 "
                              "lower-case hex digits (re-plan, or re-seal on purpose)")
    return digest


def _check_array(d: dict[str, Any]) -> None:
    C = _list(d.get("crosstalk_um"), "crosstalk_um")
    n = len(C)
    if not 1 <= n <= MAX_SITES:
        raise PlanRecordError("crosstalk_um", f"plan.crosstalk_um has {n} rows (sites): "
                              f"allowed 1 to {MAX_SITES}")
    for i, row in enumerate(C):
        for j, v in enumerate(_list(row, f"crosstalk_um[{i}]", n)):
            _num(v, f"crosstalk_um[{i}][{j}]", 0.0, AMPLITUDE_UM, i != j)
    for i, p in enumerate(_list(d.get("positions_mm"), "positions_mm", n)):
        for j, v in enumerate(_list(p, f"positions_mm[{i}]", 2)):
            _num(v, f"positions_mm[{i}][{j}]", -POSITION_MM, POSITION_MM)
    for key in ("leakage_ratio", "leakage_um", "criterion_load"):
        if d.get(key) is not None:
            for i, v in enumerate(_list(d[key], key, n)):
                _num(v, f"{key}[{i}]", 0.0, AMPLITUDE_UM)


def _check_numbers(d: dict[str, Any]) -> None:
    if d.get("best_frequency_hz") is not None:
        _num(d["best_frequency_hz"], "best_frequency_hz", *FREQUENCY_HZ, False)
    if d.get("pitch_mm") is not None:
        _num(d["pitch_mm"], "pitch_mm", 0.0, POSITION_MM, False)
    for i, c in enumerate(_list(d.get("candidates", []), "candidates")):
        if not isinstance(c, dict):
            raise PlanRecordError(f"candidates[{i}]", f"plan.candidates[{i}]: expected an "
                                  "object")
        _num(c.get("frequency_hz"), f"candidates[{i}].frequency_hz", *FREQUENCY_HZ, False)
    crit = d.get("criterion")
    if isinstance(crit, dict):
        if "drive_level" in crit:
            _num(crit["drive_level"], "criterion.drive_level", 0.0, 10.0, False)
        if "max_ratio" in crit:
            _num(crit["max_ratio"], "criterion.max_ratio", 0.0, 1.0, False)
    _check_verify(d.get("verify"))
    t = d.get("timing")
    if isinstance(t, dict):
        for key, (lo, hi, lo_incl) in TIMING_RANGES.items():
            if t.get(key) is not None:
                _num(t[key], f"timing.{key}", lo, hi, lo_incl)
        if "unavailable" in t and not isinstance(t["unavailable"], str):
            raise PlanRecordError("timing.unavailable", "plan.timing.unavailable: expected "
                                  "a text saying why")
    elif t is not None:
        raise PlanRecordError("timing", "plan.timing: expected an object or null")


def _check_verify(v: Any) -> None:
    """``verify`` (``plan --verify``): an object or null; its frequencies, counts and verdict
    flags typed (a block written before the re-ranking has only the winner's keys)."""
    if v is None:
        return
    if not isinstance(v, dict):
        raise PlanRecordError("verify", "plan.verify: expected an object or null")
    if "frequency_hz" in v:
        _num(v["frequency_hz"], "verify.frequency_hz", *FREQUENCY_HZ, False)
    for key in ("holds", "winner_agrees", "within_tolerance", "confirmed"):
        if key in v and not isinstance(v[key], bool):
            raise PlanRecordError(f"verify.{key}", f"plan.verify.{key} = {v[key]!r}: expected "
                                  "true or false")
    if "top_k" in v:
        _num(v["top_k"], "verify.top_k", 1, MAX_VERIFY_TOP)
    for i, c in enumerate(_list(v.get("candidates", []), "verify.candidates")):
        if not isinstance(c, dict):
            raise PlanRecordError(f"verify.candidates[{i}]", f"plan.verify.candidates[{i}]: "
                                  "expected an object")
        _num(c.get("frequency_hz"), f"verify.candidates[{i}].frequency_hz", *FREQUENCY_HZ,
             False)


def check_plan(d: Any, schema: dict[str, Any] | None = None) -> PlanCheck:
    """Validate ``d`` as a plan (its header, every number a player uses against its physical
    range, and ``schema`` when given); raises :class:`PlanRecordError` naming the key; returns
    whether it is sealed, edited or unsealed."""
    recorded = _header(d)
    if schema is not None and "kind" in d:
        found = schema_problems(d, schema)
        if found:
            path, message = found[0]
            raise PlanRecordError(path, f"plan.{path}: {message} (hapticrom/schemas/plan.json); "
                                  "re-plan with `hapticrom plan`")
    for key in ("model", "best"):
        if d.get(key) is not None and not isinstance(d[key], str):
            raise PlanRecordError(key, f"plan.{key}: expected a string")
    if d.get("best") is not None:
        _check_array(d)
    _check_numbers(d)
    actual = plan_digest(d)
    if recorded is None:
        return PlanCheck("unsealed", None, actual)
    return PlanCheck("sealed" if recorded == actual else "edited", recorded, actual)



_HEADER = ("schema_version", "kind", DIGEST_KEY, "format", "version")


@dataclass(frozen=True)
class PlanRecord:
    """``plan.json`` as a typed record, the one form the planner writes and a player reads.

    The keys of ``hapticrom/schemas/plan.json`` are fields (amplitudes in um, positions and
    pitches in mm, frequencies in Hz; nested parts stay JSON objects, described there and in
    docs/planner.md); ``extra`` keeps keys this version does not name, so a plan read and
    written again keeps them. ``check`` is the integrity of a record read from a file
    (None for one just made). :meth:`to_json` writes it sealed (:func:`seal_plan`);
    :meth:`from_json` reads it as untrusted input (:func:`check_plan`: header and version,
    ``schema`` when given, every number in its physical range, the digest)."""

    model: str | None = None
    array: dict[str, Any] | None = None
    criterion: dict[str, Any] | None = None
    site: Any = None
    candidates: list[dict[str, Any]] = field(default_factory=list)
    best: str | None = None
    best_inputs: dict[str, Any] | None = None
    best_frequency_hz: float | None = None
    pitch_mm: float | None = None
    margin: float | None = None
    positions_mm: list[list[float]] = field(default_factory=list)
    crosstalk_um: list[list[float]] = field(default_factory=list)
    leakage_ratio: list[Any] = field(default_factory=list)
    leakage_um: list[Any] = field(default_factory=list)
    criterion_load: list[Any] = field(default_factory=list)
    uncertainty: dict[str, Any] | None = None
    timing: dict[str, Any] | None = None
    validity: Any = None
    dropped_frequencies: list[Any] = field(default_factory=list)
    not_playable: list[Any] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    verify: dict[str, Any] | None = None
    tissue: dict[str, Any] | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    check: PlanCheck | None = field(default=None, compare=False)

    @property
    def verify_confirmed(self) -> bool | None:
        """The FE's verdict of ``plan --verify``: True (confirmed), False (refuted), None
        without one or for a ``verify`` block written before the top-K re-ranking (it
        judged the criterion alone: ``verify["holds"]``)."""
        v = self.verify
        return None if not isinstance(v, dict) or "confirmed" not in v else bool(
            v["confirmed"])

    def to_dict(self) -> dict[str, Any]:
        """The plan's content, not yet sealed (``verify``/``tissue`` only when present)."""
        out = {f.name: getattr(self, f.name) for f in fields(self)
               if f.name not in ("extra", "check")}
        for key in ("verify", "tissue"):
            if out[key] is None:
                del out[key]
        return {**out, **self.extra}

    def to_json(self) -> dict[str, Any]:
        """The sealed document: ``schema_version``, ``kind``, the content, ``plan_sha256``."""
        return seal_plan(self.to_dict())

    @classmethod
    def from_json(cls, d: Any, schema: dict[str, Any] | None = None) -> PlanRecord:
        """Read ``d`` (a parsed ``plan.json``) as untrusted input; raises
        :class:`PlanRecordError` naming the key."""
        check = check_plan(d, schema)
        names = {f.name for f in fields(cls)} - {"extra", "check"}
        known = {k: v for k, v in d.items() if k in names}
        extra = {k: v for k, v in d.items() if k not in names and k not in _HEADER}
        return cls(**known, extra=extra, check=check)


# ---- the JSON Schema subset of hapticrom/schemas/plan.json ----------------------------------

_TYPES = {
    "object": lambda v: isinstance(v, dict), "array": lambda v: isinstance(v, list),
    "string": lambda v: isinstance(v, str), "boolean": lambda v: isinstance(v, bool),
    "null": lambda v: v is None,
    "integer": lambda v: isinstance(v, int) and not isinstance(v, bool),
    "number": lambda v: isinstance(v, int | float) and not isinstance(v, bool)
    and math.isfinite(v)}
_BOUNDS = {"minimum": lambda v, b: v >= b, "maximum": lambda v, b: v <= b,
           "exclusiveMinimum": lambda v, b: v > b, "exclusiveMaximum": lambda v, b: v < b}
SCHEMA_KEYWORDS = {"$schema", "$id", "title", "description", "type", "const", "enum",
                   "pattern", "properties", "required", "additionalProperties", "items",
                   "minItems", "maxItems", *_BOUNDS}


def schema_problems(value: Any, schema: dict[str, Any], path: str = "") -> list[
        tuple[str, str]]:
    """Every way ``value`` breaks ``schema`` as (dotted path, message); empty when it
    conforms. Supports the keywords of :data:`SCHEMA_KEYWORDS` (raises on any other)."""
    unknown = set(schema) - SCHEMA_KEYWORDS
    if unknown:
        raise ValueError(f"schema keywords not supported: {sorted(unknown)}")
    where = path or "<plan>"
    if "type" in schema:
        types = schema["type"] if isinstance(schema["type"], list) else [schema["type"]]
        if not any(_TYPES[t](value) for t in types):
            return [(where, f"expected {' or '.join(types)}, got {value!r:.60}")]
    out: list[tuple[str, str]] = []
    if "const" in schema and value != schema["const"]:
        out.append((where, f"expected {schema['const']!r}, got {value!r:.60}"))
    if "enum" in schema and value not in schema["enum"]:
        out.append((where, f"{value!r:.60} is not one of {schema['enum']}"))
    if _TYPES["number"](value):
        out += [(where, f"{value!r} breaks {k} {schema[k]}") for k, ok in _BOUNDS.items()
                if k in schema and not ok(value, schema[k])]
    if isinstance(value, str) and "pattern" in schema and not re.search(schema["pattern"],
                                                                         value):
        out.append((where, f"{value!r:.60} does not match {schema['pattern']}"))
    if isinstance(value, dict):
        props = schema.get("properties", {})
        out += [(f"{path}.{k}" if path else k, "missing") for k in schema.get("required", [])
                if k not in value]
        extra = schema.get("additionalProperties", True)
        for key, v in value.items():
            sub = f"{path}.{key}" if path else key
            if key in props:
                out += schema_problems(v, props[key], sub)
            elif extra is False:
                out.append((sub, "unexpected key"))
            elif isinstance(extra, dict):
                out += schema_problems(v, extra, sub)
    if isinstance(value, list):
        if not schema.get("minItems", 0) <= len(value) <= schema.get("maxItems", math.inf):
            out.append((where, f"{len(value)} items: allowed {schema.get('minItems', 0)} to "
                        f"{schema.get('maxItems', 'any number')}"))
        if "items" in schema:
            for i, v in enumerate(value):
                out += schema_problems(v, schema["items"], f"{path}[{i}]")
    return out
