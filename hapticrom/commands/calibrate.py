"""``hapticrom calibrate MEASUREMENT.csv``: fit tissue inputs of a surrogate to a measurement.

    hapticrom calibrate examples/measurement-forearm.csv --model models/nn-default \\
        --fit skin_E_kPa,fat_thickness_mm,tissue_loss_factor --out out/cal.json \\
        --plot out/cal.png [--verify]
    hapticrom calibrate examples/measurement-forearm-ldv.csv \\
        --fit skin_E_kPa,fat_thickness_mm,tissue_loss_factor     # picks the normal model

Without ``--model`` the model is chosen by what the measurement sees
(:mod:`surrogate.runtime.defaults`): the default ``normal`` model (one that predicts the
normal component |u_z| an LDV measures, besides the magnitude: ``nn-sweep`` when installed and
trained with ``profile_normal_um``, else ``nn-normal``) when any row's component is
``normal``, else the default ``harmonic`` model (``nn-sweep``, else ``nn-default``). A model
that lacks an output a row needs is refused naming the row, the component and the model (exit 2).

Bayesian: priors from the model's ranges (``--prior NAME=KIND:A,B`` to give one), a likelihood
from the stated uncertainty and the surrogate's own predictive spread, emcee's ensemble sampler
(docs/calibration.md). Prints posterior means, 95 % intervals, correlations and which inputs the
data cannot determine; writes the versioned document (``--out``, usable as
``hapticrom plan LAYOUT --tissue``) and the figure (``--plot``). ``--verify`` re-solves the
posterior mean with the FE solver (the scene the model's training dataset builds) at every
measured frequency and compares it with the measurement and the surrogate.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from hapticrom.commands._args import number_in, positive_int
from hapticrom.outputs import atomic_path, check_output_file

__all__ = ["register"]



def _sets(items: list[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ValueError(f"--set {item!r}: expected NAME=VALUE")
        text = value.strip()
        try:
            out[name.strip()] = float(text) if "." in text or "e" in text.lower() else int(text)
        except ValueError:
            out[name.strip()] = text
    return out


def _seed(text: str) -> int:
    """A random seed: an integer in [0, 2^32)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if not 0 <= value < 2**32:
        raise argparse.ArgumentTypeError(f"{value} is not in [0, 2^32)")
    return value


def _model(args: argparse.Namespace, measurement: Any) -> str:
    """``--model``, or the model the measurement needs (printed with the reason)."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from calibration.forward import needs_normal
    from surrogate.runtime.defaults import default_model
    from surrogate.runtime.models import find_model

    if args.model is not None:
        return str(find_model(args.model))  # a directory, or a name of hapticrom models list
    normal = needs_normal(measurement)
    path = default_model("normal" if normal else "harmonic")
    print(f"model {Path(path).name} ({path}): " + ("the measurement has normal-component rows"
                                                   if normal else
                                                   "the measurement sees magnitudes"))
    return path


def _run(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from calibration import calibrate, calibration_document, read_measurement
    from surrogate.runtime import load_predictor

    for opt in ("out", "plot"):
        if getattr(args, opt):
            check_output_file(f"--{opt}", getattr(args, opt), args.overwrite)
    measurement = read_measurement(args.measurement)
    args.model = _model(args, measurement)
    predictor = load_predictor(args.model)
    fit = [n.strip() for n in args.fit.split(",") if n.strip()]
    sets = _sets(args.set)
    cal = calibrate(predictor, measurement, fit, priors=args.prior, fixed=sets,
                    walkers=args.walkers, steps=args.steps, burn=args.steps // 3,
                    seed=args.seed, std_factor=args.std_factor)
    tissue = [*fit, *measurement.site, *(k for k in sets if k not in measurement.design)]
    doc = calibration_document(cal, model_path=args.model, tissue_names=tissue, seed=args.seed,
                               interval=args.interval)
    _print(doc, len(measurement.points))
    if args.verify:
        doc["verify"] = _verify(cal, args.model)
        _print_verify(doc["verify"])
    if args.out:
        with atomic_path(args.out) as tmp:
            tmp.write_text(json.dumps(doc, indent=1) + "\n")
        print(f"wrote {args.out}")
    if args.plot:
        # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
        from calibration.plot import write_calibration_plot

        with atomic_path(args.plot) as tmp:
            write_calibration_plot(cal, tmp, seed=args.seed, interval=args.interval)
        print(f"wrote {args.plot}")
    return 0


def _error_text(likelihood: dict[str, Any]) -> str:
    """The surrogate's error model per output read, for the printout."""
    own = {"model card": " (the model's own)", "SURROGATE_ERROR_T": " (generic)"}
    return ", ".join((f"{o} Student-t nu {e['nu']:g} x{e['scale']:g}" if e["nu"] is not None
                      else f"{o} Gaussian x{e['scale']:g}") + own.get(e.get("source"), "")
                     for o, e in likelihood["surrogate_error"].items())


