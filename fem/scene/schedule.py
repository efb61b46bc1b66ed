"""The drive voltage schedule of a transient: a field kind with its own reader."""

from __future__ import annotations

from typing import Any

from fieldspec import REQUIRED, Context, Spec, check_interval, read_number

__all__ = ["Schedule", "read_schedule"]

_STEP_TIME = Spec(float, REQUIRED, "[0, 1e5]")  # the t_ms of a schedule step


class Schedule:
    """Spec kind marker: a non-empty list of [t_ms, volts] pairs, the first at t_ms = 0, times
    strictly increasing; ``Spec.interval`` bounds the volts."""


def read_schedule(value: Any, spec: Spec, path: str,
                  ctx: Context) -> tuple[tuple[float, float], ...]:
    """A list of [t_ms, volts] steps: t_ms starts at 0 and increases strictly."""
    if not isinstance(value, list | tuple) or not value:
        raise ctx.error(path, f"{path} = {value!r} has the wrong type: expected a non-empty "
                        "list of [t_ms, volts] pairs, e.g. [[0.0, 3.3], [100.0, 0.0]]")
    steps: list[tuple[float, float]] = []
    for i, pair in enumerate(value):
        where = f"{path}[{i}]"
        if not isinstance(pair, list | tuple) or len(pair) != 2:
            raise ctx.error(where, f"{where} = {pair!r} has the wrong type: expected a "
                            "[t_ms, volts] pair")
        t = read_number(pair[0], float, f"{where}[0]", ctx)
        check_interval(t, _STEP_TIME, "t_ms", f"{where}[0]", ctx)
        if i == 0 and t != 0:
            raise ctx.error(f"{where}[0]", f"{where}[0] = {t!r} is out of range: the "
                            "schedule must start at t_ms = 0")
        if i > 0 and not t > steps[-1][0]:
            raise ctx.error(f"{where}[0]", f"{where}[0] = {t!r} is out of range: times must "
                            f"increase strictly, allowed t_ms > {path}[{i - 1}][0] "
                            f"(= {steps[-1][0]:g})")
        volts = read_number(pair[1], float, f"{where}[1]", ctx)
        check_interval(volts, spec, "volts", f"{where}[1]", ctx)
        steps.append((t, volts))
    return tuple(steps)
