"""`hapticrom calibrate` end to end on the example measurement, its bad-input exits, and
`hapticrom plan --tissue` planning with the calibrated tissue and its posterior spread."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from hapticrom.cli import main
from hapticrom.documents import schema
from surrogate.runtime.defaults import default_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "hapticrom"))
from schema_check import problems

EXAMPLE = "examples/measurement-forearm.csv"
FIT = "skin_E_kPa,fat_thickness_mm,tissue_loss_factor"
QUICK = ["--walkers", "16", "--steps", "300"]


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    out = tmp_path_factory.mktemp("cal")
    # the model the example layout plans on (the default), as --tissue requires
    code = main(["calibrate", EXAMPLE, "--model", default_model("harmonic"), "--fit", FIT, *QUICK,
                 "--out", str(out / "cal.json"), "--plot", str(out / "cal.png"), "--verify"])
    assert code == 0
    return out


def test_calibrate_writes_a_valid_document_and_figure(calibrated, capsys):
    doc = json.loads((calibrated / "cal.json").read_text())
    assert problems(doc, schema("calibration")) == []
    assert doc["fit"] == FIT.split(",")
    assert len(doc["measurement"]["points"]) == 14
    assert doc["measurement"]["design"]["n_rings"] == 0
    # the example was made with skin 75 kPa and loss factor 0.22 (bench/calibration/subjects.py)
    lo, hi = doc["posterior"]["skin_E_kPa"]["ci95"]
    assert lo < 75.0 < hi
    lo, hi = doc["posterior"]["tissue_loss_factor"]["ci95"]
    assert lo < 0.22 < hi
    assert (calibrated / "cal.png").stat().st_size > 10_000
    # the reported interval is the HDI, the equal-tailed one beside it; the t per output read
    for p in doc["posterior"].values():
        assert p["interval_kind"] == "hdi" and p["ci95"] == p["ci95_hdi"]
        assert len(p["ci95_equal_tailed"]) == 2
    err = doc["likelihood"]["surrogate_error"]
    assert set(err) == {"center_amplitude_um", "profile_um"}
    assert all(0 < e["nu"] < 10 and e["scale"] > 0 for e in err.values())
    # --verify: FE at the posterior mean, point by point, close to the surrogate and the data
    v = doc["verify"]
    assert len(v["points"]) == 14 and v["dofs"] > 1000
    assert v["median_abs_log_surrogate_vs_fe"] < 0.1
    for q in v["points"]:
        assert abs(q["fe_um"] / q["measured_um"] - 1) < 0.25


def test_bad_interval_kind_exits_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "cal.json"
    code = main(["calibrate", EXAMPLE, "--fit", FIT, "--interval", "median", "--out", str(out)])
    assert code == 2 and not out.exists()
    assert "--interval" in capsys.readouterr().err


def test_bad_measurement_exits_2_and_writes_nothing(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    text = Path(EXAMPLE).read_text().replace("edge,3,120,acceleration,g,rms",
                                             "edge,3,120,acceleration,kg,rms")
    bad.write_text(text.replace("centre,0,170", "center,0,170"))
    out = tmp_path / "cal.json"
    code = main(["calibrate", str(bad), "--fit", FIT, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    assert "row 16, column unit: 'kg' is not a unit of acceleration" in err
    assert "row 21, column reference: 'center' is not one of centre, edge" in err
    assert list(tmp_path.iterdir()) == [bad]
    code = main(["calibrate", EXAMPLE, "--fit", "skin_E_kPa,n_rings", "--out", str(out)])
    assert code == 2 and "not a continuous input" in capsys.readouterr().err
    code = main(["calibrate", EXAMPLE, "--fit", FIT, "--prior", "skin_E_kPa=uniform:1,500"])
    assert code == 2 and "inside the model's range" in capsys.readouterr().err


def test_plan_with_the_calibrated_tissue(calibrated, tmp_path, capsys):
    plan = tmp_path / "plan.json"
    code = main(["plan", "examples/forearm-layout.toml", "--tissue",
                 str(calibrated / "cal.json"), "--out", str(plan)])
    text = capsys.readouterr().out
    assert code == 0, text
    doc = json.loads(plan.read_text())
    cal = json.loads((calibrated / "cal.json").read_text())
    assert doc["site"]["skin_E_kPa"] == cal["tissue"]["skin_E_kPa"]
    t = doc["tissue"]
    assert t["draws"] == 400 and t["design"] == doc["best"]
    assert t["pitch_mm_2_5"] <= t["pitch_mm_median"] <= t["pitch_mm_97_5"]
    assert t["pitch_95_mm"] <= t["pitch_95_with_surrogate_mm"]
    # the plan judges at the surrogate's 95 % bounds by default, and so does the person's pitch
    assert t["holds_at"] == "bounds_95"
    assert t["pitch_95_for_plan_mm"] == t["pitch_95_with_surrogate_mm"]
    assert t["pitch_mm_at_point_estimate"] == doc["pitch_mm"]
    assert "pitch over 400 posterior draws" in text


def test_plan_refuses_a_calibration_of_another_model(calibrated, tmp_path, capsys):
    doc = json.loads((calibrated / "cal.json").read_text())
    doc["model"]["name"] = "gp-default"
    other = tmp_path / "other.json"
    other.write_text(json.dumps(doc))
    code = main(["plan", "examples/forearm-layout.toml", "--tissue", str(other)])
    assert code == 2 and "calibrated on model 'gp-default'" in capsys.readouterr().err
