"""The envelope model's ten worst held-out runs (steady level, rise, decay), each with its cause.

    python bench/surrogate/rom_worst_runs.py [--model models/rom-default] \
        [--data datasets/transient]
        [--n 10] [--steady-levels FE.json]

Ranks the held-out runs of the model's card (``metrics.held_out.runs``) by the larger of the
centre and edge errors of each metric and prints, per run, both errors and what decides them,
measured on the run itself (the FE envelope demodulated as in training, the model simulated on
its schedule):

- every metric: attachment and rings, the speed at switch-off (Hz), whether the first burst
  starts with an overdrive kick, and the model's mode at the worse point (sigma 1/s, f_n Hz;
  with two modes the second, and w, the first's share: with ``quasi_static_share`` the share
  of the steady response passed through at once);
- steady: whether the FE envelope had settled (the card's test), the model high or low, and,
  with ``--steady-levels`` (the ``--json`` of ``bench/surrogate/rom_steady_levels.py`` on these
  runs),
  the split of the error into the harmonic NN's own (``model_vs_hyst``: the model's level
  against a hysteretic harmonic solve on the transient's mesh), the damping model
  (``own_vs_hyst``: the band model's steady state against the hysteretic one) and the FE
  window's unsteadiness (the window's level against the band model's steady state, ``own``);
- rise: ``fragile`` when an envelope crosses 90 % of its final level and falls back below it
  before switch-off (the 10-90 % rise then jumps between a resonance or an overshoot and the
  end of the approach), the FE's and the model's largest level before switch-off over the
  final one, and the model's quasi-static rise (its steady level A(f(t)) along the spin-up,
  no dynamics) against its real one: close means the rise is set by the steady response's
  shape along the spin-up, apart means the mode's lag;
- decay: the FE's and the model's 90-10 % fall (ms), brake or coast after the burst, and
  ``rings`` when the FE envelope rises again by more than 5 % of the steady level after
  first falling below 90 % (the low mode beating as the rotor slows through it).

docs/transient-model.md ("The ten worst held-out runs") quotes the tables.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

METRICS = {"steady": ("steady_um", "rel"), "rise": ("rise_ms", "abs"),
           "decay": ("decay_ms", "abs")}
REBOUND = 0.05  # an FE decay "rings" when it rises again by 5 % of the steady level


def _error(row: dict[str, Any], point: str, metric: str) -> float:
    """The card's error of one run, point and metric (relative for steady, ms otherwise)."""
    key, kind = METRICS[metric]
    fe, model = row[f"{point}_{key}_fe"], row[f"{point}_{key}_model"]
    if fe is None or model is None or not (math.isfinite(fe) and math.isfinite(model)):
        return math.nan
    return abs(model / fe - 1.0) if kind == "rel" else abs(model - fe)


def _falls_back(t: np.ndarray, y: np.ndarray, on_s: float, level: float) -> bool:
    """Whether ``y`` crosses 90 % of ``level`` before ``on_s`` and falls below it again."""
    from surrogate.envelope.metrics import first_crossing

    up = t < on_s
    t90 = first_crossing(t[up], y[up], 0.9 * level, rising=True)
    if math.isnan(t90):
        return False
    after = up & (t > t90 + 1e-4)
    return bool(np.any(y[after] < 0.9 * level))


def _rise_ms(t: np.ndarray, y: np.ndarray, on_s: float, level: float) -> float:
    from surrogate.envelope.metrics import first_crossing

    up = t < on_s
    t10 = first_crossing(t[up], y[up], 0.1 * level, rising=True)
    t90 = first_crossing(t[up], y[up], 0.9 * level, rising=True)
    return 1e3 * (t90 - t10)


def _rebounds(t: np.ndarray, y: np.ndarray, on_s: float, back_on_s: float,
              level: float) -> bool:
    """Whether the envelope, once below 90 % after switch-off, rises again by ``REBOUND``."""
    win = (t >= on_s) & (t < back_on_s)
    yw = y[win]
    below = np.flatnonzero(yw < 0.9 * level)
    if not below.size:
        return False
    tail = yw[below[0]:]
    return bool(np.max(tail - np.minimum.accumulate(tail)) > REBOUND * level)


