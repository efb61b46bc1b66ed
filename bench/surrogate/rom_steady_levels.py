"""Where the envelope model's steady-level error comes from, per held-out FE transient.

    python bench/surrogate/rom_steady_levels.py        # 56 held-out runs (about 9 min, loaded)
    python bench/surrogate/rom_steady_levels.py --limit 5 --json out.json
    python bench/surrogate/rom_steady_levels.py --samples 195 71 --json out.json   # these runs only

For each held-out run of ``datasets/transient`` the FE transient's "steady" level (the mean
envelope over the 5 ms before the first switch-off, the card's definition,
``surrogate.envelope.metrics``) is compared with steady responses at the run's mean speed in that
window (f = omega / 2 pi):

- ``tone``: the FE's own amplitude at f without demodulation: the complex amplitude of each
  displacement component at f fitted over the last two periods before switch-off (with an
  offset), combined as sqrt(sum_c |U_c|^2); ``tone`` against FE is the error of the demodulated
  envelope (``surrogate.envelope.fit.complex_envelopes``: its FFT-based analytic signal picks up the
  1/t tails of the low-frequency motion of later braking and pulses) and of the 5 ms mean;
- ``own``: a harmonic solve of the run's own scene on the transient's own matrices (linear
  elements, damping layer) with the transient's own loss model (``analysis.damping``:
  ``"viscous_at_drive"``, C = eta / omega_ref K at the rated speed, or ``"hysteretic_band"``,
  the causal band modulus of ``fem.viscoelastic``), i.e. the steady state the FE transient
  tends to: its difference from FE is what is not steady in the window (beat of the low mode,
  lag behind a still-rising speed) and time-stepping error, not a model error;
- ``hyst``: the same matrices with hysteretic damping K (1 + i eta) instead (the harmonic
  solver's damping model, the reference): ``own_vs_hyst`` is the damping model alone;
- ``nn``: the harmonic NN of the default band (``models/nn-default``, 100-250 Hz, quadratic
  elements, PML, hysteretic) at f (extrapolated below its 100 Hz; the previous envelope
  model's steady part): ``nn_vs_hyst`` is that NN's error plus element order and PML;
- ``nn_eq`` (viscous transients only): the NN with each loss factor replaced by the
  transient's equivalent at f, eta f / f_ref;
- ``model``: the envelope model's own steady level at f (``--model``, default
  ``models/rom-default``: its harmonic model, ``models/nn-wide`` over 20-250 Hz for the
  shipped one, times its learned gain if it has one, continued below the harmonic band);
  ``model_vs_hyst`` is its harmonic part's error plus element order and PML (without a learned
  gain), ``model_vs_own`` the model's steady error with the window's unsteadiness removed;
  ``tone_vs_own`` is what is not steady in the FE window (and time-stepping error) without the
  demodulation's error.

Prints each run's relative differences and the medians (all runs, below / above 100 Hz, per
attachment); docs/transient-model.md quotes them.
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

KINDS = ("tone", "own", "hyst", "nn", "nn_eq", "model")  # nn_eq: viscous transients only
PAIRS = (("tone", "own"), ("own", "hyst"), ("nn", "hyst"), ("nn", "own"), ("nn_eq", "own"),
         ("model", "hyst"), ("model", "own"))


def steady_solves(scene_json: str, omega: float, band: bool = False,
                  fits: dict[str, Any] | None = None) -> dict[str, np.ndarray]:
    """Steady (center, edge) envelope magnitudes (um) of a transient scene at ``omega``
    (rad/s) with the transient's damping (``rayleigh``) and with hysteretic damping
    (``hyst``), both on the transient's own matrices, and the rated frequency (Hz). With
    ``band`` also ``band``: the modulus of the transient's ``"hysteretic_band"`` model
    (``fem.viscoelastic``), the steady state such a transient tends to; ``fits`` (name ->
    ``BandFit``) replaces it with one output per named fit."""
    return steady_solver(scene_json)(omega, band, fits)


def steady_solver(scene_json: str) -> Any:
    """``solve(omega, band=False, fits=None)``: :func:`steady_solves` of one scene, its
    matrices built once (for many speeds of one design)."""
    import scipy.sparse.linalg as spla

    from fem import elements, probes, results
    from fem.assembly import assemble_matrix, assemble_vector
    from fem.problem import build_problem, drive_omega
    from fem.scene.io import scene_from_dict
    from fem.solve import OperatorLog, damping_layer_matrices
    from fem.transient_analysis import loss_matrix, system_matrices
    from fem.viscoelastic import default_fit

    scene = scene_from_dict(json.loads(scene_json))
    problem = build_problem(scene)
    w_ref = drive_omega(scene)
    dm, K, M, C = system_matrices(problem, w_ref, OperatorLog())
    d = problem.domain
    g = elements.gauss_data(d.mesh)
    Ke = elements.stiffness(g, problem.mode, d.element_property("mu"),
                            d.element_property("kappa"))
    K_eta = loss_matrix(dm, Ke, d.element_property("loss_factor"))
    C_layer = assemble_matrix(dm, damping_layer_matrices(d, g, problem.mode,
                                                         d.element_property("density")))
    unit_force = assemble_vector(dm, problem.load) * scene.unit.motor.unbalance_kg_m
    pts = probes.output_points(scene, problem)
    n = pts.r_probe.size

    def solve(omega: float, band: bool = False, fits: dict[str, Any] | None = None
              ) -> dict[str, np.ndarray]:
        force = unit_force * omega**2
        out = {}
        systems = [("rayleigh", K - omega**2 * M + 1j * omega * C),
                   ("hyst", K + 1j * K_eta - omega**2 * M + 1j * omega * C_layer)]
        for name, fit in ((fits or {"band": default_fit()}) if band else {}).items():
            z = complex(fit.modulus_factor(omega, 1.0))  # unit eta: 1 - c + the Prony sum
            systems.append((name, K + (z - 1) * K_eta - omega**2 * M + 1j * omega * C_layer))
        for tag, A in systems:
            u = spla.spsolve(A.tocsc(), force.astype(complex))
            vals = results.interpolate(pts.stencil, dm.nodal(dm.expand(u)))
            out[tag] = np.sqrt(np.sum(np.abs(vals[[n, n + 1]]) ** 2, axis=1)) * 1e6
        out["f_ref_hz"] = np.array(w_ref / (2 * math.pi))
        return out

    return solve


def tone_amplitude(t: np.ndarray, u: np.ndarray, omega: float, end_s: float,
                   periods: float = 2.0) -> float:
    """sqrt(sum_c |U_c|^2) of the complex amplitudes U_c at ``omega`` (rad/s) fitted (with an
    offset) to the components ``u`` (3, nt) over ``periods`` periods ending at ``end_s`` (s):
    the FE's vibration amplitude there without demodulation (unit of ``u``)."""
    sel = (t > end_s - periods * 2 * math.pi / omega) & (t <= end_s)
    basis = np.column_stack([np.cos(omega * t[sel]), np.sin(omega * t[sel]),
                             np.ones(sel.sum())])
    coef = np.linalg.lstsq(basis, u[:, sel].T, rcond=None)[0]
    return float(np.sqrt(np.sum(coef[0] ** 2 + coef[1] ** 2)))


