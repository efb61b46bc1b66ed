"""Two units on the forearm at 120 Hz: edge-to-edge distance [mm] of the bare motor and the
paper's optimised unit (A-C-D triple, reverse, pogo), the comparison with the paper's
perception study in docs/array-layout.md and the contact-area example of docs/planner.md.

    .venv/bin/python bench/planner/two_units.py

examples/forearm-layout.toml as a 1 x 2 array at 120 Hz with one neighbour, on the layout's
harmonic model (the default when it names none), timing off. Ratio criterion at max_ratio
0.1 / 0.2 / 0.3 (`superposition = "worst"`, one neighbour); the perceptual criterion (drive
level 1) at Verrillo's 2.9 cm^2 contactor and at 0.385 cm^2 (the bare motor's face). Each
edge to edge on the prediction (`holds_at = "nominal"`) and at the 95 % bounds.
"""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from planner import layout_from_dict, plan_layout  # noqa: E402

EXAMPLE = ROOT / "examples" / "forearm-layout.toml"
UNITS = ("bare motor", "A-C-D triple, pogo")


def edge_to_edge(criterion: dict) -> dict[str, tuple[float, float, float]]:
    """Each unit's (nominal, 95 % bounds) edge-to-edge distance [mm] and its width [mm]."""
    d = tomllib.loads(EXAMPLE.read_text())
    d["array"].update(rows=1, cols=2)
    d["drive"]["frequencies_hz"] = [120.0]
    d["design"] = [x for x in d["design"] if x["name"] in UNITS]
    d["criterion"] = {**d["criterion"], "superposition": "worst", **criterion}
    d["timing"] = {"enabled": False}
    plan = plan_layout(layout_from_dict(d))
    out = {}
    for c in plan.candidates:
        w = 2 * c.edge_radius_mm
        out[c.name] = (c.pitch_nominal_mm - w, c.pitch_95_mm - w, w)
    return out


def main() -> None:
    print("criterion                        unit                nominal  95 % bounds  width  [mm]")
    rows = [(f"ratio, max_ratio {r}", {"kind": "ratio", "max_ratio": r}) for r in (0.1, 0.2, 0.3)]
    rows += [(f"perceptual, {a} cm^2", {"kind": "perceptual", "contactor_area_cm2": a})
             for a in (2.9, 0.385)]
    for label, crit in rows:
        res = edge_to_edge(crit)
        for name in UNITS:
            nom, b95, w = res[name]
            print(f"{label:32s} {name:18s} {nom:8.1f} {b95:12.1f} {w:6.1f}")
        print(f"{'':32s} {'ratio triple / bare':18s} {res[UNITS[1]][0] / res[UNITS[0]][0]:8.2f}"
              f" {res[UNITS[1]][1] / res[UNITS[0]][1]:12.2f}")


if __name__ == "__main__":
    main()
