"""The run-time distributions (packaging/runtime, packaging/models): their wheels carry the
run-time code and the models only, declare numpy and onnxruntime as their only dependencies,
and once installed in a fresh environment that holds nothing but numpy and onnxruntime they
load a model by name and answer exactly as the source tree does, and the planner runs."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import onnxruntime
import pytest

from surrogate.runtime import load_predictor

REPO = Path(__file__).resolve().parents[2]
DESIGNS = {"orientation": ["forward", "reverse", "forward"], "attachment": ["glued", "pogo",
           "pogo"], "n_rings": [0, 2, 3], "ring_1_E_kPa": [95.0, 260.0, 1016.0],
           "ring_2_E_kPa": [95.0, 30.0, 260.0], "ring_3_E_kPa": [95.0, 95.0, 1400.0],
           "ring_density_kg_m3": [1070.0, 1000.0, 1400.0], "ring_nu": [0.47, 0.45, 0.49],
           "ring_loss_factor": [0.1, 0.05, 0.25], "skin_E_kPa": [49.0, 25.0, 110.0],
           "fat_thickness_mm": [14.0, 4.0, 19.0], "tissue_loss_factor": [0.3, 0.15, 0.45],
           "frequency_hz": [200.0, 120.0, 240.0]}


# offline with this environment's setuptools when it can build wheels by itself (>= 70.1, or
# with the wheel package); otherwise pip fetches a build environment
_CAN_BUILD = (importlib.util.find_spec("setuptools") is not None
              and (importlib.util.find_spec("setuptools.command.bdist_wheel") is not None
                   or importlib.util.find_spec("wheel") is not None))
ISOLATION = ["--no-build-isolation"] if _CAN_BUILD else []


def _wheel(dist: str, out: Path) -> Path:
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", *ISOLATION,
                    "--quiet", "-w", str(out), str(REPO / "packaging" / dist)], check=True)
    return next(out.glob(f"hapticrom_{dist}-*.whl"))


@pytest.fixture(scope="module")
def wheels(tmp_path_factory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("wheels")
    return {d: _wheel(d, out) for d in ("runtime", "models")}


def _metadata(wheel: Path) -> list[str]:
    with zipfile.ZipFile(wheel) as z:
        name = next(n for n in z.namelist() if n.endswith(".dist-info/METADATA"))
        return z.read(name).decode().splitlines()


def test_runtime_wheel_carries_the_runtime_only(wheels):
    names = zipfile.ZipFile(wheels["runtime"]).namelist()
    tops = {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")}
    assert tops == {"surrogate", "planner", "fieldspec", "figstyle", "motorlaw", "calibration"}
    surrogate = {n for n in names if n.startswith("surrogate/")}
    assert surrogate == {"surrogate/__init__.py"} | {
        f"surrogate/runtime/{p.name}" for p in (REPO / "surrogate/runtime").glob("*.py")}
    requires = [line.split(":", 1)[1].strip() for line in _metadata(wheels["runtime"])
                if line.startswith("Requires-Dist:") and "extra ==" not in line]
    assert sorted(r.split(">")[0] for r in requires) == ["numpy", "onnxruntime"]


def test_models_wheel_carries_every_model_with_its_card(wheels):
    z = zipfile.ZipFile(wheels["models"])
    names = set(z.namelist())
    shipped = sorted(p.name for p in (REPO / "models").iterdir() if (p / "card.json").is_file())
    assert shipped
    for model in shipped:
        card = json.loads(z.read(f"hapticrom_models/{model}/card.json"))
        assert card == json.loads((REPO / "models" / model / "card.json").read_text())
        listed = {f"hapticrom_models/{model}/{f}" for f in card["files"]}
        present = {n for n in names if n.startswith(f"hapticrom_models/{model}/")}
        assert present == listed | {f"hapticrom_models/{model}/card.json"}
    entry = z.read(next(n for n in names if n.endswith("entry_points.txt"))).decode()
    assert "[hapticrom.models]" in entry and "= hapticrom_models" in entry


def _isolated_env(tmp: Path, wheels: dict[str, Path]) -> Path:
    """A venv with the two wheels and nothing else but numpy and onnxruntime (linked from this
    environment through a .pth directory; no scipy, no fem, no hapticrom source tree)."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(tmp / "venv")],
                   check=True)
    python = tmp / "venv" / "bin" / "python"
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install",
                    "--no-deps", "--no-index", "--quiet", *map(str, wheels.values())],
                   check=True)
    deps = tmp / "deps"
    deps.mkdir()
    for module in (np, onnxruntime):
        where = Path(module.__file__).parent
        for p in where.parent.glob(f"{where.name}*"):  # numpy, numpy.libs, *.dist-info
            (deps / p.name).symlink_to(p)
    site = next((tmp / "venv" / "lib").glob("python3*/site-packages"))
    (site / "deps.pth").write_text(str(deps) + "\n")
    return python


SCRIPT = """
import json, sys
try:
    import scipy
    sys.exit("scipy importable")
except ImportError:
    pass
from surrogate.runtime import load_model
from surrogate.runtime.models import list_models
import planner
p = load_model("nn-default")
out = p.predict(json.loads(sys.argv[1]))
plan = planner.plan_layout(planner.load_layout(sys.argv[2]))
print(json.dumps({"names": sorted(list_models()), "where": str(list_models()["nn-default"]),
                  "center": out["center_amplitude_um"].tolist(),
                  "profile": out["profile_um"].tolist(), "plan_ok": plan is not None,
                  "surrogate": __import__("surrogate").__file__,
                  "modules": sorted(m for m in sys.modules if m.split(".")[0] in
                                    ("scipy", "fem", "torch", "sklearn", "hapticrom"))}))
"""


def test_installed_runtime_answers_like_the_tree(wheels, tmp_path):
    python = _isolated_env(tmp_path, wheels)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "HAPTICROM_MODEL_PATH")}
    layout = tmp_path / "layout.toml"  # the example, its model paths made absolute
    layout.write_text((REPO / "examples/forearm-layout.toml").read_text()
                      .replace('"models/', f'"{REPO}/models/'))
    run = subprocess.run([str(python), "-c", SCRIPT, json.dumps(DESIGNS), str(layout)],
                         cwd=tmp_path, env=env,
                         capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)
    assert got["modules"] == []
    assert "site-packages" in got["surrogate"]
    assert Path(got["where"]).parent.name == "hapticrom_models"
    assert {"nn-default", "gp-default", "rom-default"} <= set(got["names"])
    assert got["plan_ok"]
    want = load_predictor(REPO / "models/nn-default").predict(DESIGNS)
    np.testing.assert_array_equal(got["center"], want["center_amplitude_um"])
    np.testing.assert_array_equal(got["profile"], want["profile_um"])
