"""What accuracy costs in time: every way the toolkit answers "what are the centre and edge
amplitudes and the profile of this design", side by side on the same designs.

Modules: :mod:`.metric` (the one error metric), :mod:`.designs` (the fixed design set and the
shipped dataset), :mod:`.timing` (medians), :mod:`.fe_ladder` (mesh level x element order
against a converged reference; transient steady state), :mod:`.effects` (effects audit),
:mod:`.learning_curves` (error against FE samples and compute), :mod:`.learned` (GP and NN
in-memory vs ONNX, batch 1 vs large batch), :mod:`.band_models` (the whole band on fresh
designs: the shipped sweep models, nn-default and the MLP peer against the FE sweep),
:mod:`.study` (:func:`run_study`),
:mod:`.report` (Markdown + Pareto plot). Entry point: ``hapticrom bench accuracy``.
"""

from .study import Settings, run_study

__all__ = ["Settings", "run_study"]