def model_steady(model: Any, design: dict[str, Any], omega: float) -> np.ndarray:
    """The envelope model's steady (center, edge) level (um) at ``omega`` (rad/s)."""
    from surrogate.runtime.rom import POINTS

    levels = model.steady_levels(np.array([omega]), design, extrapolate=True)
    return np.array([float(levels[p][0]) for p in POINTS])


def diagnose(limit: int | None = None, model_path: str | Path = ROOT / "models" / "rom-default",
             reuse: dict[int, dict[str, list[float]]] | None = None,
             out_json: str | None = None, samples: set[int] | None = None
             ) -> list[dict[str, Any]]:
    """Per held-out run: f, attachment, rings, FE level, the card's settled flags and each
    kind's relative difference (center, edge). ``reuse``: sample_index -> the ``levels_um`` of
    an earlier run of this function on the same dataset (the FE solves are skipped for those
    rows: only the NN and the model are evaluated again). ``out_json``: the rows so far are
    written there after each run. ``samples``: only these held-out rows (sample indices)."""
    from surrogate.data.store import Store
    from surrogate.envelope.fit import HOLDOUT_EVERY, run_from_row
    from surrogate.envelope.metrics import SETTLED_PTP, SETTLED_WINDOW_S, STEADY_WINDOW_S
    from surrogate.runtime.predictor import load_predictor
    from surrogate.runtime.rom import load_envelope_model

    nn = load_predictor(ROOT / "models" / "nn-default")
    model = load_envelope_model(model_path)
    names = [n for n in nn.input_names if n != "frequency_hz"]
    df = Store.open(ROOT / "datasets" / "transient").read()
    df = df[(df["status"] == "ok") & df["history_center_um"].notna()]
    out = []
    for row in df.to_dict("records"):
        if int(row["sample_index"]) % HOLDOUT_EVERY != HOLDOUT_EVERY - 1:
            continue
        if samples is not None and int(row["sample_index"]) not in samples:
            continue
        run, _ = run_from_row(row, names)
        win = (run.t >= run.on_time_s - STEADY_WINDOW_S) & (run.t < run.on_time_s)
        fe = run.env[:, win].mean(axis=1)
        omega = float(run.omega[win].mean())
        f = omega / (2 * math.pi)
        tone = np.array([tone_amplitude(run.t, np.stack([np.asarray(c, dtype=float) for c in
                                                          row[f"history_{p}_um"]]), omega,
                                        run.on_time_s) for p in ("center", "edge")])
        late = (run.t >= run.on_time_s - SETTLED_WINDOW_S) & (run.t < run.on_time_s)
        settled = [bool(np.ptp(e[late]) / np.mean(e[late]) < SETTLED_PTP) for e in run.env]
        band = json.loads(row["scene_json"])["analysis"].get("damping") == "hysteretic_band"
        old = (reuse or {}).get(run.sample_index)
        if old is not None:
            levels = {k: np.asarray(v) for k, v in old.items() if k in ("rayleigh", "hyst",
                                                                           "band", "own",
                                                                           "f_ref_hz")}
        else:
            levels = steady_solves(row["scene_json"], omega, band=band)
            levels["own"] = levels["band" if band else "rayleigh"]
        scale = f / float(levels["f_ref_hz"])
        for tag, s in (("nn", 1.0), ("nn_eq", scale))[:1 if band else 2]:
            X = {k: [run.design[k]] for k in names}
            X["frequency_hz"] = [f]
            for k in ("tissue_loss_factor", "ring_loss_factor"):
                X[k] = [run.design[k] * s]
            p = nn.predict(X, extrapolate=True)
            levels[tag] = np.array([p["center_amplitude_um"][0], p["edge_amplitude_um"][0]])
        levels["model"] = model_steady(model, run.design, omega)
        levels["tone"] = tone
        kinds = [k for k in KINDS if k in levels]
        rec = {"sample_index": run.sample_index, "f_hz": f, "attachment":
               run.design["attachment"], "n_rings": int(run.design["n_rings"]),
               "fe_um": fe.tolist(), "settled": settled,
               "levels_um": {k: np.asarray(v).tolist() for k, v in levels.items()},
               **{k: (levels[k] / fe - 1).tolist() for k in kinds},
               **{f"{a}_vs_{b}": (levels[a] / levels[b] - 1).tolist() for a, b in PAIRS
                  if a in levels}}
        out.append(rec)
        print(f"{run.sample_index:4d} f={f:6.1f} {rec['attachment']:5s} {rec['n_rings']} "
              + " ".join(f"{k} {rec[k][0]:+.3f}/{rec[k][1]:+.3f}" for k in kinds), flush=True)
        if out_json:
            Path(out_json).write_text(json.dumps(out, indent=1) + "\n")
        if limit and len(out) >= limit:
            break
    return out