def describe(model_path: str | Path, data: str | Path) -> dict[int, dict[str, Any]]:
    """Per held-out run: its card metrics row and what is measured on it (see the module
    docstring), keyed by sample index."""
    from surrogate.data.store import Store
    from surrogate.envelope.metrics import POINTS, STEADY_WINDOW_S
    from surrogate.envelope.runs import run_from_row
    from surrogate.runtime.rom import load_envelope_model

    model = load_envelope_model(model_path)
    card = json.loads((Path(model_path) / "card.json").read_text())
    rows = {int(r["sample_index"]): r for r in card["metrics"]["held_out"]["runs"]}
    df = Store.open(data).read()
    df = df[df["sample_index"].isin(list(rows)) & (df["status"] == "ok")]
    out = {}
    for row in df.to_dict("records"):
        run, _ = run_from_row(row, model.design_names)
        schedule = json.loads(row["scene_json"])["analysis"]["voltage_schedule"]
        sim = model.simulate(run.t, run.volts, run.design, extrapolate=True)
        steady = model.steady_levels(run.omega, run.design, extrapolate=True)
        params = model.parameters(run.design, extrapolate=True)
        on = run.on_time_s
        drive = (run.t >= on - STEADY_WINDOW_S) & (run.t < on)
        after = np.flatnonzero((run.t > on) & (run.volts > 0.0))
        back_on = float(run.t[after[0]]) if after.size else float(run.t[-1])
        info: dict[str, Any] = {
            "row": rows[run.sample_index], "attachment": run.design["attachment"],
            "n_rings": int(run.design["n_rings"]),
            "f_off_hz": float(run.omega[drive].mean() / (2 * math.pi)),
            "kick": bool(len(schedule) > 1 and schedule[0][1] > schedule[1][1] + 1e-9),
            "brake": bool(any(v < 0 for _, v in schedule)),
            "tau_spinup_ms": float(run.design["tau_spinup_ms"])}
        for j, p in enumerate(POINTS):
            fe, mo = run.env[j], sim[f"{p}_envelope_um"]
            lf, lm = float(fe[drive].mean()), float(mo[drive].mean())
            up = run.t < on
            par = params[p]
            slow = "2" if model.modes == 2 else ""  # the dynamic mode beside a share
            info[p] = {
                "sigma_1_s": par[f"sigma{slow}_1_s"], "fn_hz": par[f"fn{slow}_hz"],
                "share": par.get("weight"),
                "fragile_fe": _falls_back(run.t, fe, on, lf),
                "fragile_model": _falls_back(run.t, mo, on, lm),
                "peak_fe": float(fe[up].max() / lf), "peak_model": float(mo[up].max() / lm),
                "quasi_static_rise_ms": _rise_ms(run.t, steady[p], on,
                                                 float(steady[p][drive].mean())),
                "rings_fe": _rebounds(run.t, fe, on, back_on, lf)}
        out[run.sample_index] = info
    return out


def _steady_cause(info: dict[str, Any], p: str, levels: dict[str, Any] | None) -> str:
    row = info["row"]
    high = row[f"{p}_steady_um_model"] > row[f"{p}_steady_um_fe"]
    parts = ["model high" if high else "model low",
             "FE settled" if row.get(f"{p}_settled") else "FE not settled"]
    if levels is not None:
        j = 0 if p == "center" else 1
        window = levels["fe_um"][j] / levels["levels_um"]["own"][j] - 1.0
        parts.append(f"NN vs hyst. FE {100 * levels['model_vs_hyst'][j]:+.0f} %, band vs "
                     f"hyst. {100 * levels['own_vs_hyst'][j]:+.0f} %, FE window vs its steady "
                     f"state {100 * window:+.0f} %")
    return ", ".join(parts)


def _rise_cause(info: dict[str, Any], p: str) -> str:
    q, row = info[p], info["row"]
    fragile = [w for w, k in (("FE", "fragile_fe"), ("model", "fragile_model")) if q[k]]
    verb = "falls" if len(fragile) == 1 else "fall"
    parts = [f"fragile ({' and '.join(fragile)} {verb} back below 90 %)" if fragile
             else "crossing final"]
    parts.append(f"peak/level FE {q['peak_fe']:.2f}, model {q['peak_model']:.2f}")
    parts.append(f"model quasi-static {q['quasi_static_rise_ms']:.1f} ms vs its real "
                 f"{row[f'{p}_rise_ms_model']:.1f} ms")
    return ", ".join(parts)


def _decay_cause(info: dict[str, Any], p: str) -> str:
    q, row = info[p], info["row"]
    fe_ms = row[f"{p}_decay_ms_fe"]
    parts = ["brake" if info["brake"] else "coast",
             f"FE {fe_ms:.1f} ms (rate ln 9 / fall {1e3 * math.log(9.0) / fe_ms:.0f} 1/s), "
             f"model {row[f'{p}_decay_ms_model']:.1f} ms"]
    if q["rings_fe"]:
        parts.append("FE rings (rises again after falling below 90 %)")
    return ", ".join(parts)


