"""Helpers of the embedding tests (a module of its own: ``conftest`` is a name every test
folder shares, so importing from it picks whichever was loaded first)."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np

from surrogate.runtime.encoding import InputSpec

REPO = Path(__file__).resolve().parents[2]
EMBED = REPO / "embed"


def canonical_sha256(card: dict) -> str:
    """sha256 hex of the canonical JSON of a card without card_sha256 (TEAM interface 1)."""
    body = {k: v for k, v in card.items() if k != "card_sha256"}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def seal_copy(model: str, dest: Path) -> Path:
    """A copy of models/MODEL under dest whose card carries card_sha256."""
    target = dest / model
    shutil.copytree(REPO / "models" / model, target)
    card = json.loads((target / "card.json").read_text())
    card["card_sha256"] = canonical_sha256(card)
    (target / "card.json").write_text(json.dumps(card, indent=1) + "\n")
    return target


def random_designs(card: dict, n: int, seed: int) -> list[dict]:
    """n designs drawn inside the trained range (log-uniform on log inputs, every choice and
    integer), the first rows at the corners of the range."""
    rng = np.random.default_rng(seed)
    rows: list[dict] = [{} for _ in range(n)]
    for d in card["inputs"]:
        s = InputSpec.from_dict(d)
        if s.type == "categorical":
            vals = [s.choices[k] for k in rng.integers(0, len(s.choices), n)]
        elif s.type == "integer":
            vals = [int(v) for v in rng.integers(int(s.low), int(s.high) + 1, n)]
        elif s.scale == "log":
            vals = np.exp(rng.uniform(np.log(s.low), np.log(s.high), n)).tolist()
        else:
            vals = rng.uniform(s.low, s.high, n).tolist()
        if s.type != "categorical":
            vals[0], vals[1] = s.low, s.high  # the ends of the range are inside it
            vals[0] = int(vals[0]) if s.type == "integer" else vals[0]
            vals[1] = int(vals[1]) if s.type == "integer" else vals[1]
        for row, v in zip(rows, vals, strict=True):
            row[s.name] = v
    return rows


def columns(rows: list[dict]) -> dict[str, list]:
    """Row objects -> the predictor's mapping name -> values."""
    return {k: [r[k] for r in rows] for k in rows[0]}
