"""The calibration proven on synthetic subjects: coverage, error and run time (issue 25, item 4).

    .venv/bin/python bench/calibration/calibrate.py [--subjects 50] [--sensors magnitude,normal]

Each of the FE subjects cached in bench/calibration/data/calibration-subjects.json (known tissue
drawn across the model's range, one of the paper's three prototypes, 1-3 frequencies; made by
bench/calibration/subjects.py) is measured with each sensor kind -- ``magnitude`` (a 3-axis
sensor: the displacement magnitude, at the unit's face or not) and ``normal`` (an LDV: the
normal component |u_z|, on the skin around the unit only) -- each at 5 % and at 10 % noise,
with a layout of 5-10 points (distances from the edge on the 1 mm grid) at each of its
frequencies, then calibrated for skin_E_kPa, fat_thickness_mm and tissue_loss_factor with the
defaults of ``hapticrom calibrate`` on nn-default (magnitude) and nn-normal (normal component),
the models calibrate picked when the study was first run, or on ``--model`` (the shipped sweep
defaults: ``--sensors magnitude --model models/nn-sweep`` and ``--sensors normal --model
models/nn-sweep-normal``, docs/calibration.md). Printed per sensor kind and input: how often
the 95 % interval holds the true value (all calibrations, and those where the input is reported as
determined), how often it is determined, the median absolute error of the posterior mean, and
the run time per calibration. Everything is seeded.
"""

from __future__ import annotations

import argparse
import json
import shlex
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from error_model import (
    SWEEP_DESIGNS_FILE,
    error_check,
    error_t_entry,
    fit_surrogate_error,
    fit_sweep_error,
    select_outputs,
    write_error_t,
)

from calibration import calibrate, surrogate_std_factor
from calibration.fit import ERROR_FREQUENCY_HZ, ERROR_LENGTH_MM, ERROR_MODELS, SPREADS
from calibration.forward import ForwardModel
from calibration.synthetic import synthetic_measurement
from surrogate.runtime import load_predictor

ROOT = Path(__file__).resolve().parents[2]
CACHE = ROOT / "bench" / "calibration" / "data" / "calibration-subjects.json"
#: sensor kind (the component it sees) -> the model the study runs without --model (the
#: single-frequency ones calibrate picked when it was first run; it now picks the sweep models)
MODELS = {"magnitude": ROOT / "models" / "nn-default", "normal": ROOT / "models" / "nn-normal"}
#: other FE subjects (bench/calibration/subjects.py --n 30 --seed 7 --out THIS): the surrogate's
#: error structure is measured on these, not on the study's subjects
RESIDUAL_CACHE = ROOT / "bench" / "calibration" / "data" / "calibration-residual-subjects.json"
FIT = ("skin_E_kPa", "fat_thickness_mm", "tissue_loss_factor")
NOISES = (0.05, 0.10)


def run(subjects: list[dict], predictor, *, component: str = "magnitude",
        steps: int = 1000, std_factor: float | None = None, quiet: bool = False,
        **likelihood: Any) -> list[dict]:
    """One record per (subject, noise) for a sensor that sees ``component``: truth, posterior
    summary, run time."""
    records = []
    for s in subjects:
        for noise in NOISES:
            rng = np.random.default_rng(1000 * int(s["id"]) + round(100 * noise))
            m = synthetic_measurement(s, rel_noise=noise, n_points=int(rng.integers(5, 11)),
                                      rng=rng, component=component,
                                      sensor="ldv" if component == "normal" else None)
            t0, c0 = time.perf_counter(), time.process_time()
            cal = calibrate(predictor, m, FIT, steps=steps, burn=steps // 3, seed=int(s["id"]),
                            std_factor=std_factor, **likelihood)
            summary = cal.summary()
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            records.append({"id": s["id"], "sensor": component, "noise": noise,
                            "points": len(m.points), "truth": s["truth"], "summary": summary,
                            "wall_s": wall, "cpu_s": cpu})
            if not quiet:
                inside = "".join("y" if sm["ci95"][0] <= s["truth"][n] <= sm["ci95"][1] else "n"
                                 for n, sm in summary.items())
                print(f"  subject {s['id']:3d} {component:9s} noise {noise:.0%} "
                      f"{len(m.points):3d} points inside {inside} {wall:5.1f} s", flush=True)
    return records


