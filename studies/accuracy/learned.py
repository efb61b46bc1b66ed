"""The learned models on the study's designs: each way of running them, its error against the
converged FE reference and its time per answer.

Paths: the GP in scikit-learn (float64) and as its ONNX graph (float64); the NN ensemble in
torch eager (float32) and as its ONNX graph (float32), plus the full run-time path
:meth:`surrogate.runtime.predictor.Predictor.predict` (input checks, encoding, ONNX). Every
path is timed at batch 1 (one design per call) and at a large batch (time per row). One
thread everywhere (onnxruntime sessions from ``make_session``, ``torch.set_num_threads(1)``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .designs import Design, StudyData
from .learning_curves import Fitted, heldout_errors
from .metric import Answer, answer_from_log, errors, summary
from .timing import median_us

__all__ = ["BATCH", "BATCH_QUICK", "learned_rows"]

#: Rows of the large-batch timing.
BATCH = 10000
BATCH_QUICK = 1000


def _predictor(sd: StudyData, session: Any, dtype: str) -> Any:
    from surrogate.runtime.predictor import Predictor
    from surrogate.train import edge_radius_rule

    d = sd.data
    card = {"inputs": [s.to_dict() for s in d.specs], "graph": {"dtype": dtype},
            "profile_distance_mm": d.grid_mm.tolist(),
            "edge_radius": edge_radius_rule(d.codes, d.specs, d.edge_radius_mm)}
    return Predictor(card, session)


def learned_rows(gp: Fitted, nn: Fitted, sd: StudyData, designs: Sequence[Design],
                 refs: Sequence[Answer], batch: int) -> tuple[list[dict[str, Any]],
                                                              dict[str, float]]:
    """Rows (method, seconds per answer, error summary on the designs, held-out median) and
    the export parity (largest |d ln| of ONNX vs in-memory, held-out rows, per model)."""
    import torch

    from surrogate.export import export_gp, export_nn
    from surrogate.runtime.predictor import make_session

    torch.set_num_threads(1)
    rows_d = np.array([des.row for des in designs])
    Xd = sd.X[rows_d]
    gp_sess = make_session(export_gp(gp.est, gp.B, gp.b, {}))
    nn_sess = make_session(export_nn(nn.est, nn.B, nn.b, {}))
    module = nn.est.to_module(nn.B, nn.b)
    pred = _predictor(sd, nn_sess, "float32")

    def sk_gp(X: np.ndarray) -> np.ndarray:
        return gp.est.predict(X) @ gp.B + gp.b

    def onnx_gp(X: np.ndarray) -> np.ndarray:
        return gp_sess.run(["log_mean"], {"x": X.astype(np.float64)})[0]

    def torch_nn(X: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return module(torch.as_tensor(X, dtype=torch.float32))[0].double().numpy()

    def onnx_nn(X: np.ndarray) -> np.ndarray:
        return nn_sess.run(["log_mean"], {"x": X.astype(np.float32)})[0].astype(float)

    def runtime_nn(codes: np.ndarray) -> np.ndarray:
        out = pred.predict(codes)
        return np.log(np.column_stack([out["center_amplitude_um"], out["edge_amplitude_um"],
                                       out["normalized_edge"], out["profile_um"]]))

    Xt = sd.X[sd.test]
    parity = {"gp": float(np.abs(onnx_gp(Xt) - sk_gp(Xt)).max()),
              "nn": float(np.abs(onnx_nn(Xt) - torch_nn(Xt)).max())}
    held = {"gp": heldout_errors(gp, sd)["worst_median"],
            "nn": heldout_errors(nn, sd)["worst_median"]}
    big = np.repeat(sd.X, batch // len(sd.X) + 1, axis=0)[:batch]
    big_codes = np.repeat(sd.data.codes, batch // len(sd.X) + 1, axis=0)[:batch]
    paths = [("GP scikit-learn", "gp", sk_gp, False), ("GP ONNX", "gp", onnx_gp, False),
             ("NN torch", "nn", torch_nn, False), ("NN ONNX", "nn", onnx_nn, False),
             ("NN Predictor.predict (checks + ONNX)", "nn", runtime_nn, True)]
    out = []
    for name, kind, fn, codes in paths:
        src = sd.data.codes[rows_d] if codes else Xd
        a = answer_from_log(fn(src))
        errs = [errors(Answer(a.center_um[i], a.edge_um[i], a.profile_um[i]), r)
                for i, r in enumerate(refs)]
        one = src[:1]
        n1 = 20 if kind == "gp" else 300
        t1 = median_us(lambda fn=fn, one=one: fn(one), n1) * 1e-6
        bsrc = big_codes if codes else big
        tb = median_us(lambda fn=fn, bsrc=bsrc: fn(bsrc), 1, repeat=3) * 1e-6 / batch
        fitted = gp if kind == "gp" else nn
        for label, t in (("batch 1", t1), (f"batch {batch}", tb)):
            out.append({"method": f"{name}, {label}", "kind": kind, "seconds": t,
                        "n_train": fitted.n, "train_s": fitted.train_s,
                        "heldout_worst_median": held[kind], **summary(errs)})
    return out, parity
