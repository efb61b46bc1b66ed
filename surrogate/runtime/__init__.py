"""Run-time prediction with numpy and onnxruntime only (no torch, scikit-learn, pysindy or
FE solver): ``load_predictor(path).predict(X)`` for the steady amplitudes and profiles,
``load_envelope_model(path).simulate(t_s, volts, design)`` for the transient envelope."""

from surrogate.runtime.card import ModelFileError
from surrogate.runtime.encoding import InputSpec, PredictorInputError
from surrogate.runtime.predictor import Predictor, load_predictor
from surrogate.runtime.rom import (
    EnvelopeModel,
    RomBlowUpError,
    RomInputError,
    load_envelope_model,
)

__all__ = ["EnvelopeModel", "InputSpec", "ModelFileError", "Predictor", "PredictorInputError",
           "RomBlowUpError", "RomInputError", "load_envelope_model", "load_predictor"]
