"""The study's data: the shipped dataset, its held-out split, and a fixed set of designs.

The designs are held-out rows of ``datasets/default`` (the split of ``hapticrom train``:
seeded 20 %, seed 0), so no learned model has seen them. They are picked by a stated,
deterministic rule that spans the space: start from the held-out row nearest the centre of
the encoded feature box (every feature scaled to [0, 1]), then repeatedly add the held-out row
farthest (Euclidean, encoded features) from those already picked (farthest-point sampling).
The full study uses the first :data:`N_DESIGNS`, ``--quick`` the first :data:`N_QUICK`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from surrogate.data.plan import Planned
from surrogate.data.store import Store
from surrogate.runtime.encoding import encode
from surrogate.train import load_datasets, split

__all__ = ["DATASET", "N_DESIGNS", "N_QUICK", "Design", "StudyData", "load_study_data",
           "pick_designs"]

#: The shipped dataset the study reads (4096 Sobol samples of datasets/spaces/default.toml).
DATASET = Path(__file__).resolve().parents[2] / "datasets" / "default"
N_DESIGNS = 8
N_QUICK = 3


@dataclass(frozen=True)
class Design(Planned):
    """One design point of the dataset, the record the dataset was planned with
    (:class:`surrogate.data.plan.Planned`: sequence ``index``, ``sample_id``, parameter
    ``values``, resolved ``scene``), and its ``row`` in the study's arrays."""

    row: int


@dataclass
class StudyData:
    """Rows of the dataset in design-sequence order (as :func:`surrogate.train.load_datasets`
    returns them), encoded features, the held-out split, and per-row generation time [s]."""

    data: Any
    X: np.ndarray
    train: np.ndarray
    test: np.ndarray
    wall_s: np.ndarray
    scene_json: list[str]
    sample_id: list[str]
    extras: dict[str, Any] = field(default_factory=dict)


def load_study_data(path: str | Path = DATASET) -> StudyData:
    """Read ``path`` with the training loader and the columns the study needs beside it."""
    data = load_datasets([path])
    df = Store.open(path).read(columns=["sample_id", "sample_index", "status", "wall_s",
                                        "scene_json"])
    df = df[df["status"] == "ok"].sort_values("sample_index", kind="stable")
    if len(df) != len(data.codes):
        raise ValueError(f"{path}: {len(df)} ok rows but the loader read {len(data.codes)}")
    tr, te = split(len(data.codes), 0.2, 0)  # the split of `hapticrom train`
    return StudyData(data, encode(data.codes, data.specs), tr, te,
                     df["wall_s"].to_numpy(float), df["scene_json"].tolist(),
                     df["sample_id"].tolist(),
                     {"sample_index": df["sample_index"].astype(int).tolist()})


def pick_designs(sd: StudyData, n: int) -> list[Design]:
    """The first ``n`` designs of the farthest-point rule (module docstring)."""
    if not 1 <= n <= sd.test.size:
        raise ValueError(f"n = {n}: allowed 1..{sd.test.size} designs")
    X = sd.X[sd.test]
    first = int(np.argmin(np.linalg.norm(X - 0.5, axis=1)))
    picked = [first]
    dist = np.linalg.norm(X - X[first], axis=1)
    while len(picked) < n:
        nxt = int(np.argmax(dist))
        picked.append(nxt)
        dist = np.minimum(dist, np.linalg.norm(X - X[nxt], axis=1))
    out = []
    for j in picked:
        row = int(sd.test[j])
        params = {s.name: _value(s, sd.data.codes[row, k]) for k, s in enumerate(sd.data.specs)}
        index = sd.extras.get("sample_index", range(len(sd.sample_id)))[row]
        out.append(Design(int(index), sd.sample_id[row], params, json.loads(sd.scene_json[row]),
                          row))
    return out


def _value(spec: Any, code: float) -> Any:
    if spec.type == "categorical":
        return spec.choices[int(code)]
    if spec.type == "integer":
        return int(code)
    return float(code)
