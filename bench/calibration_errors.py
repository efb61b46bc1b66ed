"""The surrogate's error model of a calibration measured (bench/bench_calibration.py
--surrogate-error and --error-check): its residuals on the held-out rows of its training data
and on FE subjects, the maximum-likelihood Student-t of calibration.likelihood fitted to them,
and a check of the study's errors at the true inputs against the model."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from calibration import surrogate_std_factor
from calibration.fit import ERROR_FREQUENCY_HZ, ERROR_LENGTH_MM
from calibration.forward import ForwardModel
from calibration.synthetic import synthetic_measurement

ROOT = Path(__file__).resolve().parents[1]
RESIDUAL_CACHE = ROOT / "bench" / "data" / "calibration-residual-subjects.json"
FIT = ("skin_E_kPa", "fat_thickness_mm", "tissue_loss_factor")
NOISES = (0.05, 0.10)


def held_out_residuals(predictor) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The surrogate's error on the rows of its training data it never trained on (the
    card's held-out split, where its metrics come from): per output read by a calibration,
    (ln(FE / surrogate), its predictive log-std), each (rows, points)."""
    from surrogate.data.columns import PROFILE_OUTPUTS
    from surrogate.train import load_datasets, split

    card = predictor.card
    extra = [o for o in card["training"].get("profile_outputs", {}) if o != "profile_um"]
    data = load_datasets([ROOT / d["path"] for d in card["training_data"]], outputs=extra)
    _, te = split(len(data.codes), card["training"]["test_fraction"], card["training"]["seed"])
    out = predictor.predict(data.codes[te])
    truth = {"center_amplitude_um": data.center_um[te][:, None],
             "profile_um": data.profile_um[te],
             **{o: data.extra_um[o][te] for o in extra if o in PROFILE_OUTPUTS}}
    res = {}
    for name, y in truth.items():
        mu = out[name].reshape(len(te), -1)
        res[name] = (np.log(y / mu), out[f"{name}_log_std"].reshape(len(te), -1))
    return res


