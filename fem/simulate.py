"""Transitional alias of :mod:`fem.simulation` for callers outside ``fem`` not yet updated
(``hapticrom/cli.py``, ``surrogate/generate.py``, ``bench/``); delete it once they import
``from fem import simulate``. While it is imported, ``fem.simulate`` names this module rather
than the function, which is why the solver's entry point lives in ``fem.simulation``."""

from fem.simulation import SimulationResult, simulate

__all__ = ["SimulationResult", "simulate"]
