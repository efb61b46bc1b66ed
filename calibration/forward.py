"""The forward model of a calibration: tissue parameters in, the surrogate's prediction of every
measured point out (natural log of the peak displacement amplitude [m] and its predictive
log-std), on the run-time predictor only.

Which model output a point reads is set by its reference and its component:

* ``centre`` at distance 0: the centre output (the unit's skin-side face at r = 0);
* ``edge`` at d, or ``centre`` at r >= the unit's edge radius (d = r - edge radius): the
  profile output at distance d from the edge, log-linearly interpolated on the model's
  profile grid (its log-std linearly);
* component ``magnitude``: ``center_amplitude_um`` / ``profile_um``; component ``normal``:
  the outputs listed in :data:`NORMAL_OUTPUTS` (``models/nn-normal`` and a sweep model trained
  with ``--outputs profile_um,profile_normal_um`` return ``profile_normal_um``, |U_z| on the
  skin around the unit, trained on the datasets' ``profile_uz_um`` or the sweep's complex z
  component). The datasets store no normal component at the unit's own face, so no
  shipped model predicts one there: a normal-component row at the face is refused by name, as
  is every normal-component row for a model without a normal output.

Points under the unit (0 < r < edge radius), beyond the profile grid, or at a frequency
outside the model's range are bad rows of the measurement (:class:`MeasurementError`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from calibration.likelihood import frequency_clusters
from calibration.likelihood import profile_kernel as kernel
from calibration.measurement import Measurement, MeasurementError

__all__ = ["MAGNITUDE_OUTPUTS", "NORMAL_OUTPUTS", "ForwardModel", "needs_normal",
           "output_for"]

#: (centre output, profile output) of the magnitude
MAGNITUDE_OUTPUTS = ("center_amplitude_um", "profile_um")
#: accepted names of normal-component outputs: at the face (centre) and on the profile; the
#: first one a model has is used
NORMAL_OUTPUTS = {"centre": ("center_normal_um", "center_uz_um"),
                  "profile": ("profile_normal_um", "profile_uz_um")}


def output_for(component: str, at_face: bool, available: Sequence[str]) -> str | None:
    """The predictor output that predicts ``component`` at the unit's face (``at_face``) or
    on the profile around it, or None if the model has none."""
    if component == "magnitude":
        return MAGNITUDE_OUTPUTS[0 if at_face else 1]
    names = NORMAL_OUTPUTS["centre" if at_face else "profile"]
    return next((n for n in names if n in available), None)


def needs_normal(measurement: Measurement) -> bool:
    """Whether any point of ``measurement`` is of the normal component."""
    return any(p.component == "normal" for p in measurement.points)


def _interp_weights(grid: np.ndarray, d: float) -> np.ndarray:
    """Row of linear interpolation weights on ``grid`` at ``d`` (inside the grid)."""
    w = np.zeros(grid.size)
    j = int(np.clip(np.searchsorted(grid, d, side="right") - 1, 0, grid.size - 2))
    t = (d - grid[j]) / (grid[j + 1] - grid[j])
    w[j], w[j + 1] = 1.0 - t, t
    return w


@dataclass
class _Group:
    """The points that read one predictor output (a scalar at the face, or a profile)."""

    output: str
    face: bool  # the output is the scalar at the unit's face (else a profile)
    rows: np.ndarray  # predictor row (frequency index) per point
    weights: np.ndarray  # (n_points, n_grid) profile interpolation weights (zero at the face)
    index: np.ndarray  # position of each point in the measurement


class ForwardModel:
    """Predict the measured points for many tissue parameter vectors at once.

    ``fit``: names of the model inputs to vary; ``fixed``: every other model input except
    ``frequency_hz`` (design and known tissue), in the model's units. ``theta`` passed to
    :meth:`predict` is (n, len(fit)) in the model's units (kPa, mm, ...)."""

    def __init__(self, predictor: Any, measurement: Measurement, fit: Sequence[str],
                 fixed: Mapping[str, Any]) -> None:
        # the raw spread: the likelihood widens it by its own rule (fit.surrogate_std_factor)
        self.predictor = predictor.uncalibrated() if hasattr(predictor, "uncalibrated") \
            else predictor
        self.fit = tuple(fit)
        self.fixed = dict(fixed)
        self.measurement = measurement
        pts = measurement.points
        self.frequencies_hz = np.array(measurement.frequencies_hz)
        self.y = np.log(np.array([p.amplitude_m for p in pts]))
        self.rel_sigma = np.array([p.relative_sigma for p in pts])
        grid_mm = np.asarray(predictor.profile_distance_mm, dtype=float)
        self.grid_m = grid_mm * 1e-3
        # one row at the low end of every fitted range (and of the frequency range): the edge
        # radius, the output names and the codes of the fixed inputs
        template = {k: v[:1] for k, v in self._rows(
            np.array([[predictor.input_ranges[n][0] for n in self.fit]])).items()}
        if "frequency_hz" in template:
            template["frequency_hz"] = np.array([predictor.input_ranges["frequency_hz"][0]])
        out = predictor.predict(template)
        names = list(predictor.input_names)
        self._template = predictor.features(template)[0]
        self._fit_cols = [names.index(n) for n in self.fit]
        self._freq_col = names.index("frequency_hz") if "frequency_hz" in names else None
        self.edge_radius_m = float(out["edge_radius_mm"][0]) * 1e-3
        available = tuple(out)
        lo_f, hi_f = predictor.input_ranges.get("frequency_hz", (-np.inf, np.inf))
        errors: list[tuple[str, str]] = []
        groups: dict[str, list[tuple[int, np.ndarray, int]]] = {}
        model = predictor.card.get("name")
        for k, p in enumerate(pts):
            where = f"row {p.row}"
            if not lo_f <= p.frequency_hz <= hi_f:
                errors.append((f"{where}: frequency_hz", f"{where}, column frequency_hz: "
                               f"{p.frequency_hz:g} Hz is outside the model's range "
                               f"[{lo_f:g}, {hi_f:g}] Hz"))
                continue
            at_centre = p.reference == "centre" and p.distance_m == 0.0
            output = output_for(p.component, at_centre, available)
            if output is None and output_for(p.component, False, available) is None:
                errors.append((f"{where}: component", f"{where}, column component: "
                               f"{p.component!r}: the model {model!r} predicts no normal "
                               "component (its outputs are magnitudes); use a model with a "
                               f"normal-component output ({NORMAL_OUTPUTS['profile'][0]}: the "
                               "default normal model, which hapticrom calibrate picks when "
                               "--model is not given: models/nn-sweep when trained with it, "
                               "else models/nn-normal) or give component = magnitude"))
                continue
            if output is None:
                errors.append((f"{where}: component", f"{where}, column component: "
                               f"{p.component!r} at the unit's face (centre, 0 mm): the model "
                               f"{model!r} predicts the normal component only on the skin "
                               "around the unit (0-"
                               f"{grid_mm[-1]:g} mm from its edge; its training data store no "
                               "normal component at the face); measure the face as magnitude "
                               "or leave the row out"))
                continue
            d = p.distance_m - (self.edge_radius_m if p.reference == "centre" else 0.0)
            if not at_centre and not self.grid_m[0] <= d <= self.grid_m[-1] + 1e-12:
                r_edge = self.edge_radius_m * 1e3
                allowed = (f"0 (the unit's face) or [{r_edge + grid_mm[0]:g}, "
                           f"{r_edge + grid_mm[-1]:g}] mm from the centre (edge radius "
                           f"{r_edge:g} mm)" if p.reference == "centre" else
                           f"[{grid_mm[0]:g}, {grid_mm[-1]:g}] mm from the edge")
                errors.append((f"{where}: distance_mm", f"{where}, column distance_mm: "
                               f"{p.distance_m * 1e3:g} mm is outside the model's profile; "
                               f"allowed: {allowed}"))
                continue
            w = (np.zeros(grid_mm.size) if at_centre else
                 _interp_weights(self.grid_m, min(d, self.grid_m[-1])))
            row = int(np.searchsorted(self.frequencies_hz, p.frequency_hz))
            groups.setdefault(output, []).append((row, w, k))
        if errors:
            lines = "\n  ".join(m for _, m in errors[:25])
            raise MeasurementError(errors[0][0], f"{measurement.source or 'measurement'}: "
                                   f"{len(errors)} row(s) the model cannot predict:\n  {lines}")
        face_outputs = (MAGNITUDE_OUTPUTS[0], *NORMAL_OUTPUTS["centre"])
        self.groups = [_Group(output, output in face_outputs, np.array([i[0] for i in items]),
                              np.array([i[1] for i in items]), np.array([i[2] for i in items]))
                       for output, items in groups.items()]

    def error_correlation(self, length_mm: float | Mapping[str, float],
                          frequency_scale_hz: float | Mapping[str, float], *,
                          profile_kernel: str | Mapping[str, str] = "exponential",
                          frequency_kernel: str | Mapping[str, str] = "exponential",
                          shared_within_hz: float | Mapping[str, float] | None = None
                          ) -> np.ndarray:
        """(m, m) correlation of the surrogate's errors between the measured points: along
        a profile :func:`calibration.likelihood.profile_kernel` of |d_i - d_j| (``length_mm``,
        kind ``profile_kernel``), between frequencies exp(-|f_i - f_j| / scale)
        (``frequency_kernel`` "exponential") or exp(-(f_i - f_j)^2 / (2 scale^2))
        ("gaussian"), none between points read from different outputs (the unit's face and
        the profile; the magnitude and the normal component) nor between frequencies of
        different clusters (:meth:`error_blocks`, ``shared_within_hz``; None: one cluster per
        output). ``length_mm``, ``frequency_scale_hz``, ``shared_within_hz`` and the kernels: one
        value, or one per output name (see docs/calibration.md for how these were measured)."""
        def per(value: Any, output: str) -> Any:
            return value if isinstance(value, int | float | str) else value[output]

        m = self.y.size
        rho = np.zeros((m, m))
        f = np.array([p.frequency_hz for p in self.measurement.points])
        for idx, g in self.error_blocks(shared_within_hz):
            fi = f[idx]
            df = np.abs(fi[:, None] - fi[None, :]) / float(per(frequency_scale_hz, g.output))
            fk = per(frequency_kernel, g.output)
            if fk not in ("exponential", "gaussian"):
                raise ValueError(f"frequency kernel {fk!r}: allowed exponential, gaussian")
            r = np.exp(-df) if fk == "exponential" else np.exp(-0.5 * df ** 2)
            if not g.face:
                pos = np.searchsorted(g.index, idx)
                d = g.weights[pos] @ (self.grid_m * 1e3)
                r = r * kernel(d[:, None] - d[None, :], float(per(length_mm, g.output)),
                               per(profile_kernel, g.output))
            rho[np.ix_(idx, idx)] = r
        return rho

    def error_blocks(self, shared_within_hz: float | Mapping[str, float] | None = None
                     ) -> list[tuple[np.ndarray, _Group]]:
        """The points whose surrogate errors share one mixing variable: per output read, the
        points at frequencies chained at most ``shared_within_hz`` apart
        (:func:`calibration.likelihood.frequency_clusters`; None: all its frequencies), as
        (sorted point positions, the output's group)."""
        f = np.array([p.frequency_hz for p in self.measurement.points])
        out = []
        for g in self.groups:
            idx = np.sort(g.index)
            within = (np.inf if shared_within_hz is None else
                      float(shared_within_hz) if isinstance(shared_within_hz, int | float)
                      else float(shared_within_hz.get(g.output, np.inf)))
            labels = frequency_clusters(f[idx], within)
            out += [(idx[labels == c], g) for c in np.unique(labels)]
        return out

    @property
    def profile_outputs(self) -> tuple[str, ...]:
        """The profile outputs the measured points read."""
        return tuple(g.output for g in self.groups if not g.face)

    def _rows(self, theta: np.ndarray) -> dict[str, np.ndarray]:
        """Predictor inputs by name: one row per (parameter vector, frequency), frequency
        fastest (the first call, which also finds the model's codes of the fixed inputs)."""
        n, nf = theta.shape[0], self.frequencies_hz.size
        X: dict[str, np.ndarray] = {k: np.full(n * nf, v) if not isinstance(v, str)
                                    else np.array([v] * (n * nf)) for k, v in self.fixed.items()}
        for j, name in enumerate(self.fit):
            X[name] = np.repeat(theta[:, j], nf)
        if "frequency_hz" in self.predictor.input_names:
            X["frequency_hz"] = np.tile(self.frequencies_hz, n)
        return X

    def _codes(self, theta: np.ndarray) -> np.ndarray:
        """The same rows as the (n * n_f, d) code array of the predictor's inputs (fixed
        inputs coded once), which the predictor checks and encodes without per-name work."""
        n, nf = theta.shape[0], self.frequencies_hz.size
        codes = np.repeat(self._template, n * nf, axis=0)
        for j, col in enumerate(self._fit_cols):
            codes[:, col] = np.repeat(theta[:, j], nf)
        if self._freq_col is not None:
            codes[:, self._freq_col] = np.tile(self.frequencies_hz, n)
        return codes

    def predict(self, theta: np.ndarray, *, extrapolate: bool = False
                ) -> tuple[np.ndarray, np.ndarray]:
        """(ln amplitude [m], predictive log-std), each (n, n_points), for parameter vectors
        ``theta`` (n, len(fit)) in the model's units."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        n, nf = theta.shape[0], self.frequencies_hz.size
        out = self.predictor.predict(self._codes(theta), extrapolate=extrapolate)
        mean = np.empty((n, self.y.size))
        std = np.empty((n, self.y.size))
        for g in self.groups:
            if g.face:
                mean[:, g.index] = np.log(out[g.output].reshape(n, nf) * 1e-6)[:, g.rows]
                std[:, g.index] = out[f"{g.output}_log_std"].reshape(n, nf)[:, g.rows]
                continue
            lp = np.log(out[g.output].reshape(n, nf, -1) * 1e-6)
            sp = out[f"{g.output}_log_std"].reshape(n, nf, -1)
            # per point: its frequency row, then the interpolation weights on the grid
            mean[:, g.index] = np.einsum("npg,pg->np", lp[:, g.rows, :], g.weights)
            std[:, g.index] = np.einsum("npg,pg->np", sp[:, g.rows, :], g.weights)
        return mean, std
