"""The registry of surrogate kinds: ``--kind`` name -> :class:`surrogate.kind.SurrogateKind`.

This is the one place that lists the kinds. ``hapticrom train``, :func:`surrogate.train.train`,
the model listing and the accuracy study look a kind up here; a kind's estimator, exporter and
parity tolerance live in its own module (``surrogate/estimators/gp.py``, ``nn.py``, ``mlp.py``,
``lgbm.py``). Adding a kind is one new module defining ``KIND`` plus its line in
:data:`KINDS` (docs/architecture.md).

Importing this module loads scikit-learn and torch (about 5 s): the CLI imports it
only when a command needs a kind, never to build its parser.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from fieldspec import FieldError
from surrogate.envelope import fit as rom
from surrogate.estimators import gp, lgbm, mlp, nn
from surrogate.kind import SurrogateKind
from surrogate.sweep import gp_export as sweep_gp
from surrogate.sweep import nn as sweep_nn

__all__ = ["KINDS", "STEADY_KINDS", "SWEEP_KINDS", "get"]

#: Options of the envelope model's identification (``--options`` of ``--kind rom``).
_ROM_OPTIONS = ("harmonic", "max_nfev", "equivalent_loss",
                "group_by_attachment", "learn_gain", "modes", "quasi_static_share")


def _train_rom(paths: Sequence[str | Path], out: str | Path, *, seed: int, overwrite: bool,
               options: Mapping[str, Any]) -> dict[str, Any]:
    unknown = sorted(set(options) - set(_ROM_OPTIONS))
    if unknown:
        raise FieldError("--options", f"--options: {unknown[0]!r} is not a rom option "
                         f"(allowed: {', '.join(_ROM_OPTIONS)})")
    return rom.train(paths, out, seed=seed, overwrite=overwrite, **options)


def _rom_report(card: Mapping[str, Any]) -> list[str]:
    held = card["metrics"]["held_out"]["summary"]
    return [f"identified rom on {card['split']['n_train']} runs, held out "
            f"{card['split']['n_held_out']}",
            "  " + "  ".join(f"{k} {v:.4g}" for k, v in held.items() if v is not None)]


#: The transient envelope model: identified from transient runs by its own pipeline
#: (:mod:`surrogate.envelope.fit`), written as coefficients (not an ONNX graph).
ROM = SurrogateKind(name="rom", summary="transient envelope model (grey box: motor law x "
                    "harmonic NN x damped modes, fitted by least squares)",
                    trainer=_train_rom, report=_rom_report)

#: Every kind, by name, in the order ``--help`` lists them. The GP and the NN also train on
#: sweep datasets: their part of that pipeline lives in ``surrogate/sweep/`` (built on the
#: estimators, so joined to their records here rather than in the estimators' modules).
KINDS: dict[str, SurrogateKind] = {k.name: k for k in (
    replace(gp.KIND, sweep=sweep_gp.SWEEP), replace(nn.KIND, sweep=sweep_nn.SWEEP), mlp.KIND,
    lgbm.KIND, ROM)}
#: The kinds of the steady-state pipeline (one ONNX graph contract,
#: :mod:`surrogate.estimators.export`).
STEADY_KINDS = tuple(name for name, k in KINDS.items() if k.estimator is not None)
#: The kinds sweep datasets train (their graphs decode the complex band).
SWEEP_KINDS = tuple(name for name, k in KINDS.items() if k.sweep is not None)


def get(name: str, field: str = "--kind", *, steady: bool = False) -> SurrogateKind:
    """The kind called ``name``; a :class:`fieldspec.FieldError` naming ``field`` and the
    allowed names otherwise (``steady``: only kinds of the steady-state pipeline)."""
    allowed = STEADY_KINDS if steady else tuple(KINDS)
    if name not in allowed:
        raise FieldError(field, f"{field} {name!r}: allowed {', '.join(allowed)}")
    return KINDS[name]
