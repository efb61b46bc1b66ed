"""The surrogate's error model of a calibration measured (bench/calibration/calibrate.py
--surrogate-error and --error-check): its residuals on the held-out rows of its training data
and on FE subjects, the maximum-likelihood Student-t of calibration.likelihood fitted to them,
and a check of the study's errors at the true inputs against the model."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from calibration import surrogate_std_factor
from calibration.fit import ERROR_LENGTH_MM, point_scales
from calibration.forward import ForwardModel
from calibration.synthetic import synthetic_measurement

ROOT = Path(__file__).resolve().parents[2]
RESIDUAL_CACHE = ROOT / "bench" / "calibration" / "data" / "calibration-residual-subjects.json"
FIT = ("skin_E_kPa", "fat_thickness_mm", "tissue_loss_factor")
NOISES = (0.05, 0.10)


def held_out_residuals(predictor) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The surrogate's error on the rows of its training data it never trained on (the
    card's held-out split, where its metrics come from): per output read by a calibration,
    (ln(FE / surrogate), its predictive log-std), each (rows, points)."""
    from surrogate.data.columns import PROFILE_OUTPUTS
    from surrogate.train import load_datasets, split

    card = predictor.card
    predictor = predictor.uncalibrated()  # the raw spread, which the likelihood widens
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
    predictor = predictor.uncalibrated()  # the raw spread, which the likelihood widens
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


#: the previous version's Student-t (one mixing variable per output across all its
#: frequencies, one scale, exponential kernels of ERROR_LENGTH_MM and ERROR_FREQUENCY_HZ),
#: kept here to check it beside the current one
PREVIOUS_T = {"center_amplitude_um": {"nu": 2.18, "scale": 0.98},
              "profile_um": {"nu": 1.86, "scale": 0.541},
              "profile_normal_um": {"nu": 1.32, "scale": 0.706}}


def _pit_blocks(fwd: ForwardModel, sd: np.ndarray, e: np.ndarray, version: str, k: float
                ) -> list[tuple[float, int]]:
    """(PIT, number of frequencies) of the error ``e`` per block of the error model
    ``version`` ("t": calibration.fit's; "t, previous": PREVIOUS_T; "gaussian")."""
    from scipy import stats

    from calibration.fit import error_settings

    t_model = version == "t"
    errors = {g.output: error_settings(g.output, t_model, k, card=fwd.predictor.card)
              for g in fwd.groups}
    if version == "t, previous":
        for o, e_ in errors.items():
            if o in PREVIOUS_T:
                e_.update(PREVIOUS_T[o])
    shared = {o: v["shared_within_hz"] for o, v in errors.items()
              if v["shared_within_hz"] is not None}
    corr = fwd.error_correlation(
        {o: errors[o]["length_mm"] for o in fwd.profile_outputs} or 1.0,
        {o: v["frequency_hz"] for o, v in errors.items()}, shared_within_hz=shared,
        profile_kernel={o: v["profile_kernel"] for o, v in errors.items()},
        frequency_kernel={o: v["frequency_kernel"] for o, v in errors.items()})
    x = e / (point_scales(fwd, errors, k) * sd)
    f = np.array([p.frequency_hz for p in fwd.measurement.points])
    out = []
    for ix, g in fwd.error_blocks(shared):
        delta = float(x[ix] @ np.linalg.solve(corr[np.ix_(ix, ix)], x[ix]))
        nu = errors[g.output]["nu"]
        pit = (stats.chi2.cdf(delta, ix.size) if nu is None else
               stats.f.cdf(delta / ix.size, ix.size, nu))
        out.append((float(pit), len(set(f[ix]))))
    return out


