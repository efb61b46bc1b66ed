"""Multi-fidelity by stacking: a cheap model's predictions as extra inputs of the sweep learner.

The nonlinear autoregressive scheme of Perdikaris et al. (2017, Proc. R. Soc. A 473:
20160751): the high-fidelity response is learned as f_high(x, f_low(x)), so a learner sees
the low-fidelity prediction beside the design. Here the low fidelity is a single-frequency
model (``models/nn-default``, trained on one frequency per FE row of ``datasets/default``,
its profile to 20 mm) and the high fidelity the whole-band sweep. For every design its
predicted ln centre and ln edge amplitude at a few band frequencies (the run-time predictor,
the design's inputs plus ``frequency_hz``) are appended to the encoded design features; the
same learner (the scikit-learn MLP peer of :mod:`studies.output_choice` on its complex band)
is trained with and without them on the same first designs of the sweep dataset and scored on
the same test designs at every band frequency (:func:`studies.output_choice.study.score`).

:func:`overlap` checks that the low-fidelity model never saw the test designs: the nearest
training design of its dataset to each test design, in the encoded design features.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from studies.output_choice import data as sweeps
from studies.output_choice import learners, representations, study
from surrogate.data.store import Store
from surrogate.features import codes_from_frame
from surrogate.runtime.encoding import InputSpec, encode
from surrogate.runtime.predictor import load_predictor

__all__ = ["design_codes", "low_features", "overlap", "run", "stacked", "table"]


def design_codes(path: str | Path, specs: Sequence[InputSpec]) -> np.ndarray:
    """The design codes (n, d) of ``specs`` of the ok rows of the dataset at ``path``, in its
    design-sequence order (the order :func:`studies.output_choice.data.load` reads)."""
    store = Store.open(path)
    names = [s.name for s in specs]
    df = store.read(columns=[*names, "status", "sample_index"])
    df = df[df["status"] == "ok"].sort_values("sample_index", kind="stable")
    return codes_from_frame(df.reset_index(drop=True), list(specs))


def _inputs(predictor: Any, codes: np.ndarray, specs: Sequence[InputSpec],
            frequency_hz: float) -> dict[str, np.ndarray]:
    """The predictor's named inputs of design ``codes`` at one frequency (categoricals by
    their choice names)."""
    by_name = {s.name: (codes[:, j] if s.type != "categorical"
                        else np.asarray(s.choices)[codes[:, j].astype(int)])
               for j, s in enumerate(specs)}
    by_name["frequency_hz"] = np.full(len(codes), float(frequency_hz))
    missing = [n for n in predictor.input_names if n not in by_name]
    if missing:
        raise ValueError(f"the low-fidelity model's inputs {missing} are not in the designs")
    return {n: by_name[n] for n in predictor.input_names}


def low_features(model: str | Path, codes: np.ndarray, specs: Sequence[InputSpec],
                 freqs_hz: Sequence[float]) -> tuple[np.ndarray, float]:
    """(features (n, 2 * len(freqs_hz)): the model's ln centre, then ln edge amplitude [ln um]
    at each frequency; the share of (design, frequency) rows outside its trained range)."""
    predictor = load_predictor(model)
    cols, outside = [], []
    for f in freqs_hz:
        out = predictor.predict(_inputs(predictor, codes, specs, f), extrapolate=True)
        cols.append((np.log(out["center_amplitude_um"]), np.log(out["edge_amplitude_um"])))
        outside.append(out["extrapolated"])
    feats = np.column_stack([c for c, _ in cols] + [e for _, e in cols])
    return feats, float(np.mean(outside))


def low_answers(model: str | Path, codes: np.ndarray, specs: Sequence[InputSpec],
                band_hz: np.ndarray) -> representations.Answers:
    """The low-fidelity model's own centre and edge magnitudes at every band frequency (its
    profile ends elsewhere, so none)."""
    predictor = load_predictor(model)
    c, e = [], []
    for f in band_hz:
        out = predictor.predict(_inputs(predictor, codes, specs, f), extrapolate=True)
        c.append(out["center_amplitude_um"])
        e.append(out["edge_amplitude_um"])
    return representations.Answers(np.column_stack(c), np.column_stack(e), None)


def overlap(model: str | Path, test_codes: np.ndarray, specs: Sequence[InputSpec]
            ) -> dict[str, Any]:
    """Whether the low-fidelity model's training designs include test designs: per test
    design the distance to the nearest design of the model's training datasets (its card's
    ``training_data``), in the encoded design features of ``specs`` (frequency left out)."""
    card = load_predictor(model).card
    paths = [s["path"] for s in card["training_data"]]
    train = np.concatenate([design_codes(p, specs) for p in paths])
    a, b = encode(train, list(specs)), encode(test_codes, list(specs))
    nearest = np.empty(len(b))
    for i in range(0, len(b), 64):
        d = np.sqrt(((b[i:i + 64, None, :] - a[None, :, :]) ** 2).sum(-1))
        nearest[i:i + 64] = d.min(axis=1)
    return {"training_data": paths, "training_designs": len(train), "test_designs": len(b),
            "identical": int(np.sum(nearest < 1e-9)), "nearest_min": float(nearest.min()),
            "nearest_median": float(np.median(nearest))}


def stacked(sw: sweeps.Sweeps, feats: np.ndarray) -> sweeps.Sweeps:
    """``sw`` with ``feats`` (n, k) appended to its design features."""
    if len(feats) != len(sw):
        raise ValueError(f"{len(feats)} feature rows for {len(sw)} designs")
    return dataclasses.replace(sw, x=np.column_stack([sw.x, feats]))


def run(data: str | Path, test_data: str | Path, low: str | Path, *,
        sizes: Sequence[int] = (1024, 2460), freqs_hz: Sequence[float] = (100, 150, 200, 250),
        modes: int = 48, profile_modes: int = 24, seed: int = 0, learner: str = "mlp",
        log: Callable[[str], None] = print) -> dict[str, Any]:
    """The study's record: the overlap check, the low-fidelity model alone on the test
    designs, and per training size the learner with and without the stacked features."""
    n_max = max(sizes)
    full, specs = sweeps.load(str(data), limit=n_max)
    if len(full) < n_max:
        raise ValueError(f"{data}: {len(full)} designs, fewer than --sizes asks ({n_max})")
    test, _ = sweeps.load(str(test_data), specs=specs)
    train_codes = design_codes(data, specs)[:n_max]
    test_codes = design_codes(test_data, specs)
    t0 = time.perf_counter()
    f_train, out_train = low_features(low, train_codes, specs, freqs_hz)
    f_test, out_test = low_features(low, test_codes, specs, freqs_hz)
    record: dict[str, Any] = {
        "data": str(data), "test_data": str(test_data), "low": str(low),
        "freqs_hz": [float(f) for f in freqs_hz], "modes": modes,
        "profile_modes": profile_modes, "seed": seed, "learner": learner,
        "low_features_s": time.perf_counter() - t0,
        "extrapolated_share": {"train": out_train, "test": out_test},
        "overlap": overlap(low, test_codes, specs), "records": []}
    log(f"overlap of {low}'s training designs with the test designs: {record['overlap']}")
    truth = representations.Answers.of(test)
    record["records"].append({"size": None, "inputs": f"{Path(low).name} alone",
                              **study.score(low_answers(low, test_codes, specs, test.band),
                                            truth)})
    for size in sizes:
        rows = np.arange(size)
        for inputs, tr, te in (("design", full.take(rows), test),
                               ("design + low-fidelity",
                                stacked(full.take(rows), f_train[rows]),
                                stacked(test, f_test))):
            made = learners.make(learner, seed)
            recs = study.run(tr, te, [made], [representations.ComplexBand(modes, profile_modes)],
                             seed, log=lambda s: None)
            rec = next(r for r in recs if r["learner"] != study.FLOOR)
            rec.update(size=size, inputs=inputs)
            record["records"].append(rec)
            log(f"{size} designs, {inputs}: centre {100 * rec['centre_median']:.2f} / "
                f"{100 * rec['centre_p95']:.1f} %, edge {100 * rec['edge_median']:.2f} / "
                f"{100 * rec['edge_p95']:.1f} % ({rec['fit_s']:.0f} s)")
    return record


def _q(r: dict[str, Any], name: str) -> str:
    return " / ".join(f"{100 * r[f'{name}_{k}']:.{d}f}" for k, d in
                      (("median", 2), ("p95", 1), ("p99", 1), ("max", 0)))


def table(record: dict[str, Any]) -> str:
    """The record as a markdown table (errors in %)."""
    lines = ["| designs | inputs | centre med / p95 / p99 / max % | edge med / p95 / p99 / max % "
             "| max err / field % | profile L2 median % |", "|---|---|---|---|---|---|"]
    for r in record["records"]:
        prof = r.get("profile_l2_median")
        lines.append(f"| {r['size'] or '-'} | {r['inputs']} | {_q(r, 'centre')} | "
                     f"{_q(r, 'edge')} | {100 * r['max_field']:.1f} | "
                     f"{'-' if prof is None else f'{100 * prof:.2f}'} |")
    return "\n".join(lines)
