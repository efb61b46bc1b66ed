"""Which outputs should a surrogate learn from sweep data? Measured on the same designs.

Issue 20, item 1: the magnitude at one frequency changes sharply with the design near an
antiresonance, while the complex response and the resonances move smoothly. This study
trains the same learner on three choices of output, on the same training designs of a sweep
dataset, and scores every choice on the same held-out designs at every band frequency:

* ``magnitude@f`` (today's outputs): one row per (design, frequency), inputs = design +
  frequency, outputs = ln |centre|, ln |edge| (``--freqs-per-design`` frequencies per design,
  drawn at random; 1 is today's dataset layout);
* ``ln-magnitude band``: one row per design, outputs = POD coefficients of ln |centre(f)| and
  ln |edge(f)| over the band, evaluated at the requested frequency by the band's grid;
* ``complex band``: one row per design, outputs = ln of the band's RMS centre amplitude and
  POD coefficients of the complex components of centre and edge (real and imaginary parts)
  divided by that scale; the magnitude is computed from the predicted components.

Learners: scikit-learn's MLPRegressor (3 x 128, early stopping) and a Gaussian process
(Matern 5/2, ARD) on standardised targets, identical for every choice. Errors are relative
magnitude errors at every band frequency of the test designs: median, p95, p99, max; and the
largest error on the field's scale, |error| / max(centre, edge).

    python bench/bench_output_choice.py --data /path/to/sweep-dataset [--test 0.25] [--seed 0]
"""

from __future__ import annotations

import argparse
import time
import warnings
from collections.abc import Callable

import numpy as np
from sklearn.decomposition import PCA
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel
from sklearn.neural_network import MLPRegressor
from sklearn.preprocessing import StandardScaler

from surrogate.data.columns import sweep_arrays
from surrogate.data.store import Store
from surrogate.features import SpaceEncoder, codes_from_frame, input_specs

Learner = Callable[[np.ndarray, np.ndarray], Callable[[np.ndarray], np.ndarray]]


