"""hapticrom surrogates: the dataset layer and the learned models built on it.

``surrogate.data`` holds parameter spaces, sampling, the Parquet dataset store, resumable
generation (process pool or Dask) and ingest of external results; it is the only part of the
package that imports the FE solver. The estimators, ONNX export and the model registry sit
beside it; ``surrogate.runtime`` is the run-time predictor (numpy + onnxruntime only).
Importing ``surrogate`` loads nothing heavy.
"""
