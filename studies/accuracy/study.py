"""Run the accuracy study: every way to answer on the same designs, one result dict."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

from . import band_models, effects, fe_ladder, learned, learning_curves
from .designs import N_DESIGNS, N_QUICK, load_study_data, pick_designs

__all__ = ["Settings", "run_study"]


@dataclass(frozen=True)
class Settings:
    """What one run measures (``quick``: CI-sized). ``curves``: every learned kind the study
    trains (a steady-state kind of :mod:`surrogate.kinds`) -> its training sizes and options;
    ``runtime_kind`` is also timed through the full run-time predictor. ``band_test`` and
    ``band_train``: the sweep test designs and the MLP peer's training designs of the
    whole-band section (:mod:`.band_models`; None: all test designs, the designs the shipped
    network's card records)."""

    n_designs: int
    levels: tuple[float, ...]
    ref_level: float
    repeat: int
    curves: dict[str, tuple[tuple[int, ...], dict[str, Any]]] = field(default_factory=dict)
    runtime_kind: str = learning_curves.RUNTIME_KIND
    batch: int = learned.BATCH
    quick: bool = False
    band_test: int | None = None
    band_train: int | None = None

    @classmethod
    def make(cls, quick: bool) -> Settings:
        if quick:
            return cls(N_QUICK, fe_ladder.LEVELS_QUICK, fe_ladder.REF_LEVEL_QUICK, 1,
                       learning_curves.curves(quick=True), batch=learned.BATCH_QUICK,
                       quick=True, band_test=band_models.N_TEST_QUICK,
                       band_train=band_models.N_TRAIN_QUICK)
        return cls(N_DESIGNS, fe_ladder.LEVELS, fe_ladder.REF_LEVEL, 3,
                   learning_curves.curves(quick=False))


def run_study(quick: bool = False, log: Any = print) -> dict[str, Any]:
    """Measure everything; return plain data for :func:`studies.accuracy.report.write_report`
    (the learning curves of kind K under ``curves[K]`` and ``K_curve``). ``log`` receives one
    line per finished stage."""
    s = Settings.make(quick)
    t0 = time.perf_counter()
    sd = load_study_data()
    designs = pick_designs(sd, s.n_designs)
    grid = sd.data.grid_mm
    refs, ref_dofs = fe_ladder.reference_answers(designs, grid, s.ref_level)
    log(f"reference solved ({time.perf_counter() - t0:.0f} s)")
    fe = fe_ladder.fe_ladder(designs, refs, grid, s.levels, s.repeat)
    log(f"FE ladder done ({time.perf_counter() - t0:.0f} s)")
    n_tr = 1 if quick else len(designs)  # about 8 s per design
    tr = fe_ladder.transient_rows(designs[:n_tr], refs[:n_tr], grid)
    log(f"transient done ({time.perf_counter() - t0:.0f} s)")
    eff = effects.audit(designs, grid, s.repeat)
    log(f"effects audit done ({time.perf_counter() - t0:.0f} s)")
    curves, fitted = {}, {}
    for kind, (sizes, options) in s.curves.items():
        curves[kind], fitted[kind] = learning_curves.curve(kind, sd, sizes, options)
        log(f"{kind.upper()} learning curve done ({time.perf_counter() - t0:.0f} s)")
    lr, parity = learned.learned_rows(fitted, sd, designs, refs, s.batch, s.runtime_kind)
    log(f"learned models timed ({time.perf_counter() - t0:.0f} s)")
    band = band_models.band_rows(s.band_test, s.band_train, repeat=s.repeat, log=log)
    log(f"whole band done ({time.perf_counter() - t0:.0f} s)")
    return {"settings": s, "designs": designs, "ref_dofs": ref_dofs, "fe": fe, "transient": tr,
            "effects": eff, "curves": curves, **{f"{k}_curve": v for k, v in curves.items()},
            "one_percent": {k: learning_curves.samples_for(v) for k, v in curves.items()},
            "learned": lr, "parity": parity, "band": band, "n_train": int(sd.train.size),
            "n_test": int(sd.test.size), "wall_s": time.perf_counter() - t0}
