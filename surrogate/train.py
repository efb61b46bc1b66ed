"""Train a surrogate from one or more datasets, measure it on held-out rows, register it.

    card = train(["datasets/default"], kind="nn", out="models/default-nn")

The kinds (their estimators, exporters and parity tolerances) come from the registry
:mod:`surrogate.kinds`; a kind with a pipeline of its own (``rom``) is handed to it.

Inputs are the free parameters of the datasets' space (:mod:`surrogate.features`), targets
the log center amplitude and the POD coefficients of the log profile
(:mod:`surrogate.pod`), plus one POD block per extra profile output chosen with ``outputs``
(:data:`surrogate.data.columns.PROFILE_OUTPUTS`, e.g. ``profile_normal_um``: the normal
component an LDV sees). A seeded random ``test_fraction`` of the rows is held out; the
metrics in the card are computed on those rows *through the exported ONNX graph and the
run-time encoder*, i.e. for exactly what ships. The exported graph is also checked against
the in-memory estimator (``export_parity`` in the card; training fails above tolerance).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fieldspec import FieldError
from surrogate.data.columns import PROFILE_OUTPUTS
from surrogate.data.store import Store, profile_matrix
from surrogate.features import codes_from_frame, edge_radii_mm, input_specs, merge_specs
from surrogate.intervals import (
    AUTO_CALIBRATION_FRACTION,
    AUTO_CALIBRATION_ROWS,
    Z95,
    calibrate,
    normalised_residual,
    residuals,
)
from surrogate.kind import SurrogateKind, estimator_params
from surrogate.pod import ProfileTargets, output_columns
from surrogate.registry import (
    check_model_out,
    manifest_sha256,
    package_versions,
    write_model,
)
from surrogate.runtime.encoding import InputSpec, encode
from surrogate.runtime.predictor import CALIBRATION_KEY, Predictor, make_session

__all__ = ["TrainingData", "card_head", "check_outputs", "edge_radius_rule", "evaluate",
           "load_datasets", "train"]

PREDICTS = ("Harmonic steady-state vibration amplitude of a haptic unit on the skin surface: "
            "at the center, at the unit's edge, their ratio, and the amplitude-distance "
            "profile outside the edge")


@dataclass
class TrainingData:
    """Rows of one or more datasets, ready to fit. Amplitudes in um, distances in mm."""

    specs: list[InputSpec]
    codes: np.ndarray
    center_um: np.ndarray
    profile_um: np.ndarray
    grid_mm: np.ndarray
    edge_radius_mm: np.ndarray
    sources: list[dict[str, Any]]
    extra_um: dict[str, np.ndarray] = field(default_factory=dict)  # extra profiles by output


def check_outputs(outputs: Sequence[str]) -> tuple[str, ...]:
    """The extra profile outputs of ``outputs`` (names of
    :data:`surrogate.data.columns.PROFILE_OUTPUTS`; ``profile_um`` is always learned), in
    order; a :class:`fieldspec.FieldError` naming ``--outputs`` otherwise."""
    names = [o.strip() for o in outputs if o.strip()]
    bad = [o for o in names if o not in PROFILE_OUTPUTS]
    if bad or len(set(names)) != len(names):
        what = f"{bad[0]!r} is not a profile output" if bad else "a name is given twice"
        raise FieldError("--outputs", f"--outputs {','.join(names)}: {what} (allowed: "
                         f"{', '.join(PROFILE_OUTPUTS)})")
    return tuple(o for o in names if o != "profile_um")


def load_datasets(paths: Sequence[str | Path], *, categorical: str = "onehot",
                  outputs: Sequence[str] = ()) -> TrainingData:
    """Read the "ok" rows of every dataset (all of the same space inputs and profile grid;
    numeric ranges are united), each dataset in its design-sequence order (``sample_index``;
    the order of the stored parts depends on which worker finished first), so the held-out
    split and the first n rows are the same on every machine. ``outputs``: extra profile
    outputs to read too (:func:`check_outputs`); every dataset must store their columns."""
    extra = check_outputs(outputs)
    if not paths:
        raise ValueError("--data: give at least one dataset")
    specs: list[InputSpec] | None = None
    grid: np.ndarray | None = None
    parts, sources = [], []
    for path in paths:
        store = Store.open(path)
        manifest = store.manifest
        if manifest.get("band"):
            raise ValueError(f"--data: {path} is a sweep dataset (one row per design over a "
                             "band); these models train on single-frequency rows (sweeps: "
                             "surrogate.sweep.train, which hapticrom train calls for them)")
        these = input_specs(manifest["space"]["parameter"], categorical=categorical)
        specs = these if specs is None else merge_specs(specs, these, str(path))
        g = np.asarray(manifest.get("profile_grid_mm") or [], dtype=float)
        if grid is None:
            grid = g
        elif g.shape != grid.shape or not np.allclose(g, grid):
            raise ValueError(f"{path}: profile grid differs from the first dataset's")
        df = store.read()
        df = df[df["status"] == "ok"]
        if "sample_index" in df:
            df = df.sort_values("sample_index", kind="stable")
        df = df.reset_index(drop=True)
        if len(df) == 0:
            raise ValueError(f"{path}: no rows with status 'ok'")
        for name in extra:
            column = PROFILE_OUTPUTS[name][0]
            if column not in df.columns or df[column].isna().any():
                raise FieldError("--outputs", f"--outputs {name}: {path} does not store "
                                 f"{column} for every ok row (needed for {name})")
        parts.append(df)
        sources.append({"path": str(path), "manifest_sha256": manifest_sha256(path),
                        "space_hash": manifest.get("space_hash"), "rows": len(df)})
    assert specs is not None and grid is not None
    if grid.size < 2:
        raise ValueError("the datasets have no profile grid (profile_grid_mm)")
    codes = np.concatenate([codes_from_frame(df, specs) for df in parts])
    center = np.concatenate([df["center_amplitude_um"].to_numpy(float) for df in parts])
    profile = np.concatenate([profile_matrix(df, grid) for df in parts])
    radius = np.concatenate([edge_radii_mm(df) for df in parts])
    if np.isnan(profile).any():
        raise ValueError("some rows' profiles do not cover the profile grid")
    extra_um = {name: np.concatenate([profile_matrix(df, grid, PROFILE_OUTPUTS[name][0])
                                      for df in parts]) for name in extra}
    for name, values in extra_um.items():
        if np.isnan(values).any():
            raise ValueError(f"some rows' {PROFILE_OUTPUTS[name][0]} do not cover the "
                             "profile grid")
    return TrainingData(specs, codes, center, profile, grid, radius, sources, extra_um)


def edge_radius_rule(codes: np.ndarray, specs: Sequence[InputSpec],
                     radius_mm: np.ndarray) -> dict[str, Any]:
    """The smallest set of discrete inputs whose value combination determines the edge radius
    exactly, as a lookup table (``method: table``). ValueError when none does (the radius
    then depends on a continuous input, which a table cannot hold)."""
    discrete = [j for j, s in enumerate(specs) if s.type != "continuous"]
    for size in range(len(discrete) + 1):
        for cols in itertools.combinations(discrete, size):
            table: dict[tuple[float, ...], float] = {}
            exact = True
            for key, r in zip(map(tuple, codes[:, list(cols)]), radius_mm, strict=True):
                if abs(table.setdefault(key, r) - r) > 1e-9:
                    exact = False
                    break
            if exact:
                keys = sorted(table)
                return {"method": "table", "inputs": [specs[j].name for j in cols],
                        "keys": [list(k) for k in keys], "values_mm": [table[k] for k in keys]}
    raise ValueError("edge radius is not a function of the discrete inputs alone")


def split(n: int, test_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Seeded (train, test) row indices."""
    if not 0 < test_fraction < 1:
        raise ValueError(f"test_fraction = {test_fraction}: must be in (0, 1)")
    perm = np.random.default_rng(seed).permutation(n)
    n_test = max(1, round(test_fraction * n))
    return np.sort(perm[n_test:]), np.sort(perm[:n_test])


