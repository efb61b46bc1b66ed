"""The fit of the transient envelope model (docs/transient-model.md): the identification
(``fit``), the FE runs it reads and demodulates (``runs``), its card (``card``) and its
held-out metrics (``metrics``). The model itself runs in ``surrogate.runtime.rom``."""
