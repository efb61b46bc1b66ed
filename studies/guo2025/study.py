"""``reproduce``: run every study of the paper and write the report (README.md, PNG figures,
results.json with every number) into a directory, atomically."""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fem import SOLVER_VERSION
from surrogate.data.pool import check_workers

from .cases import PROFILE_STEP_MM, SCENES_DIR, Context, plan
from .checks import (
    check_amplitude_definition,
    check_centre_definition,
    check_mesh,
    check_motor,
    check_pogo,
    check_transient,
)
from .contact import check_ring_contact
from .discussion import discussion_text
from .figures import write_figures
from .outdir import check_out_dir, write_report_dir
from .report import _model_text, closest_summary, render
from .run import run_cases
from .solved import Solved
from .studies import (
    study_context,
    study_orientation,
    study_pogo,
    study_single,
    study_sweeps,
    study_triples,
)
from .text import Section


@dataclass(frozen=True)
class Reproduction:
    """What ``reproduce`` produced: the report directory, the sections, timings (s)."""

    out_dir: Path
    sections: tuple[Section, ...]
    checks: tuple[Section, ...]
    wall_s: float
    solve_s: float
    n_cases: int
    n_solves: int
    workers: int
    quick: bool



def _json_ready(r: Mapping[str, Solved]) -> dict:
    """Per-case numbers; profiles every 1 mm (the figures use the finer samples)."""
    out = {}
    every = max(1, round(1.0 / PROFILE_STEP_MM))
    for name, s in sorted(r.items()):
        out[name] = {"centre_um": s.centre_um, "edge_um": s.edge_um, "edge_uz_um": s.edge_z_um,
                     "normalized_edge": s.norm, "normalized_edge_uz": s.norm_z,
                     "edge_mm": s.edge_mm, "centre_variants_um": s.centre_variants_um(),
                     "profile": {
                         "distance_from_edge_mm": s.profile_mm[::every].tolist(),
                         "magnitude_over_centre": s.normalized_profile()[::every].tolist(),
                         "uz_over_centre": s.normalized_profile(True)[::every].tolist()},
                     "wall_s": s.wall_s, "dofs": s.dofs, "contact": s.contact}
    return out


def reproduce(out: str | os.PathLike = "reports/reproduce", workers: int | None = None,
              quick: bool = False, scenes_dir: str | os.PathLike = SCENES_DIR,
              log: Callable[[str], None] = print, progress: bool = True) -> Reproduction:
    """Run every study and write the report (README.md, PNGs, results.json) into ``out``.

    Args:
        out: report directory: new, empty, or an earlier report (it holds the marker file of
            :mod:`.outdir`); replaced as a whole once everything succeeded.
        workers: process-pool size (None = every core).
        quick: the reduced case set of :func:`plan` (for tests).
        scenes_dir: where the ``unit-*.toml`` scenes live (default: the shipped ones).
        progress: a progress bar (rate, ETA) on stderr when it is a terminal.

    Workers are spawned processes: a script calling this needs the usual
    ``if __name__ == "__main__":`` guard (the ``hapticrom`` command has it).
    Raises:
        ValueError: bad ``workers`` or ``out`` (nothing is written).
    """
    t0 = time.perf_counter()
    n_workers = check_workers(workers)
    out_dir = check_out_dir(out)
    p = plan(quick)
    log(f"hapticrom reproduce: {len(p.cases)} cases on {n_workers} worker(s)"
        + (" (quick)" if quick else ""))
    ctx = Context.build(scenes_dir)
    r = run_cases(p.cases, n_workers, ctx.scenes_dir, log, p.follow, progress)
    sections = [study_orientation(r, ctx), study_pogo(r, ctx), study_single(r, ctx),
                study_triples(r, p.triples, ctx), study_sweeps(r, p.sweeps),
                study_context(r, ctx)]
    checks = {"a": check_amplitude_definition(r, p.triples),
              "b": check_centre_definition(r, p.triples)}
    if not quick:
        checks.update(c=check_motor(r, ctx), d=check_pogo(r, ctx))
    extra = {"e": check_transient(r, ctx), "f": check_mesh(r, ctx),
             "g": check_ring_contact(r, p.triples, ctx)}
    checks.update({k: v for k, v in extra.items() if v is not None})
    unique = {id(s): s for s in r.values()}
    solve_s = sum(s.wall_s for s in unique.values())
    keyed = dict(zip(("orientation", "pogo", "single", "triples", "sweeps", "context"),
                     sections, strict=True))
    discussion = discussion_text(r, p.triples, keyed, checks, ctx)
    note = closest_summary(keyed, checks, ctx)
    model = _model_text(r, ctx)

    def fill(tmp: Path) -> None:
        write_figures(r, p, tmp, ctx.default)
        run = {"quick": quick, "n_solves": len(unique), "n_cases": len(r),
               "workers": n_workers, "wall_s": time.perf_counter() - t0, "solve_s": solve_s}
        (tmp / "README.md").write_text(render(sections, list(checks.values()), discussion,
                                              run, r, model, note))
        doc = {"solver_version": SOLVER_VERSION, "run": run,
               "studies": {s.title: s.data for s in sections},
               "checks": {s.title: s.data for s in checks.values()}, "cases": _json_ready(r)}
        (tmp / "results.json").write_text(json.dumps(_finite(doc), indent=1, allow_nan=False)
                                          + "\n")

    write_report_dir(out_dir, fill)
    wall = time.perf_counter() - t0
    log(f"wrote {out_dir} in {wall:.1f} s ({len(unique)} solves, sum of solve times "
        f"{solve_s:.1f} s)")
    return Reproduction(out_dir, tuple(sections), tuple(checks.values()), wall, solve_s,
                        len(r), len(unique), n_workers, quick)


def _finite(x: Any) -> Any:
    """``x`` with numpy scalars as Python numbers and NaN / inf as None (strict JSON)."""
    if isinstance(x, Mapping):
        return {str(k): _finite(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_finite(v) for v in x]
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x
