"""Model cards: reading ``models/NAME/card.json`` and verifying the model directory as a whole.

A model directory holds ``card.json`` and the files it names in ``files`` (name -> sha256 hex
digest); nothing else. The card carries its own digest, ``card_sha256``: the sha256 of the
canonical JSON of the card without that key (:func:`canonical_json`), so that an edited value
(a widened input range, a changed profile grid) is refused like a changed model file.

:func:`verify_model_dir` checks, in order, and refuses with :class:`ModelFileError` naming the
file and the check that failed:

1. ``card.json`` is a plain file (no symlink), within the size and nesting limits of
   :mod:`fieldspec.documents`, UTF-8 JSON of a ``hapticrom-model`` card;
2. ``card_sha256`` matches the card;
3. every key the model kind needs is present (:data:`REQUIRED_KEYS`);
4. every listed file is a plain name (no absolute path, no ``/``, no ``..``), a regular file
   inside the directory (no symlink), with the listed sha256; every file the card names for a
   role (``graph.file``, ``coefficients``) is one of the listed files;
5. the directory holds nothing else (no unlisted file, sub-directory or symlink).

This is integrity, not authenticity: whoever rewrites a file and recomputes both digests
makes a consistent model. Loading never runs code from a model file (ONNX and JSON only).
"""

from __future__ import annotations

import hashlib
import json
import os
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fieldspec.documents import read_json_file
from fieldspec.errors import FieldError

__all__ = ["CARD_NAME", "DIGEST_KEY", "FORMAT", "MAX_MODEL_FILE_BYTES", "REQUIRED_KEYS",
           "ModelFileError", "canonical_json", "card_digest", "read_card", "read_model_file",
           "replace_card", "seal_card", "sha256_bytes", "sha256_file", "verify_model_dir"]

CARD_NAME = "card.json"
FORMAT = "hapticrom-model"
DIGEST_KEY = "card_sha256"
#: Largest model file read [bytes] (a GP graph of 4,000 training rows is about 20 MB).
MAX_MODEL_FILE_BYTES = 512 * 1024 * 1024
#: Card keys every model needs, and the extra keys of each kind with a run-time form of its
#: own; every other kind (gp, nn, mlp, ...: the registry surrogate.kinds) is a steady-state
#: predictor, one ONNX graph, and needs :data:`STEADY_KEYS`.
REQUIRED_KEYS: dict[str, tuple[str, ...]] = {
    "": ("format", "name", "kind", "files", DIGEST_KEY),
    "rom": ("coefficients",),
}
STEADY_KEYS = ("inputs", "profile_distance_mm", "edge_radius", "graph")
#: Card entries that name a file of the directory: (dotted key, path of keys).
ROLE_FILES = {"graph.file": ("graph", "file"), "coefficients": ("coefficients",)}


class ModelFileError(FieldError):
    """A model directory that is missing, malformed or fails a check; ``field`` names the
    file or card key, the message the file and the check."""