def evaluate(pred: dict[str, np.ndarray], center_um: np.ndarray,
             profile_um: np.ndarray, extra_um: dict[str, np.ndarray] | None = None
             ) -> dict[str, Any]:
    """Held-out metrics: relative errors (median, 95th percentile) of the scalar outputs,
    profile relative L2 error, and coverage of the 95 % interval exp(mu +- 1.96 sigma); for
    each extra profile (``extra_um``: name -> (n, m) truth) the pointwise relative error over
    every row and grid point (median, p95, p99, max), its relative L2 error per row and the
    pointwise coverage."""
    truth = {"center_amplitude_um": center_um, "edge_amplitude_um": profile_um[:, 0],
             "normalized_edge": profile_um[:, 0] / center_um}
    out: dict[str, Any] = {}
    for name, y in truth.items():
        rel = np.abs(pred[name] / y - 1.0)
        z = normalised_residual(y, pred[name], pred[f"{name}_log_std"])
        out[name] = {"median_rel_err": float(np.median(rel)),
                     "p95_rel_err": float(np.percentile(rel, 95)),
                     "coverage95": float(np.mean(z <= Z95))}
    l2 = np.linalg.norm(pred["profile_um"] - profile_um, axis=1) / np.linalg.norm(profile_um,
                                                                                 axis=1)
    out["profile_um"] = {"median_rel_l2": float(np.median(l2)),
                         "p95_rel_l2": float(np.percentile(l2, 95))}
    for name, y in (extra_um or {}).items():
        rel = np.abs(pred[name] / y - 1.0)
        z = normalised_residual(y, pred[name], pred[f"{name}_log_std"])
        l2 = np.linalg.norm(pred[name] - y, axis=1) / np.linalg.norm(y, axis=1)
        out[name] = {"median_rel_err": float(np.median(rel)),
                     "p95_rel_err": float(np.percentile(rel, 95)),
                     "p99_rel_err": float(np.percentile(rel, 99)),
                     "max_rel_err": float(rel.max()),
                     "median_rel_l2": float(np.median(l2)),
                     "p95_rel_l2": float(np.percentile(l2, 95)),
                     "coverage95": float(np.mean(z <= Z95))}
    return out


