"""Fit each SINDy variant on the training runs, score it and today's model on the held-out runs.

Times inside the study are in ms (the residual's rates come out per ms, of order 0.01-1),
envelopes in um as in the card; the scale s and every control are dimensionless.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm
from scipy.signal import savgol_filter

from surrogate.envelope.card import HOLDOUT_EVERY
from surrogate.envelope.metrics import POINTS, envelope_metrics, summarise
from surrogate.envelope.runs import load_runs
from surrogate.runtime.rom import EnvelopeModel, load_envelope_model

__all__ = ["VARIANTS", "Trace", "Variant", "load", "residual_response", "run", "table"]

OMEGA_REF = 2 * math.pi * 130.0  # rad/s: the speed unit of the controls (the planner's 130 Hz)
RATE_REF_MS = 10.0  # the speed's rate of change is per 10 ms
TRIM_MS = 3.0  # the demodulated FE envelope is least accurate within ~1 period of the ends
SUBSAMPLE = 2  # fit on every 2nd sample (0.5 ms): the envelope varies over ms
ALPHA_MAX = -1e-3  # 1/ms: a first-order residual's own rate is held below this (a 1 s decay)
STATE_MAX = 5.0  # a second-order residual is clipped at 5 steady levels (it can be unstable)


@dataclass(frozen=True)
class Trace:
    """One FE run at one point with today's model and the SINDy controls.

    Attributes:
        sample_index: dataset row. attachment: glued / pogo. point: 0 centre, 1 edge.
        t_ms: (nt,) times, ms. fe, model: (nt,) FE and today's envelopes, um.
        scale: the run's largest steady level of today's model, um (known at run time).
        controls: name -> (nt,) dimensionless control (see :data:`CONTROLS`).
        design: the run's encoded design features within its attachment's map (n,).
        run: the :class:`surrogate.envelope.runs.Run` (for the card's metrics).
    """

    sample_index: int
    attachment: str
    point: int
    t_ms: NDArray
    fe: NDArray
    model: NDArray
    scale: float
    controls: dict[str, NDArray]
    design: NDArray
    run: Any

    @property
    def residual(self) -> NDArray:
        """The identified state r = (e_FE - m) / s."""
        return (self.fe - self.model) / self.scale


#: the controls: d the known mode's lag, w the speed, wd its rate, A and m the steady level
#: and the mode's envelope, each over the run's scale s
CONTROLS = ("d", "w", "wd", "A", "m")


def _design_block(model: EnvelopeModel, design: dict[str, Any]) -> NDArray:
    """The design's encoded features (intercept dropped) in its attachment's block of the
    grouped map (today's ``EnvelopeModel.features``)."""
    x = model.features(design, extrapolate=True)
    width = len(model.meta["feature_columns"]) + 1
    group = model.meta["group_by"]["choices"].index(design["attachment"])
    return x[group * width: group * width + width - 1]


def load(model_dir: str | Path, data: Sequence[str | Path]) -> list[Trace]:
    """Every successful run of ``data`` at both points, with today's envelope model
    ``model_dir`` simulated on its schedule."""
    model = load_envelope_model(model_dir)
    runs, _, _ = load_runs(data, model.design_names)
    out = []
    for r in runs:
        sim = model.simulate(r.t, r.volts, r.design, extrapolate=True)
        steady = model.steady_levels(r.omega, r.design, extrapolate=True)
        t_ms = r.t * 1e3
        rate = np.gradient(r.omega, t_ms) * RATE_REF_MS / OMEGA_REF
        for j, point in enumerate(POINTS):
            m, a = sim[f"{point}_envelope_um"], steady[point]
            s = float(np.max(a))
            out.append(Trace(r.sample_index, str(r.design["attachment"]), j, t_ms, r.env[j],
                             m, s, {"d": (m - a) / s, "w": r.omega / OMEGA_REF, "wd": rate,
                                    "A": a / s, "m": m / s},
                             _design_block(model, r.design), r))
    return out


def residual_response(t_ms: NDArray, a: NDArray, b: NDArray) -> NDArray:
    """States x(t) (nt, n) of dx/dt = a(t) x + b(t) from x(t_0) = 0: ``a`` (nt, n, n) per ms,
    ``b`` (nt, n) per ms, each step integrated exactly with a and b held at their step
    averages (the exponential of the augmented matrix [[a, b], [0, 0]] h, exact also for a
    singular a)."""

    nt, n = b.shape
    h = np.diff(t_ms)
    aug = np.zeros((nt - 1, n + 1, n + 1))
    aug[:, :n, :n] = 0.5 * (a[1:] + a[:-1]) * h[:, None, None]
    aug[:, :n, n] = 0.5 * (b[1:] + b[:-1]) * h[:, None]
    step = expm(aug)  # x_{k+1} = step[:n, :n] x_k + step[:n, n]
    x = np.zeros((nt, n))
    for k in range(nt - 1):
        x[k + 1] = step[k, :n, :n] @ x[k] + step[k, :n, n]
        if not np.all(np.abs(x[k + 1]) <= STATE_MAX):  # an unstable identified residual
            x[k + 1] = np.clip(np.nan_to_num(x[k + 1]), -STATE_MAX, STATE_MAX)
    return x


@dataclass(frozen=True)
class Variant:
    """A SINDy-with-control set-up: the controls fed to ``library`` (after the state r), the
    optimiser, the Savitzky-Golay window of the derivatives (ms), whether the coefficients
    are affine in the design features (SINDyCP) and the residual's order (2: the state is
    (r, dr/dt), a damped oscillation beside the known mode, i.e. a second mode)."""

    title: str
    controls: tuple[str, ...]
    library: Callable[[], Any]
    optimizer: Callable[[], Any]
    window_ms: float
    design_mapped: bool = False
    order: int = 1


def _affine_in_r(n_controls: int, degree: int) -> Any:
    """{1, r} x every monomial of the controls up to ``degree`` (constant included)."""
    # lazy: pysindy is no dependency (bench/surrogate/envelope_sindy.py: how to install)
    import pysindy as ps

    return ps.GeneralizedLibrary(
        [ps.PolynomialLibrary(degree=1, include_bias=True),
         ps.PolynomialLibrary(degree=degree, include_bias=True)], tensor_array=[[1, 1]],
        inputs_per_library=[[0], list(range(1, n_controls + 1))], exclude_libraries=[0, 1])


def _vanishing(n_states: int = 1) -> Any:
    """{state, d, wd} x {1, w, m} (controls d, wd, w, m): every term is zero in steady running
    (r = dr/dt = d = wd = 0), so the residual keeps today's steady level."""
    # lazy: pysindy is no dependency (bench/surrogate/envelope_sindy.py: how to install)
    import pysindy as ps

    return ps.GeneralizedLibrary(
        [ps.PolynomialLibrary(degree=1, include_bias=False),
         ps.PolynomialLibrary(degree=1, include_bias=True)], tensor_array=[[1, 1]],
        inputs_per_library=[list(range(n_states + 2)), [n_states + 2, n_states + 3]],
        exclude_libraries=[0, 1])


def _stlsq(threshold: float) -> Callable[[], Any]:
    def make() -> Any:
        # lazy: pysindy is no dependency (bench/surrogate/envelope_sindy.py: how to install)
        import pysindy as ps

        return ps.STLSQ(threshold=threshold, alpha=1e-3, normalize_columns=True)
    return make


def _sr3() -> Any:
    # lazy: pysindy is no dependency (bench/surrogate/envelope_sindy.py: how to install)
    import pysindy as ps

    return ps.SR3(reg_weight_lam=0.05, regularizer="L1", normalize_columns=True, max_iter=200)


VARIANTS: dict[str, Variant] = {
    "poly": Variant("{1, r} x quadratic in (A, m, w, w'), STLSQ 0.01, per attachment",
                    ("A", "m", "w", "wd"), lambda: _affine_in_r(4, 2), _stlsq(0.01), 10.0),
    "sr3": Variant("{1, r} x quadratic in (d, w, w'), SR3 (L1), per attachment",
                   ("d", "w", "wd"), lambda: _affine_in_r(3, 2), _sr3, 10.0),
    "vanishing": Variant("{r, d, w'} x {1, w, m} (keeps the steady level), STLSQ 0.1, per "
                         "attachment", ("d", "wd", "w", "m"), _vanishing, _stlsq(0.1), 20.0),
    "sindycp": Variant("{r, d, w'} x {1, w, m} x affine in the design features (SINDyCP), "
                       "STLSQ 0.1, per attachment", ("d", "wd", "w", "m"), _vanishing,
                       _stlsq(0.1), 20.0, design_mapped=True),
    "second": Variant("second order: {r, r', d, w'} x {1, w, m}, STLSQ 0.05, per attachment",
                      ("d", "wd", "w", "m"), lambda: _vanishing(2), _stlsq(0.05), 20.0, order=2),
}


def _inputs(tr: Trace, variant: Variant, columns: NDArray | None) -> NDArray:
    """The control matrix (nt, n) of a trace: the variant's controls, then (SINDyCP) the
    design features kept in ``columns``."""
    u = np.column_stack([tr.controls[c] for c in variant.controls])
    if variant.design_mapped and columns is not None:
        u = np.column_stack([u, np.tile(tr.design[columns], (tr.t_ms.size, 1))])
    return u


def _window(variant: Variant, dt_ms: float) -> int:
    """The variant's smoothing window in samples of step ``dt_ms`` (odd)."""
    return round(variant.window_ms / dt_ms) | 1


def _state(tr: Trace, variant: Variant) -> NDArray:
    """The measured state (nt, order): r, and for a second-order residual its rate (per ms,
    by the Savitzky-Golay filter pysindy's ``SmoothedFiniteDifference`` uses)."""

    r = tr.residual
    if variant.order == 1:
        return r[:, None]
    dt = float(tr.t_ms[1] - tr.t_ms[0])
    return np.column_stack([r, savgol_filter(r, _window(variant, dt), 3, deriv=1, delta=dt)])


@dataclass
class Fitted:
    """One identified residual per (point, attachment)."""

    variant: Variant
    models: dict[tuple[int, str], Any]
    columns: dict[str, NDArray]  # attachment -> design features that vary in training

    def terms(self) -> int:
        return sum(int(np.count_nonzero(m.coefficients())) for m in self.models.values())

    def envelope(self, tr: Trace) -> tuple[NDArray, float]:
        """The corrected envelope m + s r (um) of a trace, and the share of its samples where
        the identified residual is unstable (first order: its rate alpha > ``ALPHA_MAX``,
        held there; second order: an eigenvalue with a positive real part)."""
        model = self.models[(tr.point, tr.attachment)]
        u = _inputs(tr, self.variant, self.columns.get(tr.attachment))
        lib, coef = model.feature_library, model.coefficients()  # (n, n_terms)
        n, nt = self.variant.order, tr.t_ms.size

        def rhs(x: NDArray) -> NDArray:  # (nt, n) at the state x (n,) held over the record
            return np.asarray(lib.transform(np.column_stack([np.tile(x, (nt, 1)), u]))) @ coef.T

        b = rhs(np.zeros(n))
        a = np.stack([rhs(np.eye(n)[k]) - b for k in range(n)], axis=2)  # affine in the state
        if n == 1:
            unstable = float(np.mean(a[:, 0, 0] > ALPHA_MAX))
            a = np.minimum(a, ALPHA_MAX)
        else:
            unstable = float(np.mean(np.max(np.linalg.eigvals(a).real, axis=1) > 0.0))
        r = residual_response(tr.t_ms, a, b)[:, 0]
        return np.maximum(tr.model + tr.scale * r, 0.0), unstable


def fit(variant: Variant, train: Sequence[Trace]) -> Fitted:
    """Identify the residual per point and attachment on the training traces."""
    # lazy: pysindy is no dependency (bench/surrogate/envelope_sindy.py: how to install)
    import pysindy as ps

    models, columns = {}, {}
    for attachment in sorted({tr.attachment for tr in train}):
        group = [tr for tr in train if tr.attachment == attachment]
        if variant.design_mapped:  # a feature constant within the group has no coefficient
            columns[attachment] = np.flatnonzero(np.std([tr.design for tr in group], axis=0)
                                                 > 1e-9)
        for point in (0, 1):
            xs, us = [], []
            for tr in (tr for tr in group if tr.point == point):
                keep = (tr.t_ms > tr.t_ms[0] + TRIM_MS) & (tr.t_ms < tr.t_ms[-1] - TRIM_MS)
                xs.append(_state(tr, variant)[keep][::SUBSAMPLE])
                us.append(_inputs(tr, variant, columns.get(attachment))[keep][::SUBSAMPLE])
            library = variant.library()
            if variant.design_mapped:
                n_par = us[0].shape[1] - len(variant.controls)
                library = ps.ParameterizedLibrary(
                    parameter_library=ps.PolynomialLibrary(degree=1, include_bias=True),
                    feature_library=library, num_parameters=n_par,
                    num_features=variant.order + len(variant.controls))
            dt = float(group[0].t_ms[1] - group[0].t_ms[0]) * SUBSAMPLE
            model = ps.SINDy(optimizer=variant.optimizer(), feature_library=library,
                             differentiation_method=ps.SmoothedFiniteDifference(
                                 smoother_kws={"window_length": _window(variant, dt),
                                               "polyorder": 3}))
            model.fit(xs, t=dt, u=us)
            models[(point, attachment)] = model
    return Fitted(variant, models, columns)


def _score(traces: Sequence[Trace], envelope: Callable[[Trace], NDArray]
           ) -> dict[str, float]:
    """The card's summary (:func:`surrogate.envelope.metrics.summarise`) of ``envelope`` on the
    traces (both points of each run)."""
    rows: dict[int, dict[str, Any]] = {}
    for tr in traces:
        r = tr.run
        m = envelope_metrics(r.t, r.volts, r.on_time_s, tr.fe, envelope(tr))
        row = rows.setdefault(tr.sample_index, {"sample_index": tr.sample_index})
        row.update({f"{POINTS[tr.point]}_{k}": v for k, v in m.items()})
    return summarise(list(rows.values()))


def run(model_dir: str | Path, data: Sequence[str | Path],
        variants: Sequence[str] = tuple(VARIANTS)) -> list[dict[str, Any]]:
    """One record per model (today's, then each SINDy variant): held-out and training
    summaries, the number of identified terms and the share of samples where the identified
    residual is unstable (:meth:`Fitted.envelope`; held or clipped there)."""
    traces = load(model_dir, data)
    held = [tr for tr in traces if tr.sample_index % HOLDOUT_EVERY == HOLDOUT_EVERY - 1]
    train = [tr for tr in traces if tr.sample_index % HOLDOUT_EVERY != HOLDOUT_EVERY - 1]
    records = [{"name": "today", "title": f"today's fit ({model_dir})", "terms": None,
                "clipped": 0.0, "held_out": _score(held, lambda tr: tr.model),
                "train": _score(train, lambda tr: tr.model), "fit_s": None}]
    for name in variants:
        t0 = time.perf_counter()
        with warnings.catch_warnings():  # pysindy warns of ill-conditioned columns; scored below
            warnings.simplefilter("ignore")
            fitted = fit(VARIANTS[name], train)
        fit_s = time.perf_counter() - t0
        clipped: list[float] = []

        def envelope(tr: Trace, fitted: Fitted = fitted, clipped: list = clipped) -> NDArray:
            y, c = fitted.envelope(tr)
            clipped.append(c)
            return y

        held_s = _score(held, envelope)
        records.append({"name": name, "title": VARIANTS[name].title, "terms": fitted.terms(),
                        "clipped": float(np.mean(clipped)), "held_out": held_s,
                        "train": _score(train, envelope), "fit_s": fit_s})
    return records


def _cell(s: dict[str, float], key: str, scale: float, fmt: str) -> str:
    return " \\| ".join(f"{scale * s[f'{p}_{key}_median']:{fmt}} / "
                        f"{scale * s[f'{p}_{key}_max']:{fmt}}" for p in POINTS)


def table(records: Sequence[dict[str, Any]]) -> str:
    """One markdown table: held-out steady (%), rise and decay (ms), NRMSE, median / max,
    centre | edge; then the training NRMSE medians, the identified terms and the share of
    samples where the identified residual is unstable (:meth:`Fitted.envelope`)."""
    lines = ["| model | steady % | rise ms | decay ms | NRMSE | training NRMSE median | "
             "terms | unstable |", "|---|---|---|---|---|---|---|---|"]
    for rec in records:
        h, t = rec["held_out"], rec["train"]
        lines.append(
            f"| {rec['title']} | {_cell(h, 'steady_rel_err', 100, '.1f')} | "
            f"{_cell(h, 'rise_abs_err_ms', 1, '.1f')} | {_cell(h, 'decay_abs_err_ms', 1, '.1f')} "
            f"| {_cell(h, 'nrmse', 1, '.3f')} | {t['center_nrmse_median']:.3f} \\| "
            f"{t['edge_nrmse_median']:.3f} | {rec['terms'] if rec['terms'] is not None else '-'}"
            f" | {100 * rec['clipped']:.0f} % |")
    return "\n".join(lines)