def _print(doc: dict[str, Any], n_points: int) -> None:
    s = doc["sampler"]
    n_f = len({p["frequency_hz"] for p in doc["measurement"]["points"]})
    print(f"{n_points} measured points at {n_f} frequencies, model {doc['model']['name']} "
          f"(surrogate error {_error_text(doc['likelihood'])}); emcee "
          f"{s['walkers']} walkers x "
          f"{s['steps']} steps, acceptance {s['acceptance_fraction']:.2f}, autocorrelation "
          f"{max(s['autocorr_steps']):.0f} steps, {s['wall_s']:.1f} s")
    kind = next(iter(doc["posterior"].values()))["interval_kind"]
    print(f"  {'input':22s} {'mean':>9s} {'95 % ' + kind.replace('_', '-'):>22s} "
          f"{'prior 95 %':>22s} "
          f"{'width':>6s}")
    for name, p in doc["posterior"].items():
        unit = f" {p['unit']}" if p["unit"] else ""
        flag = "" if p["identifiable"] else "  not determined"
        print(f"  {name:22s} {p['mean']:9.4g} [{p['ci95'][0]:9.4g}, {p['ci95'][1]:9.4g}] "
              f"[{p['prior_ci95'][0]:9.4g}, {p['prior_ci95'][1]:9.4g}] "
              f"{p['width_ratio']:6.2f}{unit}{flag}")
    corr = doc["correlation"]
    if len(corr["names"]) > 1:
        print("  posterior correlation: " + "; ".join(
            f"{a} / {b} {corr['matrix'][i][j]:+.2f}" for i, a in enumerate(corr["names"])
            for j, b in enumerate(corr["names"]) if j > i))
    print(f"  {doc['statement']}")
    print(f"  fit: chi^2 per point {doc['fit_quality']['chi2_per_point']:.2f} at the posterior "
          "mean (about 1: the stated uncertainties and the surrogate's spread explain the "
          "residuals)")
    print("  tissue: " + ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
                                   for k, v in doc["tissue"].items()))


def _dataset_path(model: str) -> Path:
    """The model's training dataset (its space builds the FE scene), relative to the working
    directory or to the repository holding ``models/NAME``."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.runtime.card import read_card

    rel = Path(read_card(model)["training_data"][0]["path"])
    for base in (Path.cwd(), Path(model).resolve().parents[1]):
        if (base / rel).is_dir():
            return base / rel
    raise FileNotFoundError(f"--verify: the model's training dataset {str(rel)!r} was not "
                            "found (its parameter space builds the FE scene)")


def _verify(cal: Any, model: str) -> dict[str, Any]:
    """FE solve at the posterior mean for every measured frequency; FE, surrogate and measured
    amplitude at each point."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from fem import simulate
    from fem.results import magnitude
    from fem.scene import scene_from_dict
    from surrogate.data.store import Store

    space = Store.open(_dataset_path(model)).space
    inputs = {**cal.forward.fixed, **cal.mean_inputs()}
    mean, _ = cal.forward.predict(np.array([[inputs[n] for n in cal.names]]))
    t0, fe = time.perf_counter(), {}
    for f in cal.measurement.frequencies_hz:
        res = simulate(scene_from_dict(space.resolve_at({**space.center(), **inputs}, f)))
        fe[f] = res
    points = []
    for k, p in enumerate(cal.measurement.points):
        res = fe[p.frequency_hz]
        pick = (lambda u: magnitude(u)) if p.component == "magnitude" else (
            lambda u: np.abs(u[..., 1]))  # components r, z, t: the normal one is z
        if p.reference == "centre" and p.distance_m == 0.0:
            amp = float(pick(res.center))
        else:
            d_mm = p.distance_m * 1e3 - (res.edge_mm if p.reference == "centre" else 0.0)
            amp = float(np.exp(np.interp(d_mm, res.profile_mm, np.log(pick(res.profile)))))
        points.append({"row": p.row, "measured_um": round(p.amplitude_m * 1e6, 5),
                       "surrogate_um": round(float(np.exp(mean[0, k])) * 1e6, 5),
                       "fe_um": round(amp * 1e6, 5)})
    fe_um = np.array([q["fe_um"] for q in points])
    sur = np.array([q["surrogate_um"] for q in points])
    meas = np.array([q["measured_um"] for q in points])
    rel = cal.forward.rel_sigma
    return {"inputs": {k: (round(v, 6) if isinstance(v, float) else v)
                       for k, v in inputs.items()},
            "points": points,
            "median_abs_log_surrogate_vs_fe": round(float(np.median(np.abs(np.log(sur / fe_um)))),
                                                    5),
            "chi2_per_point_fe": round(float(np.mean((np.log(meas / fe_um) / rel) ** 2)), 4),
            "dofs": int(next(iter(fe.values())).meta["dofs"]),
            "wall_s": round(time.perf_counter() - t0, 2)}