def card_head(kind: str, dtype: str, specs: Sequence[InputSpec], data: Any,
              extra: Sequence[str]) -> dict[str, Any]:
    """What every steady-state model's card says of its interface, whatever it was trained on:
    kind, what it predicts, its inputs (``specs``), outputs and their graph columns, profile
    grid [mm], edge-radius rule, graph file and the training datasets. ``data``: a
    :class:`TrainingData` or a sweep's data (``grid_mm``, ``codes``, ``specs``,
    ``edge_radius_mm``, ``sources``)."""
    return {
        "kind": kind, "predicts": PREDICTS + "".join(
            f"; {name}: {PROFILE_OUTPUTS[name][1]}" for name in extra),
        "inputs": [s.to_dict() for s in specs],
        "outputs": [{"name": "center_amplitude_um", "unit": "um"},
                    {"name": "edge_amplitude_um", "unit": "um"},
                    {"name": "normalized_edge", "unit": ""},
                    {"name": "profile_um", "unit": "um", "grid": "profile_distance_mm"},
                    *({"name": name, "unit": "um", "grid": "profile_distance_mm"}
                      for name in extra),
                    {"name": "edge_radius_mm", "unit": "mm"}],
        "log_output_columns": output_columns(data.grid_mm.size, extra),
        "profile_distance_mm": data.grid_mm.tolist(),
        "edge_radius": edge_radius_rule(data.codes, data.specs, data.edge_radius_mm),
        "graph": {"file": "model.onnx", "dtype": dtype,
                  "input": "x", "outputs": ["log_mean", "log_std"]},
        "training_data": data.sources,
    }

