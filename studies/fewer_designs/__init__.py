"""Learning from fewer, better designs (issue 36, item 2): two retrospective measurements on
the sweep datasets that need no new FE solve.

* :mod:`.active`: active learning in the sweep setting. Both arms draw from already solved
  designs of one sweep dataset: the Sobol arm takes the next designs of the sequence, the
  active arm the designs of a candidate pool where the sweep model trained on the start set
  disagrees most with itself (its members' spread of ln |u| at the centre and the edge over
  the band, spread out by a minimum distance in the encoded features); then the same model is
  trained on each arm and scored on a test set of fresh designs.
* :mod:`.multifidelity`: multi-fidelity by stacking (Perdikaris et al. 2017, nonlinear
  autoregressive): a single-frequency model's predicted ln centre and ln edge amplitudes at a
  few band frequencies appended to the design's features, the same learner with and without
  them.

Entry point: ``bench/surrogate/refine_sweep.py``; the results are in docs/sweep-models.md
("Learning from fewer, better designs").
"""
