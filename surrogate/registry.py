"""The model registry: ``models/NAME/`` directories of model files plus ``card.json``.

A card says what the model predicts, its inputs (units, valid ranges, encoding), outputs,
the profile grid, the training data (path, sha256 of each dataset's manifest, rows), held-out
metrics, when it was created, the package versions that made it, and the sha256 of every
file (``files``). Models are ONNX graphs and JSON only -- nothing is pickled, so loading a
model never runs code from the file. A directory is written complete under a temporary name
and renamed into place; loading (:func:`surrogate.runtime.card.read_card`) verifies every hash.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
import shutil
import tempfile
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

from surrogate.card_warnings import card_warnings
from surrogate.runtime import load_model
from surrogate.runtime.card import (
    CARD_NAME,
    FORMAT,
    ModelFileError,
    read_card,
    seal_card,
    sha256_file,
)

__all__ = ["CARD_VERSION", "check_model", "check_model_out", "list_models", "model_dir_files",
           "package_versions", "show_model", "write_model"]

CARD_VERSION = 1
_PACKAGES = ("hapticrom", "numpy", "scipy", "scikit-learn", "torch", "onnx",
             "onnxscript", "skl2onnx", "onnxruntime")


def package_versions() -> dict[str, str]:
    """Installed versions of the packages that shape a model (missing ones omitted)."""
    out = {}
    for name in _PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return out


def utc_now() -> str:
    """Current UTC time, ISO 8601 to the second."""
    return _dt.datetime.now(_dt.UTC).replace(microsecond=0).isoformat()


def model_dir_files(path: Path) -> list[str] | None:
    """The names in ``path`` when it is a model directory hapticrom wrote (a readable
    ``hapticrom-model`` card, every entry listed in its ``files`` or the card itself);
    None otherwise. The files need not match their digests: a damaged model may be replaced."""
    try:
        card = read_card(path, verify=False)
    except (ModelFileError, OSError):
        return None
    files = card.get("files")
    names = sorted(p.name for p in path.iterdir())
    if not isinstance(files, dict) or any(n != CARD_NAME and n not in files for n in names):
        return None
    return names


def check_model_out(out: str | Path, overwrite: bool) -> None:
    """Refuse ``out`` as a model directory to write unless it is missing, an empty
    directory, or (with ``overwrite``) a model directory hapticrom wrote holding nothing else;
    the error names ``out`` and what it holds."""
    out = Path(out)
    if not out.parent.is_dir():
        raise ValueError(f"--out {out}: the directory {out.parent} does not exist")
    if out.is_symlink() or (out.exists() and not out.is_dir()):
        raise ValueError(f"--out {out}: exists and is not a directory; refusing to replace it")
    if not out.exists() or not any(out.iterdir()):
        return
    if model_dir_files(out) is None:
        held = sorted(p.name + ("/" if p.is_dir() else "") for p in out.iterdir())
        shown = ", ".join(held[:5]) + (f" and {len(held) - 5} more" if len(held) > 5 else "")
        raise ValueError(f"--out {out}: the directory holds {shown}, which is not a model "
                         "hapticrom wrote (only such a directory is replaced, with "
                         "--overwrite); choose a new directory")
    if not overwrite:
        raise FileExistsError(f"{out} exists (pass overwrite / --overwrite to replace it)")


def write_model(out: str | Path, card: Mapping[str, Any], files: Mapping[str, bytes], *,
                overwrite: bool = False) -> Path:
    """Write ``files`` and the completed, sealed card (format, created, file hashes,
    ``card_sha256``) to ``out``: built in a temporary sibling directory and renamed into
    place. An existing ``out`` is replaced only with ``overwrite`` and only when it is a model
    directory hapticrom wrote (:func:`check_model_out`, checked again just before the swap)."""
    out = Path(out)
    check_model_out(out, overwrite)
    bad = [n for n in files if Path(n).name != n or n in (CARD_NAME, ".", "..")]
    if bad:
        raise ValueError(f"model file name {bad[0]!r} is not allowed")
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    umask = os.umask(0)
    os.umask(umask)
    tmp.chmod(0o777 & ~umask)  # mkdtemp makes it private; a model directory is not
    old = None
    try:
        for name, data in files.items():
            (tmp / name).write_bytes(data)
        full = {"format": FORMAT, "card_version": CARD_VERSION, "name": out.name,
                **card, "created": utc_now(),
                "files": {name: sha256_file(tmp / name) for name in sorted(files)}}
        full["warnings"] = card_warnings(full)
        (tmp / CARD_NAME).write_text(json.dumps(seal_card(full), indent=1) + "\n")
        for f in tmp.iterdir():
            with open(f, "rb") as fh:
                os.fsync(fh.fileno())
        check_model_out(out, overwrite)  # the user may have put files there meanwhile
        if out.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
            os.replace(out, old / out.name)
        os.replace(tmp, out)
    except BaseException:
        if old is not None and not out.exists():
            os.replace(old / out.name, out)  # put the previous model back
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    return out


def manifest_sha256(dataset: str | Path) -> str:
    """sha256 of a dataset's ``_manifest.json`` (identifies the training data)."""
    return hashlib.sha256((Path(dataset) / "_manifest.json").read_bytes()).hexdigest()


def check_model(path: str | Path) -> dict[str, Any]:
    """The card of model directory ``path`` after loading it as it will be used: the
    directory verified as a whole, then the graph (gp, nn) or coefficients (rom) checked by
    their run-time loader; :class:`ModelFileError` naming the file and the check otherwise."""
    card = read_card(path)
    load_model(path)  # the run-time form the card's contract names (graph, coefficients)
    return card


def show_model(path: str | Path) -> dict[str, Any]:
    """The card of one model directory, checked by :func:`check_model`."""
    return check_model(path)


def list_models(root: str | Path = "models") -> list[dict[str, Any]]:
    """One summary per model directory under ``root``: name, kind, created, status ("ok" or
    "refused: " and why), the headline held-out metrics and the card's warnings
    (:func:`surrogate.card_warnings.card_warnings`). Every directory holding a
    ``card.json`` is verified as a whole (:func:`surrogate.runtime.card.verify_model_dir`);
    one bad model never stops the listing."""
    root = Path(root)
    if not root.is_dir():
        raise ValueError(f"{root}: no such models directory")
    rows = []
    for d in sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith(".")):
        if not (d / CARD_NAME).exists() and not (d / CARD_NAME).is_symlink():
            continue
        try:
            card = check_model(d)
            headline = headline_metric(card)
        except Exception as err:  # any failure is this model's status, never the listing's
            rows.append({"name": d.name, "status": f"refused: {err}"})
            continue
        rows.append({"name": d.name, "kind": card.get("kind"), "created": card.get("created"),
                     "status": "ok", "headline": headline, "warnings": card_warnings(card)})
    return rows


def headline_metric(card: Mapping[str, Any]) -> str:
    """One line of held-out accuracy for listings: the center amplitude's median relative
    error (gp, nn) or the center envelope's median NRMSE (rom); empty when the card has none."""
    metrics = card.get("metrics", {})
    err = metrics.get("center_amplitude_um", {}).get("median_rel_err")
    if err is not None:
        return f"center median rel. err. {100 * err:.2f} % (held out)"
    nrmse = metrics.get("held_out", {}).get("summary", {}).get("center_nrmse_median")
    if nrmse is not None:
        return f"center envelope median NRMSE {100 * nrmse:.1f} % (held out)"
    return ""
