"""`hapticrom bench accuracy` (studies.accuracy): the quick run writes a complete report and
plot whose numbers are finite and consistent (finer mesh -> smaller error, ONNX = in-memory
model, the default mesh equals the level-1 quadratic ladder row; the whole-band section scores the
shipped sweep models, nn-default and the MLP peer), bad arguments exit 2 without writing, and the
metric and curve helpers are exact on analytic inputs; the whole-band section runs end to end on
the synthetic sweep fixture.

The tests on the quick run's result are the study itself, run CI-sized (43 s on a quiet
2-core machine, the slowest of the fast tier): they are in the slow tier (``make test-slow``);
the helpers, the designs and the argument checks stay in the fast tier."""

import math
import re

import numpy as np
import pytest

from hapticrom.cli import main
from studies.accuracy import band_models, report, run_study
from studies.accuracy.designs import load_study_data, pick_designs
from studies.accuracy.learning_curves import samples_for
from studies.accuracy.metric import Answer, errors, summary
from studies.accuracy.report import fastest_within, pareto, render

SECTIONS = ("## Findings", "## Error metric", "## Designs", "## Every way to get an answer",
            "### The whole band, on fresh designs", "## Cost of the model: learning curves",
            "## Effects audit", "## Machine")


@pytest.fixture(scope="module")
def result():
    return run_study(quick=True, log=lambda m: None)


def test_metric_is_exact_on_analytic_answers():
    ref = Answer(np.array(2.0), np.array(4.0), np.array([3.0, 4.0]))
    a = Answer(np.array(2.2), np.array(3.0), np.array([3.0, 4.0]) * 1.05)
    e = errors(a, ref)
    assert e["center"] == pytest.approx(0.1)
    assert e["edge"] == pytest.approx(0.25)
    assert e["profile"] == pytest.approx(0.05)
    assert e["worst"] == pytest.approx(0.25)
    s = summary([e, errors(ref, ref)])
    assert s["worst_max"] == pytest.approx(0.25) and s["worst_median"] == pytest.approx(0.125)


def test_samples_for_reads_measured_and_extrapolates_a_power_law():
    rows = [{"n": n, "worst_median": 0.1 * (n / 100) ** -0.5, "generation_s": n * 1.0,
             "total_s": n * 1.0} for n in (100, 400)]
    got = samples_for(rows)
    assert got["extrapolated"] and got["slope"] == pytest.approx(-0.5)
    assert got["n"] == pytest.approx(10000, rel=1e-9)
    assert got["total_s"] == pytest.approx(10000, rel=1e-9)
    rows.append({"n": 20000, "worst_median": 0.005, "generation_s": 1.0, "total_s": 7.0})
    assert samples_for(rows) == {"n": 20000, "total_s": 7.0, "extrapolated": False,
                                 "slope": None}


def test_pareto_and_fastest():
    pts = [{"seconds": 1.0, "e": 0.5}, {"seconds": 2.0, "e": 0.1}, {"seconds": 3.0, "e": 0.2},
           {"seconds": 0.5, "e": 0.9}]
    assert [p["seconds"] for p in pareto(pts, "e")] == [0.5, 1.0, 2.0]
    assert fastest_within(pts, "e", 0.2)["seconds"] == 2.0
    assert fastest_within(pts, "e", 0.01) is None


def test_designs_are_held_out_distinct_and_deterministic():
    sd = load_study_data()
    a, b = pick_designs(sd, 5), pick_designs(sd, 5)
    assert [d.row for d in a] == [d.row for d in b]
    assert len({d.row for d in a}) == 5
    assert set(d.row for d in a) <= set(sd.test.tolist())
    with pytest.raises(ValueError, match="n = 0"):
        pick_designs(sd, 0)


@pytest.mark.slow
def test_quick_study_numbers_are_finite_and_consistent(result):
    fe = {(r["order"], r["level"]): r for r in result["fe"]}
    for r in result["fe"]:
        assert r["seconds"] > 0 and all(math.isfinite(r[f"{k}_median"])
                                        for k in ("center", "edge", "profile", "worst"))
    for order in (1, 2):  # finer mesh -> smaller error; quadratic beats linear on one mesh
        assert fe[(order, 1.0)]["worst_median"] < fe[(order, 2.0)]["worst_median"]
        assert fe[(order, 1.0)]["dofs"] > fe[(order, 2.0)]["dofs"]
    assert fe[(2, 2.0)]["worst_median"] < fe[(1, 2.0)]["worst_median"]
    # the default mesh of these designs is not refined by the wavelength rule: same answer
    assert fe[(2, None)]["worst_median"] == pytest.approx(fe[(2, 1.0)]["worst_median"],
                                                           rel=1e-6)
    # ONNX equals the in-memory model (same design errors to float32 precision)
    by = {r["method"]: r for r in result["learned"]}
    assert result["parity"]["gp"] < 1e-6 and result["parity"]["nn"] < 1e-4
    for a, b in (("GP scikit-learn, batch 1", "GP ONNX, batch 1"),
                 ("NN torch, batch 1", "NN ONNX, batch 1"),
                 ("NN ONNX, batch 1", "NN Predictor.predict (checks + ONNX), batch 1")):
        assert by[a]["worst_median"] == pytest.approx(by[b]["worst_median"], rel=1e-3, abs=1e-6)
    assert all(r["seconds"] > 0 and math.isfinite(r["worst_max"]) for r in result["learned"])
    for r in (*result["gp_curve"], *result["nn_curve"]):
        assert r["total_s"] == pytest.approx(r["generation_s"] + r["train_s"])
        assert 0 < r["worst_median"] <= r["worst_p95"]
    band = result["band"]  # the shipped sweep models, nn-default and the peers, CI-sized
    assert [r["role"] for r in band["rows"]] == ["harmonic", "gaussian_process",
                                                 "single frequency",
                                                 *["peer"] * len(band_models.peers())]
    assert band["n_test"] == band_models.N_TEST_QUICK
    assert band["rows"][-1]["fitted"] == band_models.N_TRAIN_QUICK
    for r in band["rows"]:
        assert r["seconds_1"] > 0 and r["seconds_batch"] > 0
        assert all(math.isfinite(v) for v in (*r["centre"], *r["edge"], r["max_field"],
                                              r["profile_median"]))
    assert band["rows"][2]["profile_grid"] == "0-20 mm"  # nn-default's own profile
    eff = {r["variant"]: r for r in result["effects"]}
    assert eff["all effects"]["worst_max"] == 0.0
    assert sum(eff["no encapsulation"][k] for k in ("applies", "not_present", "refused")) == 3


