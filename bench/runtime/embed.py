"""What an embedding app pays: installed size of the run-time distribution and the time from
``import`` to the first answer.

    python bench/runtime/embed.py [--venv DIR] [--find-links /opt/wheels] [--runs 5]

Builds the hapticrom-runtime and hapticrom-models wheels from packaging/, creates a fresh venv
(or reuses ``--venv``), ``pip install``s the two wheels there (numpy and onnxruntime come from
``--find-links`` or PyPI) and reports:

* the installed size of every distribution in the venv's site-packages, beyond pip itself
  (sum of the files each one's RECORD lists) [MB = 1e6 bytes];
* import-to-first-answer: in a new interpreter started in an empty directory,
  ``from surrogate.runtime import load_model``, ``load_model("nn-default")`` (the sha256 of
  every file checked) and one ``predict`` of one design, timed inside the process [ms]; and
  the whole process (interpreter start to exit) timed outside [ms]; median of ``--runs``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
BASE = {"pip", "setuptools", "wheel"}

SIZES = """
import json
from importlib.metadata import distributions
from pathlib import Path
out = {}
for d in distributions():
    total = 0
    for f in d.files or []:
        p = Path(d.locate_file(f))
        if p.is_file():
            total += p.stat().st_size
    out[d.metadata["Name"]] = total
print(json.dumps(out))
"""

FIRST_ANSWER = """
import time
t0 = time.perf_counter()
from surrogate.runtime import load_model
t1 = time.perf_counter()
model = load_model("nn-default")
t2 = time.perf_counter()
out = model.predict({"orientation": ["forward"], "attachment": ["glued"], "n_rings": [2],
                     "ring_1_E_kPa": [95.0], "ring_2_E_kPa": [260.0], "ring_3_E_kPa": [95.0],
                     "ring_density_kg_m3": [1070.0], "ring_nu": [0.47],
                     "ring_loss_factor": [0.1], "skin_E_kPa": [49.0],
                     "fat_thickness_mm": [14.0], "tissue_loss_factor": [0.3],
                     "frequency_hz": [200.0]})
t3 = time.perf_counter()
assert out["center_amplitude_um"][0] > 0
import json, sys
print(json.dumps({"import_ms": 1e3 * (t1 - t0), "load_ms": 1e3 * (t2 - t1),
                  "predict_ms": 1e3 * (t3 - t2), "total_ms": 1e3 * (t3 - t0),
                  "modules": sorted({m.split(".")[0] for m in sys.modules
                                     if m.split(".")[0] in ("scipy", "torch", "sklearn", "fem",
                                                            "pandas", "pyarrow")})}))
"""


def build_wheels(out: Path) -> list[Path]:
    """The two run-time wheels, built from packaging/ into ``out``."""
    can_build = (importlib.util.find_spec("setuptools") is not None
                 and (importlib.util.find_spec("setuptools.command.bdist_wheel") is not None
                      or importlib.util.find_spec("wheel") is not None))
    isolation = ["--no-build-isolation"] if can_build else []
    for dist in ("runtime", "models"):
        subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet",
                        *isolation, "-w", str(out), str(REPO / "packaging" / dist)], check=True)
    return sorted(out.glob("hapticrom_*.whl"))


def install(venv: Path, wheels: list[Path], find_links: str | None) -> float:
    """Create the venv if needed and install the wheels; returns the install time [s]."""
    python = venv / "bin" / "python"
    if not python.exists():
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    links = ["--find-links", find_links] if find_links else []
    t0 = time.perf_counter()
    subprocess.run([str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                    *links, *map(str, wheels)], check=True)
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--venv", type=Path, help="venv to create or reuse (default: a temporary one)")
    ap.add_argument("--find-links", help="a directory of wheels to prefer (e.g. /opt/wheels)")
    ap.add_argument("--runs", type=int, default=5, help="first-answer runs (median reported)")
    ap.add_argument("--compare-full", action="store_true",
                    help="also install the full distribution (pip install '.[runtime]') in a "
                    "second fresh venv and report its size")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-embed-") as tmp:
        tmp_path = Path(tmp)
        wheels = build_wheels(tmp_path / "wheels")
        wheel_mb = {w.name: w.stat().st_size / 1e6 for w in wheels}
        venv = args.venv or tmp_path / "venv"
        seconds = install(venv, wheels, args.find_links)
        python = str(venv / "bin" / "python")
        sizes = json.loads(subprocess.run([python, "-c", SIZES], capture_output=True, text=True,
                                          check=True).stdout)
        empty = tmp_path / "empty"
        empty.mkdir()
        runs, walls = [], []
        for _ in range(args.runs):
            t0 = time.perf_counter()
            run = subprocess.run([python, "-c", FIRST_ANSWER], cwd=empty, capture_output=True,
                                 text=True, check=True)
            walls.append(1e3 * (time.perf_counter() - t0))
            runs.append(json.loads(run.stdout))
    print(f"hapticrom-runtime + hapticrom-models in a fresh venv (pip install {seconds:.0f} s)")
    print(f"{'distribution':24s} {'installed MB':>12s}")
    ours = {k: v for k, v in sizes.items() if k.lower() not in BASE}
    for name, size in sorted(ours.items(), key=lambda kv: -kv[1]):
        print(f"{name:24s} {size / 1e6:12.2f}")
    print(f"{'total (without pip)':24s} {sum(ours.values()) / 1e6:12.2f}")
    print("wheels: " + ", ".join(f"{name} {mb:.2f} MB" for name, mb in wheel_mb.items()))
    med = {k: statistics.median(r[k] for r in runs) for k in runs[0] if k != "modules"}
    print(f"import-to-first-answer (median of {args.runs}, nn-default, one design): "
          f"{med['total_ms']:.0f} ms = import {med['import_ms']:.0f} + load and verify "
          f"{med['load_ms']:.0f} + first predict {med['predict_ms']:.1f}; whole process "
          f"{statistics.median(walls):.0f} ms")
    if args.compare_full:
        with tempfile.TemporaryDirectory(prefix="bench-embed-full-") as tmp:
            full = Path(tmp) / "venv"
            subprocess.run([sys.executable, "-m", "venv", str(full)], check=True)
            subprocess.run([str(full / "bin" / "python"), "-m", "pip", "install", "--quiet",
                            "--disable-pip-version-check", f"{REPO}[runtime]"], check=True)
            sizes = json.loads(subprocess.run([str(full / "bin" / "python"), "-c", SIZES],
                                              capture_output=True, text=True,
                                              check=True).stdout)
        rest = {k: v for k, v in sizes.items() if k.lower() not in BASE}
        top = ", ".join(f"{k} {v / 1e6:.0f}" for k, v in
                        sorted(rest.items(), key=lambda kv: -kv[1])[:6])
        print(f"for comparison, pip install 'hapticrom[runtime]' (the full distribution): "
              f"{sum(rest.values()) / 1e6:.1f} MB ({top} MB, ...)")
    heavy = sorted({m for r in runs for m in r["modules"]})
    print(f"heavy modules imported: {', '.join(heavy) or 'none'}")
    return 0 if not heavy else 1


if __name__ == "__main__":
    sys.exit(main())
