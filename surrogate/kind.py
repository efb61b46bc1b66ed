"""What the training pipeline needs to know of one surrogate kind (:class:`SurrogateKind`).

Every kind is one record in :data:`surrogate.kinds.KINDS`; nothing else in the project branches
on a kind's name. A steady-state kind names a scikit-learn-style estimator class (parameters in
``__init__``, ``fit(X, T)``, ``predict(X, return_std=True)`` giving the mean and std of the
targets of :class:`surrogate.pod.ProfileTargets`) and the function that writes it as the one
ONNX graph contract of :mod:`surrogate.estimators.export`. A kind that also trains on sweep
datasets carries its part of that pipeline (:class:`SweepKind`, :mod:`surrogate.sweep.train`).
A kind with a pipeline of its own (the transient envelope model) names its ``trainer`` instead.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["SurrogateKind", "SweepKind", "estimator_params"]


def _no_extras(estimator: Any) -> dict[str, Any]:
    return {}


def _predict_log(estimator: Any, B: np.ndarray, b: np.ndarray) -> Callable[[np.ndarray],
                                                                            np.ndarray]:
    """The in-memory model's log outputs: ``estimator.predict(X) @ B + b``."""
    return lambda X: estimator.predict(X) @ B + b


def estimator_params(estimator: Any) -> dict[str, Any]:
    """The estimator's parameters as JSON values (tuples as lists, anything else as text), for
    the card's ``training.estimator``."""
    return {k: _plain(v) for k, v in estimator.get_params().items()}


def _plain(v: Any) -> Any:
    if isinstance(v, tuple):
        return list(v)
    return v if isinstance(v, (int, float, str, bool, type(None), list)) else str(v)


@dataclass(frozen=True)
class SweepKind:
    """A kind's part of the sweep pipeline (:func:`surrogate.sweep.train.train_sweep`): the
    steps that differ between kinds, the rest is shared.

    Attributes:
        check_options: ``check_options(options) -> checked``: the ``--options`` with their
            defaults, each checked (a :class:`fieldspec.FieldError` naming the bad one), before
            anything is read or written.
        fit: ``fit(checked, data, designs, seed, n_modes, normal) -> (estimator, targets,
            training entries of the card)`` on the rows ``designs`` of the sweep data.
        export: ``export(estimator, targets, normal, frequency_low, frequency_high, band_hz,
            metadata) -> ONNX bytes`` (the graph decodes the complex band).
        parity: ``parity(estimator, targets, predictor, data, designs, normal) -> card
            entries`` (``export_parity_max_abs_dln``, ...): the graph against the estimator on
            held-out ``designs``; raises above the kind's tolerance.
    """

    check_options: Callable[[Mapping[str, Any] | None], Any]
    fit: Callable[..., tuple[Any, Any, dict[str, Any]]]
    export: Callable[..., bytes]
    parity: Callable[..., dict[str, Any]]


def steady_report(card: Mapping[str, Any]) -> list[str]:
    """The lines ``hapticrom train`` prints for a steady-state model's card."""
    t = card["training"]
    lines = [f"trained {card['kind']} on {t['rows']} rows, held out {t['held_out']} "
             f"(POD {t['pod_modes']} modes, {100 * t['pod_energy']:.3f} % energy)"]
    lines += [f"  {name:22s} " + "  ".join(f"{k} {v:.4g}" for k, v in m.items())
              for name, m in card["metrics"].items()]
    lines.append(f"export parity max |d ln| {card['export_parity_max_abs_dln']:.2g}")
    return lines


@dataclass(frozen=True)
class SurrogateKind:
    """One kind of surrogate, registered once in :data:`surrogate.kinds.KINDS`.

    Attributes:
        name: the ``--kind`` value and the card's ``kind``.
        summary: one line for ``--help`` and docs.
        estimator: the estimator class (called as ``estimator(random_state=seed, **options)``).
        export: ``export(estimator, B, b, metadata) -> ONNX bytes`` (input ``x``; outputs
            ``log_mean``, ``log_std``; see :mod:`surrogate.estimators.export`).
        parity_tol: largest |d ln| allowed between the exported graph and the estimator.
        dtype: the graph's input dtype, ``"float32"`` or ``"float64"``.
        std_parity: whether the graph's ``log_std`` is checked against the estimator's std too.
        pod_modes: default POD modes of the profile (None: 99.99 % of the energy).
        card_extras: ``card_extras(estimator) -> dict`` merged into the card's ``training``.
        trainer: for a kind with its own pipeline: ``trainer(paths, out, *, seed, overwrite,
            options) -> card`` replaces the steady-state pipeline of :mod:`surrogate.train`.
        report: the lines ``hapticrom train`` prints of the card.
        engine: what runs the estimator in memory (``"scikit-learn"``, ``"torch"``), for the
            accuracy study's labels.
        in_memory: ``in_memory(estimator, B, b) -> f(X) -> log outputs``, the fastest
            in-memory path (the accuracy study times it beside the ONNX graph).
        sweep: its part of the sweep pipeline, None when it does not train on sweep datasets.
        quick_options: estimator options of a smoke-test run (the accuracy study's
            ``--quick``: fewer epochs, members or trees), not a converged model.
        row_cap: training rows a learning curve stops at (the exact GP's O(n^3) fit: the
            shipped gp-default's 500 rows), None: every row.
    """

    name: str
    summary: str
    estimator: Callable[..., Any] | None = None
    export: Callable[..., bytes] | None = None
    parity_tol: float = 1e-4
    dtype: str = "float32"
    std_parity: bool = False
    pod_modes: int | None = None
    card_extras: Callable[[Any], dict[str, Any]] = field(default=_no_extras)
    trainer: Callable[..., dict[str, Any]] | None = None
    report: Callable[[Mapping[str, Any]], list[str]] = field(default=steady_report)
    engine: str = "scikit-learn"
    in_memory: Callable[..., Callable[[np.ndarray], np.ndarray]] = field(default=_predict_log)
    sweep: SweepKind | None = None
    quick_options: Mapping[str, Any] = field(default_factory=dict)
    row_cap: int | None = None

    def fit(self, X: np.ndarray, T: np.ndarray, seed: int, options: Mapping[str, Any]) -> Any:
        """The fitted estimator of this kind (``options``: its parameters, ``--options``)."""
        assert self.estimator is not None, f"{self.name} has a pipeline of its own"
        return self.estimator(random_state=seed, **options).fit(X, T)
