"""Structure checks of a transient ROM's coefficients file (:mod:`surrogate.runtime.rom`):
everything ``simulate`` indexes is checked at load, so that a malformed file is refused by
name there and never fails at use. numpy-free."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = ["check_spec", "finite"]


def finite(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ValueError(f"{name}: need a finite number, got {value!r}")
    return float(value)


def check_spec(spec: Mapping[str, Any]) -> None:
    """The design inputs, interactions and motor ranges of a coefficients file: what
    ``simulate`` indexes, so that a malformed file is refused at load, not at use."""
    names = []
    for i, item in enumerate(spec["design"]):
        name = item["name"]
        if not isinstance(name, str) or name in names:
            raise ValueError(f"spec.design[{i}].name: need a new string, got {name!r}")
        names.append(name)
        if "choices" in item:
            ch = item["choices"]
            if not (isinstance(ch, list) and len(ch) == 2 and all(isinstance(c, str) for c in ch)
                    and ch[0] != ch[1]):
                raise ValueError(f"spec.design[{i}].choices: need two different strings")
            continue
        lo, hi = finite(f"spec.design[{i}].low", item["low"]), \
            finite(f"spec.design[{i}].high", item["high"])
        if not lo < hi or (item.get("scale") == "log" and lo <= 0):
            raise ValueError(f"spec.design[{i}]: need low < high (> 0 on a log scale)")
    for pair in spec.get("interactions", []):
        if not (isinstance(pair, list) and len(pair) == 2 and all(p in names for p in pair)):
            raise ValueError(f"spec.interactions: {pair!r} is not a pair of design inputs")
    ranges = spec["motor_ranges"]
    if not isinstance(ranges, Mapping) or set(ranges) != {"tau_spinup_ms", "tau_spindown_ms"}:
        raise ValueError("spec.motor_ranges: need exactly tau_spinup_ms and tau_spindown_ms")
    for key, rng in ranges.items():
        if not (isinstance(rng, list) and len(rng) == 2
                and 0 < finite(key, rng[0]) < finite(key, rng[1])):
            raise ValueError(f"spec.motor_ranges.{key}: need [low, high] with 0 < low < high")
