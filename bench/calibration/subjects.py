"""The FE synthetic subjects of bench/calibration/calibrate.py: known tissue across the model's
space, one of the paper's three prototypes, 1-3 frequencies, each solved with the FE solver
(fem.simulate on the scene the model's training dataset builds for those inputs).

    .venv/bin/python bench/calibration/subjects.py [--n 50] [--seed 25]

    .venv/bin/python bench/calibration/subjects.py --example
    .venv/bin/python bench/calibration/subjects.py --example-ldv

writes bench/calibration/data/calibration-subjects.json (about a minute on one core): per subject
the true inputs, the design, the frequencies, and the centre and the skin-surface profile (0-20
mm from the unit's edge, the training data's grid), each as the displacement magnitude and as the
normal component |U_z| [um]. The calibration study draws its sensor layouts and noise from
these, so reruns need no FE solve. ``--example`` writes examples/measurement-forearm.csv
instead: one synthetic forearm (:data:`EXAMPLE`), measured by FE as a 3-axis accelerometer would
see it (RMS acceleration magnitude, g) with 5 % noise. ``--example-ldv`` writes
examples/measurement-forearm-ldv.csv: the same synthetic forearm measured as a laser Doppler
vibrometer would see it (peak velocity of the normal component, mm/s, on the skin around the
unit; the models predict no normal component on the unit's own face) with 5 % noise.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from calibration.synthetic import REFERENCE_DESIGNS
from fem import SOLVER_VERSION, simulate
from fem.results import magnitude
from fem.scene import scene_from_dict
from surrogate.data.store import Store

ROOT = Path(__file__).resolve().parents[2]
CACHE = ROOT / "bench" / "calibration" / "data" / "calibration-subjects.json"
DATASET = ROOT / "datasets" / "default"
#: tissue inputs drawn, (low, high, log scale): the default model's trained ranges
TISSUE = {"skin_E_kPa": (20.0, 120.0, True), "fat_thickness_mm": (3.0, 20.0, False),
          "tissue_loss_factor": (0.1, 0.5, False)}
FREQ_RANGE_HZ = (100.0, 250.0)
EXAMPLE_CSV = ROOT / "examples" / "measurement-forearm.csv"
EXAMPLE_LDV_CSV = ROOT / "examples" / "measurement-forearm-ldv.csv"
#: the example subject: stiffer, thinner-fat skin than Table 1's forearm (49 kPa, 14 mm)
EXAMPLE = {"id": 0, "design_name": "bare motor", "design": REFERENCE_DESIGNS["bare motor"],
           "truth": {"skin_E_kPa": 75.0, "fat_thickness_mm": 8.0, "tissue_loss_factor": 0.22},
           "frequencies_hz": [120.0, 170.0]}
EXAMPLE_DISTANCES_MM = (1.0, 3.0, 5.0, 8.0, 11.0, 15.0)  # from the unit's edge


def write_example(space, seed: int, *, ldv: bool = False) -> None:
    """examples/measurement-forearm.csv (a 3-axis accelerometer: RMS acceleration magnitude at
    the face and around the unit) or, with ``ldv``, examples/measurement-forearm-ldv.csv (an
    LDV: peak velocity of the normal component around the unit) from one FE-solved subject."""
    from calibration.measurement import from_amplitude_m, measurement_from_rows, write_measurement

    rec = solve(EXAMPLE, space)
    rng = np.random.default_rng(seed)
    grid = rec["profile_distance_mm"]
    component = "normal" if ldv else "magnitude"
    quantity, unit, statistic = ("velocity", "mm/s", "peak") if ldv else (
        "acceleration", "g", "rms")
    rows = []
    for i, f in enumerate(rec["frequencies_hz"]):
        spots = [] if ldv else [("centre", 0.0, rec["centre_um"]["magnitude"][i])]
        spots += [("edge", d, rec["profile_um"][component][i][grid.index(d)])
                  for d in EXAMPLE_DISTANCES_MM]
        for ref, d, amp_um in spots:
            noisy = amp_um * 1e-6 * (1.0 + 0.05 * rng.standard_normal())
            value = from_amplitude_m(noisy, quantity, unit, statistic, f)
            rows.append({"reference": ref, "distance_mm": d, "frequency_hz": f,
                         "quantity": quantity, "unit": unit, "statistic": statistic,
                         "component": component, "value": f"{value:.4g}",
                         "uncertainty": "5%"})
    truth = ", ".join(f"{k} {v:g}" for k, v in EXAMPLE["truth"].items())
    sensor = ("a laser Doppler vibrometer's peak velocity of the normal component" if ldv else
              "a 3-axis accelerometer's RMS magnitude")
    m = measurement_from_rows(rows, design=EXAMPLE["design"], meta={
        "subject": "synthetic forearm (not a person): FE solve of the bare motor unit glued on "
                   f"a forearm with {truth}",
        "source": f"python bench/calibration/subjects.py --example{'-ldv' if ldv else ''} (FE "
                  f"solver {SOLVER_VERSION}, 5 % Gaussian noise, seed {seed}); {sensor}"})
    path = EXAMPLE_LDV_CSV if ldv else EXAMPLE_CSV
    write_measurement(m, path)
    print(f"wrote {path}")


def draw(n: int, seed: int) -> list[dict]:
    """The subjects' inputs: tissue uniform (log-uniform for the skin modulus) over the range,
    a design, 1-3 distinct frequencies on a 10 Hz grid."""
    rng = np.random.default_rng(seed)
    names = list(REFERENCE_DESIGNS)
    out = []
    for i in range(n):
        truth = {}
        for name, (lo, hi, log) in TISSUE.items():
            u = rng.uniform()
            truth[name] = float(round(lo * (hi / lo) ** u if log else lo + u * (hi - lo), 4))
        grid = np.arange(FREQ_RANGE_HZ[0], FREQ_RANGE_HZ[1] + 1, 10.0)
        freqs = sorted(rng.choice(grid, size=int(rng.integers(1, 4)), replace=False).tolist())
        design = names[int(rng.integers(len(names)))]
        out.append({"id": i, "design_name": design, "design": REFERENCE_DESIGNS[design],
                    "truth": truth, "frequencies_hz": freqs})
    return out


def solve(subject: dict, space) -> dict:
    """FE amplitudes of one subject at each of its frequencies."""
    rec = {**subject, "centre_um": {"magnitude": [], "normal": []},
           "profile_um": {"magnitude": [], "normal": []}}
    for f in subject["frequencies_hz"]:
        row = {**space.center(), **subject["design"], **subject["truth"], "frequency_hz": f}
        res = simulate(scene_from_dict(space.resolve(row)))
        rec["edge_radius_mm"] = float(res.edge_mm)
        rec["profile_distance_mm"] = res.profile_mm.tolist()
        rec["centre_um"]["magnitude"].append(float(magnitude(res.center) * 1e6))
        rec["centre_um"]["normal"].append(float(abs(res.center[1]) * 1e6))
        rec["profile_um"]["magnitude"].append((magnitude(res.profile) * 1e6).round(6).tolist())
        rec["profile_um"]["normal"].append((np.abs(res.profile[:, 1]) * 1e6).round(6).tolist())
        rec["dofs"] = int(res.meta["dofs"])
    rec["source"] = f"FE solver {SOLVER_VERSION}"
    return rec


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=50)
    ap.add_argument("--seed", type=int, default=25)
    ap.add_argument("--out", type=Path, default=CACHE)
    ap.add_argument("--example", action="store_true",
                    help="write examples/measurement-forearm.csv instead")
    ap.add_argument("--example-ldv", action="store_true",
                    help="write examples/measurement-forearm-ldv.csv instead")
    args = ap.parse_args()
    space = Store.open(DATASET).space
    if args.example or args.example_ldv:
        write_example(space, args.seed, ldv=args.example_ldv)
        return
    t0 = time.perf_counter()
    subjects = []
    for s in draw(args.n, args.seed):
        subjects.append(solve(s, space))
        print(f"subject {s['id']:3d} {s['design_name']:20s} {len(s['frequencies_hz'])} "
              f"frequencies  {time.perf_counter() - t0:6.1f} s", flush=True)
    doc = {"about": __doc__.split("\n\n")[0], "generated_by":
           f"python bench/calibration/subjects.py --n {args.n} --seed {args.seed}",
           "solver_version": SOLVER_VERSION, "dataset": "datasets/default", "seed": args.seed,
           "subjects": subjects}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_suffix(".tmp")
    tmp.write_text(json.dumps(doc, separators=(",", ":")) + "\n")
    tmp.replace(args.out)
    print(f"wrote {args.out} ({args.out.stat().st_size / 1e3:.0f} kB, "
          f"{time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