def train(paths: Sequence[str | Path], kind: str, out: str | Path, *,
          test_fraction: float = 0.2, seed: int = 0, n_modes: int | None = None,
          overwrite: bool = False, categorical: str = "onehot",
          options: dict[str, Any] | None = None,
          outputs: Sequence[str] = ("profile_um",),
          calibration_fraction: float | None = None) -> dict[str, Any]:
    """Train a ``kind`` model (a name of :data:`surrogate.kinds.KINDS`) on ``paths``, write
    ``out``; return its card. ``outputs``: the profile outputs to learn
    (:data:`surrogate.data.columns.PROFILE_OUTPUTS`; ``profile_um`` always).
    ``calibration_fraction`` > 0 keeps that share of the training rows out of the fit and
    scales the model's log-std on them so that its 95 % intervals cover 95 %
    (:mod:`surrogate.intervals`; the card's ``interval_calibration``); the held-out metrics are
    then those of the calibrated intervals. None (the default): 0.1 when that is at least
    :data:`AUTO_CALIBRATION_ROWS` rows, else no calibration; 0: none."""
    # Lazy: the registry loads torch and scikit-learn (about 5 s); what else this
    # module offers (load_datasets, evaluate, edge_radius_rule: refine, the studies) needs none.
    from surrogate.kinds import get as get_kind

    spec = get_kind(kind)
    extra = check_outputs(outputs)
    if spec.trainer is not None:
        if extra:
            raise FieldError("--outputs", f"--outputs {','.join(extra)}: the {kind} kind "
                             "learns its own outputs (profile outputs are for steady-state "
                             "kinds)")
        return spec.trainer(paths, out, seed=seed, overwrite=overwrite,
                            options=dict(options or {}))
    check_model_out(out, overwrite)  # before the work: the output may not be replaced
    data = load_datasets(paths, categorical=categorical, outputs=extra)
    tr, te = split(len(data.codes), test_fraction, seed)
    tr, cal = _calibration_rows(tr, calibration_fraction, seed)
    X = encode(data.codes, data.specs)
    if n_modes is None and spec.pod_modes is not None:
        n_modes = min(spec.pod_modes, data.grid_mm.size)
    targets = ProfileTargets(n_modes=n_modes, extra=extra)
    T = targets.fit_transform(data.center_um[tr], data.profile_um[tr],
                              [data.extra_um[name][tr] for name in extra])
    B, b = targets.output_map()
    est = spec.fit(X[tr], T, seed, dict(options or {}))
    card: dict[str, Any] = {
        **card_head(kind, spec.dtype, data.specs, data, extra),
        "training": {"rows": int(tr.size), "held_out": int(te.size), "seed": seed,
                     "test_fraction": test_fraction, "pod_modes": int(targets.pod.modes_.shape[0]),
                     "pod_energy": float(targets.pod.energy_[-1]),
                     **({"profile_outputs": {
                         name: {"column": PROFILE_OUTPUTS[name][0],
                                "pod_modes": int(pod.modes_.shape[0]),
                                "pod_energy": float(pod.energy_[-1])}
                         for name, pod in targets.pods.items()}} if extra else {}),
                     "estimator": estimator_params(est)},
        "versions": package_versions()}
    meta = {k: card[k] for k in ("kind", "inputs", "outputs", "profile_distance_mm",
                                 "training_data")}
    assert spec.export is not None
    onnx_bytes = spec.export(est, B, b, meta)
    predictor = Predictor({**card, "files": {}}, make_session(onnx_bytes))
    card["export_parity_max_abs_dln"] = _parity(spec, est, predictor, X[te], B, b)
    if cal.size:
        entry = calibrate(residuals(predictor.predict(data.codes[cal]), data.center_um[cal],
                                    data.profile_um[cal],
                                    {name: data.extra_um[name][cal] for name in extra}),
                          extra=extra)
        entry["rows"] = {"from": "training rows kept out of the fit (seed + 1)",
                         "calibration": int(cal.size)}
        card[CALIBRATION_KEY] = entry
        card["training"]["calibration_rows"] = int(cal.size)
        predictor = Predictor({**card, "files": {}}, predictor.session)
    card["metrics"] = evaluate(predictor.predict(data.codes[te]), data.center_um[te],
                               data.profile_um[te],
                               {name: data.extra_um[name][te] for name in extra})
    card["training"].update(spec.card_extras(est))
    write_model(out, card, {"model.onnx": onnx_bytes}, overwrite=overwrite)
    return card


def _calibration_rows(tr: np.ndarray, fraction: float | None, seed: int
                      ) -> tuple[np.ndarray, np.ndarray]:
    """(fitted rows, calibration rows): a seeded ``fraction`` of the training rows kept out."""
    if fraction is None:
        fraction = AUTO_CALIBRATION_FRACTION
        if round(fraction * tr.size) < AUTO_CALIBRATION_ROWS:
            return tr, tr[:0]
    if fraction == 0:
        return tr, tr[:0]
    if not 0 < fraction < 1:
        raise ValueError(f"calibration_fraction = {fraction}: must be in [0, 1)")
    n = round(fraction * tr.size)
    if n < 20:
        raise ValueError(f"calibration_fraction = {fraction}: {n} calibration rows of "
                         f"{tr.size}; a 95 % factor needs at least 20")
    perm = np.random.default_rng(seed + 1).permutation(tr)
    return np.sort(perm[n:]), np.sort(perm[:n])


def _parity(kind: SurrogateKind, est: Any, predictor: Predictor, X: np.ndarray, B: np.ndarray,
            b: np.ndarray) -> float:
    """Largest |d ln| between the graph and the estimator (mean and std); raises above the
    tolerance, so a wrong export never reaches the registry."""
    mean, std = est.predict(X, return_std=True)
    ref_mean = mean @ B + b
    ref_std = np.sqrt((std**2) @ B**2) if kind.std_parity else None
    got_mean, got_std = predictor.session.run(
        ["log_mean", "log_std"], {"x": X.astype(predictor._dtype)})
    worst = float(np.abs(got_mean - ref_mean).max())
    if ref_std is not None:
        worst = max(worst, float(np.abs(got_std - ref_std).max()))
    if not worst <= kind.parity_tol:
        raise RuntimeError(f"exported {kind.name} graph differs from the estimator by "
                           f"{worst:.3g} in log amplitude (tolerance {kind.parity_tol})")
    return worst
