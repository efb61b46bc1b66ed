"""Models trained on sweep datasets (docs/sweep-models.md): the complex-band representation
(``targets``), its basis factored into per-frequency tables times one spatial basis
(``basis``), its decode inside the ONNX graph (``export``), the Gaussian process on it and its
float64 graph (``gp``, ``gp_export``), and the training pipeline (``train``)."""
