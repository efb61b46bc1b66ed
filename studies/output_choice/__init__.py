"""Which outputs should a surrogate learn from sweep data, and how do the peers do on them?

Issue 20, items 1 and 5: the magnitude at one frequency changes sharply with the design near
an antiresonance, while the complex response and the resonances move smoothly. This study
trains each learner on each choice of outputs on the same training designs of a sweep dataset
and scores every (learner, choice) on the same test designs -- a held-out split of the training
dataset, or another dataset (fresh FE solves at another Sobol seed) -- at every band frequency.

Modules: :mod:`.data` (sweep datasets as arrays, splits, row caps), :mod:`.representations`
(the output choices: encode a design's band response to targets, decode predictions back to
magnitudes and profiles), :mod:`.learners` (scikit-learn MLP, shared-kernel GP, per-output GPs,
LightGBM), :mod:`.study` (scores, the table, the JSON record). Entry point:
``bench/surrogate/output_choice.py``.
"""

from .study import run, table

__all__ = ["run", "table"]
