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
from surrogate.sweep.export import member_targets
from surrogate.sweep.nn import fit_sweep
from surrogate.sweep.scoring import named_inputs
from surrogate.sweep.targets import load_sweep_datasets, log_magnitudes
from surrogate.train import split

__all__ = ["STACKED", "Setup", "design_codes", "low_answers", "low_features", "mlp_records",
           "overlap", "run", "stacked", "sweep_nn_answers", "sweep_nn_records", "table"]


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
    by_name = named_inputs(codes, specs)
    by_name["frequency_hz"] = np.full(len(codes), float(frequency_hz))
    missing = [n for n in predictor.input_names if n not in by_name]
    if missing:
        raise ValueError(f"the low-fidelity model's inputs {missing} are not in the designs")
    return {n: by_name[n] for n in predictor.input_names}


def _at_frequencies(model: str | Path, codes: np.ndarray, specs: Sequence[InputSpec],
                    freqs_hz: Sequence[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The model's centre and edge amplitude [um] of design ``codes`` at each of ``freqs_hz``
    and whether each (design, frequency) lies outside its trained range, each (n, n_f)."""
    predictor = load_predictor(model)
    outs = [predictor.predict(_inputs(predictor, codes, specs, f), extrapolate=True)
            for f in freqs_hz]
    return tuple(np.column_stack([o[key] for o in outs])  # type: ignore[return-value]
                 for key in ("center_amplitude_um", "edge_amplitude_um", "extrapolated"))


def low_features(model: str | Path, codes: np.ndarray, specs: Sequence[InputSpec],
                 freqs_hz: Sequence[float]) -> tuple[np.ndarray, float]:
    """(features (n, 2 * len(freqs_hz)): the model's ln centre, then ln edge amplitude [ln um]
    at each frequency; the share of (design, frequency) rows outside its trained range)."""
    centre, edge, outside = _at_frequencies(model, codes, specs, freqs_hz)
    return np.column_stack([np.log(centre), np.log(edge)]), float(np.mean(outside))


def low_answers(model: str | Path, codes: np.ndarray, specs: Sequence[InputSpec],
                band_hz: np.ndarray) -> representations.Answers:
    """The low-fidelity model's own centre and edge magnitudes at every band frequency (its
    profile ends elsewhere, so none)."""
    centre, edge, _ = _at_frequencies(model, codes, specs, band_hz)
    return representations.Answers(centre, edge, None)


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


def sweep_nn_answers(est: Any, targets: Any, X: np.ndarray, chunk: int = 128
                     ) -> representations.Answers:
    """Centre, edge and profile magnitudes [um] at every band frequency of a sweep NN fitted
    by :func:`surrogate.sweep.nn.fit_sweep` on feature rows ``X`` (what its graph's
    ``log_mean`` gives at the band's grid: the members' mean of ln |u|)."""
    parts = []
    for a in range(0, len(X), chunk):
        ln_s, z = targets.components(member_targets(est, X[a:a + chunk]))
        parts.append(np.exp(log_magnitudes(z, ln_s[..., None]).mean(axis=0)))
    mag = np.concatenate(parts)                                   # (n, n_f, P)
    return representations.Answers(mag[..., 0], mag[..., 1], mag[..., 1:])


@dataclasses.dataclass(frozen=True)
class Setup:
    """What every learner of the study is run on: the sweep datasets (paths and, as
    :class:`studies.output_choice.data.Sweeps`, the first designs and the test designs with
    the test truth), the sizes, the stacked features of the first designs and of the test
    designs, and the learners' settings."""

    data: str | Path
    test_data: str | Path
    train: sweeps.Sweeps
    test: sweeps.Sweeps
    truth: representations.Answers
    sizes: Sequence[int]
    f_train: np.ndarray
    f_test: np.ndarray
    seed: int
    modes: int
    profile_modes: int
    nn_options: dict[str, Any]
    test_fraction: float
    log: Callable[[str], None]


def _line(rec: dict[str, Any]) -> str:
    return (f"{rec['learner']}, {rec['size']} designs, {rec['inputs']}: centre "
            f"{100 * rec['centre_median']:.2f} / {100 * rec['centre_p95']:.1f} %, edge "
            f"{100 * rec['edge_median']:.2f} / {100 * rec['edge_p95']:.1f} % "
            f"({rec['fit_s']:.0f} s)")


def mlp_records(s: Setup) -> list[dict[str, Any]]:
    """The output-choice study's MLP peer on its complex band (``modes`` + ``profile_modes``),
    fitted on every one of the first ``size`` designs, with and without the stacked
    features."""
    out = []
    for size in s.sizes:
        rows = np.arange(size)
        for inputs, tr, te in (("design", s.train.take(rows), s.test),
                               ("design + low-fidelity", stacked(s.train.take(rows),
                                                                 s.f_train[rows]),
                                stacked(s.test, s.f_test))):
            recs = study.run(tr, te, [learners.make("mlp", s.seed)],
                             [representations.ComplexBand(s.modes, s.profile_modes)], s.seed,
                             log=lambda _: None)
            rec = next(r for r in recs if r["learner"] != study.FLOOR)
            rec.update(size=size, inputs=inputs)
            out.append(rec)
            s.log(_line(rec))
    return out


def sweep_nn_records(s: Setup) -> list[dict[str, Any]]:
    """The sweep NN of ``hapticrom train --kind nn`` (its two stages, ``nn_options``) fitted
    on the split ``hapticrom train --test-fraction`` makes of the first ``size`` designs, with
    and without the stacked features, scored on every test design at the band's grid."""
    train = load_sweep_datasets([s.data]).take(np.arange(len(s.f_train)))
    test = load_sweep_datasets([s.test_data])
    X_test = encode(test.codes, test.specs)
    out = []
    for size in s.sizes:
        fit_rows, _ = split(size, s.test_fraction, s.seed)
        for inputs, feats in (("design", None), ("design + low-fidelity", s.f_train)):
            t0 = time.perf_counter()
            est, targets = fit_sweep(train, fit_rows, seed=s.seed, options=dict(s.nn_options),
                                     features=feats)
            fit_s = time.perf_counter() - t0
            X = X_test if feats is None else np.column_stack([X_test, s.f_test])
            rec = {"learner": "sweep NN", "choice": "complex band (hapticrom train)",
                   "size": size, "inputs": inputs, "train_rows": int(fit_rows.size),
                   "fit_s": fit_s, **study.score(sweep_nn_answers(est, targets, X), s.truth)}
            out.append(rec)
            s.log(_line(rec))
    return out


#: The learners of the study by name (``learner_names`` of :func:`run`).
STACKED: dict[str, Callable[[Setup], list[dict[str, Any]]]] = {
    "mlp-peer": mlp_records, "sweep-nn": sweep_nn_records}


def run(data: str | Path, test_data: str | Path, low: str | Path, *,
        sizes: Sequence[int] = (1024, 2460), freqs_hz: Sequence[float] = (100, 150, 200, 250),
        modes: int = 48, profile_modes: int = 24, seed: int = 0,
        learner_names: Sequence[str] = ("mlp-peer",), nn_options: dict[str, Any] | None = None,
        test_fraction: float = 0.1, log: Callable[[str], None] = print) -> dict[str, Any]:
    """The study's record: the overlap check, the low-fidelity model alone on the test
    designs, and per training size each learner with and without the stacked features.
    ``learner_names``: ``mlp-peer`` (the output-choice study's peer on its complex band, ``modes`` +
    ``profile_modes``, every one of the first ``size`` designs) and ``sweep-nn`` (the network
    of ``hapticrom train --kind nn`` with ``nn_options``, on the split ``--test-fraction``
    ``test_fraction`` makes of them)."""
    unknown = sorted(set(learner_names) - set(STACKED))
    if unknown:
        raise ValueError(f"learners {unknown}: allowed {', '.join(STACKED)}")
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
        "profile_modes": profile_modes, "seed": seed, "learners": list(learner_names),
        "low_features_s": time.perf_counter() - t0,
        "extrapolated_share": {"train": out_train, "test": out_test},
        "overlap": overlap(low, test_codes, specs), "records": []}
    log(f"overlap of {low}'s training designs with the test designs: {record['overlap']}")
    truth = representations.Answers.of(test)
    record["records"].append({"learner": Path(low).name, "size": None, "inputs": "alone",
                              **study.score(low_answers(low, test_codes, specs, test.band),
                                            truth)})
    setup = Setup(data, test_data, full, test, truth, sizes, f_train, f_test, seed, modes,
                  profile_modes, dict(nn_options or {}), test_fraction, log)
    for name in learner_names:
        record["records"] += STACKED[name](setup)
    return record


def _q(r: dict[str, Any], name: str) -> str:
    return " / ".join(f"{100 * r[f'{name}_{k}']:.{d}f}" for k, d in
                      (("median", 2), ("p95", 1), ("p99", 1), ("max", 0)))


def table(record: dict[str, Any]) -> str:
    """The record as a markdown table (errors in %)."""
    lines = ["| learner | designs | inputs | centre med / p95 / p99 / max % "
             "| edge med / p95 / p99 / max % | max err / field % | profile L2 median % |",
             "|---|---|---|---|---|---|---|"]
    for r in record["records"]:
        prof = r.get("profile_l2_median")
        lines.append(f"| {r.get('learner', '-')} | {r['size'] or '-'} | {r['inputs']} | "
                     f"{_q(r, 'centre')} | "
                     f"{_q(r, 'edge')} | {100 * r['max_field']:.1f} | "
                     f"{'-' if prof is None else f'{100 * prof:.2f}'} |")
    return "\n".join(lines)
