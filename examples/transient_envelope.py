"""Drive schedules through the shipped transient ROM: how overdrive and braking shape a pulse.

    .venv/bin/python examples/transient_envelope.py [--model models/rom-default]

A 60 ms haptic pulse of the optimised unit (reverse motor on pogo pins in three silicone
rings, the third row of examples/designs.csv) driven three ways: plain 3.3 V on/off; a 10 ms
4.5 V overdrive kick; the kick plus 8 ms of reverse voltage to brake. Prints the center
envelope and the motor speed every 10 ms, from the run-time envelope model (numpy and
onnxruntime: the motor law's speed, the harmonic NN shipped inside the model for the steady
response at that speed, and per point one damped mode beside a share of that response passed
through at once, whose coefficients, plain JSON, are fitted to FE transients by least squares
in ``surrogate/rom.py``; docs/transient-model.md).
The envelope is not monotonic in the speed: as the motor sweeps up (and down again) its
frequency passes the unit's resonances on the tissue, which the FE runs show too.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from surrogate.runtime.rom import load_envelope_model

ROOT = Path(__file__).resolve().parents[1]
DESIGN = {"orientation": "reverse", "attachment": "pogo", "n_rings": 3, "ring_1_E_kPa": 95.0,
          "ring_2_E_kPa": 260.0, "ring_3_E_kPa": 1016.0, "ring_density_kg_m3": 1060.0,
          "ring_nu": 0.49, "ring_loss_factor": 0.1, "skin_E_kPa": 49.0,
          "fat_thickness_mm": 14.0, "tissue_loss_factor": 0.3, "tau_spinup_ms": 20.0,
          "tau_spindown_ms": 35.0}
#: (start ms, volts) steps of each schedule; the pulse is on for 60 ms.
SCHEDULES = {
    "plain 3.3 V": [(0, 3.3), (60, 0.0)],
    "overdrive": [(0, 4.5), (10, 3.3), (60, 0.0)],
    "overdrive + brake": [(0, 4.5), (10, 3.3), (60, -3.3), (68, 0.0)],
}


def volts_at(t_ms: np.ndarray, steps: list[tuple[float, float]]) -> np.ndarray:
    """Voltage held from each step's start to the next."""
    starts = np.array([s for s, _ in steps])
    levels = np.array([v for _, v in steps])
    return levels[np.searchsorted(starts, t_ms, side="right") - 1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=str(ROOT / "models" / "rom-default"))
    args = ap.parse_args()
    model = load_envelope_model(args.model)
    t_ms = np.arange(0.0, 150.0, 0.2)
    every = 50  # print every 10 ms
    outs = {name: model.simulate(t_ms * 1e-3, volts_at(t_ms, steps), DESIGN)
            for name, steps in SCHEDULES.items()}
    print("center envelope [um] (motor speed [rev/s]); the drive ends at 60 ms")
    print(f"{'t ms':>5s} " + " ".join(f"{name:>20s}" for name in outs))
    for i in range(0, t_ms.size, every):
        cells = [f"{o['center_envelope_um'][i]:10.2f} ({o['speed_hz'][i]:5.0f})"
                 for o in outs.values()]
        print(f"{t_ms[i]:5.0f} " + " ".join(f"{c:>20s}" for c in cells))


if __name__ == "__main__":
    main()
