"""Run-time predictors: numpy (+ onnxruntime) only; no fem, torch, sklearn or pysindy."""
