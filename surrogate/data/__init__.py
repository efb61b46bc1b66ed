"""The dataset layer: parameter spaces, sampling, dataset store, generation and ingest.

Public calls (imported lazily, so ``import surrogate.data`` stays cheap)::

    load_space(path) / space_from_dict(d)      -> Space            (surrogate.data.space)
    generate(space, n, out, ...)               -> GenerateReport   (surrogate.data.generate)
    Store.open(path), dataset_info(path), validate_dataset(path), merge_datasets(out, inputs)
    ingest_profile(...), ingest_table(...)                          (surrogate.data.ingest)
    process_map(fn, items, workers=..., desc=...)                   (surrogate.data.pool)

Errors: :class:`SpaceError` and :class:`DatasetError`, both ``fieldspec.FieldError``.
"""

from __future__ import annotations

import importlib
from typing import Any

from surrogate.data.errors import DatasetError, SpaceError

_LAZY = {
    "Space": "space", "load_space": "space", "space_from_dict": "space",
    "generate": "generate", "GenerateReport": "generate",
    "Store": "store", "dataset_info": "inspect", "validate_dataset": "inspect",
    "merge_datasets": "inspect",
    "ingest_profile": "ingest", "ingest_table": "ingest",
    "process_map": "pool",
}

__all__ = ["DatasetError", "SpaceError", *_LAZY]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f"surrogate.data.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'surrogate.data' has no attribute {name!r}")
