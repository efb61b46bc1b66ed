"""Synthetic subjects: measurements made from known amplitudes (an FE solve, or the surrogate
itself) with a sensor layout and measurement noise, to prove a calibration.

A *subject* is a mapping (the records of bench/calibration/data/calibration-subjects.json)::

    {"id": 3, "truth": {"skin_E_kPa": 61.2, ...}, "design": {"orientation": "forward", ...},
     "frequencies_hz": [120.0, 180.0], "edge_radius_mm": 3.5,
     "profile_distance_mm": [0, 1, ..., 20],
     "centre_um": {"magnitude": [..per frequency..], "normal": [...]},
     "profile_um": {"magnitude": [[..per distance..] per frequency], "normal": [...]}}

:func:`synthetic_measurement` picks sensor positions (the unit's face and distances from the
edge, the same at every frequency), a sensor (LDV velocity, accelerometer, displacement) and
draws Gaussian noise of the stated relative size; the stated uncertainty is that fraction of
the measured value, as a lab would write it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from calibration.measurement import (
    Measurement,
    from_amplitude_m,
    measurement_from_rows,
)

__all__ = ["REFERENCE_DESIGNS", "SENSORS", "subject_from_predictor", "synthetic_measurement"]

#: the paper's three prototypes as model inputs (rings A 95, C 260, D 1016 kPa)
_RINGS = {"ring_density_kg_m3": 1060.0, "ring_nu": 0.49, "ring_loss_factor": 0.1}
REFERENCE_DESIGNS: dict[str, dict[str, Any]] = {
    "bare motor": {"orientation": "forward", "attachment": "glued", "n_rings": 0,
                   "ring_1_E_kPa": 95.0, "ring_2_E_kPa": 260.0, "ring_3_E_kPa": 1016.0,
                   **_RINGS},
    "A-D double": {"orientation": "forward", "attachment": "glued", "n_rings": 2,
                   "ring_1_E_kPa": 95.0, "ring_2_E_kPa": 1016.0, "ring_3_E_kPa": 1016.0,
                   **_RINGS},
    "A-C-D triple, pogo": {"orientation": "reverse", "attachment": "pogo", "n_rings": 3,
                           "ring_1_E_kPa": 95.0, "ring_2_E_kPa": 260.0,
                           "ring_3_E_kPa": 1016.0, **_RINGS},
}
#: sensor -> (quantity, unit, statistic)
SENSORS = {"ldv": ("velocity", "mm/s", "peak"), "accelerometer": ("acceleration", "g", "rms"),
           "displacement": ("displacement", "um", "peak")}


def synthetic_measurement(subject: Mapping[str, Any], *, rel_noise: float, n_points: int,
                          rng: np.random.Generator, component: str = "magnitude",
                          sensor: str | None = None) -> Measurement:
    """A noisy measurement of ``subject``: ``n_points`` positions (the unit's face with
    probability 1/2 for the magnitude, never for the normal component, which no model predicts
    there; the rest distinct whole-mm distances from the edge on the profile grid), each at
    every frequency of the subject."""
    grid = np.asarray(subject["profile_distance_mm"], dtype=float)
    with_face = bool(rng.integers(2)) and component == "magnitude"
    far = rng.choice(grid.size, size=n_points - int(with_face), replace=False)
    sensor = sensor or str(rng.choice(list(SENSORS)))
    quantity, unit, statistic = SENSORS[sensor]
    rows = []
    for i, f in enumerate(subject["frequencies_hz"]):
        spots = [("centre", 0.0, subject["centre_um"][component][i])] if with_face else []
        spots += [("edge", grid[j], subject["profile_um"][component][i][j]) for j in sorted(far)]
        for ref, d_mm, amp_um in spots:
            noisy_m = amp_um * 1e-6 * max(1.0 + rel_noise * rng.standard_normal(), 0.05)
            value = from_amplitude_m(noisy_m, quantity, unit, statistic, float(f))
            rows.append({"reference": ref, "distance_mm": d_mm, "frequency_hz": f,
                         "quantity": quantity, "unit": unit, "statistic": statistic,
                         "component": component, "value": f"{value:.5g}",
                         "uncertainty": f"{100 * rel_noise:g}%"})
    return measurement_from_rows(rows, design=subject["design"], meta={
        "subject": f"synthetic subject {subject.get('id', '')}".strip(),
        "source": str(subject.get("source", "synthetic"))})


def subject_from_predictor(predictor: Any, truth: Mapping[str, float], design: Mapping[str, Any],
                           frequencies_hz: list[float], subject_id: int = 0) -> dict[str, Any]:
    """A subject whose amplitudes are the surrogate's own (magnitude only): for tests of the
    inference that leave the surrogate's error out."""
    nf = len(frequencies_hz)
    X = {k: np.array([v] * nf) for k, v in {**design, **truth}.items()}
    X["frequency_hz"] = np.asarray(frequencies_hz, dtype=float)
    out = predictor.predict(X)
    return {"id": subject_id, "truth": dict(truth), "design": dict(design),
            "frequencies_hz": list(map(float, frequencies_hz)),
            "edge_radius_mm": float(out["edge_radius_mm"][0]),
            "profile_distance_mm": np.asarray(predictor.profile_distance_mm).tolist(),
            "centre_um": {"magnitude": out["center_amplitude_um"].tolist()},
            "profile_um": {"magnitude": out["profile_um"].tolist()},
            "source": f"surrogate {predictor.card.get('name')}"}
