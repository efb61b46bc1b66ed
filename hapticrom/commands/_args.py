"""argparse value types shared by several subcommands (each error names the value)."""

from __future__ import annotations

import argparse

__all__ = ["positive_int", "seconds"]


def positive_int(text: str) -> int:
    """An integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not >= 1")
    return value


def seconds(text: str) -> float:
    """A duration in (0, 3600] s."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not 0 < value <= 3600:
        raise argparse.ArgumentTypeError(f"{value} is not in (0, 3600]")
    return value
