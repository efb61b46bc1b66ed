"""The Bayesian fit: the posterior of chosen tissue inputs given a measurement, sampled with
emcee's ensemble sampler on the run-time surrogate.

Likelihood (docs/calibration.md, :mod:`calibration.likelihood`): each measured amplitude y_i
(peak displacement [m], converted by :mod:`calibration.measurement`) is about the surrogate's
prediction mu_i(theta) as

    ln y - ln mu(theta) = e + n,  n ~ N(0, diag((sigma_i / y_i)^2)),
    e | lam ~ N(0, lam diag(c s) C diag(c s)),  lam ~ InverseGamma(nu / 2, nu / 2)

per output read and cluster of its frequencies (frequencies chained at most
``shared_within_hz`` apart share lam; clusters are independent), with sigma_i the stated
standard uncertainty (independent between points), s_i the surrogate's own predictive log-std
(its 95 % bounds are exp(+-1.96 s)), nu, c_i (per frequency) and the clusters per output read
(:func:`surrogate_error_t`: a multivariate Student-t measured on FE solves the model never
trained on, the model's own from its card's :data:`CARD_ERROR_KEY` entry when measured there,
else :data:`SURROGATE_ERROR_T`; for an output in neither, or with
``error_model = "gaussian"`` or a given ``std_factor``, lam = 1 and c = ``k`` =
:func:`surrogate_std_factor`, the card's widening), and C the correlation of the surrogate's
errors between points (:meth:`ForwardModel.error_correlation`: a surrogate that is wrong at
5 mm is wrong at 6 mm too, and at 160 Hz when it is at 150 Hz, so its error does not average
out over many points; Matern 3/2 along the profile, Gaussian across frequency). Priors:
:mod:`calibration.priors`.

The surrogate's spread s is held fixed while the kept chain is sampled (``spread =
"posterior"``): s_i^2 is the mean of s_i(theta)^2 over the walkers of the second half of the
burn-in (over the starting walkers when there is no burn-in). Evaluated at every theta
(``spread = "local"``, as before), the normalising term -1/2 ln det of the (Gaussian's)
covariance moved
with the ensemble's spread: by 5.2 nats (a factor of about 180) along the fat thickness at
fixed skin and loss for one synthetic subject (the ensemble has 5 members, so its spread is
itself a noisy estimate), an implicit prior towards wherever the members happen to agree
(docs/calibration.md, "The fit" and "Proven on synthetic subjects").

Sampling: ``walkers`` walkers started at the best of ``n_init`` prior draws (one vectorised
surrogate call), differential-evolution moves (emcee's DEMove 0.8 / DESnookerMove 0.2: robust
for the correlated, sometimes bimodal posteriors of decay data), ``steps`` steps of which the
first ``burn`` are dropped. Everything is seeded: the same input gives the same posterior.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from statistics import NormalDist
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from calibration.forward import ForwardModel
from calibration.likelihood import hdi, mixture_log_likelihood
from calibration.measurement import Measurement
from calibration.priors import Prior, PriorError, priors_for
from surrogate.runtime.card import ModelFileError

__all__ = ["CARD_ERROR_KEY", "ERROR_MODELS", "IDENTIFIABLE_WIDTH_RATIO", "INTERVAL_KINDS",
           "SCALE_HZ", "SPREADS", "SURROGATE_ERROR_T", "Calibration", "calibrate",
           "card_error_t", "check_error_t", "error_settings", "point_scales",
           "surrogate_error_t", "surrogate_std_factor"]

#: a parameter whose 95 % posterior interval is wider than this fraction of its prior's 95 %
#: interval (in the sampling coordinate) is reported as not determined by the data
IDENTIFIABLE_WIDTH_RATIO = 0.8
Z95 = 1.959964
KEPT_SAMPLES = 400  # posterior draws stored in the calibration document
#: the first versions' correlation of the surrogate's errors (the Gaussian error model, and the
#: t's lengths when none is given): exponential along each profile output [mm] and across
#: frequencies [Hz], measured with a Gaussian by bench/calibration/calibrate.py --residuals on FE
#: solves apart from the study's (19.2 mm for nn-default's magnitude profile, 22.1 mm for
#: nn-normal's, 4.5 mm for nn-normal's normal component; 60 Hz)
ERROR_LENGTH_MM = {"profile_um": 20.0, "profile_normal_um": 4.5}
ERROR_FREQUENCY_HZ = 60.0
#: how the surrogate's spread enters the likelihood (see the module docstring)
SPREADS = ("posterior", "local")
#: frequencies [Hz] of the t's scale per frequency (linear in between, constant outside)
SCALE_HZ = tuple(float(f) for f in range(100, 251, 10))
#: the surrogate's error per output read: a multivariate Student-t per cluster of frequencies
#: (calibration.likelihood), ``nu`` degrees of freedom, ``scale`` per frequency of
#: :data:`SCALE_HZ` (the factor on its predictive log-std), correlation along the profile Matern
#: 3/2 with ``length_mm``, across frequencies exp(-df^2 / (2 frequency_hz^2)), one mixing
#: variable shared by the frequencies of a cluster (neighbours at most ``shared_within_hz``
#: apart), independent between clusters. Measured (``python bench/calibration/calibrate.py
#: --sweep-error``): the profile length by maximum likelihood on the held-out rows of the
#: model's own split (1 mm grid); nu and the scales on the sweep dataset (its first 1600 FE
#: designs x the 16 frequencies of a 10 Hz grid, which no model trained on), frequency by
#: frequency; the
#: mixing variable shared at a frequency difference where a shared one has the higher
#: likelihood on the sweep's pairs of frequencies of one design, the frequency length fitted to
#: the pairs' correlation there (nn-default for the magnitude outputs, nn-normal for the normal
#: component). It serves every model and output whose card has no t of its own
#: (:data:`CARD_ERROR_KEY`); an output in neither: the Gaussian with the card's factor
#: (:func:`surrogate_std_factor`).
SURROGATE_ERROR_T: dict[str, dict[str, Any]] = {
    "center_amplitude_um": {
        "nu": 2.54, "frequency_hz": 17.7, "shared_within_hz": 40.0,
        "scale": (1.65, 1.25, 1.14, 1.07, 1.01, 0.913, 0.883, 0.892, 0.865, 0.86, 0.844, 0.824,
                  0.809, 0.782, 0.785, 0.799)},
    "profile_um": {
        "nu": 1.91, "length_mm": 10.2, "frequency_hz": 16.5, "shared_within_hz": 20.0,
        "scale": (0.942, 0.942, 0.997, 1.01, 0.985, 0.968, 1.02, 1.06, 1.1, 1.15, 1.22, 1.26,
                  1.28, 1.28, 1.27, 1.25)},
    "profile_normal_um": {
        "nu": 1.48, "length_mm": 4.1, "frequency_hz": 12.4, "shared_within_hz": 10.0,
        "scale": (1.01, 0.925, 0.992, 1.1, 1.18, 1.23, 1.29, 1.31, 1.31, 1.31, 1.34, 1.41, 1.4,
                  1.43, 1.51, 1.61)},
}
#: The model card's key for the surrogate's error model measured on that model (the same
#: Student-t per output read as :data:`SURROGATE_ERROR_T`, in the model's own card so that a
#: model retrained under the same name does not inherit it). Written by ``python
#: bench/calibration/calibrate.py --sweep-error --model models/NAME --sweep DIR --write-card``;
#: read at run time by :func:`surrogate_error_t`. Its form (:func:`check_error_t`):
#: ``outputs`` {output: {nu, scale (one per ``scale_hz``), frequency_hz, shared_within_hz,
#: length_mm (profile outputs)}}, ``scale_hz``, ``graph_sha256`` (the digest of the graph it
#: was measured on, which must be the card's), ``measured_on`` (the dataset's path,
#: ``manifest_sha256``, ``designs``, ``n_designs``, frequencies and profile points),
#: ``command`` and ``measured`` (UTC).
CARD_ERROR_KEY = "calibration_error_t"
#: the outputs read at one point (the unit's face): no correlation length along a profile
FACE_OUTPUTS = ("center_amplitude_um", "center_normal_um", "center_uz_um")
#: "t": the Student-t of :func:`surrogate_error_t` (the model card's own, else
#: SURROGATE_ERROR_T); "gaussian": the first versions' Gaussian widened by the card's k
ERROR_MODELS = ("t", "gaussian")
#: the reported 95 % interval: highest posterior density in the sampling coordinate (includes
#: a prior bound the posterior piles against) or equal-tailed (2.5-97.5 percentiles)
INTERVAL_KINDS = ("hdi", "equal_tailed")


def surrogate_std_factor(card: Mapping[str, Any]) -> float:
    """How much to widen the surrogate's log-std so its 95 % bounds cover 95 %: from the card's
    held-out ``coverage95`` of the amplitude outputs (the smallest), the factor 1.96 / z with
    z the normal quantile that coverage implies; 1 when the card has none or covers well."""
    cov = [v.get("coverage95") for k, v in card.get("metrics", {}).items()
           if isinstance(v, dict) and k.endswith("_um")]
    cov = [c for c in cov if isinstance(c, int | float) and 0.0 < c < 0.95]
    if not cov:
        return 1.0

    z = NormalDist().inv_cdf(0.5 + 0.5 * min(cov))
    return float(Z95 / z)


@dataclass
class Calibration:
    """A fitted posterior and everything the document and the figure need."""

    measurement: Measurement
    forward: ForwardModel
    priors: list[Prior]
    samples: np.ndarray  # (n, k) posterior draws, model units
    log_prob: np.ndarray  # (n,)
    std_factor: float
    sampler: dict[str, Any] = field(default_factory=dict)
    error_length_mm: dict[str, float] = field(default_factory=dict)  # per profile output
    #: per output read: the frequency scale of its error correlation [Hz]
    error_frequency_hz: dict[str, float] = field(default_factory=dict)
    spread: str = "posterior"
    #: per output read (:func:`error_settings`): "nu" (None: Gaussian), "scale" (one factor
    #: on its log-std, or one per frequency of "scale_hz"), the kernels, "shared_within_hz"
    error_model: dict[str, dict[str, Any]] = field(default_factory=dict)

    @property
    def point_scale(self) -> np.ndarray:
        """(m,) the factor on the surrogate's log-std at each measured point."""
        return self.scale_for(self.forward)

    def scale_for(self, fwd: ForwardModel) -> np.ndarray:
        """The factor on the surrogate's log-std at each point ``fwd`` reads."""
        return point_scales(fwd, self.error_model, self.std_factor)

    def surrogate_error_draws(self, fwd: ForwardModel, std: np.ndarray,
                              rng: np.random.Generator) -> np.ndarray:
        """Draws of the surrogate's error at the points ``fwd`` reads (rows of ``std`` (n, m),
        its log-std at each draw): per cluster of frequencies of an output
        (:meth:`ForwardModel.error_blocks`) a common lam ~ InverseGamma(nu/2, nu/2) (1 for
        the Gaussian) times independent normals of sd scale * std."""
        e = self.scale_for(fwd) * std * rng.standard_normal(std.shape)
        shared = {o: v.get("shared_within_hz") for o, v in self.error_model.items()
                  if v.get("shared_within_hz") is not None}
        for idx, g in fwd.error_blocks(shared):
            nu = self.error_model.get(g.output, {}).get("nu")
            if nu is not None:
                lam = nu / rng.chisquare(nu, size=(std.shape[0], 1))
                e[:, idx] *= np.sqrt(lam)
        return e

    @property
    def names(self) -> tuple[str, ...]:
        return self.forward.fit

    def z_samples(self) -> np.ndarray:
        return np.column_stack([p.to_z(self.samples[:, j]) for j, p in enumerate(self.priors)])

    def summary(self, rng_seed: int = 0, interval: str = "hdi") -> dict[str, dict[str, Any]]:
        """Per parameter: mean, median, sd, the 95 % interval ``ci95`` of kind ``interval``
        (:data:`INTERVAL_KINDS`: the highest-density interval of the draws in the sampling
        coordinate, or the 2.5-97.5 percentiles; both are given, as ``ci95_hdi`` and
        ``ci95_equal_tailed``), the prior's 95 % interval (equal-tailed: for a uniform prior
        every 95 % interval is as wide), the width ratio of ``ci95`` to it (in the sampling
        coordinate) and identifiability, decided on that ratio."""
        if interval not in INTERVAL_KINDS:
            raise PriorError("interval", f"interval {interval!r}: allowed "
                             f"{', '.join(INTERVAL_KINDS)}")
        rng = np.random.default_rng(rng_seed)
        z = self.z_samples()
        out = {}
        for j, p in enumerate(self.priors):
            x = self.samples[:, j]
            prior_z = p.sample_z(20000, rng)
            pw = np.subtract(*np.percentile(prior_z, [97.5, 2.5]))
            zi = {"hdi": np.array(hdi(z[:, j], 0.95, p.z_bounds)),
                  "equal_tailed": np.percentile(z[:, j], [2.5, 97.5])}
            ratio = float((zi[interval][1] - zi[interval][0]) / pw) if pw > 0 else math.inf
            ci = {k: [float(v) for v in p.from_z(v)] for k, v in zi.items()}
            out[p.name] = {
                "unit": p.unit, "mean": float(x.mean()), "median": float(np.median(x)),
                "sd": float(x.std(ddof=1)), "ci95": ci[interval], "interval_kind": interval,
                "ci95_hdi": ci["hdi"], "ci95_equal_tailed": ci["equal_tailed"],
                "prior_ci95": [float(v) for v in p.from_z(np.percentile(prior_z, [2.5, 97.5]))],
                "width_ratio": ratio, "identifiable": ratio <= IDENTIFIABLE_WIDTH_RATIO}
        return out

    def correlation(self) -> np.ndarray:
        """Posterior correlation matrix (sampling coordinate)."""
        k = len(self.priors)
        if k == 1:
            return np.ones((1, 1))
        return np.corrcoef(self.z_samples(), rowvar=False)

    def mean_inputs(self) -> dict[str, float]:
        """Posterior means in model units (the point estimate written as the tissue)."""
        return {n: float(self.samples[:, j].mean()) for j, n in enumerate(self.names)}

    def predictive(self, n: int = 200, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Posterior predictive of the measured points: (ln mean draws (n, m), total log-std
        of the surrogate (n, m)) at ``n`` posterior draws."""
        rng = np.random.default_rng(seed)
        pick = rng.choice(len(self.samples), size=min(n, len(self.samples)), replace=False)
        mean, std = self.forward.predict(self.samples[pick])
        return mean, self.point_scale * std


def _positive(value: Any) -> bool:
    return (isinstance(value, int | float) and not isinstance(value, bool)
            and math.isfinite(value) and value > 0)


def check_error_t(entry: Any, card: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """The per-output Student-t of a :data:`CARD_ERROR_KEY` entry ``entry`` for the model card
    ``card``, each with its ``scale_hz``, after checking the entry's form: ``outputs`` a
    non-empty mapping of the card's own outputs to {nu > 0, scale (positive, one per
    ``scale_hz``, which increases strictly), frequency_hz > 0, shared_within_hz >= 0, and for
    an output along the profile length_mm > 0}, ``graph_sha256`` the digest of the card's
    graph file (the entry was measured on this very model), ``measured_on`` with the dataset's
    ``manifest_sha256`` and ``n_designs``, ``command`` and ``measured``. Anything else raises
    :class:`surrogate.runtime.card.ModelFileError` naming the key and what is wrong."""

    def bad(key: str, why: str) -> ModelFileError:
        return ModelFileError(f"{CARD_ERROR_KEY}.{key}" if key else CARD_ERROR_KEY,
                              f"model {card.get('name')!r}: card entry {CARD_ERROR_KEY}"
                              + (f".{key}" if key else "") + f": {why} (re-measure it: python "
                              "bench/calibration/calibrate.py --sweep-error --model DIR "
                              "--sweep DATASET --write-card)")

    if not isinstance(entry, Mapping):
        raise bad("", f"{type(entry).__name__}, not an object")
    graph = card.get("graph", {}).get("file") if isinstance(card.get("graph"), Mapping) else None
    want = card.get("files", {}).get(graph) if graph else None
    if want is None or entry.get("graph_sha256") != want:
        raise bad("graph_sha256", f"{str(entry.get('graph_sha256'))[:12]}... is not the "
                  f"digest of this model's graph ({str(want)[:12]}...): measured on another "
                  "model")
    where = entry.get("measured_on")
    if (not isinstance(where, Mapping) or not isinstance(where.get("manifest_sha256"), str)
            or not isinstance(where.get("n_designs"), int) or where["n_designs"] < 1):
        raise bad("measured_on", "must name the dataset (manifest_sha256) and the number of "
                  "designs (n_designs >= 1) it was measured on")
    for key in ("command", "measured"):
        if not isinstance(entry.get(key), str) or not entry[key]:
            raise bad(key, "missing; must say how and when it was measured")
    hz = entry.get("scale_hz")
    if (not isinstance(hz, list | tuple) or not hz
            or not all(isinstance(f, int | float) and math.isfinite(f) for f in hz)
            or any(b <= a for a, b in itertools.pairwise(hz))):
        raise bad("scale_hz", f"{hz!r}: must be frequencies [Hz] increasing strictly")
    outputs = entry.get("outputs")
    if not isinstance(outputs, Mapping) or not outputs:
        raise bad("outputs", "must map at least one output to its Student-t")
    known = {o.get("name") for o in card.get("outputs", []) if isinstance(o, Mapping)}
    out: dict[str, dict[str, Any]] = {}
    for name, t in outputs.items():
        key = f"outputs.{name}"
        if name not in known:
            raise bad(key, f"not an output of the model ({', '.join(sorted(map(str, known)))})")
        if not isinstance(t, Mapping):
            raise bad(key, "must be an object")
        need = ("nu", "frequency_hz") + (() if name in FACE_OUTPUTS else ("length_mm",))
        for k in need:
            if not _positive(t.get(k)):
                raise bad(f"{key}.{k}", f"{t.get(k)!r}: must be a finite number > 0")
        sw = t.get("shared_within_hz")
        if not (_positive(sw) or sw == 0):
            raise bad(f"{key}.shared_within_hz", f"{sw!r}: must be a finite number >= 0")
        sc = t.get("scale")
        if (not isinstance(sc, list | tuple) or len(sc) != len(hz)
                or not all(_positive(c) for c in sc)):
            raise bad(f"{key}.scale", f"must be {len(hz)} numbers > 0, one per scale_hz")
        out[name] = {"nu": float(t["nu"]), "scale": tuple(float(c) for c in sc),
                     "scale_hz": tuple(float(f) for f in hz),
                     "frequency_hz": float(t["frequency_hz"]), "shared_within_hz": float(sw),
                     **({} if name in FACE_OUTPUTS else {"length_mm": float(t["length_mm"])})}
    return out


def card_error_t(card: Mapping[str, Any] | None) -> dict[str, dict[str, Any]]:
    """The Student-t per output measured on the model of ``card`` (its
    :data:`CARD_ERROR_KEY` entry, checked by :func:`check_error_t`); {} when it has none."""
    if not card or card.get(CARD_ERROR_KEY) is None:
        return {}
    return check_error_t(card[CARD_ERROR_KEY], card)


def surrogate_error_t(output: str, card: Mapping[str, Any] | None = None
                      ) -> dict[str, Any] | None:
    """The Student-t of the surrogate's error of ``output`` for the model of ``card`` (its
    card dict, ``Predictor.card``): the card's own (:data:`CARD_ERROR_KEY`) when measured
    there, else :data:`SURROGATE_ERROR_T`'s; None for an output in neither. Keys: nu, scale
    (one per scale_hz), scale_hz, frequency_hz, shared_within_hz, length_mm (profile outputs),
    source ("model card" or "SURROGATE_ERROR_T")."""
    own = card_error_t(card).get(output)
    if own is not None:
        return {**own, "source": "model card"}
    t = SURROGATE_ERROR_T.get(output)
    return None if t is None else {**t, "scale": tuple(t["scale"]), "scale_hz": SCALE_HZ,
                                   "source": "SURROGATE_ERROR_T"}


def error_settings(output: str, t_model: bool, k: float, length_mm: float | None = None,
                   frequency_hz: float | None = None, card: Mapping[str, Any] | None = None
                   ) -> dict[str, Any]:
    """The surrogate's error model of one output read: the Student-t of
    :func:`surrogate_error_t` (``t_model`` and the output listed; the one in the model's
    ``card`` when measured there) or the first versions' Gaussian (factor ``k``, exponential
    kernels of :data:`ERROR_LENGTH_MM` and :data:`ERROR_FREQUENCY_HZ`, lam = 1); ``length_mm``
    and ``frequency_hz`` replace the lengths when given. Keys: nu (None: Gaussian), scale (a
    number, or a tuple over scale_hz), scale_hz, length_mm (None at the unit's face),
    frequency_hz, shared_within_hz (None: all frequencies), profile_kernel, frequency_kernel,
    source (where the t came from: "model card", "SURROGATE_ERROR_T"; "gaussian")."""
    t = surrogate_error_t(output, card) if t_model else None
    face = output in FACE_OUTPUTS
    if t is None:
        length = ERROR_LENGTH_MM.get(output, ERROR_LENGTH_MM["profile_um"])
        return {"nu": None, "scale": float(k), "scale_hz": None,
                "length_mm": None if face else float(length_mm or length),
                "frequency_hz": float(frequency_hz or ERROR_FREQUENCY_HZ),
                "shared_within_hz": None, "profile_kernel": "exponential",
                "frequency_kernel": "exponential", "source": "gaussian"}
    return {"nu": t["nu"], "scale": tuple(t["scale"]), "scale_hz": tuple(t["scale_hz"]),
            "length_mm": None if face else float(length_mm or t["length_mm"]),
            "frequency_hz": float(frequency_hz or t["frequency_hz"]),
            "shared_within_hz": t["shared_within_hz"], "profile_kernel": "matern32",
            "frequency_kernel": "gaussian", "source": t["source"]}


def point_scales(fwd: ForwardModel, errors: Mapping[str, Mapping[str, Any]],
                 default: float) -> np.ndarray:
    """(m,) the factor on the surrogate's log-std at each point ``fwd`` reads: its output's
    scale, at its frequency when the scale is given per frequency (linear in between)."""
    f = np.array([p.frequency_hz for p in fwd.measurement.points])
    c = np.full(fwd.y.size, float(default))
    for g in fwd.groups:
        e = errors.get(g.output, {})
        sc = e.get("scale", default)
        c[g.index] = (np.interp(f[g.index], e["scale_hz"], sc) if e.get("scale_hz") is not None
                      else sc)
    return c


def calibrate(predictor: Any, measurement: Measurement, fit: Sequence[str], *,
              priors: Sequence[str] = (), fixed: Mapping[str, Any] | None = None,
              walkers: int = 32, steps: int = 1000, burn: int = 333, n_init: int = 4096,
              seed: int = 0, std_factor: float | None = None,
              error_length_mm: float | None = None,
              error_frequency_hz: float | None = None,
              spread: str = "posterior", error_model: str = "t") -> Calibration:
    """Sample the posterior of the inputs ``fit`` (model input names) given ``measurement``.

    Inputs not fitted come from ``fixed``, then the measurement's ``site`` and ``design``
    (model units); a model input with no value is an error naming it. ``priors``: given priors
    (``NAME=KIND:A,B``), the rest default (:mod:`calibration.priors`). ``spread``: how the
    surrogate's spread enters the likelihood (:data:`SPREADS`, module docstring);
    ``error_length_mm``, ``error_frequency_hz``: one correlation length for every profile
    output and one frequency scale for every output, instead of the error model's per output
    (:func:`error_settings`). ``error_model``: :data:`ERROR_MODELS` (a given
    ``std_factor`` means the Gaussian with that factor)."""
    if not 0 <= burn < steps:
        raise PriorError("steps", f"steps {steps} must exceed burn {burn} >= 0")
    if error_model not in ERROR_MODELS:
        raise PriorError("error_model", f"error_model {error_model!r}: allowed "
                         f"{', '.join(ERROR_MODELS)}")
    if spread not in SPREADS:
        raise PriorError("spread", f"spread {spread!r}: allowed {', '.join(SPREADS)}")
    prs = priors_for(fit, predictor.specs, priors)
    values = {**measurement.design, **measurement.site, **(fixed or {})}
    # a fitted input that also has a value (a site. line): the fit wins, the value is a guess
    given = {k: v for k, v in values.items() if k not in fit}
    missing = [n for n in predictor.input_names if n not in given and n not in fit
               and n != "frequency_hz"]
    unknown = [k for k in given if k not in predictor.input_names]
    if unknown:
        raise PriorError(unknown[0], f"{unknown[0]}: not an input of the model (inputs: "
                         f"{', '.join(predictor.input_names)})")
    if missing:
        raise PriorError(missing[0], f"{missing[0]}: no value for this model input; give it in "
                         "the measurement file ('# design.NAME = ...' or '# site.NAME = ...'), "
                         "with --set NAME=VALUE, or fit it")
    fwd = ForwardModel(predictor, measurement, [p.name for p in prs], given)
    k = surrogate_std_factor(predictor.card) if std_factor is None else std_factor
    y, rel = fwd.y, fwd.rel_sigma
    t_model = error_model == "t" and std_factor is None
    errors = {g.output: error_settings(g.output, t_model, k, error_length_mm,
                                       error_frequency_hz, predictor.card)
              for g in fwd.groups}
    lengths = {o: errors[o]["length_mm"] for o in fwd.profile_outputs}
    freq_hz = {o: e["frequency_hz"] for o, e in errors.items()}
    shared = {o: e["shared_within_hz"] for o, e in errors.items()
              if e["shared_within_hz"] is not None}
    corr = fwd.error_correlation(
        lengths or 1.0, freq_hz, shared_within_hz=shared,
        profile_kernel={o: e["profile_kernel"] for o, e in errors.items()},
        frequency_kernel={o: e["frequency_kernel"] for o, e in errors.items()})
    scale = point_scales(fwd, errors, k)
    blocks = [(idx, errors[g.output]["nu"] or math.inf) for idx, g in fwd.error_blocks(shared)]
    fixed_std: list[np.ndarray] = []  # the surrogate's spread held fixed ("posterior")

    def x_of(z: np.ndarray) -> np.ndarray:
        return np.column_stack([p.from_z(z[:, j]) for j, p in enumerate(prs)])

    def log_post(z: np.ndarray) -> np.ndarray:
        z = np.atleast_2d(z)
        lp = np.sum([p.log_density_z(z[:, j]) for j, p in enumerate(prs)], axis=0)
        ok = np.isfinite(lp)
        out = np.full(z.shape[0], -np.inf)
        if ok.any():
            mean, std = fwd.predict(x_of(z[ok]))
            cs = scale * (fixed_std[-1] if fixed_std else std)
            cov = (cs[:, None] * corr * cs[None, :] if cs.ndim == 1 else
                   cs[:, :, None] * corr[None] * cs[:, None, :])
            out[ok] = lp[ok] + mixture_log_likelihood(y - mean, rel ** 2, cov, blocks)
        return out

    def rms_std(z: np.ndarray) -> np.ndarray:
        """The surrogate's spread per point, root-mean-square over the rows of ``z``."""
        return np.sqrt(np.mean(fwd.predict(x_of(z))[1] ** 2, axis=0))

    import emcee  # here, so that reading a calibration (the planner) needs numpy only

    def sampler_for() -> Any:
        s = emcee.EnsembleSampler(
            walkers, len(prs), log_post, vectorize=True,
            moves=[(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)])
        s.random_state = np.random.RandomState(int(rng.integers(2**31))).get_state()
        return s

    # One BLAS thread: the likelihood's eigen-decompositions are of matrices of the
    # measurement's size (5-30 points), where OpenBLAS's threads only cost: a 30 x 30 eigh
    # took 16 ms of CPU with two threads on the loaded 2-core machine, 0.15 ms with one.
    with threadpool_limits(limits=1):
        rng = np.random.default_rng(seed)
        t0 = time.perf_counter()
        z0 = np.column_stack([p.sample_z(n_init, rng) for p in prs])
        if spread == "posterior":  # rank the prior draws at their median spread
            fixed_std.append(np.median(fwd.predict(x_of(z0))[1], axis=0))
        lp0 = log_post(z0)
        start = z0[np.argsort(lp0)[::-1][:walkers]]
        if spread == "local":
            sampler = sampler_for()
            sampler.run_mcmc(start, steps, progress=False)
            kept = burn
        else:
            fixed_std.append(rms_std(start))
            if burn:
                pilot = sampler_for()
                pilot.run_mcmc(start, burn, progress=False)
                fixed_std.append(rms_std(pilot.get_chain(discard=burn // 2, flat=True)))
                start = pilot.get_last_sample().coords
            sampler = sampler_for()  # the kept chain: one fixed likelihood from its first step
            sampler.run_mcmc(start, steps - burn, progress=False)
            kept = 0
        chain = sampler.get_chain(discard=kept, flat=True)
        lps = sampler.get_log_prob(discard=kept, flat=True)
    samples = x_of(chain)
    try:
        tau = sampler.get_autocorr_time(discard=kept, tol=0)
    except emcee.autocorr.AutocorrError:  # pragma: no cover - tol=0 never raises
        tau = np.full(len(prs), np.nan)
    info = {"library": "emcee", "version": emcee.__version__, "walkers": walkers,
            "steps": steps, "burn": burn, "n_init": n_init, "seed": seed,
            "moves": "DEMove 0.8, DESnookerMove 0.2",
            "acceptance_fraction": float(np.mean(sampler.acceptance_fraction)),
            "autocorr_steps": [float(t) for t in tau],
            "effective_samples": float(walkers * (steps - burn) / max(np.nanmax(tau), 1.0)),
            "wall_s": time.perf_counter() - t0}
    return Calibration(measurement, fwd, prs, samples, lps, k, info, lengths, freq_hz,
                       spread, errors)
