"""Run-time prediction with numpy and onnxruntime only (no torch, scikit-learn or FE
solver): ``load_predictor(path).predict(X)`` for the steady amplitudes and profiles,
``load_envelope_model(path).simulate(t_s, volts, design)`` for the transient envelope;
``load_model(name_or_path)`` for either, by name (installed model packages) or path."""

from surrogate.runtime.card import ModelFileError
from surrogate.runtime.encoding import InputSpec, PredictorInputError
from surrogate.runtime.models import find_model, load_model
from surrogate.runtime.predictor import Predictor, load_predictor
from surrogate.runtime.rom import (
    EnvelopeModel,
    RomBlowUpError,
    RomInputError,
    load_envelope_model,
)

__all__ = ["EnvelopeModel", "InputSpec", "ModelFileError", "Predictor", "PredictorInputError",
           "RomBlowUpError", "RomInputError", "find_model", "load_envelope_model", "load_model",
           "load_predictor"]
