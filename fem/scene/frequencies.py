"""The drive frequency field: one frequency, or the band of a sweep (a list or a
``{start, stop, step}`` table), with its own reader."""

from __future__ import annotations

import math
from typing import Any

from fieldspec import REQUIRED, Context, Spec, check_interval, read_number

__all__ = ["MAX_SWEEP_FREQUENCIES", "Frequencies", "band_grid", "read_frequencies"]

#: Most frequencies one sweep may ask for (each is a row of the result).
MAX_SWEEP_FREQUENCIES = 100_000
_STEP = Spec(float, REQUIRED, "(0, 1e5]")


class Frequencies:
    """Spec kind marker: a number (Hz), a non-empty list of strictly increasing numbers, or a
    table ``{start, stop, step}`` (Hz); ``Spec.interval`` bounds every frequency."""


def band_grid(start: float, stop: float, step: float) -> tuple[float, ...]:
    """``start, start + step, ...`` up to ``stop`` (included when it lies on the grid, to
    1e-9 of a step), each rounded to 1e-9 Hz so that the same band always gives the same
    floats."""
    n = math.floor((stop - start) / step + 1e-9) + 1
    return tuple(round(start + step * i, 9) for i in range(n))


def read_frequencies(value: Any, spec: Spec, path: str,
                     ctx: Context) -> float | tuple[float, ...]:
    """A float for one frequency; a tuple of floats for a band (list or table)."""
    if isinstance(value, dict):
        return _read_band_table(value, spec, path, ctx)
    if isinstance(value, list | tuple):
        if not value:
            raise ctx.error(path, f"{path} = [] is empty: give at least one frequency in Hz")
        freqs = []
        for i, item in enumerate(value):
            where = f"{path}[{i}]"
            f = read_number(item, float, where, ctx)
            check_interval(f, spec, "frequency_hz", where, ctx)
            if freqs and not f > freqs[-1]:
                raise ctx.error(where, f"{where} = {f!r} is out of range: frequencies must "
                                f"increase strictly, allowed > {freqs[-1]:g}")
            freqs.append(f)
        return _checked_size(tuple(freqs), path, ctx)
    f = read_number(value, float, path, ctx)
    check_interval(f, spec, "frequency_hz", path, ctx)
    return f


def _read_band_table(value: dict, spec: Spec, path: str, ctx: Context) -> tuple[float, ...]:
    extra = sorted(set(value) - {"start", "stop", "step"})
    if extra:
        raise ctx.error(f"{path}.{extra[0]}", f"{path}.{extra[0]} is not a key of a band: "
                        "allowed start, stop, step (Hz)")
    got = {}
    for key in ("start", "stop", "step"):
        if key not in value:
            raise ctx.error(f"{path}.{key}", f"{path}.{key} is missing: a band is "
                            "{ start = ..., stop = ..., step = ... } in Hz")
        got[key] = read_number(value[key], float, f"{path}.{key}", ctx)
    for key in ("start", "stop"):
        check_interval(got[key], spec, "frequency_hz", f"{path}.{key}", ctx)
    check_interval(got["step"], _STEP, "step", f"{path}.step", ctx)
    if not got["stop"] > got["start"]:
        raise ctx.error(f"{path}.stop", f"{path}.stop = {got['stop']!r} is out of range: "
                        f"allowed stop > start (= {got['start']:g})")
    count = (got["stop"] - got["start"]) / got["step"] + 1
    if count > MAX_SWEEP_FREQUENCIES:
        raise ctx.error(f"{path}.step", f"{path}.step = {got['step']!r} gives {count:.3g} "
                        f"frequencies: allowed step >= "
                        f"{(got['stop'] - got['start']) / (MAX_SWEEP_FREQUENCIES - 1):.3g} "
                        f"(at most {MAX_SWEEP_FREQUENCIES})")
    return band_grid(got["start"], got["stop"], got["step"])


def _checked_size(freqs: tuple[float, ...], path: str, ctx: Context) -> tuple[float, ...]:
    if len(freqs) > MAX_SWEEP_FREQUENCIES:
        raise ctx.error(path, f"{path} lists {len(freqs)} frequencies: allowed at most "
                        f"{MAX_SWEEP_FREQUENCIES}")
    return freqs
