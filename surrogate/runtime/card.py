"""Model cards: reading ``models/NAME/card.json`` and verifying the files it lists.

A model directory holds ``card.json`` and the files it names in ``files`` (name -> sha256
hex digest). Loading recomputes every digest and refuses a directory whose files differ
from the card, are missing, or that holds files the card does not list.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

__all__ = ["CARD_NAME", "FORMAT", "ModelFileError", "read_card", "sha256_file"]

CARD_NAME = "card.json"
FORMAT = "hapticrom-model"


class ModelFileError(ValueError):
    """A model directory that is missing, malformed or fails its hash check."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


def sha256_file(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def read_card(path: str | Path, *, verify: bool = True) -> dict[str, Any]:
    """The card of model directory ``path``; with ``verify`` every listed file's sha256 is
    checked and unlisted files are an error."""
    root = Path(path)
    card_path = root / CARD_NAME
    if not card_path.is_file():
        raise ModelFileError("path", f"{root}: not a model directory (no {CARD_NAME})")
    try:
        card = json.loads(card_path.read_text())
    except (OSError, json.JSONDecodeError) as err:
        raise ModelFileError(CARD_NAME, f"{card_path}: unreadable card: {err}") from None
    if not isinstance(card, dict) or card.get("format") != FORMAT:
        raise ModelFileError("format", f"{card_path}: not a {FORMAT} card")
    files = card.get("files")
    if not isinstance(files, dict) or not files:
        raise ModelFileError("files", f"{card_path}: the card lists no files")
    if verify:
        present = {p.name for p in root.iterdir() if p.is_file()} - {CARD_NAME}
        extra = sorted(present - set(files))
        if extra:
            raise ModelFileError("files", f"{root}: file {extra[0]!r} is not listed in the "
                                 "card (refusing a directory that was changed)")
        for name, digest in files.items():
            f = root / name
            if Path(name).name != name or not f.is_file():
                raise ModelFileError("files", f"{root}: listed file {name!r} is missing")
            actual = sha256_file(f)
            if actual != digest:
                raise ModelFileError("files", f"{f}: sha256 {actual[:12]}... does not match "
                                     f"the card's {str(digest)[:12]}... (file changed)")
    return card
