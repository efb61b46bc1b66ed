"""The calibration document (``kind = "hapticrom.calibration"``, schema version 1; its JSON Schema
is ``hapticrom/schemas/calibration.json``, docs/calibration.md describes every key), and reading
it back as the tissue of a layout.

``tissue`` holds the point estimate a layout's ``[site]`` takes (posterior means of the fitted
inputs, plus the known tissue inputs the fit held fixed); ``samples`` holds posterior draws of
the fitted inputs, which the planner plans over to carry the uncertainty into the pitch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from calibration.fit import IDENTIFIABLE_WIDTH_RATIO, KEPT_SAMPLES, Calibration
from fieldspec import FieldError
from fieldspec.documents import read_json_file

__all__ = ["KIND", "SCHEMA_VERSION", "CalibrationFileError", "Tissue", "calibration_document",
           "read_calibration", "statement"]

KIND = "hapticrom.calibration"
SCHEMA_VERSION = 1
LIKELIHOOD = ("ln y - ln mu(theta) = e + n, n ~ N(0, diag((sigma_i/y_i)^2)), per output read "
              "and cluster of its frequencies (neighbours at most shared_within_hz apart) "
              "e | lam ~ N(0, lam diag(c s) C diag(c s)), lam ~ InverseGamma(nu/2, nu/2) (a "
              "multivariate Student-t; independent between clusters; lam = 1, c = k for an "
              "output whose surrogate_error nu is null: the Gaussian): y the "
              "measured peak displacement amplitudes, sigma_i their stated standard "
              "uncertainties, mu the surrogate's prediction, s its predictive log-std (95 % "
              "bounds exp(+-1.96 s); surrogate_spread 'posterior': s held fixed at its root-mean-"
              "square over the late burn-in walkers, 'local': s at each theta), c (per frequency: "
              "scale_by_frequency_hz) and nu per output in surrogate_error, k the surrogate's "
              "std factor, C the correlation of its errors: along a profile output its "
              "profile_kernel of |d_i - d_j| / error_length_mm[output] (matern32: (1 + a) "
              "exp(-a), a = sqrt(3) |d_i - d_j| / length; exponential: exp(-|d_i - d_j| / "
              "length)) times, across frequencies, its frequency_kernel (gaussian: "
              "exp(-(f_i - f_j)^2 / (2 error_frequency_hz[output]^2)); exponential: "
              "exp(-|f_i - f_j| / error_frequency_hz[output])), none between clusters nor "
              "between points of different outputs (the face and the profile, the magnitude and "
              "the normal component)")


class CalibrationFileError(FieldError):
    """A calibration document that cannot be used (``.field`` names the key)."""


def _r(x: float, digits: int = 6) -> float:
    return float(f"{x:.{digits}g}")


def statement(summary: dict[str, dict[str, Any]]) -> str:
    """One sentence on what the data determine and what they do not."""
    bad = [n for n, s in summary.items() if not s["identifiable"]]
    good = [n for n in summary if n not in bad]
    text = (f"determined by the data: {', '.join(good)}" if good else
            "the data determine none of the fitted inputs")
    if bad:
        text += (f"; not determined (95 % posterior interval wider than "
                 f"{IDENTIFIABLE_WIDTH_RATIO:g} of the prior's): {', '.join(bad)} - its "
                 "posterior is mostly the prior; measure more points, farther from the unit "
                 "or at more frequencies, or fix it")
    return text


def _error_model(cal: Calibration) -> dict[str, dict[str, Any]]:
    """Per output read: the surrogate's error model as used (the scale at each measured
    frequency of that output, and its mean over the output's points) and where it came from
    (``source``: the model card's own, SURROGATE_ERROR_T, or the Gaussian)."""
    fwd = cal.forward
    c = cal.point_scale
    f = np.array([p.frequency_hz for p in fwd.measurement.points])
    out = {}
    for g in fwd.groups:
        e = cal.error_model[g.output]
        per_f = {f"{x:g}": _r(float(np.mean(c[g.index][f[g.index] == x])), 4)
                 for x in np.unique(f[g.index])}
        out[g.output] = {
            "nu": None if e["nu"] is None else _r(e["nu"], 4),
            "scale": _r(float(np.mean(c[g.index])), 4), "scale_by_frequency_hz": per_f,
            "length_mm": e["length_mm"], "frequency_hz": e["frequency_hz"],
            "shared_within_hz": e["shared_within_hz"], "profile_kernel": e["profile_kernel"],
            "frequency_kernel": e["frequency_kernel"], "source": e["source"]}
    return out


def calibration_document(cal: Calibration, *, model_path: str, tissue_names: list[str],
                         seed: int = 0, interval: str = "hdi") -> dict[str, Any]:
    """The versioned document of a fitted calibration (``interval``: the kind of the
    reported ``ci95``, :data:`calibration.fit.INTERVAL_KINDS`)."""
    card = cal.forward.predictor.card
    summary = cal.summary(seed, interval=interval)
    m = cal.measurement
    mean, std = cal.forward.predict(np.array([[cal.mean_inputs()[n] for n in cal.names]]))
    total = np.sqrt(cal.forward.rel_sigma ** 2 + (cal.point_scale * std[0]) ** 2)
    resid = (cal.forward.y - mean[0]) / total
    point = {**{k: v for k, v in cal.forward.fixed.items() if k in tissue_names},
             **{k: _r(v) for k, v in cal.mean_inputs().items()}}
    rng = np.random.default_rng(seed)
    keep = rng.choice(len(cal.samples), size=min(KEPT_SAMPLES, len(cal.samples)), replace=False)
    corr = cal.correlation()
    return {
        "schema_version": SCHEMA_VERSION, "kind": KIND,
        "model": {"path": str(model_path), "name": card.get("name"), "kind": card.get("kind"),
                  "card_sha256": card.get("card_sha256")},
        "measurement": {
            "file": m.source or None, "subject": m.meta.get("subject"),
            "source": m.meta.get("source"), "design": m.design, "site": m.site,
            "points": [{"row": p.row, "reference": p.reference,
                        "distance_mm": _r(p.distance_m * 1e3), "frequency_hz": p.frequency_hz,
                        "quantity": p.quantity, "unit": p.unit, "statistic": p.statistic,
                        "component": p.component, "value": p.value,
                        "uncertainty": _r(p.uncertainty),
                        "amplitude_um": _r(p.amplitude_m * 1e6),
                        "sigma_um": _r(p.sigma_m * 1e6)} for p in m.points]},
        "fit": list(cal.names),
        "fixed": cal.forward.fixed,
        "priors": {p.name: p.to_dict() for p in cal.priors},
        "likelihood": {"text": LIKELIHOOD, "surrogate_std_factor": _r(cal.std_factor, 4),
                       "error_length_mm": cal.error_length_mm,
                       "error_frequency_hz": cal.error_frequency_hz,
                       "surrogate_spread": cal.spread,
                       "surrogate_error": _error_model(cal)},
        "sampler": {k: (_r(v, 4) if isinstance(v, float) else
                        [_r(x, 4) for x in v] if isinstance(v, list) else v)
                    for k, v in cal.sampler.items()},
        "posterior": {n: {k: (_r(v) if isinstance(v, float) and math.isfinite(v) else
                              [_r(x) for x in v] if isinstance(v, list) else v)
                          for k, v in s.items()} for n, s in summary.items()},
        "correlation": {"names": list(cal.names),
                        "matrix": [[_r(float(x), 4) for x in row] for row in corr]},
        "unidentifiable": [n for n, s in summary.items() if not s["identifiable"]],
        "statement": statement(summary),
        "fit_quality": {"points": int(resid.size),
                        "chi2_per_point": _r(float(np.mean(resid ** 2)), 4),
                        "normalised_residuals": [_r(float(x), 4) for x in resid]},
        "tissue": point,
        "samples": {n: [_r(float(x)) for x in cal.samples[keep, j]]
                    for j, n in enumerate(cal.names)},
        "verify": None,
    }


@dataclass(frozen=True)
class Tissue:
    """A calibration read back for planning: the point estimate (``site`` values in model
    units), posterior draws of the fitted inputs, and where it came from."""

    path: str
    model_name: str | None
    point: dict[str, Any]
    samples: dict[str, np.ndarray]
    posterior: dict[str, Any]
    statement: str

    @property
    def n_samples(self) -> int:
        return len(next(iter(self.samples.values()))) if self.samples else 0


def _need(d: Any, key: str, kind: type | tuple[type, ...], where: str) -> Any:
    if not isinstance(d, dict) or key not in d:
        raise CalibrationFileError(key, f"{where}: key {key!r} is missing")
    if not isinstance(d[key], kind):
        raise CalibrationFileError(key, f"{where}: {key} has the wrong type "
                                   f"({type(d[key]).__name__})")
    return d[key]


def read_calibration(path: str | Path) -> Tissue:
    """Read a calibration document as a :class:`Tissue`; raises
    :class:`CalibrationFileError` naming the key that is wrong."""
    where = str(path)
    doc = read_json_file(path, CalibrationFileError, "calibration")  # size and nesting limits
    if not isinstance(doc, dict) or doc.get("kind") != KIND:
        raise CalibrationFileError("kind", f"{where}: not a calibration document (kind must be "
                                   f"{KIND!r})")
    if doc.get("schema_version") != SCHEMA_VERSION:
        raise CalibrationFileError("schema_version", f"{where}: schema_version "
                                   f"{doc.get('schema_version')!r} is not supported (expected "
                                   f"{SCHEMA_VERSION})")
    point = _need(doc, "tissue", dict, where)
    fit = _need(doc, "fit", list, where)
    raw = _need(doc, "samples", dict, where)
    samples = {}
    for name in fit:
        vals = raw.get(name)
        arr = np.asarray(vals if isinstance(vals, list) else [], dtype=float)
        if arr.size < 2 or not np.all(np.isfinite(arr)):
            raise CalibrationFileError(f"samples.{name}", f"{where}: samples.{name} must be a "
                                       "list of at least two finite numbers")
        samples[name] = arr
        if not isinstance(point.get(name), int | float):
            raise CalibrationFileError(f"tissue.{name}", f"{where}: tissue.{name} (the fitted "
                                       "input's point estimate) is missing")
    if len({a.size for a in samples.values()}) > 1:
        raise CalibrationFileError("samples", f"{where}: the sample lists differ in length")
    for k, v in point.items():
        if isinstance(v, bool) or not isinstance(v, int | float | str):
            raise CalibrationFileError(f"tissue.{k}", f"{where}: tissue.{k} = {v!r}: expected "
                                       "a number or a choice")
    model = doc.get("model") if isinstance(doc.get("model"), dict) else {}
    return Tissue(where, model.get("name"), dict(point), samples,
                  dict(doc.get("posterior") or {}), str(doc.get("statement", "")))
