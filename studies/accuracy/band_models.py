"""The whole band on fresh designs: the shipped sweep models, the single-frequency model they
replace and a scikit-learn MLP peer, against the FE sweep they answer for.

Every model answers the question the sweep dataset asks of a design: the centre and edge
amplitudes and the 0-40 mm profile at every band frequency (100-250 Hz every 2 Hz). The test
designs are those of ``datasets/default-sweep-test`` (another Sobol seed than the training set;
no model saw them), in design order: all of them, or the first :data:`N_TEST_QUICK` with
``--quick``. The models:

* the shipped defaults of the ``harmonic`` and ``gaussian_process`` roles
  (:func:`surrogate.runtime.defaults.default_model_path`: ``nn-sweep`` and ``gp-sweep`` when
  installed) and ``nn-default`` (the former single-frequency default, its profile 0-20 mm),
  each through the run-time :class:`surrogate.runtime.predictor.Predictor` at every
  (design, band frequency) pair;
* the MLP peer of ``bench/surrogate/output_choice.py`` (:mod:`studies.output_choice`: its
  ``mlp`` learner on its complex-band representation, :data:`MODES` + :data:`PROFILE_MODES`
  POD modes), fitted here on the training designs the shipped network's card records (its
  ``training_data`` rows of ``datasets/default-sweep``: the first that many designs in Sobol
  order; ``--quick``: the first :data:`N_TRAIN_QUICK`). The shipped models fit on part of those
  designs (their cards' ``training`` rows; the rest held out for their cards and interval
  calibration); the peer on all.

The errors are those of the cards' ``test_set`` and ``bench/surrogate/sweep_nn.py``
(:func:`surrogate.sweep.scoring.score_pairs`, over every test design x band frequency). Time per
answer is one design's whole band: one call with the design's 76 frequencies (batch 1), and
one call with every test design divided by their number (batched); one thread. The FE sweep's
time per design is the solver time the test dataset recorded for those designs (``wall_s``,
one core each, the generation's two workers beside other jobs).

* the LightGBM peer of the same study (its ``lgbm`` learner, one booster of 3,000 trees per
  target, on the same complex band; :data:`PEER_WORKERS` processes fit the boosters), fitted
  on the same designs, when the ``bench`` extra has installed ``lightgbm`` (otherwise left
  out, and the report says so).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from studies.output_choice import data as oc_data
from studies.output_choice import learners as oc_learners
from studies.output_choice.representations import ComplexBand
from surrogate.data.store import Store
from surrogate.runtime.card import read_card
from surrogate.runtime.defaults import default_model_path, is_sweep_model
from surrogate.runtime.models import find_model
from surrogate.runtime.predictor import load_predictor
from surrogate.sweep.scoring import predict_pairs, score_pairs
from surrogate.sweep.targets import load_sweep_datasets, pair_rows

from .timing import median_us, timed

__all__ = ["LEAD", "MODES", "N_TEST_QUICK", "N_TRAIN_QUICK", "PEERS", "PEER_WORKERS",
           "PROFILE_MODES", "ROLES", "SINGLE", "TARGETS", "TEST", "TRAIN", "band_rows", "lead",
           "meets", "model_row", "peer_row", "peers", "shipped_models", "training_designs"]

_DATASETS = Path(__file__).resolve().parents[2] / "datasets"
#: The sweep training set and the fresh test designs.
TRAIN = _DATASETS / "default-sweep"
TEST = _DATASETS / "default-sweep-test"
N_TEST_QUICK = 32
N_TRAIN_QUICK = 256
#: POD modes of the peer's complex band (centre + edge, profile): those of docs/peers.md.
MODES = 48
PROFILE_MODES = 24
#: The peers: (``studies.output_choice`` learner on the complex band, short name, label).
PEERS = (("mlp", "MLP", "scikit-learn MLP 3x128"),
         ("lgbm", "LightGBM", "LightGBM, 3,000 trees a target"))
#: Processes fitting LightGBM's per-target boosters (the boosters do not depend on it).
PEER_WORKERS = 2
#: The roles whose shipped defaults are scored, then the single-frequency model.
ROLES = ("harmonic", "gaussian_process")
SINGLE = "nn-default"
#: Issue 36's targets for the shipped harmonic model on fresh designs (fractions).
TARGETS = {"centre median": 0.01, "centre p95": 0.05, "max error / field": 0.10,
           "profile L2 median": 0.02}
#: The p95 lead the shipped model should have over every peer (peer p95 / model p95).
LEAD = 2.0
#: Wall time [s] the batch-1 timing of one model aims at (3..100 calls).
SINGLE_BUDGET_S = 0.3


def shipped_models() -> list[tuple[str, Path]]:
    """(role label, model directory) of the scored Predictor models, in table order."""
    out = [(role, default_model_path(role)) for role in ROLES]
    single = find_model(SINGLE)
    if all(path.resolve() != single.resolve() for _, path in out):
        out.append(("single frequency", single))
    return out


def training_designs(model: Path, train: Path = TRAIN) -> int:
    """How many designs of ``train`` the card of ``model`` records (``training_data`` rows of
    the dataset of the same name); ValueError when the card names none."""
    rows = [int(s["rows"]) for s in read_card(model, verify=False).get("training_data", [])
            if Path(s["path"]).name == train.name]
    if not rows:
        raise ValueError(f"{model}: its card names no training rows of {train.name}")
    return rows[0]


def _calls(fn: Callable[[], Any]) -> int:
    """Batch-1 calls that fit :data:`SINGLE_BUDGET_S`, from one call's time."""
    t = median_us(fn, 1, repeat=1) * 1e-6
    return int(np.clip(SINGLE_BUDGET_S / max(t, 1e-9), 3, 100))


