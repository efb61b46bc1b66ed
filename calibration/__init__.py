"""Calibrating the tissue inputs of a surrogate to a person's own vibration measurement
(run-time path: numpy, onnxruntime and emcee; never the FE solver or a training stack).

    from calibration import read_measurement, calibrate
    from surrogate.runtime import load_predictor
    cal = calibrate(load_predictor("models/nn-default"), read_measurement("m.csv"),
                    ["skin_E_kPa", "fat_thickness_mm", "tissue_loss_factor"])
    cal.summary()   # posterior mean, 95 % interval, identifiability per input

See docs/calibration.md for the measurement format, the likelihood and the document.
"""

from calibration.document import (
    CalibrationFileError,
    Tissue,
    calibration_document,
    read_calibration,
)
from calibration.fit import Calibration, calibrate, surrogate_std_factor
from calibration.measurement import (
    MeasuredPoint,
    Measurement,
    MeasurementError,
    measurement_from_rows,
    read_measurement,
    write_measurement,
)
from calibration.priors import Prior, PriorError

__all__ = [
    "Calibration",
    "CalibrationFileError",
    "MeasuredPoint",
    "Measurement",
    "MeasurementError",
    "Prior",
    "PriorError",
    "Tissue",
    "calibrate",
    "calibration_document",
    "measurement_from_rows",
    "read_calibration",
    "read_measurement",
    "surrogate_std_factor",
    "write_measurement",
]
