"""The default models, named in one place (numpy + onnxruntime free: card reading only).

Every command that takes a model and is given none asks :func:`default_model` for a *role*:

* ``harmonic``: the steady-state amplitudes of a design at a frequency (``hapticrom plan``,
  ``hapticrom design`` through the layout's ``[model] path``, ``hapticrom predict``,
  ``hapticrom explore``, the magnitude rows of ``hapticrom calibrate``);
* ``normal``: a harmonic model that also predicts the normal component ``profile_normal_um``
  (``hapticrom calibrate`` of a measurement with normal-component rows, e.g. an LDV's);
* ``envelope_harmonic``: the harmonic model the envelope fit takes its steady part from
  (``hapticrom train --kind rom``; the envelope model carries a copy of it). It must cover the
  motor's whole speed range, 20-250 Hz from spin-up to full speed, so only ``nn-wide`` serves:
  the sweep models are trained over the drive band 100-250 Hz and would answer a spin-up at
  40 Hz with their 100 Hz value (``extrapolate=True`` clamps to the band);
* ``gaussian_process``: the shipped Gaussian process, the peer with its own intervals that
  the benches and the FE comparison example run beside the network
  (``bench/runtime/predict.py``, ``examples/surrogate_vs_fe.py``).

Each role lists its candidates in order of preference: the sweep-trained models first
(``nn-sweep``, ``nn-sweep-normal`` and ``gp-sweep``: trained on the complex band of
``datasets/spaces/default-sweep.toml``, their profiles to 40 mm; docs/sweep-models.md), then
the single-frequency models that served before them. ``nn-sweep-normal`` is a network of its
own because learning the normal component beside the magnitude costs the magnitude outputs
accuracy (measured in docs/sweep-models.md). The first candidate that is installed
(:func:`surrogate.runtime.models.find_model`) and whose card has what the role needs wins, so
the same code runs with or without ``models/nn-sweep``: installing a model switches every
command.
"""

from __future__ import annotations

from pathlib import Path

from surrogate.runtime.card import ModelFileError, read_card
from surrogate.runtime.models import find_model

__all__ = ["DEFAULT_MODELS", "ROLE_OUTPUTS", "default_model", "default_model_path",
           "is_sweep_model"]

#: role -> candidate model names, preferred first (see the module docstring)
DEFAULT_MODELS: dict[str, tuple[str, ...]] = {
    "harmonic": ("nn-sweep", "nn-default"),
    "normal": ("nn-sweep-normal", "nn-sweep", "nn-normal"),
    "envelope_harmonic": ("nn-wide",),
    "gaussian_process": ("gp-sweep", "gp-default"),
}
#: role -> the outputs a candidate's card must list to serve it
ROLE_OUTPUTS: dict[str, tuple[str, ...]] = {"normal": ("profile_normal_um",)}


def is_sweep_model(card: dict) -> bool:
    """Whether ``card`` is a sweep-trained model's (its ``representation`` records the band it
    was trained over; the graph contract is the single-frequency one either way)."""
    return isinstance(card.get("representation"), dict) and "band_hz" in card["representation"]


def _serves(path: Path, role: str) -> bool:
    outputs = read_card(path, verify=False).get("outputs", [])
    names = {o.get("name") if isinstance(o, dict) else o for o in outputs}
    return all(name in names for name in ROLE_OUTPUTS.get(role, ()))


def default_model_path(role: str) -> Path:
    """The directory of the default model for ``role``; :class:`ModelFileError` (field
    ``model``) when the role is unknown or none of its candidates is installed."""
    if role not in DEFAULT_MODELS:
        raise ModelFileError("model", f"no default model for {role!r}; roles: "
                             f"{', '.join(DEFAULT_MODELS)}")
    for name in DEFAULT_MODELS[role]:
        try:
            path = find_model(name)
        except ModelFileError:
            continue
        if _serves(path, role):
            return path
    need = ROLE_OUTPUTS.get(role)
    raise ModelFileError("model", f"no default {role} model installed: tried "
                         f"{', '.join(DEFAULT_MODELS[role])}"
                         + (f" (with outputs {', '.join(need)})" if need else "")
                         + "; give a model path")


def default_model(role: str) -> str:
    """:func:`default_model_path` as text, relative to the working directory when it lies
    below it (``models/nn-default`` from a checkout's root, as plan records show it)."""
    path = default_model_path(role).resolve()
    cwd = Path.cwd()
    return str(path.relative_to(cwd) if path.is_relative_to(cwd) else path)