def table(records: list[dict], interval: str = "ci95") -> list[str]:
    """The summary lines per sensor kind, fitted input and noise level (and over all);
    coverage by the records' ``interval`` (``ci95``, the reported one; ``ci95_hdi`` or
    ``ci95_equal_tailed``); "determined" is always the reported interval's."""
    lines = [f"{'sensor':9s} {'input':20s} {'noise':>5s} {'n':>4s} {'coverage':>9s} "
             f"{'determined':>10s} {'cov. det.':>14s} {'med |err|':>10s} "
             f"{'med |err|/range':>15s}"]
    ranges = {"skin_E_kPa": 100.0, "fat_thickness_mm": 17.0, "tissue_loss_factor": 0.4}
    sensors = sorted({r.get("sensor", "magnitude") for r in records})
    groups = [(s, n) for s in sensors for n in (*NOISES, None)]
    if len(sensors) > 1:
        groups.append(("all", None))
    for name in FIT:
        for sensor, noise in groups:
            rs = [r for r in records if (noise is None or r["noise"] == noise)
                  and sensor in ("all", r.get("sensor", "magnitude"))]
            inside = [r["summary"][name][interval][0] <= r["truth"][name]
                      <= r["summary"][name][interval][1] for r in rs]
            det = [r["summary"][name]["identifiable"] for r in rs]
            cov_det = [i for i, d in zip(inside, det, strict=True) if d]
            err = [abs(r["summary"][name]["mean"] - r["truth"][name]) for r in rs]
            label = "all" if noise is None else f"{noise:.0%}"
            cd = (f"{np.mean(cov_det):.1%} ({sum(cov_det)}/{len(cov_det)})" if cov_det
                  else "-")
            lines.append(f"{sensor:9s} {name:20s} {label:>5s} {len(rs):4d} "
                         f"{np.mean(inside):9.1%} {np.mean(det):10.1%} {cd:>14s} "
                         f"{statistics.median(err):10.4g} "
                         f"{statistics.median(err) / ranges[name]:15.1%}")
    walls = [r["wall_s"] for r in records]
    lines.append(f"run time per calibration: median {statistics.median(walls):.1f} s, max "
                 f"{max(walls):.1f} s ({len(records)} calibrations)")
    cpus = [r["cpu_s"] for r in records if "cpu_s" in r]  # records before it lack it
    if cpus:  # the process's CPU time: what the run takes on an unloaded machine
        lines.append(f"CPU time per calibration: median {statistics.median(cpus):.1f} s, max "
                     f"{max(cpus):.1f} s ({len(cpus)} calibrations)")
    return lines


def residuals(subjects: list[dict], predictor, component: str = "magnitude") -> list[str]:
    """The surrogate's error against FE at the true inputs: its size in units of the predictive
    log-std (the factor k the likelihood needs), and its correlation along the profile and
    across frequencies, each fitted with an exponential (calibration.fit's ERROR_* values)."""
    res, z, freq, subj = [], [], [], []
    for s in subjects:
        for i, f in enumerate(s["frequencies_hz"]):
            X = {k: np.array([v]) for k, v in {**s["design"], **s["truth"]}.items()}
            X["frequency_hz"] = np.array([f])
            o = predictor.predict(X)
            if component == "magnitude":
                fe = np.r_[s["centre_um"]["magnitude"][i], s["profile_um"]["magnitude"][i]]
                sur = np.r_[o["center_amplitude_um"][0], o["profile_um"][0]]
                sd = np.r_[o["center_amplitude_um_log_std"][0], o["profile_um_log_std"][0]]
            else:  # no normal output at the face: its column repeats the magnitude's
                fe = np.r_[s["centre_um"]["magnitude"][i], s["profile_um"]["normal"][i]]
                sur = np.r_[o["center_amplitude_um"][0], o["profile_normal_um"][0]]
                sd = np.r_[o["center_amplitude_um_log_std"][0], o["profile_normal_um_log_std"][0]]
            res.append(np.log(fe / sur))
            z.append(np.log(fe / sur) / sd)
            freq.append(f)
            subj.append(s["id"])
    R, Z = np.array(res), np.array(z)
    grid = np.asarray(subjects[0]["profile_distance_mm"])
    C = np.corrcoef(R[:, 1:].T)
    lags = np.arange(1, 11)
    rho_d = np.array([np.mean(np.diagonal(C, offset=int(lag))) for lag in lags])
    length = -1.0 / np.polyfit(lags * (grid[1] - grid[0]), np.log(np.clip(rho_d, 1e-3, 1)),
                               1)[0]
    pairs = [(R[a, 1:], R[b, 1:], abs(freq[a] - freq[b])) for a in range(len(R))
             for b in range(a + 1, len(R)) if subj[a] == subj[b]]
    df = np.array([p[2] for p in pairs])
    rho_f = np.array([np.corrcoef(p[0], p[1])[0, 1] for p in pairs])
    fit_f = -1.0 / np.polyfit(np.r_[0.0, df], np.log(np.clip(np.r_[1.0, rho_f], 1e-2, 1)),
                              1)[0] if pairs else float("nan")
    k = float(np.sqrt(np.mean(Z ** 2)))
    return [f"surrogate error at the true inputs, {len(R)} FE solves of {len(subjects)} subjects:",
            f"  rms ln(FE/surrogate) {np.sqrt(np.mean(R ** 2)):.3f}; rms in units of its "
            f"log-std {k:.2f} (card-based factor {surrogate_std_factor(predictor.card):.2f})",
            f"  profile points: within 1.96 log-std {np.mean(np.abs(Z[:, 1:]) <= 1.96):.1%}, "
            f"median |z| {np.median(np.abs(Z[:, 1:])) / 0.6745:.2f} of a unit Gaussian's, "
            f"99th percentile |z| {np.percentile(np.abs(Z[:, 1:]), 99):.1f}",
            "  correlation along the profile at lags 1-10 mm: "
            + " ".join(f"{r:.2f}" for r in rho_d) + f" -> length {length:.1f} mm",
            f"  correlation between frequencies of one subject ({len(pairs)} pairs, "
            f"|df| {df.min() if pairs else 0:g}-{df.max() if pairs else 0:g} Hz) -> scale "
            f"{fit_f:.0f} Hz",
            "  centre vs profile correlation "
            + f"{np.mean(np.corrcoef(R.T)[0, 1:]):.2f} (mean over the profile)"]


