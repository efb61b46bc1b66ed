"""`hapticrom simulate`: outputs, what the scene switches on and off, and bad input."""

import json

import numpy as np
import pytest

from fem import simulate
from fem.scene import load_scene, scene_from_dict, scene_to_dict
from hapticrom.cli import main

EXAMPLE = "examples/forearm.toml"


def _scene(**changes):
    d = scene_to_dict(load_scene(EXAMPLE))
    for path, value in changes.items():
        table, key = path.split("__")
        d[table][key] = value
    return scene_from_dict(d)


def test_simulate_writes_json_vtk_and_png(tmp_path, capsys):
    out = {k: tmp_path / f"f.{ext}" for k, ext in (("json", "json"), ("vtk", "vtu"),
                                                    ("plot", "png"))}
    rc = main(["simulate", EXAMPLE, "--json", str(out["json"]), "--vtk", str(out["vtk"]),
               "--plot", str(out["plot"])])
    assert rc == 0
    printed = capsys.readouterr().out
    assert "dofs" in printed and "Fourier modes [1]" in printed
    data = json.loads(out["json"].read_text())
    assert data["schema_version"] == 1 and data["kind"] == "hapticrom.simulate.harmonic"
    assert data["scene"]["name"] == "forearm.toml"
    assert data["analysis"]["frequency_hz"] == pytest.approx(120.0)
    surf = data["surface"]
    n = len(load_scene(EXAMPLE).output.radii_mm)
    for c in ("ur", "ut", "uz"):
        z = np.asarray(surf[f"{c}_complex_um"]["re"]) + 1j * np.asarray(
            surf[f"{c}_complex_um"]["im"])
        assert z.size == n
        assert np.allclose(np.abs(z), surf[f"{c}_amplitude_um"])
    assert len(surf["r_mm"]) == len(surf["magnitude_um"]) == n
    mag = np.sqrt(sum(np.square(surf[f"{c}_amplitude_um"]) for c in ("ur", "ut", "uz")))
    assert np.allclose(mag, surf["magnitude_um"])
    meta = data["meta"]
    assert meta["modes"] == [1] and meta["dofs"] > 0 and meta["elements"] > 0
    assert data["analysis"]["time_convention"] == "exp(+i omega t)"
    assert data["normalized_edge"] == pytest.approx(
        data["edge"]["magnitude_um"] / data["centre"]["magnitude_um"])
    assert data["edge"]["radius_mm"] == data["definitions"]["edge"]["radius_mm"] > 0
    assert data["profile"]["distance_from_edge_mm"][0] == 0.0

    import meshio

    vtk = meshio.read(out["vtk"])
    assert "magnitude_um" in vtk.point_data and vtk.points.shape[0] > 0
    assert out["plot"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.json", "f.png", "f.vtu"]


@pytest.mark.parametrize(("content", "field"), [
    ("[tissue]\nradius_mm = -1.0\n", "tissue.radius_mm"),
    ("[analysis]\nkind = \"modal\"\n", "analysis.kind"),
    ("[mesh]\norder = 3\n", "mesh.order"),
    ("[load]\nradiuss_mm = 2.0\n", "radius_mm"),
])
def test_bad_scene_exits_2_and_writes_nothing(tmp_path, capsys, content, field):
    scene = tmp_path / "bad.toml"
    scene.write_text(content)
    rc = main(["simulate", str(scene), "--json", str(tmp_path / "o.json"),
               "--plot", str(tmp_path / "o.png")])
    assert rc == 2
    assert field in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_missing_scene_file_and_missing_output_directory_exit_2(tmp_path, capsys):
    assert main(["simulate", str(tmp_path / "nope.toml")]) == 2
    assert main(["simulate", EXAMPLE, "--json", str(tmp_path / "no" / "dir.json")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_static_scene_builds_no_mass_and_no_pml():
    res = simulate(_scene(analysis__kind="static"))
    assert not any(op.startswith(("mass", "PML")) for op in res.meta["operators"])
    assert "inertia" in res.meta["skipped"]
    assert "static far field (side)" in res.meta["effects"]


def test_normal_load_solves_mode_0_only():
    res = simulate(_scene(load__direction="normal"))
    assert res.meta["modes"] == [0]
    assert all(op.endswith("[n=0]") for op in res.meta["operators"])
    assert np.all(res.U[:, 2] == 0)  # no torsion is solved or reported


def test_fixed_side_adds_no_absorber_and_loss_factor_switches_hysteresis_on():
    d = scene_to_dict(load_scene(EXAMPLE))
    d["tissue"]["side"] = "fixed"
    for layer in d["tissue"]["layer"]:
        layer["loss_factor"] = 0.0
    res = simulate(scene_from_dict(d))
    assert "PML" not in " ".join(res.meta["operators"])
    assert "absorbing boundary" in res.meta["skipped"]
    assert "hysteretic damping" in res.meta["skipped"]
    d["tissue"]["layer"][0]["loss_factor"] = 0.2
    lossy = simulate(scene_from_dict(d))
    assert "hysteretic damping" in lossy.meta["effects"]
    assert "hysteretic damping[n=1]" in lossy.meta["operators"]