def _share(q: dict[str, Any]) -> str:
    """Mode 1's share w of the force, for a model with two modes (with
    ``quasi_static_share``: the share passed through at once)."""
    return "" if q["share"] is None else f", w {q['share']:.2f}"


def table(described: dict[int, dict[str, Any]], metric: str, n: int = 10,
          levels: dict[int, dict[str, Any]] | None = None) -> list[str]:
    """Markdown rows of the ``n`` worst runs of ``metric``: ranked by the larger of the centre
    and edge errors; the cause is given at the worse point."""
    unit = "%" if metric == "steady" else "ms"
    scale = 100.0 if metric == "steady" else 1.0

    def worst(item: tuple[int, dict[str, Any]]) -> float:
        errs = [_error(item[1]["row"], p, metric) for p in ("center", "edge")]
        finite = [e for e in errs if math.isfinite(e)]
        return max(finite) if finite else -1.0

    ranked = sorted(described.items(), key=worst, reverse=True)[:n]
    lines = [f"| run | unit | f at switch-off | kick | error {unit} centre \\| edge | mode at "
             "the worse point | cause (worse point) |", "|---|---|---|---|---|---|---|"]
    for idx, info in ranked:
        errs = {p: _error(info["row"], p, metric) for p in ("center", "edge")}
        p = max(errs, key=lambda k: errs[k] if math.isfinite(errs[k]) else -1.0)
        if metric == "steady":
            cause = _steady_cause(info, p, (levels or {}).get(idx))
        else:
            cause = (_rise_cause if metric == "rise" else _decay_cause)(info, p)
        cells = " \\| ".join("-" if not math.isfinite(e) else f"{scale * e:.1f}"
                             for e in errs.values())
        lines.append(f"| {idx} | {info['attachment']}, {info['n_rings']} ring"
                     f"{'' if info['n_rings'] == 1 else 's'} | "
                     f"{info['f_off_hz']:.0f} Hz | {'yes' if info['kick'] else 'no'} | {cells} | "
                     f"{p}: sigma {info[p]['sigma_1_s']:.0f} 1/s, f_n "
                     f"{info[p]['fn_hz']:.0f} Hz{_share(info[p])} | {cause} |")
    return lines


def decay_summary(described: dict[int, dict[str, Any]]) -> list[str]:
    """Per point: on how many runs with a defined decay the model's is shorter than the FE's,
    and the median ratio of the FE's ring-down rate (ln 9 / its 90-10 % fall, 1/s) to the
    model's sigma, split by brake and coast."""
    lines = []
    for p in ("center", "edge"):
        for label, brake in (("brake", True), ("coast", False)):
            rows = [(i["row"], i[p]["sigma_1_s"]) for i in described.values()
                    if i["brake"] == brake and math.isfinite(_error(i["row"], p, "decay"))]
            if not rows:
                continue
            shorter = sum(r[f"{p}_decay_ms_model"] < r[f"{p}_decay_ms_fe"] for r, _ in rows)
            ratio = np.median([1e3 * math.log(9.0) / r[f"{p}_decay_ms_fe"] / s for r, s in rows])
            lines.append(f"{p}, {label}: decay defined on {len(rows)} runs; the model's is "
                         f"shorter on {shorter}; FE rate ln 9 / fall over the mode's sigma: "
                         f"median {ratio:.2f}")
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default=str(ROOT / "models" / "rom-default"))
    ap.add_argument("--data", default=str(ROOT / "datasets" / "transient"))
    ap.add_argument("--n", type=int, default=10, help="runs per table")
    ap.add_argument("--steady-levels",
                    help="the --json of bench/surrogate/rom_steady_levels.py: splits "
                    "the steady errors of the runs it holds into NN, damping and window")
    args = ap.parse_args(argv)
    if args.n < 1:
        print(f"--n {args.n}: allowed 1 or more", file=sys.stderr)
        return 2
    levels = None
    if args.steady_levels:
        levels = {int(r["sample_index"]): r
                  for r in json.loads(Path(args.steady_levels).read_text())}
    described = describe(args.model, args.data)
    for metric in METRICS:
        print(f"\n{metric}: the {args.n} worst of {len(described)} held-out runs\n")
        print("\n".join(table(described, metric, args.n, levels)))
    print()
    print("\n".join(decay_summary(described)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