def _row(method: str, s: dict[str, Any], t1: float, tb: float, n_designs: int,
         **extra: Any) -> dict[str, Any]:
    """A table row from :func:`score_pairs`'s result: centre and edge [median, p95, p99, max],
    the largest error over the field, the profile's L2 median (its grid)."""
    whole = "profile_all" in s
    prof = s["profile_all" if whole else "profile_0_20mm"]
    return {"method": method, "seconds_1": t1, "seconds_batch": tb, "batch": n_designs,
            "centre": s["centre"][:4], "edge": s["edge"][:4],
            "max_field": max(s["centre"][4], s["edge"][4]),
            "profile_median": prof[0], "profile_p95": prof[1],
            "profile_grid": "0-40 mm" if whole else "0-20 mm",
            "coverage": [s.get("centre_coverage95"), s.get("edge_coverage95")], **extra}


def model_row(label: str, path: Path, test: Any, designs: np.ndarray, repeat: int
              ) -> dict[str, Any]:
    """Score and time the model directory ``path`` through the run-time predictor on
    ``designs`` of the sweep test data ``test`` (:func:`load_sweep_datasets`)."""
    p = load_predictor(path)
    card = read_card(path, verify=False)
    codes, centre, profile, _ = pair_rows(test, designs)
    pred, tb = timed(lambda: predict_pairs(p, test, codes), repeat)
    one = codes[:test.band_hz.size]

    def single() -> Any:
        return predict_pairs(p, test, one)

    t1 = median_us(single, _calls(single), repeat=3) * 1e-6
    unit = "designs" if is_sweep_model(card) else "rows (one frequency each)"
    trained = ", ".join(f"{int(s.get('rows', 0)):,} {unit} of {Path(s.get('path', '?')).name}"
                        for s in card.get("training_data", []))
    return _row(f"{path.name} ({label})", score_pairs(pred, centre, profile, test.grid_mm), t1,
                tb / designs.size, designs.size, model=path.name, role=label,
                trained=trained, fitted=int(card.get("training", {}).get("rows", 0)))


def peers() -> list[str]:
    """The peers this machine can fit: those whose optional package (the MLP needs none,
    LightGBM ``lightgbm``) imports."""
    return [learner for learner, *_ in PEERS
            if (need := oc_learners.LEARNERS[learner].needs) is None
            or oc_learners.importable(need)]


