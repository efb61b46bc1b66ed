"""The self-describing JSON documents the command line writes besides ``simulate`` (whose
document is :mod:`fem.output`): ``predict --json`` and ``dataset info --json``.

Every document carries ``schema_version`` (1) and ``kind``; its JSON Schema ships in
``hapticrom/schemas/`` (:func:`schema`) and docs/output-schema.md describes every key. Units are
in the key names; magnitudes are named ``*_magnitude_um``.
"""

from __future__ import annotations

import json
from importlib import resources
from typing import Any

import numpy as np

__all__ = ["SCHEMA_VERSION", "dataset_info_document", "predict_document", "schema"]

SCHEMA_VERSION = 1

#: What the amplitude columns of datasets and surrogate predictions mean (the same quantities
#: as ``hapticrom simulate``; see fem.output).
DEFINITIONS = {
    "centre": "the unit's face at r = 0: the skin-side face of the haptic unit (its board "
              "underside on pogo pins, the skin itself when glued), not the r = 0 skin point",
    "edge": "the skin surface at the unit's outer radius edge_radius_mm",
    "profile": "skin-surface samples at profile_distance_mm from the edge, outwards",
    "magnitude": "sqrt(|U_r|^2 + |U_z|^2 + |U_t|^2) of the complex Fourier amplitudes of the "
                 "harmonic steady state, um",
    "log_std": "predictive standard deviation of the natural log of the output (so "
               "exp(+-1.96 log_std) brackets about 95 %)",
}

#: old predictor output name -> name in the document
_RENAMES = {"center_amplitude_um": "centre_magnitude_um",
            "edge_amplitude_um": "edge_magnitude_um",
            "profile_um": "profile_magnitude_um"}


def _renamed(key: str) -> str:
    for old, new in _RENAMES.items():
        if key == old or key.startswith(old + "_"):
            return new + key[len(old):]
    return key


def predict_document(model_path: str, card: dict[str, Any], inputs: dict[str, Any],
                     out: dict[str, np.ndarray], profile_distance_mm: np.ndarray
                     ) -> dict[str, Any]:
    """The ``predict --json`` document of version 1."""
    freq = inputs.get("frequency_hz")
    return {
        "schema_version": SCHEMA_VERSION,
        "kind": "hapticrom.predict",
        "model": {"path": str(model_path), "name": card.get("name"), "kind": card.get("kind"),
                  "predicts": card.get("predicts")},
        "analysis": {"kind": "harmonic",
                     "frequency_hz": None if freq is None else np.asarray(freq).tolist(),
                     "text": "harmonic steady state of an ERM unit; frequency_hz per row "
                             "(the ERM spin frequency) when it is an input of the model"},
        "definitions": DEFINITIONS,
        "rows": len(out["center_amplitude_um"]),
        "inputs": {k: np.asarray(v).tolist() for k, v in inputs.items()},
        "profile_distance_mm": np.asarray(profile_distance_mm).tolist(),
        "outputs": {_renamed(k): np.asarray(v).tolist() for k, v in out.items()},
    }


def dataset_info_document(info: dict[str, Any]) -> dict[str, Any]:
    """The ``dataset info --json`` document of version 1: the summary of
    :func:`surrogate.data.inspect.dataset_info` with its version, kind and the meaning of the
    amplitude columns of the rows."""
    return {"schema_version": SCHEMA_VERSION, "kind": "hapticrom.dataset.info",
            "column_definitions": {
                "center_amplitude_um": "magnitude at the centre (" + DEFINITIONS["centre"] + ")",
                "edge_amplitude_um": "magnitude at the edge (" + DEFINITIONS["edge"] + ")",
                "normalized_edge": "edge_amplitude_um / center_amplitude_um",
                "profile_magnitude_um": "magnitude on profile_distance_mm",
                "profile_uz_um": "|U_z| on profile_distance_mm"},
            **info}


def schema(name: str) -> dict[str, Any]:
    """The JSON Schema ``hapticrom/schemas/NAME.json`` (e.g. ``simulate-harmonic``)."""
    text = resources.files("hapticrom").joinpath("schemas", f"{name}.json").read_text()
    return json.loads(text)