def spread_swing(subjects: list[dict], predictor, ids: tuple[int, ...] = (0, 5)) -> list[str]:
    """How much the surrogate's spread, evaluated at each theta, moves the likelihood's
    normalising term -1/2 ln det(cov) along the fat thickness (3-20 mm, the true skin and loss)
    for the study's measurements of subjects ``ids`` at 5 % noise (the first version's
    implicit prior, docs/calibration.md)."""
    k = surrogate_std_factor(predictor.card)
    lines = []
    for s in (x for x in subjects if x["id"] in ids):
        rng = np.random.default_rng(1000 * int(s["id"]) + 5)
        m = synthetic_measurement(s, rel_noise=0.05, n_points=int(rng.integers(5, 11)), rng=rng)
        fwd = ForwardModel(predictor, m, FIT, s["design"])
        corr = fwd.error_correlation({o: ERROR_LENGTH_MM[o] for o in fwd.profile_outputs},
                                     ERROR_FREQUENCY_HZ)
        theta = np.array([[s["truth"]["skin_E_kPa"], f, s["truth"]["tissue_loss_factor"]]
                          for f in np.linspace(3.0, 20.0, 35)])
        _, sd = fwd.predict(theta)
        term = [-0.5 * np.linalg.slogdet((k * r)[:, None] * corr * (k * r)[None, :]
                                         + np.diag(fwd.rel_sigma ** 2))[1] for r in sd]
        sum_ln = np.log(sd).sum(axis=1)
        lines.append(f"subject {s['id']} ({len(m.points)} points): along fat 3-20 mm, sum ln s "
                     f"moves by {np.ptp(sum_ln):.1f}, -1/2 ln det(cov) by {np.ptp(term):.1f} "
                     "nats")
    return lines


