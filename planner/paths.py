"""Model paths in a plan file: stored relative to the plan file's own directory, so a plan
can be played from any working directory (and moved together with the models beside it).

``hapticrom plan --out DIR/plan.json`` writes ``model`` and ``timing.model`` relative to DIR
(:func:`relative_plan_models`); readers resolve them against the plan file's directory
(:func:`resolve_from_plan`). Plans written before this rule held paths relative to the
working directory they were made in: when the path does not exist beside the plan but does
from the working directory, that one is used.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

__all__ = ["relative_plan_models", "relative_to_plan", "resolve_from_plan",
           "resolve_plan_models"]


def relative_to_plan(model: str, plan_path: str | Path) -> str:
    """``model`` (relative to the working directory, or absolute) as a path relative to the
    directory of ``plan_path`` (absolute when no relative path exists, e.g. another drive)."""
    target = Path(model).resolve()
    base = Path(plan_path).resolve().parent
    try:
        return Path(os.path.relpath(target, base)).as_posix()
    except ValueError:  # Windows: another drive
        return str(target)


def resolve_from_plan(model: str, plan_path: str | Path) -> str:
    """A plan's stored model path as a path usable from the working directory."""
    p = Path(model)
    if p.is_absolute():
        return str(p)
    beside = Path(plan_path).parent / p
    if beside.exists() or not p.exists():
        return str(beside)
    return str(p)  # an older plan: relative to the working directory


def resolve_plan_models(data: Any, plan_path: str | Path) -> Any:
    """``data`` (a plan mapping) with ``model`` and ``timing.model`` resolved against the plan
    file's directory (other values untouched; a malformed plan is returned as it is)."""
    if not isinstance(data, dict):
        return data
    if isinstance(data.get("model"), str):
        data["model"] = resolve_from_plan(data["model"], plan_path)
    timing = data.get("timing")
    if isinstance(timing, dict) and isinstance(timing.get("model"), str):
        timing["model"] = resolve_from_plan(timing["model"], plan_path)
    return data


def relative_plan_models(doc: dict[str, Any], plan_path: str | Path) -> dict[str, Any]:
    """A copy of the plan mapping ``doc`` (``planner.plan_to_dict``) with ``model`` and
    ``timing.model`` relative to the directory ``plan_path`` will be written in."""
    out = dict(doc)
    if isinstance(out.get("model"), str):
        out["model"] = relative_to_plan(out["model"], plan_path)
    timing = out.get("timing")
    if isinstance(timing, dict) and isinstance(timing.get("model"), str):
        out["timing"] = {**timing, "model": relative_to_plan(timing["model"], plan_path)}
    return out
