"""Models by name or by path: ``load_model("nn-default")`` (numpy + onnxruntime only).

A model is a directory holding ``card.json`` and the files its card lists (see
docs/embedding.md). :func:`find_model` turns a name or a path into that directory, looking in
this order:

1. ``name`` itself when it is an existing directory (``load_model("models/nn-default")``);
2. every directory of the ``HAPTICROM_MODEL_PATH`` environment variable (``os.pathsep``
   separated), as ``DIR/name``;
3. installed model packages: every entry point of the group ``hapticrom.models`` names a
   module whose directory holds model directories (the ``hapticrom-models`` distribution,
   built from ``packaging/models``, advertises ``hapticrom_models``);
4. the ``models/`` directory of a source checkout, when this module runs from one.

:func:`load_model` verifies the directory (every listed file's sha256, nothing unlisted) and
returns a :class:`~surrogate.runtime.predictor.Predictor` for ``nn``/``gp`` cards or an
:class:`~surrogate.runtime.rom.EnvelopeModel` for ``rom`` cards.
"""

from __future__ import annotations

import importlib.util
import os
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

from surrogate.runtime.card import CARD_NAME, ModelFileError, read_card

__all__ = ["ENTRY_POINT_GROUP", "MODEL_PATH_ENV", "find_model", "list_models", "load_model",
           "model_roots"]

ENTRY_POINT_GROUP = "hapticrom.models"
MODEL_PATH_ENV = "HAPTICROM_MODEL_PATH"
_CHECKOUT_MODELS = Path(__file__).resolve().parents[2] / "models"


def _package_dir(module: str) -> Path | None:
    """Directory of an installed module without importing it (None when absent)."""
    spec = importlib.util.find_spec(module)
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(next(iter(spec.submodule_search_locations)))


def model_roots() -> list[Path]:
    """The directories searched for a model name, in search order (steps 2-4 above)."""
    roots = [Path(p) for p in os.environ.get(MODEL_PATH_ENV, "").split(os.pathsep) if p]
    for ep in sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        where = _package_dir(ep.value.split(":")[0])
        if where is not None:
            roots.append(where)
    if _CHECKOUT_MODELS.is_dir():
        roots.append(_CHECKOUT_MODELS)
    return roots


def find_model(name_or_path: str | os.PathLike[str]) -> Path:
    """The model directory for a name (``"nn-default"``) or a path; raises
    :class:`ModelFileError` (field ``model``) listing where it looked."""
    path = Path(name_or_path)
    if (path / CARD_NAME).is_file():
        return path
    name = str(name_or_path)
    roots = model_roots()
    if path.name == name and name not in ("", ".", ".."):  # a bare name, not a path
        for root in roots:
            if (root / name / CARD_NAME).is_file():
                return root / name
    known = sorted({p.name for r in roots if r.is_dir() for p in r.iterdir()
                    if (p / CARD_NAME).is_file()})
    raise ModelFileError("model", f"model {name!r} not found: not a model directory, and no "
                         f"{name!r} in {', '.join(map(str, roots)) or '(no model roots)'}; "
                         f"known names: {', '.join(known) or 'none'} (install hapticrom-models "
                         f"or set {MODEL_PATH_ENV})")


def list_models() -> dict[str, Path]:
    """Every model name found in :func:`model_roots` -> its directory (first one wins)."""
    found: dict[str, Path] = {}
    for root in model_roots():
        if root.is_dir():
            for p in sorted(root.iterdir()):
                if (p / CARD_NAME).is_file():
                    found.setdefault(p.name, p)
    return found


def load_model(name_or_path: str | os.PathLike[str]) -> Any:
    """A verified, loaded model: a ``Predictor`` (card kind ``nn`` or ``gp``) or an
    ``EnvelopeModel`` (card kind ``rom``). Raises :class:`ModelFileError` for a name that is
    not found or a directory that fails its checks."""
    path = find_model(name_or_path)
    kind = read_card(path, verify=False).get("kind")
    if kind == "rom":
        from surrogate.runtime.rom import load_envelope_model

        return load_envelope_model(path)
    if kind in ("nn", "gp"):
        from surrogate.runtime.predictor import load_predictor

        return load_predictor(path)
    raise ModelFileError("kind", f"{path}: card kind {kind!r} is not one of 'nn', 'gp', 'rom'")