def error_check(subjects: list[dict], predictor, component: str) -> list[str]:
    """Whether the study's surrogate errors at the true inputs look like draws of the error
    model: per measurement of the study (both noise levels' layouts) and block of points that
    share a mixing variable (an output read, and for the current t a cluster of its
    frequencies), the noise-free error e = ln(FE) - ln(surrogate) at the measured points, its
    Mahalanobis distance delta under S = diag(c s) C diag(c s), and its probability integral
    transform, F(delta / m; m, nu) for a Student-t, chi^2(delta; m) for the Gaussian with the
    card's k: uniform on [0, 1] if the model describes the errors. Per version of the error
    model, over all blocks and by the number of frequencies of the measurement."""
    k = surrogate_std_factor(predictor.card)
    pit: dict[str, list[float]] = {}
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
            for version in ("t", "t, previous", "gaussian"):
                for value, _ in _pit_blocks(fwd, sd[0], e, version, k):
                    for key in (version, f"{version}, {len(freqs)} frequenc"
                                + ("y" if len(freqs) == 1 else "ies")):
                        pit.setdefault(key, []).append(value)
    lines = []
    for name in sorted(pit, key=lambda n: (n.split(",")[0] != "t", n)):
        a = np.array(pit[name])
        q = np.histogram(a, bins=[0, 0.25, 0.5, 0.75, 1.0])[0] / max(a.size, 1)
        lines.append(f"  {name}: {a.size} blocks; PIT quartile fractions "
                     + " ".join(f"{x:.2f}" for x in q)
                     + f"; below 0.025 {np.mean(a < 0.025):.2f}, above 0.975 "
                     f"{np.mean(a > 0.975):.2f} (uniform: 0.25 each; 0.025, 0.025)")
    return lines


#: the sweep dataset the cross-frequency structure is measured on (FE solves of the same space
#: and solver as datasets/default, each design at every 2 Hz in 100-250 Hz; not trained on:
#: ``hapticrom generate --space datasets/spaces/default-sweep.toml``); --sweep DIR for another
#: the sweep designs the error model was measured on, by ``sample_index`` (a fixed set: the
#: first 1,600 a generation of datasets/spaces/default-sweep.toml wrote; any dataset of that
#: space holding them reproduces the fit)
SWEEP_DESIGNS_FILE = Path(__file__).resolve().parent / "data" / "sweep-error-designs.txt"
SWEEP_STEP_HZ = 10.0  # its frequencies used: the study's 10 Hz grid