def _print_verify(v: dict[str, Any]) -> None:
    print(f"verify (FE at the posterior mean, {v['dofs']} dofs, {v['wall_s']:.1f} s): "
          f"median |ln(surrogate / FE)| {v['median_abs_log_surrogate_vs_fe']:.3f}; "
          f"chi^2 per point of the measurement against FE (stated uncertainty only) "
          f"{v['chi2_per_point_fe']:.2f}")
    for q in v["points"]:
        print(f"  row {q['row']:3d}  measured {q['measured_um']:8.4f} um  surrogate "
              f"{q['surrogate_um']:8.4f} um  FE {q['fe_um']:8.4f} um")


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``calibrate`` subcommand."""
    p = subparsers.add_parser("calibrate", help="fit tissue inputs of a surrogate to a "
                              "measured vibration (Bayesian, with uncertainty)")
    p.add_argument("measurement", help="measurement CSV (docs/calibration.md)")
    p.add_argument("--model", default=None, help="model directory or name (default: the "
                   "default normal-component model when the measurement has normal-component "
                   "rows, else the default harmonic model: nn-sweep when installed, else "
                   "nn-normal / nn-default; surrogate.runtime.defaults)")
    p.add_argument("--fit", required=True, metavar="NAMES",
                   help="comma-separated model inputs to fit, e.g. "
                   "skin_E_kPa,fat_thickness_mm,tissue_loss_factor")
    p.add_argument("--prior", action="append", default=[], metavar="NAME=KIND:A,B",
                   help="a prior of one fitted input: uniform:LOW,HIGH, loguniform:LOW,HIGH or "
                   "normal:MEAN,SD (default: uniform over the model's range, log-uniform for "
                   "log-scale inputs)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a model input held fixed (overrides the file's design./site. lines)")
    p.add_argument("--walkers", type=positive_int, default=32, help="emcee walkers (32)")
    p.add_argument("--steps", type=positive_int, default=1000,
                   help="steps per walker (1000; the first third is burn-in)")
    p.add_argument("--seed", type=_seed, default=0,
                   help="random seed, an integer in [0, 2^32) (0)")
    p.add_argument("--std-factor", type=number_in(0.0, 100.0), default=None, metavar="K",
                   help="a Gaussian surrogate error, its predictive log-std widened by K, "
                   "instead of the Student-t fitted to the model's held-out rows "
                   "(docs/calibration.md)")
    p.add_argument("--interval", choices=("hdi", "equal_tailed"), default="hdi",
                   help="the reported 95 %% interval, on which 'determined' is decided: the "
                   "highest posterior density (hdi, default) or the 2.5-97.5 percentiles; the "
                   "document holds both")
    p.add_argument("--out", metavar="JSON", help="write the calibration document")
    p.add_argument("--plot", metavar="PNG", help="write the figure")
    p.add_argument("--verify", action="store_true",
                   help="re-solve the posterior mean with the FE solver and compare")
    p.add_argument("--overwrite", action="store_true",
                   help="replace existing output files even if hapticrom did not write them")
    p.set_defaults(func=_run)
