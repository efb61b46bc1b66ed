"""Report text helpers: number formats, Markdown tables, the verdict rules, a report section."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

REL_TOL = 0.20  # "agrees" with a paper number: within 20 % of it (stated in the report)


def pct(x: float) -> str:
    return "n/a" if not math.isfinite(x) else f"{100 * x:.1f} %"


def um(x: float) -> str:
    return f"{x:.4g}"


def md_table(columns: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(str(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def near(ours: float, paper: float) -> bool:
    return abs(ours - paper) <= REL_TOL * abs(paper)


def verdict(ok: bool, partly: bool = False) -> str:
    return "agrees" if ok else ("partly" if partly else "disagrees")


def design(letters: str) -> str:
    return "-".join(letters)


def gap_phrase(before: float, after: float, target: float) -> str:
    """Whether a change of definition or parameter brings a value to the paper's."""
    if near(after, target):
        return f"reaches the paper's {pct(target)} (within {REL_TOL:.0%})"
    if abs(after - target) < abs(before - target):
        return f"moves towards the paper's {pct(target)} but does not reach it"
    return f"does not move it towards the paper's {pct(target)}"


@dataclass
class Section:
    """One report section: Markdown text and the numbers behind it (for results.json)."""

    title: str
    text: str
    data: dict = field(default_factory=dict)
    claims: list[list[str]] = field(default_factory=list)  # for the summary: item, paper, ours,
    # verdict