def subject_residuals(subjects: list[dict], predictor, component: str
                      ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """As :func:`held_out_residuals` on FE subjects (one row per subject and frequency): the
    unit's face (magnitude) and the profile of the ``component``."""
    prof = "profile_um" if component == "magnitude" else "profile_normal_um"
    rows: dict[str, list] = {"center_amplitude_um": [], prof: []}
    for s in subjects:
        for i, f in enumerate(s["frequencies_hz"]):
            X = {k: np.array([v]) for k, v in {**s["design"], **s["truth"]}.items()}
            X["frequency_hz"] = np.array([f])
            o = predictor.predict(X)
            fe = {"center_amplitude_um": [s["centre_um"]["magnitude"][i]],
                  prof: s["profile_um"][component][i]}
            for name, y in fe.items():
                rows[name].append((np.log(np.asarray(y) / o[name][0]),
                                   np.atleast_1d(o[f"{name}_log_std"][0])))
    return {n: (np.array([r[0] for r in v]), np.array([r[1] for r in v]))
            for n, v in rows.items()}


def fit_t(r: np.ndarray, sd: np.ndarray, corr: np.ndarray) -> dict[str, float]:
    """Maximum likelihood of the multivariate Student-t of calibration.likelihood for the
    residual vectors ``r`` (rows) with log-std ``sd``: nu and the scale c of
    S = c^2 diag(sd) corr diag(sd); the Gaussian's scale and both log-likelihoods (of r / sd)."""
    from scipy.optimize import minimize

    from calibration.likelihood import mvt_logpdf

    x = r / sd  # in units of the log-std: S = c^2 corr (the Jacobian sum ln sd is a constant)

    def nll(p: np.ndarray, nu: float | None = None) -> float:
        v = np.exp(p[1]) if nu is None else nu
        return -float(np.sum(mvt_logpdf(x, np.exp(2 * p[0]) * corr, v)))

    t = minimize(nll, np.array([0.0, 1.0]), method="Nelder-Mead",
                 options={"xatol": 1e-4, "fatol": 1e-4, "maxiter": 2000})
    g = minimize(lambda p: nll(p, np.inf), np.array([0.0]), method="Nelder-Mead")
    return {"nu": float(np.exp(t.x[1])), "scale": float(np.exp(t.x[0])), "loglik": -t.fun,
            "gauss_scale": float(np.exp(g.x[0])), "gauss_loglik": -g.fun}


def fit_surrogate_error(predictor, component: str) -> list[str]:
    """Fit the multivariate Student-t of calibration.likelihood to the held-out residual
    vectors of each output a ``component`` sensor reads (one vector per held-out row: the
    profile's points, correlated as the calibration assumes, ERROR_LENGTH_MM); beside it the
    same fit on the FE subjects of --residuals (one vector per subject and frequency)."""
    outputs = (("center_amplitude_um", "profile_um") if component == "magnitude" else
               ("profile_normal_um",))
    grid = np.asarray(predictor.profile_distance_mm, dtype=float)
    other = subject_residuals(json.loads(RESIDUAL_CACHE.read_text())["subjects"], predictor,
                              component)
    lines = []
    for name, (r, sd) in held_out_residuals(predictor).items():
        if name not in outputs:
            continue
        m = r.shape[1]
        C = (np.ones((1, 1)) if m == 1 else
             np.exp(-np.abs(grid[:, None] - grid[None, :]) / ERROR_LENGTH_MM.get(name, 20.0)))
        f, o = fit_t(r, sd, C), fit_t(*other[name], C)
        z = np.abs(r / sd).ravel()
        lines += [f"  {name}: {r.shape[0]} held-out rows x {m} points: Student-t nu "
                  f"{f['nu']:.3g}, scale {f['scale']:.3g} (log-lik {f['loglik']:.1f}); Gaussian "
                  f"scale {f['gauss_scale']:.3g} (log-lik {f['gauss_loglik']:.1f}); |z| within "
                  f"1.96: {np.mean(z <= 1.96):.1%}, 99th percentile {np.percentile(z, 99):.1f}",
                  f"    on the {len(other[name][0])} FE solves of --residuals: nu {o['nu']:.3g}, "
                  f"scale {o['scale']:.3g} (log-lik {o['loglik']:.1f}); Gaussian scale "
                  f"{o['gauss_scale']:.3g} (log-lik {o['gauss_loglik']:.1f})"]
    return lines


def error_check(subjects: list[dict], predictor, component: str) -> list[str]:
    """Whether the study's surrogate errors at the true inputs look like draws of the error
    model: per measurement of the study (both noise levels' layouts) and output read, the
    noise-free error e = ln(FE) - ln(surrogate) at the measured points, its Mahalanobis
    distance delta under S = c^2 diag(s) C diag(s), and its probability integral transform,
    F(delta / m; m, nu) for the Student-t (SURROGATE_ERROR_T), chi^2(delta; m) for the Gaussian
    with the card's k: uniform on [0, 1] if the model describes the errors."""
    from scipy import stats

    from calibration.fit import SURROGATE_ERROR_T

    k = surrogate_std_factor(predictor.card)
    pit: dict[str, list[float]] = {"t": [], "gaussian": [], "t, one frequency": [],
                                   "t, 2-3 frequencies": []}
    for s in subjects:
        grid = list(s["profile_distance_mm"])
        for noise in NOISES:
            rng = np.random.default_rng(1000 * int(s["id"]) + round(100 * noise))
            m = synthetic_measurement(s, rel_noise=noise, n_points=int(rng.integers(5, 11)),
                                      rng=rng, component=component,
                                      sensor="ldv" if component == "normal" else None)
            fwd = ForwardModel(predictor, m, FIT, s["design"])
            freqs = list(s["frequencies_hz"])
            fe = np.array([s["centre_um"][component][freqs.index(p.frequency_hz)]
                           if p.reference == "centre" else
                           s["profile_um"][component][freqs.index(p.frequency_hz)][
                               grid.index(round(p.distance_m * 1e3, 6))] for p in m.points])
            mean, sd = fwd.predict(np.array([[s["truth"][n] for n in FIT]]))
            e = np.log(fe * 1e-6) - mean[0]
            corr = fwd.error_correlation({o: ERROR_LENGTH_MM[o] for o in fwd.profile_outputs},
                                         ERROR_FREQUENCY_HZ)
            for g in fwd.groups:
                ix = g.index
                x = e[ix] / sd[0, ix]
                delta = float(x @ np.linalg.solve(corr[np.ix_(ix, ix)], x))
                t = SURROGATE_ERROR_T.get(g.output)
                if t is not None:
                    pit["t"].append(float(stats.f.cdf(delta / t["scale"] ** 2 / ix.size,
                                                      ix.size, t["nu"])))
                    pit["t, one frequency" if len(freqs) == 1 else
                        "t, 2-3 frequencies"].append(pit["t"][-1])
                pit["gaussian"].append(float(stats.chi2.cdf(delta / k ** 2, ix.size)))
    lines = []
    for name, v in pit.items():
        a = np.array(v)
        q = np.histogram(a, bins=[0, 0.25, 0.5, 0.75, 1.0])[0] / max(a.size, 1)
        lines.append(f"  {name}: {a.size} output blocks; PIT quartile fractions "
                     + " ".join(f"{x:.2f}" for x in q)
                     + f"; below 0.025 {np.mean(a < 0.025):.2f}, above 0.975 "
                     f"{np.mean(a > 0.975):.2f} (uniform: 0.25 each; 0.025, 0.025)")
    return lines