def summary(rows: list[dict[str, Any]]) -> list[str]:
    """Median (max) |difference| per comparison and point: all runs, split at 100 Hz and
    per attachment."""
    lines = []
    keys = [k for k in (*KINDS, *(f"{a}_vs_{b}" for a, b in PAIRS)) if rows and k in rows[0]]
    for label, sel in (("all", rows), ("f < 100 Hz", [r for r in rows if r["f_hz"] < 100]),
                       ("f >= 100 Hz", [r for r in rows if r["f_hz"] >= 100]),
                       ("glued", [r for r in rows if r["attachment"] == "glued"]),
                       ("pogo", [r for r in rows if r["attachment"] == "pogo"]),
                       ("settled (both points)", [r for r in rows if all(r["settled"])])):
        if not sel:
            continue
        parts = []
        for k in keys:
            a = np.abs(np.array([r[k] for r in sel]))
            parts.append(f"{k} {np.median(a[:, 0]):.3f}/{np.median(a[:, 1]):.3f} (max "
                         f"{a[:, 0].max():.3f}/{a[:, 1].max():.3f})")
        lines.append(f"{label} ({len(sel)} runs), median |rel. diff| center/edge: "
                     + ", ".join(parts))
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--limit", type=int, default=None, help="stop after this many runs")
    ap.add_argument("--json", help="write the per-run rows to this file")
    ap.add_argument("--model", default=str(ROOT / "models" / "rom-default"),
                    help="envelope model directory whose steady level is compared")
    ap.add_argument("--reuse", help="a --json file of an earlier run on the same dataset: its "
                    "FE levels are reused (only the NN and --model are evaluated again)")
    ap.add_argument("--samples", type=int, nargs="+",
                    help="only these held-out runs (sample indices, each % 4 == 3)")
    args = ap.parse_args(argv)
    if args.samples and any(s % 4 != 3 for s in args.samples):
        print(f"--samples {args.samples}: held-out runs only (sample_index % 4 == 3)",
              file=sys.stderr)
        return 2
    reuse = None
    if args.reuse:
        reuse = {int(r["sample_index"]): r["levels_um"]
                 for r in json.loads(Path(args.reuse).read_text())}
    rows = diagnose(args.limit, args.model, reuse, args.json,
                    set(args.samples) if args.samples else None)
    for line in summary(rows):
        print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
