"""Read a ``hapticrom simulate --json`` document back as a profile to ingest: the version-1
layout and the unversioned one before it (:func:`fem.output.read_result`), for one release."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from fem.output import read_result
from fieldspec.documents import read_json_file
from surrogate.data.errors import DatasetError

__all__ = ["read_simulate_json"]


def read_simulate_json(path: str | Path) -> tuple[np.ndarray, np.ndarray, float | None]:
    """(distance from the edge [mm], magnitude [um], centre magnitude [um] or None) of the
    profile of a harmonic simulate document. Raises :class:`DatasetError` naming the file."""
    path = Path(path)
    try:
        doc = read_result(read_json_file(path, DatasetError, "simulate result"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, ValueError) as err:
        raise DatasetError(str(path), f"cannot read simulate result {path}: {err}") from None
    kind = doc["analysis"]["kind"]
    if kind != "harmonic":
        raise DatasetError(str(path), f"{path}: a {kind} result; only harmonic results "
                           "(magnitudes of the steady state) can be ingested")
    prof = doc["profile"]
    dist = np.asarray(prof["distance_from_edge_mm"], dtype=float)
    amp = np.asarray(prof["magnitude_um"], dtype=float)
    if dist.size == 0:
        raise DatasetError(str(path), f"{path}: the result has no profile samples")
    centre = doc.get("centre")
    return dist, amp, None if centre is None else float(centre["magnitude_um"])
