"""Copies of the shipped model directories to alter in tests, and re-sealing after an edit
(what someone who rewrites a model and recomputes every digest would do)."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

from surrogate.runtime.card import seal_card

REPO = Path(__file__).resolve().parents[2]
SHIPPED = {"gp": REPO / "models" / "gp-default", "nn": REPO / "models" / "nn-default",
           "rom": REPO / "models" / "rom-default"}


def copy_model(kind: str, dest: Path) -> Path:
    """A copy of the shipped ``kind`` model at ``dest``."""
    shutil.copytree(SHIPPED[kind], dest)
    return dest


def read(d: Path) -> dict:
    return json.loads((d / "card.json").read_text())


def write(d: Path, card: dict) -> None:
    (d / "card.json").write_text(json.dumps(card, indent=1) + "\n")


def reseal(d: Path, card: dict | None = None) -> dict:
    """Recompute every listed file's sha256 (files that exist) and the card digest."""
    card = read(d) if card is None else card
    if isinstance(card.get("files"), dict):  # an edited map itself (not a dict) is sealed as is
        card["files"] = {name: (hashlib.sha256((d / name).read_bytes()).hexdigest()
                                if (d / name).is_file() else digest)
                         for name, digest in card["files"].items()}
    sealed = seal_card(card)
    write(d, sealed)
    return sealed


def tree(root: Path) -> dict[str, bytes]:
    """Every file under ``root`` and its bytes (to show that nothing was written)."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file() and not p.is_symlink()}
