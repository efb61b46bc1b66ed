"""The accuracy-vs-time report: Markdown tables and a log-log Pareto plot (beside it, the
whole band on fresh designs), from :func:`studies.accuracy.study.run_study`'s result. Returns
text and PNG bytes; the caller writes them (atomically, see ``hapticrom bench accuracy``)."""

from __future__ import annotations

import io
import math
import os
import platform
from typing import Any

import figstyle
from surrogate.registry import package_versions

from .band_models import LEAD, PEER_WORKERS, TARGETS, lead, meets
from .designs import DATASET
from .fe_ladder import TRANSIENT
from .metric import __doc__ as METRIC_DOC

__all__ = ["TARGET", "fastest_within", "machine", "pareto", "render", "write_plot"]

#: The error the headline asks about: 1 % (the surrogate accuracy target of the README).
TARGET = 0.01


def machine() -> dict[str, str]:
    """CPU model, cores, load, OS, Python and package versions of this run."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")),
                       cpu)
    except OSError:
        pass
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    return {"cpu": cpu, "cores": str(os.cpu_count()), "load average (1, 5, 15 min)": load,
            "os": platform.platform(), **package_versions()}


def _points(res: dict[str, Any]) -> list[dict[str, Any]]:
    return [r for r in (*res["fe"], *res["transient"], *res["learned"])
            if math.isfinite(r["worst_median"])]


def pareto(points: list[dict[str, Any]], key: str = "worst_median") -> list[dict[str, Any]]:
    """Points no other point beats on both time per answer and ``key``, fastest first."""
    out, best = [], math.inf
    for p in sorted(points, key=lambda p: (p["seconds"], p[key])):
        if p[key] < best:
            out.append(p)
            best = p[key]
    return out


def fastest_within(points: list[dict[str, Any]], key: str,
                   target: float = TARGET) -> dict[str, Any] | None:
    """The fastest point whose ``key`` is at most ``target``."""
    ok = [p for p in points if p.get(key, math.inf) <= target]
    return min(ok, key=lambda p: p["seconds"]) if ok else None


def _pct(x: float) -> str:
    if x is None or not math.isfinite(x):
        return "n/a"
    return f"{100 * x:.2g} %" if x < 0.1 else f"{100 * x:.0f} %"


def _t(s: float) -> str:
    if s < 1e-3:
        return f"{s * 1e6:.3g} us"
    return f"{s * 1e3:.3g} ms" if s < 1 else f"{s:.3g} s"


def write_plot(res: dict[str, Any]) -> bytes:
    """PNG bytes: median error over the designs against time per answer, log-log; beside it,
    when the result has the whole-band section, each model's centre error on the fresh sweep
    designs against its time per design."""
    band = res.get("band")
    fig, axes = figstyle.figure(1, 2 if band else 1, width_in=13.0 if band else 7.5,
                                height_in=5.8, squeeze=False)
    ax = axes[0][0]
    groups = [("FE order 1", [r for r in res["fe"] if r["order"] == 1 and r["level"]], "o-"),
              ("FE order 2", [r for r in res["fe"] if r["order"] == 2 and r["level"]], "s-"),
              ("FE default mesh", [r for r in res["fe"] if not r["level"]], "D"),
              ("FE transient", res["transient"], "v")]
    groups += [(kind.upper(), [r for r in res["learned"] if r["kind"] == kind], marker)
               for kind, marker in zip(res["curves"], "^PX*hd", strict=False)]
    for label, rows, style in groups:
        if rows:
            ax.plot([r["seconds"] for r in rows], [max(r["worst_median"], 1e-6) for r in rows],
                    style, label=label, ms=6)
    front = pareto(_points(res))
    ax.step([p["seconds"] for p in front], [max(p["worst_median"], 1e-6) for p in front],
            where="post", color="k", lw=0.8, alpha=0.5, label="Pareto front")
    ax.axhline(TARGET, color="r", lw=0.8, ls="--", label="1 % error")
    ax.set(xscale="log", yscale="log", xlabel="time per answer [s] (this machine, one thread)",
           ylabel="error: median over designs of max(center, edge, profile L2)",
           title=f"One frequency: {len(res['designs'])} designs against a converged FE "
           "reference")
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=8)
    plotted = ("left: median over the designs of the largest of the centre error, the edge "
               "error and the profile's relative L2 error, against time per answer on this "
               "machine; black: the Pareto front")
    design = f"{len(res['designs'])} held-out designs of the default space"
    if band:
        _band_panel(axes[0][1], band)
        plotted += ("; right: centre relative error over every fresh design x band frequency "
                    "(median: circles, p95: triangles; filled: one design per call, open: "
                    "every design in one call) against the time to answer one design's whole "
                    "band, the FE sweep at its recorded median time per design")
        design += f"; right: {band['n_test']} designs of {band['test']}"
    figstyle.annotate(fig, "What accuracy costs in time", design=design,
                      frequency="left: each design's own (100-250 Hz); right: the whole band",
                      plotted=plotted)
    buf = io.BytesIO()
    figstyle.save(fig, buf, format="png")
    return buf.getvalue()


def _band_panel(ax: Any, band: dict[str, Any]) -> None:
    """The whole-band models on the right-hand axes."""
    for i, r in enumerate(band["rows"]):
        c = figstyle.color(i)
        for t, fill in ((r["seconds_1"], c), (r["seconds_batch"], "none")):
            ax.plot([t, t], [r["centre"][0], r["centre"][1]], color=c, lw=0.8, alpha=0.6)
            label = (f"{r['short']} peer" if r["role"] == "peer"
                     else f"{r['model']} ({r['role']})")
            ax.plot(t, r["centre"][0], "o", color=c, mfc=fill, ms=6,
                    label=label if fill != "none" else None)
            ax.plot(t, r["centre"][1], "^", color=c, mfc=fill, ms=6)
    if band["fe"]:
        ax.axvline(band["fe"]["median_s"], color="k", lw=0.8, ls=":",
                   label="FE sweep (median per design)")
    ax.axhline(TARGETS["centre median"], color="r", lw=0.8, ls="--", label="target: median 1 %")
    ax.axhline(TARGETS["centre p95"], color="r", lw=0.8, ls="-.", label="target: p95 5 %")
    lo, hi = band["band_hz"][0], band["band_hz"][1]
    ax.set(xscale="log", yscale="log",
           xlabel=f"time per answer [s]: one design, {band['band_hz'][2]} frequencies "
           f"{lo:g}-{hi:g} Hz", ylabel="centre relative error (median, p95)",
           title=f"The whole band: {band['n_test']} fresh designs ({band['test']})")
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=7, loc="upper right")


def render(res: dict[str, Any], png_name: str, command: str) -> str:
    """The Markdown report."""
    s = res["settings"]
    pts = _points(res)
    L: list[str] = [
        "# What accuracy costs in time", "",
        f"Generated by `{command}` in {res['wall_s']:.0f} s"
        f"{' (quick: a CI-sized run, not the shipped numbers)' if s.quick else ''}. "
        "Every number below is measured by that command on the current code; timings are "
        "medians on the machine listed at the end, which was shared with other jobs, so "
        "ratios are more telling than absolute times.", "",
        f"![error against time per answer]({png_name})", ""]
    L += ["## Findings", ""]
    for key, what in (("worst_median", "median"), ("worst_max", "worst design")):
        p = fastest_within(pts, key)
        L.append(f"- Fastest way to {_pct(TARGET)} error ({what} over the designs): "
                 + (f"**{p['method']}**, {_t(p['seconds'])} per answer "
                    f"(error {_pct(p[key])})." if p else "none of the methods measured."))
    for kind, o in res["one_percent"].items():
        if o["n"] is None:
            txt = "the held-out error does not fall with n on the measured sizes"
        elif o["extrapolated"]:
            txt = (f"about {o['n']:.3g} FE samples (extrapolated on the log-log fit, slope "
                   f"{o['slope']:.2f}; about {o['total_s'] / 3600:.3g} core-hours of generation)")
        else:
            txt = f"{o['n']} FE samples (measured; {o['total_s'] / 3600:.3g} core-hours in all)"
        L.append(f"- {kind.upper()}: 1 % median held-out error needs {txt}.")
    L += _more_findings(res)
    L += _band_findings(res)
    L += ["", "## Error metric", "", METRIC_DOC.strip().split("\n\n", 1)[1].strip(), "",
          "The reference is the FE solver with quadratic elements at "
          f"{s.ref_level:.3g} x the default element sizes (median {_median_int(res['ref_dofs'])} "
          "unknowns). Learned models are measured against that reference on the same designs "
          "(their error therefore includes the discretisation error of the data they learned "
          "from), and on the dataset's held-out rows for the learning curves.", ""]
    L += ["## Designs", "",
          f"{len(res['designs'])} held-out rows of `{DATASET.relative_to(DATASET.parents[1])}` "
          "(split of `hapticrom train`), picked by farthest-point sampling in the encoded "
          "feature box from the row nearest its centre (`studies/accuracy/designs.py`).", ""]
    names = list(res["designs"][0].values)
    L += ["| row | " + " | ".join(names) + " |", "|---" * (len(names) + 1) + "|"]
    for d in res["designs"]:
        L.append(f"| {d.row} | " + " | ".join(_fmt(d.values[n]) for n in names) + " |")
    L += ["", "## Every way to get an answer", "",
          "Time per answer: FE = one full solve (mesh, assembly, factorisation, solve), median "
          f"of {s.repeat} runs per design, median over designs; learned models = median call "
          "time at batch 1, or the time per row at the large batch.", "",
          "| method | unknowns | time per answer | center med / max | edge med / max | "
          "profile L2 med / max | error med / max |", "|---|---|---|---|---|---|---|"]
    for r in (*res["fe"], *res["transient"], *res["learned"]):
        L.append(f"| {r['method']} | {r.get('dofs', '')} | {_t(r['seconds'])} | "
                 + " | ".join(f"{_pct(r[f'{k}_median'])} / {_pct(r[f'{k}_max'])}"
                              for k in ("center", "edge", "profile", "worst")) + " |")
    L += [""]
    for tr in res["transient"]:
        L += [f"Transient steady state ({tr['designs']} designs; {tr['refused']} refused by the "
              "solver: a bare unit on frictionless pins has nothing holding it sideways in "
              f"time): order {TRANSIENT['order']}, default element sizes, "
          f"{TRANSIENT['time_step_ms']} ms step, {TRANSIENT['duration_ms']:g} ms run, peaks over "
          f"the last {TRANSIENT['window_ms']:g} ms (motor at its rated voltage, rated speed = the "
          "design's frequency, instant spin-up). Against the harmonic answer on the same mesh "
          f"it differs by at most {_pct(tr['vs_harmonic_center_max'])} (center) and "
          f"{_pct(tr['vs_harmonic_edge_max'])} (edge) and takes "
          f"{tr['seconds'] / tr['harmonic_seconds']:.0f}x the harmonic solve's time; its profile "
          "is not compared (a transient's profile is a peak over the whole run). The peaks "
          "still change by up to "
          f"{_pct(tr['unsettled_max'])} from the window before the last to the last (the "
          "part of the difference that is start-up not yet decayed, not discretisation).", ""]
    L += ["Export parity (largest |d ln amplitude| between the ONNX graph and the in-memory "
          "model on the held-out rows): " + ", ".join(
              f"{kind.upper()} {p:.2g}" for kind, p in res["parity"].items()) + ".", ""]
    L += _band_section(res)
    L += ["## Cost of the model: learning curves", "",
          f"Held-out error on all {res['n_test']} held-out rows (against the dataset's FE "
          "answers) after training on the first n rows in Sobol order. Generation = the "
          "solver time the dataset recorded for those rows (one core each); training measured "
          "here (one run, fit and POD included). The extrapolated sample count's compute "
          "counts generation only.", "",
          "| model | FE samples | generation | training | total | error median | "
          "error p95 | center median | edge median | profile L2 median |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for r in (r for rows in res["curves"].values() for r in rows):
        L.append(f"| {r['kind'].upper()} | {r['n']} | {_t(r['generation_s'])} | "
                 f"{_t(r['train_s'])} | {_t(r['total_s'])} | {_pct(r['worst_median'])} | "
                 f"{_pct(r['worst_p95'])} | {_pct(r['center_median'])} | "
                 f"{_pct(r['edge_median'])} | {_pct(r['profile_median'])} |")
    for kind, (_, options) in s.curves.items():
        if options:
            L.append(f"\n{kind.upper()} options of this run: {options}.")
    L += ["", "## Effects audit", "",
          "Each optional effect switched off alone, on every design that contains it; the change "
          "is the error metric of that answer against the all-effects answer on the same mesh, "
          "so it is what skipping the effect costs in accuracy; time is relative to the "
          "all-effects solve (median over designs).", "",
          "| variant | designs | not present | refused | time x full | change median | "
          "change max | center max | edge max |", "|---|---|---|---|---|---|---|---|---|"]
    for r in res["effects"]:
        if "time_ratio" in r:
            L.append(f"| {r['variant']} | {r['applies']} | {r['not_present']} | {r['refused']}"
                     f" | {r['time_ratio']:.2f} | {_pct(r['worst_median'])} | "
                     f"{_pct(r['worst_max'])} | {_pct(r['center_max'])} | "
                     f"{_pct(r['edge_max'])} |")
        else:
            L.append(f"| {r['variant']} | 0 | {r['not_present']} | {r['refused']} | n/a | "
                     "n/a | n/a | n/a | n/a |")
    L += ["", "## Machine", ""] + [f"- {k}: {v}" for k, v in machine().items()] + [""]
    return "\n".join(L)


def _more_findings(res: dict[str, Any]) -> list[str]:
    """Findings on the learned models, the transient and the effects, from the tables."""
    out = []
    fe_default = next(r for r in res["fe"] if not r["level"])
    for kind in res["curves"]:
        label = kind.upper()
        rows = [r for r in res["learned"] if r["kind"] == kind]
        if not rows:
            continue
        fast = min(rows, key=lambda r: r["seconds"])
        one = min((r for r in rows if r["method"].endswith("batch 1")),
                  key=lambda r: r["seconds"])
        out.append(f"- {label} ({rows[0]['n_train']} FE samples): error {_pct(one['worst_median'])}"
                   f" median / {_pct(one['worst_max'])} worst design against the reference; "
                   f"{_t(one['seconds'])} per answer at batch 1 ({one['method']}), "
                   f"{_t(fast['seconds'])} per row batched: "
                   f"{fe_default['seconds'] / one['seconds']:.0f}x and "
                   f"{fe_default['seconds'] / fast['seconds']:.0f}x faster than the FE solver "
                   f"at its default mesh ({_t(fe_default['seconds'])}, error "
                   f"{_pct(fe_default['worst_median'])} median).")
    for tr in res["transient"]:
        ratio = tr["seconds"] / tr["harmonic_seconds"]
        diff = max(tr["vs_harmonic_center_max"], tr["vs_harmonic_edge_max"])
        out.append(f"- The transient steady state costs {ratio:.0f}x a harmonic solve on the "
                   f"same mesh and differs from it by up to {_pct(diff)} (start-up still "
                   f"decaying: up to {_pct(tr['unsettled_max'])} change between the last two "
                   "windows); the harmonic analysis answers the steady question directly.")
    eff = [r for r in res["effects"] if "time_ratio" in r and r["variant"] != "all effects"]
    safe = [r["variant"] for r in eff if r["worst_max"] <= TARGET]
    best = min(eff, key=lambda r: r["worst_max"]) if eff else None
    if safe:
        out.append(f"- Variants within {_pct(TARGET)} of the full answer on every design: "
                   f"{', '.join(safe)}.")
    elif best is not None:
        out.append("- No variant (effect switched off, or model choice) stays within "
                   f"{_pct(TARGET)} on every design; "
                   f"the least influential is '{best['variant']}' (change up to "
                   f"{_pct(best['worst_max'])}, median {_pct(best['worst_median'])}, time "
                   f"x{best['time_ratio']:.2f}).")
    return out


def _quad(v: list[float]) -> str:
    return f"{100 * v[0]:.2f} / {100 * v[1]:.1f} / {100 * v[2]:.1f} / {100 * v[3]:,.0f}"


def _band_findings(res: dict[str, Any]) -> list[str]:
    """Findings of the whole-band section: each shipped model against the targets and its p95
    lead over every peer; the shipped network against the single-frequency model."""
    band = res.get("band")
    if not band:
        return []
    rows = band["rows"]
    peer_rows = [r for r in rows if r["role"] == "peer"]
    single = next((r for r in rows if r["role"] == "single frequency"), None)
    fe = band["fe"]["median_s"] if band["fe"] else None
    out = []
    for r in (r for r in rows if r["role"] not in ("peer", "single frequency")):
        m = meets(r)
        met = [k for k, (_, ok) in m.items() if ok]
        verdict = ("meets all four targets" if len(met) == len(m) else
                   "meets none of the four targets" if not met else
                   f"meets {len(met)} of the four targets ({', '.join(met)})")
        leads = {p["short"]: lead(r, p) for p in peer_rows}
        ld = {k: min(v[k] for v in leads.values()) for k in ("centre", "edge")}
        out.append(
            f"- Shipped {r['role']} model `{r['model']}` on {band['n_test']} fresh designs x "
            f"{band['band_hz'][2]} band frequencies: "
            + ", ".join(f"{k} {100 * v:.3g} % (target < {100 * TARGETS[k]:g} %: "
                        f"{'met' if ok else 'not met'})" for k, (v, ok) in m.items())
            + f": **it {verdict}**. Its p95 lead over every peer trained on "
            f"{peer_rows[0]['fitted']:,} designs: {ld['centre']:.2f}x centre, "
            f"{ld['edge']:.2f}x edge ("
            + "; ".join(f"{n} {v['centre']:.2f}x / {v['edge']:.2f}x" for n, v in leads.items())
            + f"; target {LEAD:g}x: {'met' if min(ld.values()) >= LEAD else 'not met'}). "
            f"One design's whole band in {_t(r['seconds_1'])} (one design per call), "
            f"{_t(r['seconds_batch'])} per design batched"
            + (f": {fe / r['seconds_1']:.0f}x and {fe / r['seconds_batch']:.0f}x faster than "
               f"the FE sweep ({_t(fe)} per design)." if fe else "."))
    shipped = next((r for r in rows if r["role"] == "harmonic"), None)
    if single is not None and shipped is not None:
        out.append(
            f"- Against the single-frequency `{single['model']}` on the same pairs, "
            f"`{shipped['model']}`'s centre median / p95 are "
            f"{single['centre'][0] / shipped['centre'][0]:.2f}x / "
            f"{single['centre'][1] / shipped['centre'][1]:.2f}x lower, the edge's "
            f"{single['edge'][0] / shipped['edge'][0]:.2f}x / "
            f"{single['edge'][1] / shipped['edge'][1]:.2f}x; `{single['model']}` answers "
            f"a design's band {shipped['seconds_1'] / single['seconds_1']:.1f}x faster at one "
            "design per call, its profile only to 20 mm.")
    return out


def _band_section(res: dict[str, Any]) -> list[str]:
    """The whole-band table and what it measures."""
    band = res.get("band")
    if not band:
        return []
    fe = band["fe"]
    n_f = band["band_hz"][2]
    peer_rows = [r for r in band["rows"] if r["role"] == "peer"]
    fits = ", ".join(f"{r['short']} {_t(r['fit_s'])}" for r in peer_rows)
    L = ["### The whole band, on fresh designs: the shipped models and the peers", "",
         f"{band['n_test']} of the {band['n_test_all']} designs of `datasets/{band['test']}` "
         f"(Sobol seed {band['test_seed']}, no model saw them), every band frequency "
         f"({n_f}, {band['band_hz'][0]:g}-{band['band_hz'][1]:g} Hz): {band['n_test'] * n_f:,} "
         "(design, frequency) pairs, against the FE sweep's answers (default mesh). The shipped "
         "defaults of the `harmonic` and `gaussian_process` roles "
         "(`surrogate/runtime/defaults.py`) and `nn-default` (the former single-frequency "
         "default) answer through the run-time `Predictor.predict`; the peers of "
         "`bench/surrogate/output_choice.py` (`studies/output_choice/`, on the complex band "
         "with 48 + 24 POD modes: the scikit-learn MLP, 3 x 128 with early stopping, and, "
         "when the `bench` extra is installed, LightGBM, one booster of 3,000 trees a target) "
         "are fitted here on the first "
         f"{band['n_train']:,} designs of `datasets/{band['train']}` in Sobol order ("
         + (f"the {band['recorded_train']:,} training designs `{band['first_model']}`'s card "
            f"records; it fits on {band['rows'][0]['fitted']:,} of them, the rest held out for "
            "its card and interval calibration" if band["n_train"] == band["recorded_train"] else
            f"a CI-sized subset of the {band['recorded_train']:,} `{band['first_model']}`'s "
            "card records")
         + f"; fit {fits}, one thread, LightGBM's boosters on {PEER_WORKERS} processes). "
         "Errors as the cards' `test_set` and "
         "`bench/surrogate/sweep_nn.py` score them (`surrogate.sweep.scoring.score_pairs`): "
         "relative error of the centre and the edge (median / p95 / p99 / max over the pairs, "
         "%), the largest error on the field's scale max |error| / max(FE centre, FE edge), "
         "the profile's relative L2 error (median over the pairs; 0-40 mm, `nn-default`'s "
         "0-20 mm). Time per answer: one design's whole band, one call with its "
         f"{n_f} frequencies (batch 1) and one call with all {band['n_test']} designs divided "
         "by their number (batched), wall time, one thread. "
         + (f"The FE sweep's time is the solver time the test set recorded per design "
            f"(`wall_s`, median of {fe['designs']}; mean {_t(fe['mean_s'])}, p95 "
            f"{_t(fe['p95_s'])}; one core each, the generation running two designs at a "
            "time)." if fe else "The test set recorded no solver times."), "",
         "| method | trained on | time per answer: batch 1 / batched | x faster than the FE "
         "sweep | centre med / p95 / p99 / max % | edge med / p95 / p99 / max % | max err / "
         "field % | profile L2 median % |", "|---|---|---|---|---|---|---|---|",
         f"| FE sweep (the test set's own solves, reference) | - | "
         f"{_t(fe['median_s']) if fe else 'not recorded'} | 1 | - | - | - | - |"]
    for r in band["rows"]:
        trained = r["trained"] + (f" ({r['fitted']:,} fitted)" if r["fitted"] and
                                  r["role"] != "peer" else "")
        faster = (f"{fe['median_s'] / r['seconds_1']:,.0f} / "
                  f"{fe['median_s'] / r['seconds_batch']:,.0f}" if fe else "-")
        L.append(f"| {r['method']} | {trained} | {_t(r['seconds_1'])} / "
                 f"{_t(r['seconds_batch'])} | {faster} | {_quad(r['centre'])} | "
                 f"{_quad(r['edge'])} | {100 * r['max_field']:.1f} | "
                 f"{100 * r['profile_median']:.2f}"
                 + (f" ({r['profile_grid']})" if r["profile_grid"] != "0-40 mm" else "")
                 + " |")
    L += ["", "Targets for the shipped harmonic model (issue 36): centre median < 1 %, p95 "
          "< 5 %, max error / field < 10 %, profile L2 median < 2 %, and a p95 lead of 2x over "
          "every peer trained on the same designs."
          + ("" if "LightGBM" in {r["short"] for r in peer_rows} else
             " LightGBM is not installed here (the `bench` extra), so its row is left out; "
             "[docs/peers.md](peers.md#the-shipped-models-against-the-peers) has it."), ""]
    return L


def _median_int(values: list[int]) -> int:
    return sorted(values)[len(values) // 2]


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return "-" if not math.isfinite(v) else f"{v:.3g}"
    return str(v)
