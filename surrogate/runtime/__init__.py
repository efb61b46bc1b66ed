"""Run-time prediction with numpy and onnxruntime only (no torch, scikit-learn, pysindy or
FE solver): ``load_predictor(path).predict(X)``."""

from surrogate.runtime.card import ModelFileError
from surrogate.runtime.encoding import InputSpec, PredictorInputError
from surrogate.runtime.predictor import Predictor, load_predictor

__all__ = ["InputSpec", "ModelFileError", "Predictor", "PredictorInputError", "load_predictor"]