def test_band_section_on_the_synthetic_sweeps(sweep_dataset, sweep_model, tmp_path):
    from sweep_fixture import make_dataset

    test = make_dataset(tmp_path / "test", 6, seed=777)
    band = band_models.band_rows(None, None, train=sweep_dataset, test=test,
                                 models=[("harmonic", sweep_model)], repeat=1,
                                 peer_learners=["mlp"])
    model, peer = band["rows"]
    assert model["role"] == "harmonic" and peer["role"] == "peer"
    # the peer fits on every design the model's card records; every test design is scored
    assert band["n_train"] == band["recorded_train"] == peer["fitted"] == 48
    assert band["n_test"] == band["n_test_all"] == peer["batch"] == 6
    for r in (model, peer):
        assert r["profile_grid"] == "0-40 mm" and r["seconds_1"] > 0 and r["seconds_batch"] > 0
        assert 0 <= r["centre"][0] <= r["centre"][1] <= r["centre"][2] <= r["centre"][3]
        assert math.isfinite(r["max_field"]) and math.isfinite(r["profile_median"])
    assert model["coverage"][0] is not None and peer["coverage"] == [None, None]
    assert band["fe"] is None  # the synthetic set records no solver time
    assert band_models.lead(model, peer)["centre"] == pytest.approx(
        peer["centre"][1] / model["centre"][1])
    assert set(band_models.meets(model)) == set(band_models.TARGETS)
    res = {"band": band}
    assert "- Shipped harmonic model" in "\n".join(report._band_findings(res))
    table = "\n".join(report._band_section(res))
    assert "not recorded" in table and "nan" not in table
    # the rows the model fitted are its card's, not a fixed share of the recorded designs
    assert 0 < model["fitted"] < 48 and f"it fits on {model['fitted']:,} of them" in table
    assert "LightGBM is not installed here" in table  # only the MLP was fitted
    # a second peer with a smaller p95: the lead is over every peer, the smaller one, and
    # both are named
    other = {**peer, "short": "LightGBM", "centre": [v / 2 for v in peer["centre"]],
             "edge": [v / 2 for v in peer["edge"]]}
    res = {"band": {**band, "rows": [model, peer, other]}}
    finding = report._band_findings(res)[0]
    mlp, lgbm = (band_models.lead(model, p) for p in (peer, other))
    assert f"Its p95 lead over every peer trained on 48 designs: {lgbm['centre']:.2f}x " \
           "centre" in finding
    assert f"MLP {mlp['centre']:.2f}x / {mlp['edge']:.2f}x" in finding and "LightGBM" in finding
    table = "\n".join(report._band_section(res))
    assert "LightGBM is not installed" not in table and table.count("complex band (48") == 2


@pytest.mark.slow
def test_report_structure(result):
    text = render(result, "x.png", "hapticrom bench accuracy --quick")
    positions = [text.index(s) for s in SECTIONS]
    assert positions == sorted(positions)
    assert "![error against time per answer](x.png)" in text
    assert "nan" not in text.replace("n/a", "")
    table = [ln for ln in text.splitlines() if ln.startswith("| FE order")]
    assert len(table) == 4
    band = text[text.index("### The whole band"):text.index("## Cost of the model")]
    for name in ("| FE sweep", "| nn-sweep (harmonic)", "| gp-sweep (gaussian_process)",
                 "| nn-default (single frequency)", "| scikit-learn MLP"):
        assert name in band
    assert "- Shipped harmonic model `nn-sweep`" in text
    # LightGBM is a row when the bench extra installed it; otherwise the page says where it is
    assert ("| LightGBM" in band) == ("lgbm" in band_models.peers()) != ("peers.md" in band)


@pytest.mark.slow
def test_cli_writes_report_and_plot(tmp_path, result, monkeypatch):
    import studies.accuracy as acc

    monkeypatch.setattr(acc, "run_study", lambda quick, log: result)
    out = tmp_path / "acc.md"
    assert main(["bench", "accuracy", "--quick", "--out", str(out)]) == 0
    assert out.read_text().startswith("# What accuracy costs in time")
    assert (tmp_path / "acc.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("out", ["report.txt", "missing-dir/acc.md"])
def test_cli_bad_out_exits_2_and_writes_nothing(tmp_path, out, capsys):
    assert main(["bench", "accuracy", "--quick", "--out", str(tmp_path / out)]) == 2
    assert re.search(r"--out", capsys.readouterr().err)
    assert list(tmp_path.iterdir()) == []
