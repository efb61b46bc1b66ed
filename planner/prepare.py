"""Everything a plan checks before it ranks: the models, the validity domain, the request's
values, the drive frequencies the actuator reaches, and the predictions of every candidate.

Order (each failure a :class:`planner.layout.LayoutError` naming the field, exit 2 in the
CLI): the harmonic model; the envelope ROM (when ``[timing] enabled``); the domain, their
intersection (:mod:`planner.domain`); ``[site]`` values (unknown keys under ``site.KEY``);
the ROM's motor time constants (``timing.tau_*``); the drive frequencies (unreachable ones are
dropped and listed, out-of-domain ones refused or flagged); each design's values; then one
batched prediction. Values outside the domain with ``model.allow_extrapolation = true`` are
:class:`planner.domain.Extrapolation` records, kept per candidate.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from motorlaw import SpeedLaw, drive_law
from planner.candidates import expand_any
from planner.domain import Domain, Extrapolation, build_domain, check_value, drive_reach
from planner.layout import LayoutError, LayoutRequest, short_repr
from surrogate.runtime import load_predictor
from surrogate.runtime.encoding import PredictorInputError
from surrogate.runtime.rom import RomBlowUpError, RomInputError, load_envelope_model

__all__ = ["Prepared", "prepare"]


@dataclass
class Prepared:
    """The checked request: models, domain, candidates (design, frequency) and their
    predictions, extrapolations per candidate, and the dropped frequencies."""

    predictor: Any
    rom: Any  # surrogate.runtime.rom.EnvelopeModel or None (timing disabled)
    motor: Any  # the actuator's drive law (the envelope model's, else motorlaw's defaults)
    domain: Domain
    combos: list[tuple[dict[str, Any], float]]
    out: dict[str, np.ndarray]
    extrapolations: list[list[Extrapolation]]
    dropped: list[dict[str, Any]] = field(default_factory=list)
    shared: list[Extrapolation] = field(default_factory=list)  # site and timing values


def load_rom(req: LayoutRequest) -> Any:
    """The envelope model of ``timing.model`` ("": none, the drive law's own envelope),
    trained for ``timing.actuator``."""
    if not req.timing.model:
        return None
    try:
        rom = load_envelope_model(req.timing.model)
    except (OSError, ValueError, KeyError, RomBlowUpError) as err:
        raise LayoutError("timing.model", f"timing.model = {short_repr(req.timing.model)}: "
                          f"{err} (set timing.enabled = false to plan without timing; play "
                          "needs it)") from None
    try:
        rom.check_actuator(req.timing.actuator)
    except RomInputError as err:
        raise LayoutError("timing.actuator", f"timing.actuator = {req.timing.actuator!r}: "
                          f"{req.timing.model} {str(err).split(': ', 2)[-1]} (timing.model = "
                          '"" times it by its drive law alone)') from None
    return rom


def _check_actuator(req: LayoutRequest, predictor: Any) -> None:
    """The harmonic model's amplitudes are those of the actuator it was trained for (its
    card's ``actuator``; a card without one: the coin ERM); another one is refused."""
    trained = str(predictor.card.get("actuator", SpeedLaw.kind))
    if req.timing.actuator != trained:
        raise LayoutError("timing.actuator", f"timing.actuator = {req.timing.actuator!r}: the "
                          f"model {req.model} predicts the amplitudes of the actuator "
                          f"{trained!r} ({drive_law(trained).title}); a plan for another "
                          "actuator needs a harmonic model trained on it")


def _unknown(where: str, key: str, req: LayoutRequest, names: tuple[str, ...]) -> LayoutError:
    return LayoutError(f"{where}.{key}", f"{where}.{key}: not an input of {req.model} "
                       f"(inputs: {', '.join(n for n in names if n != 'frequency_hz')})")


def _site(req: LayoutRequest, domain: Domain, names: tuple[str, ...]) -> list[Extrapolation]:
    out = []
    for key, value in req.site.items():
        if key == "frequency_hz":
            raise LayoutError("site.frequency_hz", "site.frequency_hz: the drive frequency "
                              "goes in [drive] frequencies_hz")
        if key not in names:
            raise _unknown("site", key, req, names)
        x = check_value(domain.bounds[key], value, f"site.{key}", req.allow_extrapolation)
        out += [x] if x else []
    return out


def _timing(req: LayoutRequest, domain: Domain) -> list[Extrapolation]:
    out = []
    for key in ("tau_spinup_ms", "tau_spindown_ms"):
        if key in domain.bounds:
            x = check_value(domain.bounds[key], getattr(req.timing, key), f"timing.{key}",
                            req.allow_extrapolation)
            out += [x] if x else []
    return out


def _frequencies(req: LayoutRequest, domain: Domain, motor: Any
                 ) -> tuple[list[tuple[float, list[Extrapolation]]], list[dict[str, Any]]]:
    kept, dropped = [], []
    for j, f in enumerate(req.frequencies_hz):
        why = drive_reach(motor, f)
        if why is not None:
            dropped.append(why)
            continue
        x = check_value(domain.bounds["frequency_hz"], f, f"drive.frequencies_hz[{j}]",
                        req.allow_extrapolation)
        kept.append((f, [x] if x else []))
    if not kept:
        raise LayoutError("drive.frequencies_hz", f"drive.frequencies_hz: the {motor.noun} "
                          f"reaches none of them: {dropped[0]['reason']}")
    return kept, dropped


def _designs(req: LayoutRequest, predictor: Any, domain: Domain
             ) -> list[tuple[int, dict[str, Any], list[Extrapolation]]]:
    """(index in the request, design, its extrapolations) for every candidate: named designs
    as given, each ``any = true`` table expanded from the domain
    (:func:`planner.candidates.expand_any`)."""
    names = predictor.input_names
    fixed = {*req.site, "frequency_hz"}
    out: list[tuple[int, dict[str, Any], list[Extrapolation]]] = []
    for i, d in enumerate(req.designs):
        where = f"design[{i}]"
        ex = []
        for key, value in d["inputs"].items():
            if key not in names:
                raise _unknown(where, key, req, names)
            x = check_value(domain.bounds[key], value, f"{where}.{key}",
                            req.allow_extrapolation)
            ex += [x] if x else []
        if not d.get("any"):
            missing = [n for n in names if n not in d["inputs"] and n not in fixed]
            if missing:
                raise LayoutError(f"{where}.{missing[0]}", f"{where}: no value for model input "
                                  f"{missing[0]!r}; give it in the design or in [site]")
            out.append((i, d, ex))
            continue
        try:
            drawn = expand_any(d, domain.narrowed_specs(predictor.specs), fixed, where)
        except ValueError as err:
            raise LayoutError(f"{where}.n_candidates", str(err)) from None
        out += [(i, x, ex) for x in drawn]
    return out


def prepare(req: LayoutRequest) -> Prepared:
    """Check the request against its models and predict every candidate (module docstring)."""
    try:
        predictor = load_predictor(req.model)
    except (OSError, ValueError) as err:  # ModelFileError: missing, malformed, altered
        raise LayoutError("model.path", f"model.path = {short_repr(req.model)}: {err}") from None
    _check_actuator(req, predictor)
    rom = load_rom(req) if req.timing.enabled else None
    motor = rom.motor if rom is not None else drive_law(req.timing.actuator)
    domain = build_domain(predictor, req.model, rom, req.timing.model if rom else None)
    names = predictor.input_names
    shared = _site(req, domain, names) + (_timing(req, domain) if rom is not None else [])
    freqs, dropped = _frequencies(req, domain, motor)
    designs = _designs(req, predictor, domain)
    combos = list(itertools.product(designs, freqs))
    rows = [{**req.site, **d["inputs"], "frequency_hz": f} for (_, d, _), (f, _) in combos]
    X = {n: np.array([r[n] for r in rows]) for n in names}
    try:
        out = predictor.predict(X, extrapolate=req.allow_extrapolation)
    except PredictorInputError as err:
        raise LayoutError(f"design.{err.field}", f"design or site input {err}") from None
    return Prepared(predictor, rom, motor, domain, [(d, f) for (_, d, _), (f, _) in combos], out,
                    [shared + dx + fx for (_, _, dx), (_, fx) in combos], dropped, shared)