def load(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Design features (n, d), band [Hz] (n_f,), complex centre and edge (n, n_f, 3) [um]."""
    store = Store.open(path)
    df = store.read()
    df = df[df["status"] == "ok"].reset_index(drop=True)
    specs = input_specs(store.manifest["space"]["parameter"])
    codes = codes_from_frame(df, specs)
    features = SpaceEncoder([s.to_dict() for s in specs]).fit_transform(codes)
    rows = df.to_dict("records")
    center = np.stack([sweep_arrays(r, "center") for r in rows])
    edge = np.stack([sweep_arrays(r, "edge") for r in rows])
    band = np.asarray(rows[0]["sweep_frequency_hz"], dtype=float)
    return features, band, center, edge


def mlp(seed: int) -> Learner:
    def fit(x: np.ndarray, y: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        sx, sy = StandardScaler().fit(x), StandardScaler().fit(y)
        net = MLPRegressor(hidden_layer_sizes=(128, 128, 128), early_stopping=True, max_iter=3000,
                           n_iter_no_change=50, random_state=seed, learning_rate_init=1e-3)
        net.fit(sx.transform(x), sy.transform(y))
        return lambda q: sy.inverse_transform(net.predict(sx.transform(q)).reshape(len(q), -1))
    return fit


def gp(seed: int) -> Learner:
    def fit(x: np.ndarray, y: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        sx, sy = StandardScaler().fit(x), StandardScaler().fit(y)
        kernel = ConstantKernel() * Matern(np.ones(x.shape[1]), nu=2.5) + WhiteKernel(1e-4)
        model = GaussianProcessRegressor(kernel, normalize_y=False, random_state=seed,
                                         n_restarts_optimizer=0)
        model.fit(sx.transform(x), sy.transform(y))
        return lambda q: sy.inverse_transform(model.predict(sx.transform(q)).reshape(len(q), -1))
    return fit


def magnitude(u: np.ndarray) -> np.ndarray:
    """|u| over the last axis of complex components (r, z, t)."""
    return np.sqrt(np.sum(np.abs(u) ** 2, axis=-1))


def choice_point(learner: Learner, xf: np.ndarray, band: np.ndarray, c: np.ndarray,
                 e: np.ndarray, test_x: np.ndarray, per_design: int, rng: np.random.Generator
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Today's layout: (design, frequency) rows, ln magnitudes out."""
    f01 = (band - band[0]) / (band[-1] - band[0])
    idx = np.stack([rng.choice(band.size, per_design, replace=False) for _ in range(len(xf))])
    rows = np.repeat(np.arange(len(xf)), per_design)
    cols = idx.reshape(-1)
    x = np.column_stack([xf[rows], f01[cols]])
    y = np.column_stack([np.log(magnitude(c[rows, cols])), np.log(magnitude(e[rows, cols]))])
    model = learner(x, y)
    n_t = len(test_x)
    q = np.column_stack([np.repeat(test_x, band.size, axis=0), np.tile(f01, n_t)])
    out = np.exp(model(q)).reshape(n_t, band.size, 2)
    return out[..., 0], out[..., 1]


def choice_lnmag_band(learner: Learner, xf: np.ndarray, c: np.ndarray, e: np.ndarray,
                      test_x: np.ndarray, modes: int) -> tuple[np.ndarray, np.ndarray]:
    """Whole ln |u(f)| curves out, through POD."""
    y = np.column_stack([np.log(magnitude(c)), np.log(magnitude(e))])
    pca = PCA(min(modes, y.shape[1], len(y) - 1)).fit(y)
    model = learner(xf, pca.transform(y))
    out = np.exp(pca.inverse_transform(model(test_x)))
    n_f = c.shape[1]
    return out[:, :n_f], out[:, n_f:]


def _complex_targets(c: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    scale = np.sqrt(np.mean(magnitude(c) ** 2, axis=1))
    z = np.concatenate([c, e], axis=1) / scale[:, None, None]
    return np.log(scale), np.concatenate([z.real.reshape(len(z), -1),
                                          z.imag.reshape(len(z), -1)], axis=1)


def choice_complex_band(learner: Learner, xf: np.ndarray, c: np.ndarray, e: np.ndarray,
                        test_x: np.ndarray, modes: int) -> tuple[np.ndarray, np.ndarray]:
    """Complex components over the band out, normalised by the band's RMS centre level."""
    ln_scale, shape = _complex_targets(c, e)
    pca = PCA(min(modes, shape.shape[1], len(shape) - 1)).fit(shape)
    model = learner(xf, np.column_stack([ln_scale, pca.transform(shape)]))
    pred = model(test_x)
    flat = pca.inverse_transform(pred[:, 1:])
    half = flat.shape[1] // 2
    z = (flat[:, :half] + 1j * flat[:, half:]).reshape(len(test_x), -1, 3)
    z *= np.exp(pred[:, :1])[:, :, None]
    n_f = c.shape[1]
    return magnitude(z[:, :n_f]), magnitude(z[:, n_f:])


def score(pred_c: np.ndarray, pred_e: np.ndarray, c: np.ndarray, e: np.ndarray
          ) -> dict[str, float]:
    true_c, true_e = magnitude(c), magnitude(e)
    field = np.maximum(true_c, true_e)
    out = {}
    for name, p, t in (("centre", pred_c, true_c), ("edge", pred_e, true_e)):
        rel = np.abs(p / t - 1.0).ravel()
        out[f"{name}_median"] = float(np.median(rel))
        out[f"{name}_p95"] = float(np.percentile(rel, 95))
        out[f"{name}_p99"] = float(np.percentile(rel, 99))
        out[f"{name}_max"] = float(rel.max())
        out[f"{name}_max_field"] = float(np.max(np.abs(p - t) / field))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True, help="sweep dataset directory")
    ap.add_argument("--test", type=float, default=0.25, help="held-out design fraction")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--modes", type=int, default=24, help="POD modes of the band choices")
    ap.add_argument("--freqs-per-design", type=int, default=1,
                    help="training frequencies per design of the magnitude@f choice")
    ap.add_argument("--learners", default="mlp,gp")
    args = ap.parse_args(argv)
    warnings.filterwarnings("ignore", module="sklearn")
    xf, band, c, e = load(args.data)
    rng = np.random.default_rng(args.seed)
    order = rng.permutation(len(xf))
    n_test = max(1, round(args.test * len(xf)))
    te, tr = order[:n_test], order[n_test:]
    print(f"{len(xf)} designs ({len(tr)} train, {len(te)} test), {band.size} frequencies "
          f"{band[0]:g}-{band[-1]:g} Hz; errors over every test design x frequency")
    learners = {"mlp": mlp(args.seed), "gp": gp(args.seed)}
    header = (f"{'learner':5} {'outputs':22} {'centre med/p95/p99/max %':>28} "
              f"{'edge med/p95/p99/max %':>28} {'max |err|/field %':>18} {'fit s':>6}")
    print(header)
    for lname in args.learners.split(","):
        learner = learners[lname]
        runs = {
            f"magnitude@f x{args.freqs_per_design}": lambda learner=learner: choice_point(
                learner, xf[tr], band, c[tr], e[tr], xf[te], args.freqs_per_design,
                np.random.default_rng(args.seed)),
            "ln-magnitude band": lambda learner=learner: choice_lnmag_band(
                learner, xf[tr], c[tr], e[tr], xf[te], args.modes),
            "complex band": lambda learner=learner: choice_complex_band(
                learner, xf[tr], c[tr], e[tr], xf[te], args.modes),
        }
        for name, run in runs.items():
            t0 = time.perf_counter()
            pc, pe = run()
            s = score(pc, pe, c[te], e[te])
            fmt = "{:.2f}/{:.1f}/{:.1f}/{:.0f}"
            cs = fmt.format(*(100 * s[f"centre_{k}"] for k in ("median", "p95", "p99", "max")))
            es = fmt.format(*(100 * s[f"edge_{k}"] for k in ("median", "p95", "p99", "max")))
            mf = 100 * max(s["centre_max_field"], s["edge_max_field"])
            print(f"{lname:5} {name:22} {cs:>28} {es:>28} {mf:>18.1f} "
                  f"{time.perf_counter() - t0:>6.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