def canonical_json(obj: Any) -> bytes:
    """The canonical form hashed by ``card_sha256`` (and by plan digests): sorted keys, no
    whitespace, UTF-8."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"),
                      ensure_ascii=False).encode("utf-8")


def card_digest(card: Mapping[str, Any]) -> str:
    """sha256 hex of the canonical card without its ``card_sha256`` key."""
    return hashlib.sha256(canonical_json({k: v for k, v in card.items()
                                          if k != DIGEST_KEY})).hexdigest()


def seal_card(card: Mapping[str, Any]) -> dict[str, Any]:
    """A copy of ``card`` with ``card_sha256`` set (last key) over everything else."""
    out = {k: v for k, v in card.items() if k != DIGEST_KEY}
    out[DIGEST_KEY] = card_digest(out)
    return out


def replace_card(path: str | Path, card: Mapping[str, Any]) -> dict[str, Any]:
    """Replace the card of the verified model directory ``path`` with ``card``, sealed
    (:func:`seal_card`), atomically: written to a temporary sibling of the directory, flushed
    to disk, renamed over ``card.json`` (a reader sees the old card or the new one, never half
    of one), then the directory verified again (:func:`verify_model_dir`). The model files are
    not touched, so ``card`` must list the same ``files``. Returns the sealed card. The one
    writer of an existing card (``hapticrom models calibrate-intervals``, and the error model
    of ``bench/calibration/calibrate.py --write-card``)."""
    root = Path(path)
    old = verify_model_dir(root)
    if card.get("files") != old["files"]:
        raise ModelFileError("files", f"{root / CARD_NAME}: the new card lists other files "
                             "than the directory holds; only a card's entries may change here")
    sealed = seal_card(card)
    tmp = root.parent / f".{root.name}.{CARD_NAME}.tmp"
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(json.dumps(sealed, indent=1) + "\n")
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, root / CARD_NAME)
    finally:
        tmp.unlink(missing_ok=True)
    try:  # the rename itself reaches the disk with the directory's entry
        fd = os.open(root, os.O_RDONLY)
    except OSError:  # pragma: no cover - a platform without directory handles
        pass
    else:
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
    verify_model_dir(root)
    return sealed


def sha256_bytes(data: bytes) -> str:
    """Hex sha256 of ``data``."""
    return hashlib.sha256(data).hexdigest()


def sha256_file(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _parse_card(root: Path) -> dict[str, Any]:
    card_path = root / CARD_NAME
    if card_path.is_symlink():
        raise ModelFileError(CARD_NAME, f"{card_path}: a symlink; the card must be a plain "
                             "file inside the model directory (check: path)")
    if not card_path.is_file():
        raise ModelFileError(CARD_NAME, f"{root}: not a model directory (no {CARD_NAME})")
    card = read_json_file(card_path, ModelFileError, "model card")
    if not isinstance(card, dict) or card.get("format") != FORMAT:
        raise ModelFileError(CARD_NAME, f"{card_path}: not a {FORMAT} card (check: format)")
    return card


def _check_keys(card: dict[str, Any], card_path: Path) -> None:
    kind = card.get("kind")
    if not isinstance(kind, str) or not kind.isidentifier():
        raise ModelFileError("kind", f"{card_path}: kind {kind!r} is not a kind name "
                             "(check: keys)")
    for key in (*REQUIRED_KEYS[""], *REQUIRED_KEYS.get(kind, STEADY_KEYS)):
        if key not in card:
            raise ModelFileError(key, f"{card_path}: the card has no {key!r} key "
                                 "(check: keys)")
    files = card["files"]
    if not isinstance(files, dict) or not files:
        raise ModelFileError("files", f"{card_path}: 'files' must map file names to sha256 "
                             "digests (check: keys)")


def _role_files(card: dict[str, Any], card_path: Path) -> None:
    for key, keys in ROLE_FILES.items():
        value: Any = card
        for k in keys:
            value = value.get(k) if isinstance(value, dict) else None
        if value is None and keys[0] not in card:
            continue
        if not isinstance(value, str) or value not in card["files"]:
            raise ModelFileError(key, f"{card_path}: {key} = {value!r} is not one of the "
                                 f"files the card lists ({', '.join(sorted(card['files']))}) "
                                 "(check: named files)")


def _plain_name(name: Any, root: Path) -> str:
    if (not isinstance(name, str) or not name or name in (".", "..", CARD_NAME)
            or "/" in name or "\\" in name or "\0" in name or Path(name).is_absolute()):
        raise ModelFileError("files", f"{root}: listed file {name!r} is not a plain file name "
                             "inside the model directory (check: path)")
    return name


def _check_files(card: dict[str, Any], root: Path) -> None:
    files = card["files"]
    for name, digest in files.items():
        _plain_name(name, root)
        f = root / name
        try:
            mode = f.lstat().st_mode
        except OSError:
            raise ModelFileError(name, f"{f}: listed in the card but missing "
                                 "(check: files)") from None
        if not stat.S_ISREG(mode):
            what = "a symlink" if stat.S_ISLNK(mode) else "not a regular file"
            raise ModelFileError(name, f"{f}: {what}; a model file must be a plain file "
                                 "inside the model directory (check: path)")
        if f.stat().st_size > MAX_MODEL_FILE_BYTES:
            raise ModelFileError(name, f"{f}: larger than {MAX_MODEL_FILE_BYTES} bytes "
                                 "(check: size)")
        actual = sha256_file(f)
        if actual != digest:
            raise ModelFileError(name, f"{f}: sha256 {actual[:12]}... does not match the "
                                 f"card's {str(digest)[:12]}... (check: file digest; the "
                                 "file was changed)")
    for entry in sorted(root.iterdir()):
        if entry.name != CARD_NAME and entry.name not in files:
            what = ("symlink" if entry.is_symlink() else "directory" if entry.is_dir()
                    else "file")
            raise ModelFileError(entry.name, f"{root}: {what} {entry.name!r} is not listed in "
                                 "the card (check: unlisted files; refusing a directory "
                                 "that was changed)")


def verify_model_dir(path: str | Path) -> dict[str, Any]:
    """The card of model directory ``path`` after every check of the module docstring;
    :class:`ModelFileError` naming the file and the check otherwise."""
    root = Path(path)
    if not root.is_dir():
        raise ModelFileError("path", f"{root}: not a model directory (no such directory)")
    card = _parse_card(root)
    card_path = root / CARD_NAME
    digest = card.get(DIGEST_KEY)
    if digest is None:
        raise ModelFileError(DIGEST_KEY, f"{card_path}: the card is not sealed (no "
                             f"{DIGEST_KEY}); re-train, or re-seal a card you trust "
                             "(check: card digest)")
    if digest != card_digest(card):
        raise ModelFileError(CARD_NAME, f"{card_path}: {DIGEST_KEY} does not match the "
                             "card's content (check: card digest; the card was edited)")
    _check_keys(card, card_path)
    _role_files(card, card_path)
    _check_files(card, root)
    return card


def read_model_file(path: str | Path, card: Mapping[str, Any], name: str) -> bytes:
    """The bytes of listed file ``name`` of a verified model directory, checked once more
    against the card's digest (the bytes used are the bytes checked)."""
    f = Path(path) / _plain_name(name, Path(path))
    if f.is_symlink() or name not in card["files"]:
        raise ModelFileError(name, f"{f}: not a listed plain file of the model (check: path)")
    data = f.read_bytes()
    if sha256_bytes(data) != card["files"][name]:
        raise ModelFileError(name, f"{f}: sha256 does not match the card (check: file digest; "
                             "the file changed while it was loaded)")
    return data


def read_card(path: str | Path, *, verify: bool = True) -> dict[str, Any]:
    """The card of model directory ``path``: verified as a whole (:func:`verify_model_dir`)
    unless ``verify`` is False (then only parsed)."""
    return verify_model_dir(path) if verify else _parse_card(Path(path))
