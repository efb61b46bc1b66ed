"""The card of the grey-box envelope model (``surrogate.envelope.fit``): inputs, files, split,
targets and the held-out metrics, with non-finite floats written as null."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from surrogate.registry import package_versions
from surrogate.runtime.rom import EnvelopeModel

__all__ = ["card", "finite"]

COEFFICIENTS_FILE = "coefficients.json"
HARMONIC_CARD_FILE = "harmonic_card.json"
HARMONIC_GRAPH_FILE = "harmonic.onnx"
HOLDOUT_EVERY = 4  # rows with sample_index % 4 == 3 are held out (never used in fitting)


def finite(obj: Any) -> Any:
    """``obj`` with every non-finite float replaced by None (strict JSON for the card)."""
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [finite(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _dynamics(model: EnvelopeModel) -> str:
    """What carries the dynamics, in words."""
    if "quasi_static_share" in model.meta:
        return "a learned quasi-static share and one learned rotating-frame mode"
    return f"{'one' if model.modes == 1 else 'two'} learned rotating-frame " \
           f"mode{'' if model.modes == 1 else 's'}"


def card(model: EnvelopeModel, coefficients: Mapping[str, Any], data: Sequence[Any],
          hashes: Sequence[str], harmonic: Any, hcard: Mapping[str, Any], n_train: int,
          n_held: int, seed: int, metrics: dict[str, Any]) -> dict[str, Any]:
    """The envelope model's card (before :func:`surrogate.registry.write_model` seals it)."""
    inputs: dict[str, Any] = {
        "t_s": {"units": "s", "description": "increasing times, from rest at t_s[0]"},
        "volts": {"units": "V", "range": [-model.motor.max_voltage_V,
                                          model.motor.max_voltage_V],
                  "description": "drive voltage held from each time to the next"}}
    for name, rng in model.input_ranges.items():
        inputs[name] = ({"choices": list(rng)} if isinstance(rng[0], str)
                        else {"range": list(rng)})
    return {
        "kind": "rom",
        "actuator": model.actuator,
        "predicts": {"center_envelope_um": "vibration envelope at the unit's center "
                     "(skin-side face on the axis), um",
                     "edge_envelope_um": "skin-surface vibration envelope at the unit's "
                     "outer radius, um"},
        "interface": "surrogate.runtime.rom.load_envelope_model(path).simulate(t_s, volts, "
                     "design)",
        "model": "grey box: motorlaw speed x harmonic steady response at the instantaneous "
                 f"speed x {_dynamics(model)} per point (surrogate.runtime.rom)",
        "inputs": inputs,
        "coefficients": COEFFICIENTS_FILE,
        "harmonic": {"card": HARMONIC_CARD_FILE, "graph": HARMONIC_GRAPH_FILE,
                     "source": str(harmonic), "source_files": hcard["files"]},
        "training_data": [{"path": str(p), "manifest_sha256": h}
                          for p, h in zip(data, hashes, strict=True)],
        "split": {"held_out": f"sample_index % {HOLDOUT_EVERY} == {HOLDOUT_EVERY - 1} (never "
                  "used in fitting)", "n_train": n_train, "n_held_out": n_held},
        "training": {"seed": seed, "fit": coefficients["fit"]},
        "targets": {"steady_rel_err_median": 0.02, "steady_rel_err_max": 0.05,
                    "rise_abs_err_ms_median": 0.5, "rise_abs_err_ms_max": 2.0,
                    "decay_abs_err_ms_median": 0.5, "decay_abs_err_ms_max": 2.0,
                    "nrmse_median": 0.03},
        "metrics": finite(metrics),
        "versions": package_versions(),
    }