def misses(records: list[dict], predictors: dict, name: str = "fat_thickness_mm",
           edge: float = 1.0) -> list[str]:
    """Why a determined input's interval misses, per sensor kind: the misses (subject, noise,
    true value), the coverage when determined of truths farther than ``edge`` from the prior's
    bounds, and the rms over the measured points of the residual at the true inputs in units
    of its likelihood standard deviation (median over covered and over missed cases)."""
    subjects = {s["id"]: s for s in json.loads(CACHE.read_text())["subjects"]}
    lines = []
    for sensor, predictor in predictors.items():
        k = surrogate_std_factor(predictor.card)
        lo, hi = predictor.input_ranges[name]
        rms: dict[bool, list[float]] = {True: [], False: []}
        interior, missed = [], []
        for r in (x for x in records if x.get("sensor", "magnitude") == sensor):
            sm, truth = r["summary"][name], r["truth"][name]
            if not sm["identifiable"]:
                continue
            inside = sm["ci95"][0] <= truth <= sm["ci95"][1]
            s = subjects[r["id"]]
            rng = np.random.default_rng(1000 * int(s["id"]) + round(100 * r["noise"]))
            m = synthetic_measurement(s, rel_noise=r["noise"], n_points=int(rng.integers(5, 11)),
                                      rng=rng, component=sensor,
                                      sensor="ldv" if sensor == "normal" else None)
            fwd = ForwardModel(predictor, m, FIT, s["design"])
            mean, sd = fwd.predict(np.array([[s["truth"][n] for n in FIT]]))
            z = (fwd.y - mean[0]) / np.sqrt((k * sd[0]) ** 2 + fwd.rel_sigma ** 2)
            rms[inside].append(float(np.sqrt(np.mean(z ** 2))))
            if min(truth - lo, hi - truth) > edge:
                interior.append(inside)
            if not inside:
                missed.append(f"{s['id']} at {r['noise']:.0%} ({truth:.2f})")
        lines += [f"{sensor} ({predictor.card.get('name')}), {name} when determined: missed "
                  f"{', '.join(missed) or 'none'}",
                  f"  truth farther than {edge:g} from the bounds [{lo:g}, {hi:g}]: covered "
                  f"{sum(interior)} of {len(interior)}",
                  "  rms normalised residual at the truth, median: covered "
                  f"{np.median(rms[True]) if rms[True] else float('nan'):.2f}, missed "
                  f"{np.median(rms[False]) if rms[False] else float('nan'):.2f}"]
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=50, help="first N cached subjects")
    ap.add_argument("--sensors", default="magnitude,normal",
                    help="sensor kinds, comma-separated: magnitude (3-axis, model nn-default), "
                    "normal (LDV, model nn-normal)")
    ap.add_argument("--model", default=None, help="one model for every sensor kind (default: "
                    "nn-default for magnitude, nn-normal for normal)")
    ap.add_argument("--spread", default="posterior", choices=SPREADS,
                    help="how the surrogate's spread enters the likelihood (calibration.fit)")
    ap.add_argument("--error-model", default="t", choices=ERROR_MODELS,
                    help="the surrogate's error: Student-t (the model card's "
                    "calibration_error_t, else SURROGATE_ERROR_T) or the Gaussian with the "
                    "card's factor (calibration.fit)")
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--std-factor", type=float, default=None)
    ap.add_argument("--error-length-mm", type=float, default=None,
                    help="one correlation length of the surrogate's error along every profile "
                    f"output (default per output: {ERROR_LENGTH_MM}; tiny: independent "
                    "errors)")
    ap.add_argument("--error-frequency-hz", type=float, default=ERROR_FREQUENCY_HZ)
    ap.add_argument("--json", type=Path, help="write the records")
    ap.add_argument("--residuals", action="store_true",
                    help="only measure the surrogate's error structure on the residual subjects")
    ap.add_argument("--surrogate-error", action="store_true",
                    help="only fit the Student-t of the surrogate's error (nu, scale) to its "
                    "held-out rows, per output the sensor kind reads")
    ap.add_argument("--sweep-error", action="store_true",
                    help="only measure the surrogate's error across frequency on the sweep "
                    "dataset (scale per frequency, shared mixing variable, frequency length)")
    ap.add_argument("--sweep", type=Path,
                    help="with --sweep-error: a dataset of datasets/spaces/default-sweep.toml "
                    "(hapticrom generate --space datasets/spaces/default-sweep.toml --n 8192 "
                    "--out DIR) holding the designs of --sweep-designs; not one the model "
                    "trained on (refused)")
    ap.add_argument("--sweep-designs", default=str(SWEEP_DESIGNS_FILE), metavar="FILE|all",
                    help="with --sweep-error: the designs of --sweep to use, a file of "
                    "sample_index values (default: the 1,600 the error model was measured on) or "
                    "'all' (e.g. datasets/default-sweep-test for a model trained on sweeps)")
    ap.add_argument("--sweep-max-mm", type=float, default=None,
                    help="with --sweep-error: only the profile points up to this distance from "
                    "the edge [mm] (default: to the end of the model's profile)")
    ap.add_argument("--write-card", action="store_true",
                    help="with --sweep-error and --model: write what was measured into that "
                    "model's card as its calibration_error_t (the t calibrate applies to it; "
                    "replaces an earlier one; measure every output wanted in one run, e.g. "
                    "--sensors magnitude,normal), re-sealed and replaced atomically")
    ap.add_argument("--write-outputs", default=None, metavar="NAMES",
                    help="with --write-card: only these measured outputs, comma-separated "
                    "(default: every output measured); the others keep SURROGATE_ERROR_T")
    ap.add_argument("--error-check", action="store_true",
                    help="only check the surrogate's error at the true inputs of the study's "
                    "measurements against the error model (probability integral transform)")
    ap.add_argument("--spread-swing", action="store_true",
                    help="only print how the spread at each theta moves the likelihood's "
                    "normalising term along the fat thickness (subjects 0 and 5)")
    ap.add_argument("--table", type=Path, nargs="+", metavar="JSON",
                    help="only print the table of records written by earlier runs (--json)")
    ap.add_argument("--interval", default="ci95",
                    choices=("ci95", "ci95_hdi", "ci95_equal_tailed"),
                    help="with --table: the interval whose coverage is counted")
    ap.add_argument("--misses", action="store_true",
                    help="with --table: why the fat thickness's interval misses when determined")
    args = ap.parse_args()
    if args.table:
        records = [r for p in args.table for r in json.loads(p.read_text())]
        print("\n".join(table(records, args.interval)))
        if args.misses:
            kinds = sorted({r.get("sensor", "magnitude") for r in records})
            print("\n".join(misses(records, {s: load_predictor(args.model or MODELS[s])
                                              for s in kinds})))
        return
    sensors = [s.strip() for s in args.sensors.split(",") if s.strip()]
    if not sensors or any(s not in MODELS for s in sensors):
        ap.error(f"--sensors {args.sensors!r}: allowed {', '.join(MODELS)}")
    predictors = {s: load_predictor(args.model or MODELS[s]) for s in sensors}
    if args.spread_swing:
        print("\n".join(spread_swing(json.loads(CACHE.read_text())["subjects"],
                                     predictors[sensors[0]])))
        return
    if args.error_check:
        subjects = json.loads(CACHE.read_text())["subjects"][: args.subjects]
        for s, predictor in predictors.items():
            print(f"{s} ({predictor.card.get('name')}):")
            print("\n".join(error_check(subjects, predictor, s)))
        return
    if args.write_card and (not args.sweep_error or args.model is None):
        ap.error("--write-card needs --sweep-error and --model DIR (the card written)")
    if args.write_outputs is not None and not args.write_card:
        ap.error("--write-outputs needs --write-card")
    if args.sweep_error:
        if args.sweep is None:
            ap.error("--sweep-error needs --sweep DIR: a dataset of "
                     "datasets/spaces/default-sweep.toml")
        designs = None if args.sweep_designs == "all" else Path(args.sweep_designs)
        measured: dict = {"outputs": {}}
        for s, predictor in predictors.items():
            print(f"{s} ({predictor.card.get('name')}):")
            lines, fitted = fit_sweep_error(predictor, s, args.sweep, designs, args.sweep_max_mm)
            print("\n".join(lines), flush=True)
            measured = {**fitted, "outputs": {**measured["outputs"], **fitted["outputs"]}}
        if args.write_card:
            try:
                measured = select_outputs(measured, args.write_outputs)
            except ValueError as e:
                sys.exit(f"--write-outputs: nothing written: {e}")
            command = "python bench/calibration/calibrate.py " + shlex.join(sys.argv[1:])
            entry = error_t_entry(predictors[sensors[0]], measured, args.sweep, designs, command)
            try:
                write_error_t(Path(args.model), entry)
            except ValueError as e:
                sys.exit(f"--write-card: nothing written: {e}")
            print(f"wrote calibration_error_t ({', '.join(entry['outputs'])}) into "
                  f"{Path(args.model) / 'card.json'}")
        return
    if args.surrogate_error:
        for s, predictor in predictors.items():
            print(f"{s} ({predictor.card.get('name')}):")
            print("\n".join(fit_surrogate_error(predictor, s)))
        return
    if args.residuals:
        for s, predictor in predictors.items():
            print(f"{s} ({predictor.card.get('name')}):")
            print("\n".join(residuals(json.loads(RESIDUAL_CACHE.read_text())["subjects"],
                                      predictor, s)))
        return
    subjects = json.loads(CACHE.read_text())["subjects"][: args.subjects]
    t0 = time.perf_counter()
    records = []
    for s, predictor in predictors.items():
        records += run(subjects, predictor, component=s, steps=args.steps,
                       std_factor=args.std_factor, error_length_mm=args.error_length_mm,
                       error_frequency_hz=args.error_frequency_hz, spread=args.spread,
                       error_model=args.error_model)
    print(f"{len(subjects)} FE subjects x {len(NOISES)} noise levels x sensors "
          + ", ".join(f"{s} (model {p.card.get('name')})" for s, p in predictors.items())
          + f", spread {args.spread}, error model {args.error_model}, "
          f"{time.perf_counter() - t0:.0f} s in all")
    print("\n".join(table(records)))
    if args.json:
        args.json.write_text(json.dumps(records, indent=1) + "\n")


if __name__ == "__main__":
    main()
