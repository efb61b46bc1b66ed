"""``hapticrom predict`` and ``hapticrom models``: outputs, exit codes, nothing half-written."""

from __future__ import annotations

import json
import shutil

from hapticrom.cli import main


def run(argv: list[str]) -> int:
    """The real command line (exit code returned, not raised)."""
    return main(argv)


POINT = ["--set", "orientation=reverse", "--set", "n_rings=2", "--set", "skin_E_kPa=60",
         "--set", "frequency_hz=180"]


def test_predict_prints_and_writes_json(trained_models, tmp_path, capsys):
    path = str(trained_models["nn"][0])
    out = tmp_path / "p.json"
    assert run(["predict", path, *POINT, "--json", str(out)]) == 0
    assert "centre (unit face) magn." in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert doc["schema_version"] == 1 and doc["kind"] == "hapticrom.predict"
    assert len(doc["outputs"]["profile_magnitude_um"][0]) == len(doc["profile_distance_mm"])


def test_predict_bad_input_exit_2_nothing_written(trained_models, tmp_path, capsys):
    path = str(trained_models["gp"][0])
    out = tmp_path / "p.json"
    bad = [*POINT[:-1], "frequency_hz=999"]
    assert run(["predict", path, *bad, "--json", str(out)]) == 2
    assert "frequency_hz" in capsys.readouterr().err
    assert not out.exists() and list(tmp_path.iterdir()) == []
    assert run(["predict", path, *bad, "--extrapolate"]) == 0
    assert "extrapolated" in capsys.readouterr().out


def test_predict_csv(trained_models, tmp_path):
    csv = tmp_path / "d.csv"
    csv.write_text("orientation,n_rings,skin_E_kPa,frequency_hz\nforward,0,30,120\n"
                   "reverse,1,90,240\n")
    out = tmp_path / "o.json"
    assert run(["predict", str(trained_models["nn"][0]), "--csv", str(csv),
                "--json", str(out)]) == 0
    assert len(json.loads(out.read_text())["outputs"]["centre_magnitude_um"]) == 2


def test_models_list_and_show(trained_models, tmp_path, capsys):
    root = tmp_path / "models"
    root.mkdir()
    for kind, (path, _) in trained_models.items():
        shutil.copytree(path, root / f"m-{kind}")
    assert run(["models", "list", "--root", str(root)]) == 0
    text = capsys.readouterr().out
    assert "m-nn" in text and "m-gp" in text
    assert run(["models", "show", str(root / "m-gp")]) == 0
    assert json.loads(capsys.readouterr().out)["kind"] == "gp"
    (root / "m-gp" / "model.onnx").write_bytes(b"tampered")
    assert run(["models", "list", "--root", str(root)]) == 2  # broken model: bad input
    assert run(["models", "show", str(root / "m-gp")]) == 2


def test_train_bad_kind_and_existing_out(synthetic_dataset, trained_models, capsys):
    assert run(["train", "--data", str(synthetic_dataset), "--kind", "svm", "--out", "x"]) == 2
    assert "--kind" in capsys.readouterr().err
    assert run(["train", "--data", str(synthetic_dataset), "--kind", "nn",
                "--out", str(trained_models["nn"][0])]) == 2
    assert "exists" in capsys.readouterr().err
