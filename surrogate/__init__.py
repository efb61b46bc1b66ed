"""hapticrom surrogates: the dataset layer and the learned models built on it.

``surrogate.data`` holds parameter spaces, sampling, the Parquet dataset store, resumable
generation (process pool or Dask) and ingest of external results; it is the only part of the
package that imports the FE solver. The models are grouped by family: ``estimators`` (one
module per steady-state kind, with its exporter), ``sweep`` (models trained on sweep
datasets), ``envelope`` (the fit of the transient envelope model); ``kinds`` is the one list of
kinds, ``train`` the steady-state pipeline, ``registry`` the model directories.
``surrogate.runtime`` is the run-time predictor (numpy + onnxruntime only). Importing
``surrogate`` loads nothing heavy.
"""
