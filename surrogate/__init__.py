"""hapticrom surrogates: parameter spaces, dataset generation and storage, learned models.

Import-light on purpose: ``import surrogate`` loads nothing heavy. Use the submodules:
``surrogate.space`` (parameter spaces), ``surrogate.sampling`` (Sobol / Halton / LHS designs),
``surrogate.store`` (Parquet dataset store), ``surrogate.generate`` (resumable generation on a
process pool or a Dask cluster), ``surrogate.ingest`` (external results), ``surrogate.cli``
(the ``generate``, ``dataset`` and ``ingest`` subcommands).
"""
