"""The steady-state estimators, one module per surrogate kind (``gp``, ``nn``, ``mlp``,
``lgbm``), each with its ONNX exporter and its ``KIND`` record (listed in
:mod:`surrogate.kinds`); the graph contract they share (``export``) and the checks of their
parameters (``params``)."""