def sweep_design_indices(path: Path = SWEEP_DESIGNS_FILE) -> np.ndarray:
    """The ``sample_index`` of the designs listed in ``path`` (comment lines start with #)."""
    lines = [ln for ln in path.read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    return np.array([int(ln) for ln in lines], dtype=np.int64)


def trained_on(predictor, path: Path) -> bool:
    """Whether ``predictor``'s card names the dataset ``path`` among its training data."""
    here = Path(path).resolve()
    return any((ROOT / d["path"]).resolve() == here
               for d in predictor.card.get("training_data", []) if "path" in d)


def sweep_residuals(predictor, path: Path, designs: Path | None = SWEEP_DESIGNS_FILE,
                    max_mm: float | None = None
                    ) -> tuple[np.ndarray, np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """The surrogate's error on the sweep dataset at the frequencies of a 10 Hz grid and the
    profile points it shares with the model (every 2 mm, to the end of the model's profile:
    20 mm for nn-default, 40 mm for a sweep model): (frequencies [Hz], distances [mm], per
    output read {name: (ln(FE / surrogate), raw predictive log-std), each (designs,
    frequencies[, points])}); magnitude |U| and normal component |U_z|; ``max_mm`` ends the
    profile sooner. ``designs``: the file
    of ``sample_index`` values to use, or None for every design of the dataset. A model whose
    card names ``path`` as its training data is refused: its errors there are not a new
    design's."""
    from surrogate.data.store import Store

    if trained_on(predictor, path):
        raise ValueError(f"--sweep {path}: the model {predictor.card.get('name')!r} trained on "
                         "this dataset; measure its error on designs it never saw (e.g. "
                         "datasets/default-sweep-test with --sweep-designs all)")
    df = Store.open(path).read()
    df = df[df["status"] == "ok"]
    if designs is not None:
        want = sweep_design_indices(designs)
        df = df[df["sample_index"].isin(want)]
        if len(df) < want.size:
            raise ValueError(f"--sweep {path}: holds {len(df)} of the {want.size} designs of "
                             f"{designs.name}; extend it with `hapticrom generate --space "
                             "datasets/spaces/default-sweep.toml --n 8192 --out DIR`")
    df = df.sort_values("sample_index", kind="stable").reset_index(drop=True)
    n = len(df)
    freq = np.asarray(df["sweep_frequency_hz"].iloc[0], dtype=float)
    keep = np.flatnonzero(np.isclose(np.mod(freq, SWEEP_STEP_HZ), 0.0))
    dist = np.asarray(df["profile_distance_mm"].iloc[0], dtype=float)
    grid = np.asarray(predictor.profile_distance_mm, dtype=float)
    pk = np.flatnonzero(dist <= min(grid[-1], np.inf if max_mm is None else max_mm))
    gi = np.array([int(np.argmin(np.abs(grid - d))) for d in dist[pk]])
    if not np.allclose(grid[gi], dist[pk]):
        raise ValueError("the sweep's profile points are not on the model's grid")

    def comp(where: str, c: str) -> np.ndarray:
        re = np.stack([np.asarray(v, float) for v in df[f"sweep_{where}_{c}_re_um"]])
        im = np.stack([np.asarray(v, float) for v in df[f"sweep_{where}_{c}_im_um"]])
        return (re + 1j * im).reshape(n, freq.size, -1)[:, keep]

    prof = {c: comp("profile", c)[:, :, pk] for c in ("ur", "uz", "ut")}
    cen = {c: comp("center", c)[:, :, 0] for c in ("ur", "uz", "ut")}
    fe = {"center_amplitude_um": np.sqrt(sum(np.abs(v) ** 2 for v in cen.values())),
          "profile_um": np.sqrt(sum(np.abs(v) ** 2 for v in prof.values())),
          "profile_normal_um": np.abs(prof["uz"])}
    f = freq[keep]
    X = {k: np.repeat(df[k].to_numpy(), f.size) for k in predictor.input_names
         if k != "frequency_hz"}
    X["frequency_hz"] = np.tile(f, n)
    out = predictor.uncalibrated().predict(X)
    res = {}
    for name, y in fe.items():
        if name not in out:
            continue
        mu = out[name].reshape(n, f.size, -1)
        sd = out[f"{name}_log_std"].reshape(n, f.size, -1)
        if name != "center_amplitude_um":
            mu, sd = mu[:, :, gi], sd[:, :, gi]
        else:
            mu, sd = mu[:, :, 0], sd[:, :, 0]
        res[name] = (np.log(y / mu), sd)
    return f, dist[pk], res


def fit_matern_profile(r: np.ndarray, sd: np.ndarray, grid_mm: np.ndarray,
                       previous_length_mm: float) -> dict[str, dict[str, Any]]:
    """Maximum likelihood of the multivariate t with the profile correlation
    calibration.likelihood.profile_kernel on residual vectors ``r`` (rows) with log-std
    ``sd``: nu, the scale c and the length L [mm] for Matern 3/2 and for the exponential, and
    nu and c for the previous version's exponential of ``previous_length_mm``; each with its
    log-likelihood and the scale refitted on every 2nd and 4th point (its length kept): a
    kernel of the right shape gives the same scale whatever the spacing of the points."""
    from scipy.optimize import minimize

    from calibration.likelihood import mvt_logpdf, profile_kernel

    x = r / sd
    lag = np.abs(grid_mm[:, None] - grid_mm[None, :])

    def fit(xs: np.ndarray, lags: np.ndarray, kind: str, length: float | None
            ) -> tuple[np.ndarray, float]:
        def nll(p: np.ndarray) -> float:
            ln = float(np.exp(p[2])) if length is None else length
            return -float(np.sum(mvt_logpdf(xs, np.exp(2 * p[0]) * profile_kernel(
                lags, ln, kind), float(np.exp(p[1])))))
        p0 = np.array([0.0, 0.7] + ([np.log(10.0)] if length is None else []))
        t = minimize(nll, p0, method="Nelder-Mead",
                     options={"xatol": 1e-4, "fatol": 1e-3, "maxiter": 3000})
        return np.exp(t.x), -float(t.fun)

    fits: dict[str, dict[str, Any]] = {}
    for label, kind, length in (("matern32", "matern32", None),
                                ("exponential", "exponential", None),
                                (f"exponential {previous_length_mm:g} mm (previous)",
                                 "exponential", previous_length_mm)):
        p, ll = fit(x, lag, kind, length)
        ln = float(p[2]) if length is None else length
        fits[label] = {"scale": float(p[0]), "nu": float(p[1]), "length_mm": ln, "loglik": ll,
                       "scale_spaced": [float(fit(x[:, ::k], lag[::k, ::k], kind, ln)[0][0])
                                        for k in (2, 4)]}
    return fits


def fit_t_per_frequency(x: np.ndarray, corr: np.ndarray) -> tuple[float, np.ndarray]:
    """Maximum likelihood of the multivariate t of calibration.likelihood with one scale per
    frequency: ``x`` (designs, frequencies, points) the errors in units of the log-std, each
    (design, frequency) vector one draw with scale matrix c_f^2 ``corr`` and one nu shared by
    every frequency. Returns nu and c (frequencies,)."""
    from scipy.optimize import minimize

    from calibration.likelihood import mvt_logpdf

    nf = x.shape[1]

    def nll(p: np.ndarray) -> float:
        return -sum(float(np.sum(mvt_logpdf(x[:, i], np.exp(2 * p[1 + i]) * corr,
                                            float(np.exp(p[0]))))) for i in range(nf))

    t = minimize(nll, np.r_[0.7, np.zeros(nf)], method="Powell",
                 options={"xtol": 1e-3, "ftol": 1e-5})
    return float(np.exp(t.x[0])), np.exp(t.x[1:])


def current_t_check(x: np.ndarray, f: np.ndarray, dist: np.ndarray, name: str,
                    nu: float, c: np.ndarray, length: float | None,
                    t: dict[str, Any], label: str) -> str:
    """How the Student-t ``t`` (of :func:`calibration.fit.surrogate_error_t`, with its
    ``scale_hz``; called ``label``) of ``name`` describes the errors ``x`` (designs,
    frequencies, points; in units of the raw log-std), one frequency at a time: the mean
    log-likelihood per (design, frequency) vector under it and under the refit (nu, scales
    ``c``, Matern length ``length``), and the quartile fractions of the probability integral
    transform F(delta / m; m, nu) under ``t`` (0.25 each if it describes them; the upper
    quarters crowd when it is too narrow)."""
    from scipy import stats

    from calibration.likelihood import mvt_logpdf, profile_kernel

    lag = np.abs(dist[:, None] - dist[None, :])
    m = x.shape[2]
    Kc = np.ones((1, 1)) if m == 1 else profile_kernel(lag, t["length_mm"], "matern32")
    Kn = np.ones((1, 1)) if m == 1 else profile_kernel(lag, float(length), "matern32")
    cc = np.interp(f, t["scale_hz"], t["scale"])
    ll_cur = ll_new = 0.0
    pit = []
    for i in range(f.size):
        ll_cur += float(np.sum(mvt_logpdf(x[:, i], cc[i] ** 2 * Kc, t["nu"])))
        ll_new += float(np.sum(mvt_logpdf(x[:, i], c[i] ** 2 * Kn, nu)))
        xi = x[:, i] / cc[i]
        delta = np.einsum("ij,ij->i", xi, np.linalg.solve(Kc, xi.T).T)
        pit.append(stats.f.cdf(delta / m, m, t["nu"]))
    n = x.shape[0] * f.size
    q = np.histogram(np.concatenate(pit), bins=[0, 0.25, 0.5, 0.75, 1.0])[0] / n
    return (f"    against {label} (nu {t['nu']:g}, scale "
            + " / ".join(f"{a:.3g}" for a in np.interp([100, 150, 200, 250], t["scale_hz"],
                                                         t["scale"]))
            + " at 100 / 150 / 200 / 250 Hz"
            + ("" if m == 1 else f", length {t['length_mm']:g} mm") + "): log-lik per vector "
            f"{ll_cur / n:.3f} (refit {ll_new / n:.3f}); PIT quartile fractions under it "
            + " ".join(f"{v:.2f}" for v in q) + "; refit scale / current at 100 / 150 / 200 / "
            "250 Hz " + " / ".join(f"{a:.2f}" for a in np.interp([100, 150, 200, 250], f, c)
                                   / np.interp([100, 150, 200, 250], t["scale_hz"],
                                               t["scale"])))


def fit_sweep_error(predictor, component: str, path: Path,
                    designs: Path | None = SWEEP_DESIGNS_FILE,
                    max_mm: float | None = None
                    ) -> tuple[list[str], dict[str, Any]]:
    """The surrogate's error structure across frequency, per output a ``component`` sensor
    reads (calibration.fit.SURROGATE_ERROR_T): the correlation length along the profile
    (Matern 3/2 against the exponential, on the model's held-out rows, 1 mm grid; for a model
    trained on sweeps, on the sweep dataset's own vectors, every 2 mm to the end of its
    profile, or to ``max_mm``); on the sweep dataset, nu and a scale per frequency (the
    profile's length fixed), then for each frequency difference df of one design: the
    correlation rho of its errors under one shared mixing variable lam, and that model's log-
    likelihood per pair of frequencies against independent lams (no correlation): lam is shared
    where it wins. The frequency length is the Gaussian kernel exp(-df^2 / (2 L_f^2)) fitted to
    rho at those df. Last, per output, how SURROGATE_ERROR_T and the t of the model's card
    (calibration.fit.CARD_ERROR_KEY), if any, fit the same errors (:func:`current_t_check`).
    Returns the printed lines and what was measured: {"outputs": {output: the t as the card
    holds it (rounded as printed)}, "scale_hz" (the frequencies measured, where the scales
    are), "n_designs", "profile_mm"} (:func:`error_t_entry` makes the card's entry of it)."""
    from scipy.optimize import minimize_scalar

    from calibration.fit import card_error_t, surrogate_error_t
    from calibration.likelihood import mvt_logpdf, profile_kernel
    from surrogate.runtime.defaults import is_sweep_model

    outputs = (("center_amplitude_um", "profile_um") if component == "magnitude" else
               ("profile_normal_um",))
    sweep_model = is_sweep_model(predictor.card)
    held = None if sweep_model else held_out_residuals(predictor.uncalibrated())
    grid = np.asarray(predictor.profile_distance_mm, dtype=float)
    f, dist, sweep = sweep_residuals(predictor, path, designs, max_mm)
    n_designs = int(next(iter(sweep.values()))[0].shape[0])
    own = card_error_t(predictor.card)  # checked before an hour of fitting, not after
    fitted: dict[str, Any] = {"outputs": {}, "scale_hz": [float(x) for x in f],
                              "n_designs": n_designs, "profile_mm": [float(x) for x in dist]}
    lines = [f"  sweep dataset {path}: {n_designs} designs x "
             f"{f.size} frequencies ({f[0]:g}-{f[-1]:g} Hz every {SWEEP_STEP_HZ:g}), profile "
             f"points {dist[0]:g}-{dist[-1]:g} mm every {dist[1] - dist[0]:g} mm"]
    for name in outputs:
        r, sd = sweep[name]
        x = r / sd
        if x.ndim == 2:
            x = x[:, :, None]
            K, length = np.ones((1, 1)), None
            lines.append(f"  {name}: held-out rows: the face (one point)")
        else:
            if sweep_model:  # no single-frequency held-out rows: the sweep's own vectors
                hr = (r.reshape(-1, r.shape[2]), sd.reshape(-1, sd.shape[2]))
                where, pts = "sweep vectors (design, frequency)", dist
            else:
                hr, where, pts = held[name], "held-out rows", grid
            fits = fit_matern_profile(*hr, pts, ERROR_LENGTH_MM[name])
            length = round(fits["matern32"]["length_mm"], 1)
            K = profile_kernel(np.abs(dist[:, None] - dist[None, :]), length, "matern32")
            lines.append(f"  {name}: {hr[0].shape[0]} {where} x {pts.size} points: "
                         + "; ".join(f"{k} nu {v['nu']:.3g} scale {v['scale']:.3g} length "
                                     f"{v['length_mm']:.3g} mm log-lik {v['loglik']:.1f} "
                                     "(scale on every 2nd / 4th point: "
                                     + " / ".join(f"{c:.3g}" for c in v["scale_spaced"]) + ")"
                                     for k, v in fits.items()))
        m = x.shape[2]
        nu, c = fit_t_per_frequency(x, K)
        lines.append(f"    sweep, one frequency at a time: nu {nu:.3g}; scale per frequency "
                     + " ".join(f"{a:g}:{b:.3g}" for a, b in zip(f, c, strict=True)))
        xs = x / c[None, :, None]
        nf = x.shape[1]
        rows = []
        for df_hz in SWEEP_STEP_HZ * np.arange(1, 9):
            pairs = [(i, j) for i in range(nf) for j in range(nf)
                     if np.isclose(f[j] - f[i], df_hz)]
            X = np.concatenate([np.concatenate([xs[:, i], xs[:, j]], axis=1)
                                for i, j in pairs])
            ind = float(np.sum(mvt_logpdf(X[:, :m], K, nu)) + np.sum(mvt_logpdf(X[:, m:], K, nu)))

            def shared(rho: float, X: np.ndarray = X, K: np.ndarray = K, nu: float = nu
                       ) -> float:
                return -float(np.sum(mvt_logpdf(X, np.kron(np.array([[1.0, rho], [rho, 1.0]]),
                                                           K), nu)))
            s = minimize_scalar(shared, bounds=(-0.5, 0.99), method="bounded")
            rows.append((df_hz, float(s.x), (-float(s.fun) - ind) / len(X)))
        win = [(d, rho) for d, rho, gain in rows if gain > 0 and rho > 0]
        shared_hz = max((d for d, _ in win), default=0.0)
        lf = (float(np.sqrt(np.mean([d ** 2 / (-2.0 * np.log(rho)) for d, rho in win])))
              if win else float("nan"))
        lines.append("    pairs of frequencies of one design, df: rho under a shared lam, "
                     "log-likelihood gain per pair over independent lams: "
                     + "; ".join(f"{d:g} Hz {rho:.2f} {g:+.3f}" for d, rho, g in rows))
        lines.append(f"    -> lam shared within {shared_hz:g} Hz, frequency length (Gaussian) "
                     f"{lf:.1f} Hz" + ("" if length is None else
                                       f", profile length (Matern 3/2) {length:g} mm"))
        fitted["outputs"][name] = {
            "nu": float(f"{nu:.3g}"), "scale": [float(f"{a:.3g}") for a in c],
            "frequency_hz": round(lf, 1), "shared_within_hz": float(shared_hz),
            **({} if length is None else {"length_mm": float(length)})}
        checks = {"SURROGATE_ERROR_T": surrogate_error_t(name)}
        if name in own:
            checks["the model card's t"] = own[name]
        lines += [current_t_check(x, f, dist, name, nu, c, length, t, f"{label}[{name!r}]")
                  for label, t in checks.items()]
    return lines, fitted


def error_t_entry(predictor, fitted: dict[str, Any], sweep: Path, designs: Path | None,
                  command: str) -> dict[str, Any]:
    """The model card's :data:`calibration.fit.CARD_ERROR_KEY` entry for what
    :func:`fit_sweep_error` measured on ``predictor`` (``fitted``, merged over the sensor kinds
    measured): the t per output, ``scale_hz``, the digest of the graph measured, the dataset
    (path relative to the repository when inside it, ``manifest_sha256``, ``space_hash``, which
    designs and how many, frequencies, profile points), ``command`` and the UTC time."""
    import datetime

    from surrogate.registry import manifest_sha256

    card = predictor.card
    here = Path(sweep).resolve()
    rel = here.relative_to(ROOT) if here.is_relative_to(ROOT) else here
    manifest = json.loads((here / "_manifest.json").read_text())
    dfile = (None if designs is None else str(Path(designs).resolve().relative_to(ROOT))
             if Path(designs).resolve().is_relative_to(ROOT) else str(designs))
    return {
        "method": "multivariate Student-t of ln(FE / surrogate) per output read, in units of "
                  "the graph's raw log-std (calibration.fit, docs/calibration.md 'The fit')",
        "outputs": fitted["outputs"], "scale_hz": fitted["scale_hz"],
        "graph_sha256": card["files"][card["graph"]["file"]],
        "measured_on": {"dataset": str(rel), "manifest_sha256": manifest_sha256(here),
                        "space_hash": manifest.get("space_hash"),
                        "designs": "all" if dfile is None else dfile,
                        "n_designs": fitted["n_designs"],
                        "frequencies_hz": fitted["scale_hz"],
                        "profile_mm": fitted["profile_mm"]},
        "command": command,
        "measured": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")}


def select_outputs(measured: dict[str, Any], names: str | None) -> dict[str, Any]:
    """``measured`` (of :func:`fit_sweep_error`) with only the outputs ``names``
    (comma-separated; None: all of them), for the card (``--write-outputs``): an output not
    measured, or none, raises ValueError naming what was measured."""
    if names is None:
        return measured
    keep = [o.strip() for o in names.split(",") if o.strip()]
    other = [o for o in keep if o not in measured["outputs"]]
    if not keep or other:
        raise ValueError(f"{names!r}: not measured here ({', '.join(other) or 'none given'}); "
                         f"measured: {', '.join(measured['outputs'])}")
    return {**measured, "outputs": {o: measured["outputs"][o] for o in keep}}


def write_error_t(model_dir: Path, entry: dict[str, Any]) -> dict[str, Any]:
    """Write ``entry`` as the :data:`calibration.fit.CARD_ERROR_KEY` of the card of
    ``model_dir`` (replacing any earlier one; every other key unchanged): the entry checked
    against the card (calibration.fit.check_error_t: a malformed entry, or one measured on
    another graph, raises ModelFileError and nothing is written), then the card re-sealed and
    replaced atomically (surrogate.runtime.card.replace_card, which verifies the directory
    before and after). Returns the new card."""
    from calibration.fit import CARD_ERROR_KEY, check_error_t
    from surrogate.runtime.card import read_card, replace_card

    card = read_card(model_dir, verify=False)  # replace_card verifies the directory
    check_error_t(entry, card)
    return replace_card(model_dir, {**card, CARD_ERROR_KEY: entry})
