"""The one error metric of the accuracy study, and the answers it compares.

An *answer* to "what does this design do" is the center amplitude, the edge amplitude and the
amplitude-distance profile outside the unit's edge (magnitude sqrt(|u_r|^2 + |u_z|^2 +
|u_theta|^2), um, on the dataset's profile grid: 0-20 mm from the edge every 1 mm). The error of
an answer ``a`` against a reference ``r`` has three parts,

    center = |a.center / r.center - 1|,   edge = |a.edge / r.edge - 1|,
    profile = ||a.profile - r.profile||_2 / ||r.profile||_2      (relative L2 over the grid),

and its *error* is the largest of the three (``worst``). Over a set of designs the study
reports the median and the maximum of ``worst``. The held-out errors of the learning curves
use the same function against the dataset's FE answers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fem.results import magnitude

__all__ = ["PARTS", "Answer", "answer_from_log", "answer_from_result", "errors", "summary"]

#: The parts of the error, in report order.
PARTS = ("center", "edge", "profile", "worst")


@dataclass(frozen=True)
class Answer:
    """Center and edge amplitude [um] and the profile [um] on the profile grid; a batch when
    the arrays have a leading row axis."""

    center_um: np.ndarray
    edge_um: np.ndarray
    profile_um: np.ndarray


def answer_from_result(res, grid_mm: np.ndarray) -> Answer:
    """The answer of a harmonic :class:`fem.simulation.SimulationResult`, its profile
    interpolated onto ``grid_mm`` (distances from the edge, mm)."""
    prof = np.interp(grid_mm, res.profile_mm, magnitude(res.profile) * 1e6)
    return Answer(np.asarray(res.center_amplitude_um), np.asarray(res.edge_amplitude_um), prof)


def answer_from_log(log_outputs: np.ndarray) -> Answer:
    """The answer from log outputs in the column order of :func:`surrogate.pod.output_columns`
    ([center, edge, normalized edge, profile...], natural log of um)."""
    y = np.exp(np.asarray(log_outputs, dtype=float))
    return Answer(y[..., 0], y[..., 1], y[..., 3:])


def errors(a: Answer, ref: Answer) -> dict[str, np.ndarray]:
    """The parts of the error of ``a`` against ``ref`` (see the module docstring), one value
    per row (or a scalar for single answers); relative, dimensionless."""
    out = {"center": np.abs(a.center_um / ref.center_um - 1.0),
           "edge": np.abs(a.edge_um / ref.edge_um - 1.0),
           "profile": np.linalg.norm(a.profile_um - ref.profile_um, axis=-1)
           / np.linalg.norm(ref.profile_um, axis=-1)}
    out["worst"] = np.maximum(np.maximum(out["center"], out["edge"]), out["profile"])
    return out


def summary(errs: list[dict[str, np.ndarray]] | dict[str, np.ndarray]) -> dict[str, float]:
    """Median and maximum of every part over designs (a list of per-design errors) or rows
    (one dict of arrays); also the 95th percentile for rows."""
    if isinstance(errs, list):
        errs = {k: np.array([float(e[k]) for e in errs]) for k in PARTS}
    out = {}
    for k in PARTS:
        v = np.asarray(errs[k], dtype=float).ravel()
        out[f"{k}_median"] = float(np.median(v))
        out[f"{k}_p95"] = float(np.percentile(v, 95))
        out[f"{k}_max"] = float(np.max(v))
    return out
