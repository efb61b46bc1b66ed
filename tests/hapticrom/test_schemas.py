"""Every JSON document the command line writes conforms to its shipped JSON Schema (one per
analysis kind of `simulate`, `predict`, `dataset info`), the checker catches a broken document,
and documents of the unversioned layout before schema version 1 are still read."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from schema_check import problems

from fem import simulate
from fem.output import SCHEMA_VERSION, read_result
from fem.scene import load_scene, scene_from_dict, scene_hash, scene_to_dict
from hapticrom.cli import main
from hapticrom.documents import schema

COARSE = {"order": 1, "near_size_mm": 1.0, "far_size_mm": 4.0}


def _scene(path: str, **analysis):
    d = scene_to_dict(load_scene(path))
    d["mesh"].update(COARSE)
    d["tissue"]["radius_mm"] = 25.0
    d["analysis"].update(analysis)
    return scene_from_dict(d)


@pytest.fixture(scope="module")
def documents():
    """One solved document per analysis kind (coarse meshes; a 6 ms transient)."""
    scenes = {
        "harmonic": _scene("examples/forearm.toml", kind="harmonic"),
        "static": _scene("examples/forearm.toml", kind="static"),
        "transient": _scene("examples/unit-transient.toml", duration_ms=6.0,
                            time_step_ms=0.2, voltage_schedule=[[0.0, 3.3], [4.0, 0.0]]),
        "sweep": _scene("examples/unit-bare-forward.toml", kind="sweep",
                        frequency_hz=[110.0, 160.0, 210.0]),
    }
    out = {}
    for kind, scene in scenes.items():
        res = simulate(scene)
        out[kind] = (res, json.loads(json.dumps(res.to_dict(f"{kind}.toml"))))
    return out


@pytest.mark.parametrize("kind", ["harmonic", "static", "transient", "sweep"])
def test_simulate_document_conforms_to_its_schema(documents, kind):
    res, doc = documents[kind]
    assert problems(doc, schema(f"simulate-{kind}")) == []
    assert doc["schema_version"] == SCHEMA_VERSION == 1
    assert doc["scene"]["digest"] == scene_hash(res.scene)
    assert doc["scene"]["name"] == f"{kind}.toml"
    assert doc["analysis"]["kind"] == kind
    # the other kinds' schemas refuse it: the names say what the values are
    for other in {"harmonic", "static", "transient", "sweep"} - {kind}:
        assert problems(doc, schema(f"simulate-{other}"))


def test_sweep_values_are_lists_over_the_band(documents):
    res, doc = documents["sweep"]
    assert doc["analysis"]["frequency_hz"] == [110.0, 160.0, 210.0]
    z = (np.asarray(doc["centre"]["ur_complex_um"]["re"])
         + 1j * np.asarray(doc["centre"]["ur_complex_um"]["im"]))
    assert np.allclose(z, res.center[:, 0] * 1e6)
    assert np.asarray(doc["profile"]["magnitude_um"]).shape == res.profile.shape[:2]
    assert doc["reduced_model"]["full_solves"] == res.full_solves


def test_harmonic_values_amplitudes_and_complex_agree(documents):
    res, doc = documents["harmonic"]
    assert doc["analysis"]["frequency_hz"] == pytest.approx(120.0)
    assert "omega" in doc["analysis"]["phase_reference"]
    for c, k in (("ur", 0), ("uz", 1), ("ut", 2)):
        z = (np.asarray(doc["surface"][f"{c}_complex_um"]["re"])
             + 1j * np.asarray(doc["surface"][f"{c}_complex_um"]["im"]))
        assert np.allclose(z, res.U[:, k] * 1e6)
        assert np.allclose(np.abs(z), doc["surface"][f"{c}_amplitude_um"])
    assert doc["centre"]["magnitude_um"] == pytest.approx(res.center_amplitude_um)
    assert doc["edge"]["radius_mm"] == doc["definitions"]["edge"]["radius_mm"] == res.edge_mm
    assert doc["normalized_edge"] == pytest.approx(
        doc["edge"]["magnitude_um"] / doc["centre"]["magnitude_um"])


def test_static_document_has_no_frequency_and_signed_values(documents):
    res, doc = documents["static"]
    assert doc["analysis"]["frequency_hz"] is None
    assert doc["analysis"]["phase_reference"] is None
    assert np.allclose(doc["surface"]["ur_displacement_um"], np.real(res.U[:, 0]) * 1e6)


def test_transient_document_holds_centre_and_edge_histories(documents):
    res, doc = documents["transient"]
    h = doc["histories"]
    labels = [p["label"] for p in h["points"]]
    assert labels.count("centre") == 1 and labels.count("edge") == 1
    edge = h["points"][labels.index("edge")]
    assert edge["radius_mm"] == pytest.approx(res.edge_mm)
    assert len(edge["uz_um"]) == len(h["t_ms"]) == res.histories.t.size
    # the peak of a component over the run is the peak stored for that point
    centre = h["points"][labels.index("centre")]
    assert max(abs(v) for v in centre["ur_um"]) == pytest.approx(doc["centre"]["ur_peak_um"])
    assert doc["definitions"]["centre"]["z_mm"] == pytest.approx(res.centre_z_mm) != 0.0


@pytest.mark.parametrize(("path", "change"), [
    ("surface.uz_amplitude_um", lambda s: {"re": [1.0], "im": [0.0]}),  # complex as magnitude
    ("schema_version", lambda v: 0),
    ("analysis.frequency_hz", lambda v: None),
    ("surface.magnitude_um", lambda v: [-1.0]),
    ("edge", lambda v: {"radius_mm": 1.0}),
])
def test_the_checker_catches_a_broken_document(documents, path, change):
    doc = copy.deepcopy(documents["harmonic"][1])
    *parents, last = path.split(".")
    target = doc
    for p in parents:
        target = target[p]
    target[last] = change(target[last])
    assert problems(doc, schema("simulate-harmonic"))
    missing = copy.deepcopy(documents["harmonic"][1])
    del missing["definitions"]
    assert "missing key 'definitions'" in " ".join(problems(missing,
                                                            schema("simulate-harmonic")))


def test_predict_and_dataset_info_documents_conform(tmp_path, capsys):
    out = tmp_path / "p.json"
    assert main(["predict", "models/nn-default", "--csv", "examples/designs.csv",
                 "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert problems(doc, schema("predict")) == []
    assert doc["rows"] == len(doc["outputs"]["centre_magnitude_um"]) > 0
    capsys.readouterr()
    assert main(["dataset", "info", "datasets/transient", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert problems(info, schema("dataset-info")) == []


@pytest.mark.parametrize("kind", ["harmonic", "transient"])
def test_unversioned_documents_are_still_read(documents, kind):
    res, new = documents[kind]
    old = json.loads(json.dumps(res.to_dict_v0()))
    assert "schema_version" not in old
    conv = read_result(old)
    assert conv["schema_version"] == 1 and conv["converted_from"] == 0
    assert conv["analysis"]["kind"] == kind
    mag = "magnitude_of_peaks_um" if kind == "transient" else "magnitude_um"
    assert np.allclose(conv["surface"][mag], new["surface"][mag])
    assert np.allclose(conv["profile"][mag], new["profile"][mag])
    assert conv["centre"]["magnitude_um"] == pytest.approx(res.center_amplitude_um)
    assert read_result(new) is new


def test_read_result_refuses_unknown_versions_naming_the_key():
    with pytest.raises(ValueError, match="schema_version = 7"):
        read_result({"schema_version": 7})
    with pytest.raises(ValueError, match="'surface'"):
        read_result({"profile": {}})
