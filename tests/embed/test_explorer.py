"""The design explorer (embed/explorer), built by `hapticrom explore`'s builder and served by
its server, in a real headless chromium: it loads with every other origin blocked, a slider
moved with the keyboard updates the plot and the numbers, and for 20 random designs the
numbers on the page equal the Python predictor's."""

from __future__ import annotations

import json
import subprocess
import threading

import numpy as np
import pytest
from embed_cases import EMBED, columns, random_designs

from hapticrom.commands.explore import build_explorer, make_server
from surrogate.runtime import load_predictor
from surrogate.runtime.defaults import is_sweep_model

RTOL = 1e-6
SCALE = 2.1  # the largest interval_calibration factor of the shipped models (nn-default 2.09)
Z95 = 1.959964


@pytest.fixture(scope="module", params=["nn-default", "sweep", "gp-sweep"])
def page(request, chromium, node, sealed, tmp_path_factory):
    """Build, serve, drive the page once per model (nn-default; a sweep-trained network, its
    profile to 40 mm; the shipped float64 sweep GP); the check script's report and the
    designs."""
    model = (request.getfixturevalue("sweep_model") if request.param == "sweep" else
             sealed[request.param])
    tmp = tmp_path_factory.mktemp("explorer")
    site = build_explorer(str(model), tmp / "site")
    server = make_server(site, port=0)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    predictor = load_predictor(model)
    designs = random_designs(predictor.card, 20, seed=7)
    (tmp / "designs.json").write_text(json.dumps(designs))
    try:
        run = subprocess.run([node, "explorer/check.mjs", "--url",
                              f"http://127.0.0.1:{server.server_address[1]}/",
                              "--designs", str(tmp / "designs.json"), "--out",
                              str(tmp / "result.json"), "--chromium", chromium,
                              "--screenshot", str(tmp / "shot.png")],
                             cwd=EMBED, capture_output=True, text=True, timeout=180, check=False)
    finally:
        server.shutdown()
        server.server_close()
    assert run.returncode == 0, run.stderr
    return json.loads((tmp / "result.json").read_text()), designs, predictor, tmp


def test_loads_offline_without_errors(page):
    result, _, _, tmp = page
    assert result["offline"] == []  # nothing asked of another origin (no CDN)
    assert result["errors"] == []
    assert (tmp / "shot.png").stat().st_size > 10_000


def test_a_slider_change_redraws_the_plot(page):
    result, _, predictor, _ = page
    before, after = result["slider"]["before"], result["slider"]["after"]
    high = predictor.input_ranges["frequency_hz"][1]
    assert before["frequency_hz"] < high == after["frequency_hz"]  # End key: the range's end
    assert after["runs"] == before["runs"] + 1 and after["status"] == ""
    assert after["mean"] != before["mean"] and after["band"] != before["band"]
    assert after["center"] != before["center"]


def test_page_numbers_equal_the_python_predictor(page):
    result, designs, predictor, _ = page
    want = predictor.predict(columns(designs))
    band = {"profile_um_low95": want["profile_um"] * np.exp(-Z95 * want["profile_um_log_std"]),
            "profile_um_high95": want["profile_um"] * np.exp(Z95 * want["profile_um_log_std"])}
    # A sweep graph decodes each magnitude from complex components in float32: where they
    # nearly cancel (a dip of the profile) the two runtimes' float32 sums differ by more than
    # 1e-6 of the value, not of the field; so for it the tolerance is on the field's scale
    # (the design's largest value of that output), as the sweep cards' largest error is.
    field_scale = is_sweep_model(predictor.card)
    worst = worst_field = 0.0
    for i, got in enumerate(result["designs"]):
        assert got["status"] == ""
        assert len(got["profile_um"]) == predictor.profile_distance_mm.size  # 40 mm: sweep
        for key in ("center_amplitude_um", "edge_amplitude_um", "normalized_edge",
                    "edge_radius_mm", "profile_um", "profile_um_low95", "profile_um_high95"):
            ref = band[key][i] if key in band else want[key][i]
            # a band's exponent carries 1.96 x the card's interval factor (up to 2.1) x the
            # log-std's own difference between the two runtimes
            tol = RTOL * (1 + Z95 * SCALE) if key in band else RTOL
            scale = float(np.max(np.abs(ref)))
            np.testing.assert_allclose(got[key], ref, rtol=0 if field_scale else tol,
                                       atol=tol * scale if field_scale else 0,
                                       err_msg=f"design {i}: {key}")
            diff = np.abs(np.subtract(got[key], ref))
            worst = max(worst, float(np.max(diff / np.abs(ref))))
            worst_field = max(worst_field, float(np.max(diff)) / scale)
    print(f"explorer vs Python, 20 designs: max relative difference {worst:.2e}, on the "
          f"field's scale {worst_field:.2e}")


def test_array_preview_follows_the_planner(page):
    """The page's neighbour amplitude and worst leakage are the planner's crosstalk rules
    (planner/crosstalk.py) applied to the page's own predicted profile."""
    from planner.crosstalk import UnitField, crosstalk_matrix, leakage_ratio, site_positions

    result, _, predictor, _ = page
    for got in result["designs"]:
        a = got["array"]
        field = UnitField(got["center_amplitude_um"], got["edge_radius_mm"],
                          predictor.profile_distance_mm, np.asarray(got["profile_um"]))
        pitch = max(a["pitch"], 2 * got["edge_radius_mm"])
        C = crosstalk_matrix(field, site_positions(a["rows"], a["cols"], pitch, a["grid"]))
        np.testing.assert_allclose(a["neighbour_um"], field.amplitude(np.array([pitch]))[0],
                                   rtol=1e-9)
        np.testing.assert_allclose(a["worst_leakage"], leakage_ratio(C, "incoherent").max(),
                                   rtol=1e-9)


def test_explore_refuses_an_unsealed_or_non_predictor_model(tmp_path, capsys):
    import shutil

    from embed_cases import REPO

    from hapticrom.cli import main

    unsealed = tmp_path / "nn"
    shutil.copytree(REPO / "models/nn-default", unsealed)
    card = json.loads((unsealed / "card.json").read_text())
    card.pop("card_sha256", None)
    (unsealed / "card.json").write_text(json.dumps(card))
    site = tmp_path / "site"
    assert main(["explore", str(unsealed), "--build-only", "--out", str(site)]) == 2
    assert "card_sha256" in capsys.readouterr().err
    from embed_cases import seal_copy

    rom = seal_copy("rom-default", tmp_path)
    assert main(["explore", str(rom), "--build-only", "--out", str(site)]) == 2
    assert "'rom' model" in capsys.readouterr().err
    assert not site.exists()  # nothing written


def test_explore_builds_once_then_reuses(node, sealed, tmp_path, capsys):
    from hapticrom.cli import main

    site = tmp_path / "site"
    assert main(["explore", str(sealed["nn-default"]), "--build-only", "--out", str(site)]) == 0
    stamp = (site / "build.json").stat().st_mtime_ns
    assert sorted(p.name for p in (site / "model").iterdir()) == ["card.json", "model.onnx"]
    assert (site / "ort" / "ort-wasm-simd-threaded.wasm").is_file()
    assert main(["explore", str(sealed["nn-default"]), "--build-only", "--out", str(site)]) == 0
    assert (site / "build.json").stat().st_mtime_ns == stamp  # up to date: not rebuilt
    assert not (tmp_path / "site.building").exists()
