"""One integrity envelope per model directory (issue 21, item 2): every defect found by
altering the shipped models is refused with exit 2, a message naming the file and the check,
and no traceback; ``models list`` reports every model and never aborts."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from model_dirs import SHIPPED, copy_model, read, reseal, write

from hapticrom.cli import main
from surrogate.runtime import ModelFileError, load_envelope_model, load_predictor
from surrogate.runtime.card import card_digest, seal_card, verify_model_dir


def _point(**override) -> dict:
    """A design inside the shipped models' ranges (categoricals at their first choice)."""
    card = json.loads((SHIPPED["nn"] / "card.json").read_text())
    point = {s["name"]: (s["choices"][0] if s.get("choices") else
                         round(0.5 * (s["low"] + s["high"]), 6)) for s in card["inputs"]}
    point["n_rings"] = 2
    return {**point, **override}


def _args(point: dict) -> list[str]:
    return [a for k, v in point.items() for a in ("--set", f"{k}={v}")]


POINT = _args(_point())


def refused(argv: list[str], capsys, *words: str) -> str:
    """Run the command line; assert exit 2, no traceback, and ``words`` in the message."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    for w in words:
        assert w in err, (w, err)
    return err


def test_shipped_models_are_sealed_and_verify():
    for d in SHIPPED.values():
        card = verify_model_dir(d)
        assert card["card_sha256"] == card_digest(card)
    raw = json.loads((SHIPPED["gp"] / "card.json").read_text())
    body = {k: v for k, v in raw.items() if k != "card_sha256"}
    canon = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    import hashlib

    assert raw["card_sha256"] == hashlib.sha256(canon.encode("utf-8")).hexdigest()
    assert seal_card(body)["card_sha256"] == raw["card_sha256"]


def test_trained_cards_are_sealed(trained_models):
    for path, _ in trained_models.values():
        assert "card_sha256" in read(path)
        verify_model_dir(path)


def test_a_widened_input_range_in_the_card_is_refused(tmp_path, capsys):
    """Before: predict --set skin_E_kPa=1e7 answered with no extrapolation flag."""
    d = copy_model("nn", tmp_path / "m")
    card = read(d)
    for spec in card["inputs"]:
        if spec["name"] == "skin_E_kPa":
            spec["high"] = 1e8
    write(d, card)
    assert main(["predict", str(SHIPPED["nn"]), *_args(_point(skin_E_kPa=1e7))]) == 2
    assert "skin_E_kPa" in capsys.readouterr().err  # out of range for the sealed card
    refused(["predict", str(d), *_args(_point(skin_E_kPa=1e7))], capsys,
            "card.json", "card digest")


def test_a_flipped_byte_with_the_file_digest_recomputed_is_refused(tmp_path, capsys):
    d = copy_model("gp", tmp_path / "m")
    data = bytearray((d / "model.onnx").read_bytes())
    data[len(data) // 2] ^= 0x01
    (d / "model.onnx").write_bytes(bytes(data))
    card = read(d)
    import hashlib

    card["files"]["model.onnx"] = hashlib.sha256(bytes(data)).hexdigest()
    write(d, card)  # the file digest matches, the card digest does not
    refused(["predict", str(d), *POINT], capsys, "card.json", "card digest")


@pytest.mark.parametrize("where", ["../_evil/model.onnx", "ABS", "sub/model.onnx"])
def test_a_graph_file_outside_the_directory_is_refused(tmp_path, capsys, where):
    """Before: ../_evil/model.onnx (or an absolute path) was loaded and answered from."""
    d = copy_model("gp", tmp_path / "m")
    evil = tmp_path / "_evil"
    evil.mkdir()
    (evil / "model.onnx").write_bytes((d / "model.onnx").read_bytes())
    name = str(evil / "model.onnx") if where == "ABS" else where
    card = read(d)
    card["graph"]["file"] = name
    card["files"] = {name: card["files"]["model.onnx"]}
    (d / "model.onnx").unlink()
    reseal(d, card)
    err = refused(["predict", str(d), *POINT], capsys, "check: path")
    assert name in err
    assert main(["models", "list", "--root", str(tmp_path)]) == 2
    out = capsys.readouterr().out
    assert "m " in out and "refused" in out and "check: path" in out


def test_graph_file_not_listed_is_refused(tmp_path, capsys):
    d = copy_model("gp", tmp_path / "m")
    card = read(d)
    card["graph"]["file"] = "other.onnx"
    reseal(d, card)
    refused(["predict", str(d), *POINT], capsys, "graph.file", "named files")


def test_a_symlinked_model_file_is_refused(tmp_path, capsys):
    d = copy_model("gp", tmp_path / "m")
    outside = tmp_path / "outside.onnx"
    os.replace(d / "model.onnx", outside)
    os.symlink(outside, d / "model.onnx")
    refused(["predict", str(d), *POINT], capsys, "model.onnx", "symlink", "check: path")


def test_a_rom_coefficients_file_outside_is_refused(tmp_path):
    d = copy_model("rom", tmp_path / "m")
    card = read(d)
    card["coefficients"] = "../c.json"
    card["files"] = {"../c.json": card["files"]["coefficients.json"]}
    (tmp_path / "c.json").write_bytes((d / "coefficients.json").read_bytes())
    (d / "coefficients.json").unlink()
    reseal(d, card)
    with pytest.raises(ModelFileError, match=r"\.\./c\.json.*check: path"):
        load_envelope_model(d)


def test_an_unlisted_file_is_refused(tmp_path, capsys):
    d = copy_model("nn", tmp_path / "m")
    (d / "notes.txt").write_text("x")
    refused(["models", "show", str(d)], capsys, "notes.txt", "unlisted")


def _graph(nodes, opsets, inits=()):
    from onnx import TensorProto, helper

    g = helper.make_graph(nodes, "g",
                          [helper.make_tensor_value_info("x", TensorProto.FLOAT, [None, 5])],
                          [helper.make_tensor_value_info(n, TensorProto.FLOAT, [None, None])
                           for n in ("log_mean", "log_std")], initializer=list(inits))
    m = helper.make_model(g, opset_imports=opsets)
    m.ir_version = 10
    return m.SerializeToString()


def _custom_op() -> bytes:
    from onnx import helper

    return _graph([helper.make_node("Evil", ["x"], ["log_mean"], domain="com.evil"),
                   helper.make_node("Identity", ["x"], ["log_std"])],
                  [helper.make_opsetid("", 18), helper.make_opsetid("com.evil", 1)])


def _external_data() -> bytes:
    from onnx import TensorProto, helper, numpy_helper

    t = numpy_helper.from_array(np.ones((1,), np.float32), "w")
    t.ClearField("raw_data")
    t.data_location = TensorProto.EXTERNAL
    for k, v in (("location", "w.bin"), ("offset", "0"), ("length", "4")):
        e = t.external_data.add()
        e.key, e.value = k, v
    return _graph([helper.make_node("Add", ["x", "w"], ["log_mean"]),
                   helper.make_node("Identity", ["x"], ["log_std"])],
                  [helper.make_opsetid("", 18)], [t])


def _wrong_contract() -> bytes:
    from onnx import helper

    return _graph([helper.make_node("Identity", ["x"], ["log_mean"]),
                   helper.make_node("Identity", ["x"], ["log_std"])],
                  [helper.make_opsetid("", 18)])


@pytest.mark.parametrize("make", [lambda: b"not a protobuf \x00\xff" * 10, _custom_op,
                                  _external_data, _wrong_contract],
                         ids=["invalid", "custom-op", "external-data", "wrong-contract"])
def test_a_bad_graph_is_a_named_refusal(tmp_path, capsys, make):
    """Before: InvalidProtobuf and friends with exit 1 and a traceback; `models list` ok."""
    d = copy_model("nn", tmp_path / "m")
    (d / "model.onnx").write_bytes(make())
    (tmp_path / "w.bin").write_bytes(np.ones(1, np.float32).tobytes())
    reseal(d)
    cwd = os.getcwd()
    os.chdir(tmp_path)  # an external-data file in the working directory is not used either
    try:
        refused(["predict", str(d), *POINT], capsys, "model.onnx", "check: graph")
    finally:
        os.chdir(cwd)
    assert main(["models", "list", "--root", str(tmp_path)]) == 2
    out = capsys.readouterr().out
    assert "m " in out and "refused" in out and "model.onnx" in out


@pytest.mark.parametrize("key", ["inputs", "graph", "edge_radius", "profile_distance_mm"])
def test_a_card_missing_a_key_is_a_named_refusal(tmp_path, capsys, key):
    """Before: KeyError 'inputs', exit 1."""
    d = copy_model("gp", tmp_path / "m")
    card = read(d)
    del card[key]
    reseal(d, card)
    refused(["predict", str(d), *POINT], capsys, key, "check: keys")


def test_a_malformed_card_value_is_a_named_refusal(tmp_path, capsys):
    d = copy_model("gp", tmp_path / "m")
    card = read(d)
    card["inputs"][0] = {"name": 3}
    reseal(d, card)
    refused(["predict", str(d), *POINT], capsys, "card.json", "check: card values")


def test_a_deep_or_undecodable_card_is_a_named_refusal_and_list_goes_on(tmp_path, capsys):
    """Before: RecursionError (deep card), a UTF-8 error with no file name, and `models list`
    printing nothing at all."""
    root = tmp_path / "models"
    root.mkdir()
    deep, binary = copy_model("gp", root / "a-deep"), copy_model("gp", root / "b-binary")
    copy_model("rom", root / "c-good")
    text = (deep / "card.json").read_text()
    (deep / "card.json").write_text(text[:-3] + ', "x": ' + "[" * 1000 + "]" * 1000 + "}\n")
    (binary / "card.json").write_bytes(b"\xff\xfe" + (binary / "card.json").read_bytes())
    refused(["predict", str(deep), *POINT], capsys, "card.json", "nested deeper")
    refused(["predict", str(binary), *POINT], capsys, "card.json", "not UTF-8")
    assert main(["models", "list", "--root", str(root)]) == 2
    captured = capsys.readouterr()
    lines = captured.out.splitlines()
    assert [ln.split()[0] for ln in lines] == ["a-deep", "b-binary", "c-good"]
    assert "refused" in lines[0] and "refused" in lines[1] and "refused" not in lines[2]
    assert "Traceback" not in captured.err


def test_an_unsealed_card_is_refused(tmp_path):
    d = copy_model("rom", tmp_path / "m")
    card = read(d)
    del card["card_sha256"]
    write(d, card)
    with pytest.raises(ModelFileError, match="not sealed"):
        load_envelope_model(d)


def test_loading_the_shipped_models_still_works():
    p = load_predictor(SHIPPED["nn"])
    out = p.predict({k: [v] for k, v in _point().items()})
    assert np.isfinite(out["center_amplitude_um"]).all()
    assert load_envelope_model(SHIPPED["rom"]).input_names


@pytest.mark.parametrize("edit", ["motor_ranges", "feature_columns", "weights", "clip",
                                  "motor"])
def test_a_resealed_rom_with_a_malformed_spec_is_refused_at_load(tmp_path, edit):
    """Found by bench/runtime/model_mutations.py: a renamed motor range loaded, then simulate
    failed with KeyError 'tau_spindown_ms'. Everything the model indexes is checked at load."""
    d = copy_model("rom", tmp_path / "m")
    coef = json.loads((d / "coefficients.json").read_text())
    if edit == "motor_ranges":
        coef["motor_ranges"]["tau_spindown_mt"] = coef["motor_ranges"].pop("tau_spindown_ms")
    elif edit == "feature_columns":
        coef["feature_columns"][0] = 10_000
    elif edit == "weights":
        coef["weights"]["center"] = coef["weights"]["center"][:-1]
    elif edit == "clip":
        del coef["clip"]["fn_hz"]
    else:
        coef["motor"]["max_voltage_V"] = 1.0
    (d / "coefficients.json").write_text(json.dumps(coef))
    reseal(d)
    with pytest.raises(ModelFileError, match=r"coefficients\.json: malformed coefficients"):
        load_envelope_model(d)
