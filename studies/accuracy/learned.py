"""The learned models on the study's designs: each way of running them, its error against the
converged FE reference and its time per answer.

Paths, for every kind the study trains (a steady-state kind of :mod:`surrogate.kinds`): the
estimator in memory (its kind's ``engine``: scikit-learn float64, torch float32) and its ONNX
graph (the kind's dtype); plus, for one kind (``runtime_kind``), the full run-time path
:meth:`surrogate.runtime.predictor.Predictor.predict` (input checks, encoding, ONNX). Every
path is timed at batch 1 (one design per call) and at a large batch (time per row). One
thread everywhere (onnxruntime sessions from ``make_session``, ``torch.set_num_threads(1)``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import torch

from surrogate import kinds
from surrogate.runtime.predictor import Predictor, make_session
from surrogate.train import edge_radius_rule

from .designs import Design, StudyData
from .learning_curves import Fitted, heldout_errors
from .metric import Answer, answer_from_log, errors, summary
from .timing import median_us

__all__ = ["BATCH", "BATCH_QUICK", "learned_rows"]

#: Rows of the large-batch timing.
BATCH = 10000
BATCH_QUICK = 1000
#: Wall time [s] the batch-1 timing of one path aims at (5..300 calls).
SINGLE_BUDGET_S = 0.05


def _predictor(sd: StudyData, session: Any, dtype: str) -> Predictor:
    d = sd.data
    card = {"inputs": [s.to_dict() for s in d.specs], "graph": {"dtype": dtype},
            "profile_distance_mm": d.grid_mm.tolist(),
            "edge_radius": edge_radius_rule(d.codes, d.specs, d.edge_radius_mm)}
    return Predictor(card, session)


def _paths(m: Fitted, sd: StudyData, runtime: bool) -> tuple[
        list[tuple[str, Callable[[np.ndarray], np.ndarray], bool]], float]:
    """(label, function, takes codes) of each way to run ``m``, and the export parity (largest
    |d ln| of ONNX vs in memory on the held-out rows)."""
    spec = kinds.get(m.kind, "kind", steady=True)
    assert spec.export is not None
    sess = make_session(spec.export(m.est, m.B, m.b, {}))
    dtype = np.dtype(spec.dtype)
    in_memory = spec.in_memory(m.est, m.B, m.b)

    def onnx(X: np.ndarray) -> np.ndarray:
        return sess.run(["log_mean"], {"x": X.astype(dtype)})[0].astype(float)

    name = m.kind.upper()
    paths = [(f"{name} {spec.engine}", in_memory, False), (f"{name} ONNX", onnx, False)]
    if runtime:
        pred = _predictor(sd, sess, spec.dtype)

        def predict(codes: np.ndarray) -> np.ndarray:
            out = pred.predict(codes)
            return np.log(np.column_stack([out["center_amplitude_um"], out["edge_amplitude_um"],
                                           out["normalized_edge"], out["profile_um"]]))

        paths.append((f"{name} Predictor.predict (checks + ONNX)", predict, True))
    Xt = sd.X[sd.test]
    return paths, float(np.abs(onnx(Xt) - in_memory(Xt)).max())


def _single_calls(fn: Callable[[np.ndarray], Any], one: np.ndarray) -> int:
    """How many batch-1 calls fit :data:`SINGLE_BUDGET_S`, from one call's time."""
    t = median_us(lambda: fn(one), 1, repeat=1) * 1e-6
    return int(np.clip(SINGLE_BUDGET_S / max(t, 1e-9), 5, 300))


def learned_rows(fitted: Mapping[str, Fitted], sd: StudyData, designs: Sequence[Design],
                 refs: Sequence[Answer], batch: int, runtime_kind: str | None = None
                 ) -> tuple[list[dict[str, Any]], dict[str, float]]:
    """Rows (method, seconds per answer, error summary on the designs, held-out median) of
    every path of every fitted kind, and the export parity per kind."""
    torch.set_num_threads(1)
    rows_d = np.array([des.row for des in designs])
    Xd = sd.X[rows_d]
    big = np.repeat(sd.X, batch // len(sd.X) + 1, axis=0)[:batch]
    big_codes = np.repeat(sd.data.codes, batch // len(sd.X) + 1, axis=0)[:batch]
    out, parity = [], {}
    for kind, m in fitted.items():
        paths, parity[kind] = _paths(m, sd, kind == runtime_kind)
        held = heldout_errors(m, sd)["worst_median"]
        for name, fn, codes in paths:
            src = sd.data.codes[rows_d] if codes else Xd
            a = answer_from_log(fn(src))
            errs = [errors(Answer(a.center_um[i], a.edge_um[i], a.profile_um[i]), r)
                    for i, r in enumerate(refs)]
            one = src[:1]
            t1 = median_us(lambda fn=fn, one=one: fn(one), _single_calls(fn, one)) * 1e-6
            bsrc = big_codes if codes else big
            tb = median_us(lambda fn=fn, bsrc=bsrc: fn(bsrc), 1, repeat=3) * 1e-6 / batch
            for label, t in (("batch 1", t1), (f"batch {batch}", tb)):
                out.append({"method": f"{name}, {label}", "kind": kind, "seconds": t,
                            "n_train": m.n, "train_s": m.train_s,
                            "heldout_worst_median": held, **summary(errs)})
    return out, parity
