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
returns a :class:`~surrogate.runtime.predictor.Predictor` for a card with an ONNX ``graph``
(every steady-state kind: gp, nn, mlp, ...) or an :class:`~surrogate.runtime.rom.EnvelopeModel`
for a card with ``coefficients`` (the transient envelope model). The run-time form is told by
the card's contract, never by the kind's name, so a new steady-state kind loads unchanged.
"""

from __future__ import annotations

import importlib.util
import os
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

from surrogate.runtime.card import CARD_NAME, ModelFileError, read_card
from surrogate.runtime.predictor import load_predictor
from surrogate.runtime.rom import load_envelope_model

__all__ = ["ENTRY_POINT_GROUP", "LOADERS", "MODEL_PATH_ENV", "find_model", "is_steady_state",
           "list_models", "load_model", "model_roots"]

ENTRY_POINT_GROUP = "hapticrom.models"
MODEL_PATH_ENV = "HAPTICROM_MODEL_PATH"
_CHECKOUT_MODELS = Path(__file__).resolve().parents[2] / "models"
#: The card key of each run-time contract -> its loader, tried in this order.
LOADERS = (("graph", load_predictor), ("coefficients", load_envelope_model))


def is_steady_state(card: dict[str, Any]) -> bool:
    """Whether ``card`` is a steady-state predictor's (one ONNX graph, :class:`Predictor`)."""
    return "graph" in card


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
    """A verified, loaded model: a ``Predictor`` (a card with an ONNX ``graph``) or an
    ``EnvelopeModel`` (a card with ``coefficients``). Raises :class:`ModelFileError` for a
    name that is not found or a directory that fails its checks."""
    path = find_model(name_or_path)
    card = read_card(path, verify=False)
    for key, loader in LOADERS:
        if key in card:
            return loader(path)
    raise ModelFileError("kind", f"{path}: card kind {card.get('kind')!r} has neither a "
                         f"'graph' nor 'coefficients' (the two run-time contracts)")
