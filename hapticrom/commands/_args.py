"""argparse value types shared by several subcommands (each error names the value)."""

from __future__ import annotations

import argparse
from collections.abc import Callable

__all__ = ["number_in", "positive_int", "seconds"]


def positive_int(text: str) -> int:
    """An integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not >= 1")
    return value


def number_in(low: float, high: float, unit: str = "") -> Callable[[str], float]:
    """An argparse type: a number in the half-open interval (low, high] (``unit`` for the
    message, e.g. "ms")."""
    interval = f"({low:g}, {high:g}]" + (f" {unit}" if unit else "")

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not low < value <= high:
            raise argparse.ArgumentTypeError(f"{value:g} is not in {interval}")
        return value

    parse.__name__ = f"number in {interval}"
    return parse


#: A duration in (0, 3600] s.
seconds = number_in(0.0, 3600.0, "s")
