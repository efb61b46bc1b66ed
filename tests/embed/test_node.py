"""The Node.js example (embed/node/predict.mjs on embed/lib/hapticrom-model.mjs) answers as the
Python predictor does on 1,000 random in-range designs, refuses every bad input with the
predictor's field and message, and refuses a model that fails its integrity check."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from embed_cases import EMBED, columns, random_designs

from surrogate.runtime import PredictorInputError, load_predictor

SCRIPT = EMBED / "node" / "predict.mjs"
RTOL = 1e-6  # amplitudes: relative; log_std (a log): absolute, i.e. relative on exp(band)
AMPLITUDES = ("center_amplitude_um", "edge_amplitude_um", "normalized_edge", "profile_um",
              "edge_radius_mm")
LOGS = ("center_amplitude_um_log_std", "edge_amplitude_um_log_std", "normalized_edge_log_std",
        "profile_um_log_std")


def run_node(node: str, model: Path, designs, tmp: Path, *flags: str):
    src = tmp / "designs.json"
    src.write_text(json.dumps(designs))
    return subprocess.run([node, str(SCRIPT), str(model), str(src), *flags], cwd=EMBED,
                          capture_output=True, text=True, timeout=120, check=False)


def max_rel(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)))


@pytest.mark.parametrize(("model", "n"), [("nn-default", 1000), ("gp-default", 200),
                                          ("nn-normal", 300), ("nn-sweep", 300),
                                          ("gp-sweep", 300)])
def test_node_equals_python_on_random_designs(node, sealed, tmp_path, model, n):
    _node_equals_python(node, sealed[model], n, tmp_path)


def test_node_equals_python_on_a_sweep_model(node, sweep_model, tmp_path):
    """A sweep-trained graph (the band decode: gathers at two grid frequencies, the factored
    basis) and its 40 mm profile, read by the same JavaScript."""
    _node_equals_python(node, sweep_model, 300, tmp_path)


def test_node_equals_python_on_a_sweep_gp(node, sweep_gp_model, tmp_path):
    """The float64 sweep GP's graph (its mean with alpha as the left operand, the DTC variance
    as one product, the linearised log-std), read by the same JavaScript."""
    _node_equals_python(node, sweep_gp_model, 300, tmp_path)


def _node_equals_python(node: str, path: Path, n: int, tmp_path: Path) -> None:
    model = path.name
    predictor = load_predictor(path)
    rows = random_designs(predictor.card, n, seed=24)
    run = run_node(node, path, rows, tmp_path)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)["outputs"]
    want = predictor.predict(columns(rows))
    assert set(AMPLITUDES) <= set(predictor.output_names)
    worst = {k: max_rel(got[k], want[k]) for k in predictor.output_names}  # nn-normal: 1 more
    worst_log = {k: float(np.max(np.abs(np.subtract(got[k], want[k]))))
                 for k in want if k.endswith("_log_std")}
    assert set(LOGS) <= set(worst_log)
    print(f"{model}, {n} designs: max relative difference Node - Python "
          f"{max(worst.values()):.2e}, log_std max absolute {max(worst_log.values()):.2e}")
    assert max(worst.values()) <= RTOL, worst
    assert max(worst_log.values()) <= RTOL, worst_log
    assert got["profile_distance_mm"] == predictor.profile_distance_mm.tolist()


BASE = {"orientation": "forward", "attachment": "glued", "n_rings": 2, "ring_1_E_kPa": 95.0,
        "ring_2_E_kPa": 260.0, "ring_3_E_kPa": 95.0, "ring_density_kg_m3": 1070.0,
        "ring_nu": 0.47, "ring_loss_factor": 0.1, "skin_E_kPa": 49.0, "fat_thickness_mm": 14.0,
        "tissue_loss_factor": 0.3, "frequency_hz": 200.0}
BAD = {
    "modulus above range": ([{**BASE, "ring_1_E_kPa": 2000.0}], ()),
    "third row below range": ([BASE, BASE, {**BASE, "frequency_hz": 99.99}], ()),
    "unknown choice": ([{**BASE, "orientation": "sideways"}], ()),
    "choice index out of range": ([{**BASE, "attachment": 2}], ("--extrapolate",)),
    "non-integer count": ([{**BASE, "n_rings": 1.5}], ()),
    "count above range": ([{**BASE, "n_rings": 4}], ()),
    "missing input": ([{k: v for k, v in BASE.items() if k != "skin_E_kPa"}], ()),
    "unknown input": ([{**BASE, "colour": "red"}], ()),
    "text for a number": ([{**BASE, "ring_nu": "soft"}], ()),
    "log input not positive": ([{**BASE, "ring_loss_factor": 0.0}], ("--extrapolate",)),
    "tiny modulus": ([{**BASE, "ring_3_E_kPa": 1e-7}], ()),
}


@pytest.mark.parametrize("case", BAD)
def test_node_refuses_like_the_predictor(node, sealed, tmp_path, case):
    rows, flags = BAD[case]
    predictor = load_predictor(sealed["nn-default"])
    with pytest.raises(PredictorInputError) as want:
        predictor.predict(columns(rows), extrapolate=bool(flags))
    run = run_node(node, sealed["nn-default"], rows, tmp_path, *flags)
    assert run.returncode == 2, run.stdout
    got = json.loads(run.stderr.splitlines()[-1])
    assert (got["field"], got["message"]) == (want.value.field, str(want.value))


def test_node_extrapolates_when_asked_like_the_predictor(node, sealed, tmp_path):
    rows = [BASE, {**BASE, "frequency_hz": 300.0, "skin_E_kPa": 10.0}]
    want = load_predictor(sealed["nn-default"]).predict(columns(rows), extrapolate=True)
    run = run_node(node, sealed["nn-default"], rows, tmp_path, "--extrapolate")
    got = json.loads(run.stdout)["outputs"]
    assert got["extrapolated"] == [False, True] == want["extrapolated"].tolist()
    assert max_rel(got["profile_um"], want["profile_um"]) <= RTOL


@pytest.mark.parametrize("damage", ["card edited", "graph changed", "extra file", "unsealed",
                                    "path in files"])
def test_node_refuses_a_damaged_model(node, sealed, tmp_path, damage):
    import shutil

    model = tmp_path / "m"
    shutil.copytree(sealed["nn-default"], model)
    card = json.loads((model / "card.json").read_text())
    if damage == "card edited":
        card["inputs"][12]["high"] = 300.0
    elif damage == "graph changed":
        (model / "model.onnx").write_bytes((model / "model.onnx").read_bytes() + b"\0")
    elif damage == "extra file":
        (model / "notes.txt").write_text("x")
    elif damage == "unsealed":
        del card["card_sha256"]
    else:  # a listed name that leaves the directory, resealed so only the name is wrong
        from embed_cases import canonical_sha256

        card["files"] = {"../nn-default/model.onnx": card["files"]["model.onnx"]}
        card["card_sha256"] = canonical_sha256(card)
    (model / "card.json").write_text(json.dumps(card, indent=1))
    run = run_node(node, model, [BASE], tmp_path)
    assert run.returncode == 2, run.stdout
    got = json.loads(run.stderr.splitlines()[-1])
    assert got["error"] == "ModelFileError"
    assert got["field"] in {"card_sha256", "files"}


def test_js_canonical_json_is_pythons(node, tmp_path):
    """The card digest's canonical text, rebuilt in JS from the file's literals, equals
    Python's json.dumps(sort_keys, compact, ensure_ascii=False) for awkward values."""
    card = {"format": "hapticrom-model", "z": [1e-05, 0.0001, 1e16, 9999999999999998.0,
            1.5e300, -0.0, 0.1 + 0.2, 3.0, 6.550000000000001, -2.5e-310],
            "ints": [0, -3, 123456789012345678901234567890], "é": "ünï\u2028\"\\\n\t\x01",
            "a": {"b": True, "c": None, "B": False, "\U0001f600": "astral", "\uffff": 1},
            "card_sha256": "ignored"}
    src = tmp_path / "card.json"
    src.write_text(json.dumps(card, indent=2, ensure_ascii=False), encoding="utf-8")
    js = ("import { canonicalCardText } from './lib/hapticrom-model.mjs';"
          "import { readFileSync } from 'node:fs';"
          "process.stdout.write(canonicalCardText(readFileSync(process.argv[1], 'utf8')));")
    run = subprocess.run([node, "--input-type=module", "-e", js, str(src)], cwd=EMBED,
                         capture_output=True, timeout=60, check=True)
    want = json.dumps({k: v for k, v in card.items() if k != "card_sha256"}, sort_keys=True,
                      separators=(",", ":"), ensure_ascii=False)
    assert run.stdout.decode("utf-8") == want
