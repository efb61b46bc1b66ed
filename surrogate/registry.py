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

from surrogate.runtime.card import CARD_NAME, FORMAT, ModelFileError, read_card, sha256_file

__all__ = ["CARD_VERSION", "list_models", "package_versions", "show_model", "write_model"]

CARD_VERSION = 1
_PACKAGES = ("hapticrom", "numpy", "scipy", "scikit-learn", "torch", "pysindy", "onnx",
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


def write_model(out: str | Path, card: Mapping[str, Any], files: Mapping[str, bytes], *,
                overwrite: bool = False) -> Path:
    """Write ``files`` and the completed card (format, created, file hashes) to ``out``
    atomically; an existing directory is replaced only with ``overwrite``."""
    out = Path(out)
    if out.exists() and not overwrite:
        raise FileExistsError(f"{out} exists (pass overwrite / --overwrite to replace it)")
    if not out.parent.is_dir():
        raise ValueError(f"--out {out}: the directory {out.parent} does not exist")
    bad = [n for n in files if Path(n).name != n or n == CARD_NAME]
    if bad:
        raise ValueError(f"model file name {bad[0]!r} is not allowed")
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    umask = os.umask(0)
    os.umask(umask)
    tmp.chmod(0o777 & ~umask)  # mkdtemp makes it private; a model directory is not
    try:
        for name, data in files.items():
            (tmp / name).write_bytes(data)
        full = {"format": FORMAT, "card_version": CARD_VERSION, "name": out.name,
                **card, "created": utc_now(),
                "files": {name: sha256_file(tmp / name) for name in sorted(files)}}
        (tmp / CARD_NAME).write_text(json.dumps(full, indent=1, sort_keys=False) + "\n")
        for f in tmp.iterdir():
            with open(f, "rb") as fh:
                os.fsync(fh.fileno())
        if out.exists():
            old = out.with_name(f".{out.name}.old")
            shutil.rmtree(old, ignore_errors=True)
            os.replace(out, old)
            os.replace(tmp, out)
            shutil.rmtree(old)
        else:
            os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out


def manifest_sha256(dataset: str | Path) -> str:
    """sha256 of a dataset's ``_manifest.json`` (identifies the training data)."""
    return hashlib.sha256((Path(dataset) / "_manifest.json").read_bytes()).hexdigest()


def show_model(path: str | Path) -> dict[str, Any]:
    """The verified card of one model directory."""
    return read_card(path)


def list_models(root: str | Path = "models") -> list[dict[str, Any]]:
    """One summary per model directory under ``root``: name, kind, created, status ("ok" or
    the verification error) and the headline held-out metrics."""
    root = Path(root)
    if not root.is_dir():
        raise ValueError(f"{root}: no such models directory")
    rows = []
    for d in sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith(".")):
        if not (d / CARD_NAME).exists():
            continue
        try:
            card = read_card(d)
        except ModelFileError as err:
            rows.append({"name": d.name, "status": str(err)})
            continue
        rows.append({"name": d.name, "kind": card.get("kind"), "created": card.get("created"),
                     "status": "ok", "headline": headline_metric(card)})
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