def peer_row(learner: str, train: Path, test: Path, n_train: int,
             truth: tuple[np.ndarray, ...], n_test: int, repeat: int,
             seed: int = 0) -> dict[str, Any]:
    """Fit the peer ``learner`` (:data:`PEERS`; :mod:`studies.output_choice` on the complex
    band) on the first ``n_train`` designs of ``train``; score and time it on the first
    ``n_test`` designs of ``test`` against ``truth`` (their pairs' centre, profile and grid, as
    :func:`model_row` scores them), one BLAS thread (LightGBM's boosters fitted by
    :data:`PEER_WORKERS` processes, its answers timed on one)."""
    with threadpool_limits(1), warnings.catch_warnings():
        warnings.filterwarnings("ignore", module="sklearn")
        tr, specs = oc_data.load(str(train), limit=n_train)
        te, _ = oc_data.load(str(test), limit=n_test, specs=specs)
        if te.band.shape != tr.band.shape or (te.band != tr.band).any():
            raise ValueError(f"{test}: its band differs from {train}'s")
        choice = ComplexBand(MODES, PROFILE_MODES)
        t0 = time.perf_counter()
        x, y = choice.training(tr, np.random.default_rng(seed))
        model = oc_learners.make(learner, seed, workers=PEER_WORKERS).fit(x, y)
        fit_s = time.perf_counter() - t0

        def answer(sw: oc_data.Sweeps) -> dict[str, np.ndarray]:
            a = choice.decode(model(choice.query(sw)), sw)
            n_pairs = a.center.size
            return {"center_amplitude_um": a.center.reshape(n_pairs),
                    "edge_amplitude_um": a.edge.reshape(n_pairs),
                    "profile_um": a.profile.reshape(n_pairs, -1)}

        pred, tb = timed(lambda: answer(te), repeat)
        one = te.take(np.arange(1))

        def single() -> Any:
            return answer(one)

        t1 = median_us(single, _calls(single), repeat=3) * 1e-6
    short, label = next(p[1:] for p in PEERS if p[0] == learner)
    name = f"{label}, complex band ({MODES} + {PROFILE_MODES} modes)"
    return _row(name, score_pairs(pred, *truth), t1, tb / len(te), len(te), model=learner,
                short=short,
                role="peer", trained=f"{len(tr):,} designs of {train.name}", fitted=len(tr),
                fit_s=fit_s)


def meets(row: dict[str, Any]) -> dict[str, tuple[float, bool]]:
    """Each of :data:`TARGETS` -> (the row's value, whether it is below the target)."""
    got = {"centre median": row["centre"][0], "centre p95": row["centre"][1],
           "max error / field": row["max_field"], "profile L2 median": row["profile_median"]}
    return {k: (v, v < TARGETS[k]) for k, v in got.items()}


def lead(row: dict[str, Any], peer: dict[str, Any]) -> dict[str, float]:
    """The p95 lead of ``row`` over ``peer`` at the centre and the edge (peer p95 / row p95)."""
    return {k: peer[k][1] / row[k][1] for k in ("centre", "edge")}


def band_rows(n_test: int | None, n_train: int | None, *, train: Path = TRAIN,
              test: Path = TEST, models: Sequence[tuple[str, Path]] | None = None,
              repeat: int = 3, log: Callable[[str], None] = lambda m: None,
              peer_learners: Sequence[str] | None = None) -> dict[str, Any]:
    """Every row of the section (the Predictor models, then the peers), the FE sweep's
    recorded time per design (``fe``; None when the test set recorded none), and what was
    used: ``n_test`` test designs (None: all), ``n_train`` peer training designs (None: what
    the card of the first of ``models`` records), ``models`` ((label, directory); None:
    :func:`shipped_models`), ``peer_learners`` (None: :func:`peers`)."""
    t0 = time.perf_counter()
    models = list(models) if models is not None else shipped_models()
    first = models[0][1]
    recorded = training_designs(first, train)
    n_train = recorded if n_train is None else min(n_train, recorded)
    data = load_sweep_datasets([test])
    n = len(data.codes) if n_test is None else min(n_test, len(data.codes))
    designs = np.arange(n)
    rows = []
    for label, path in models:
        rows.append(model_row(label, path, data, designs, repeat))
        log(f"whole band: {path.name} scored ({time.perf_counter() - t0:.0f} s)")
    _, centre, profile, _ = pair_rows(data, designs)
    for learner in peers() if peer_learners is None else peer_learners:
        rows.append(peer_row(learner, train, test, n_train, (centre, profile, data.grid_mm), n,
                             repeat))
        log(f"whole band: {learner} peer fitted and scored ({time.perf_counter() - t0:.0f} s)")
    df = Store.open(test).read(columns=["sample_index", "status", "wall_s"])
    df = df[df["status"] == "ok"].sort_values("sample_index", kind="stable")
    wall = df["wall_s"].to_numpy(float)[:n]
    wall = wall[np.isfinite(wall)]  # a dataset written without solver times has NaN
    return {"rows": rows, "n_test": n, "n_test_all": len(data.codes), "n_train": n_train,
            "recorded_train": recorded, "train": train.name, "test": test.name,
            "test_seed": int(Store.open(test).space.seed),
            "band_hz": [float(data.band_hz[0]), float(data.band_hz[-1]), int(data.band_hz.size)],
            "fe": {"median_s": float(np.median(wall)), "mean_s": float(np.mean(wall)),
                   "p95_s": float(np.percentile(wall, 95)), "designs": int(wall.size)}
            if wall.size else None,
            "first_model": first.name, "wall_s": time.perf_counter() - t0}
