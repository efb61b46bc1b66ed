"""The reproduction of Guo et al. 2025 (Biomimetics 10:597): every study of the paper re-run on
the `fem` solver, our numbers beside theirs, and checks of why they may differ.

Every study is a set of harmonic steady-state solves at 120 Hz on the default forearm, each scene
built from one of the shipped prototype scenes (``scenes/unit-*.toml``) by edits (the defaults
are never tuned):

1. orientation: forward vs reverse, bare motor, glued and pogo (the paper's Fig. 8a);
2. pogo pins: glued vs pogo, reverse, bare (Fig. 8b: edge amplitude halved);
3. single layers A-D, forward, glued (Fig. 9a: normalized edge 50-58 %);
4. all 64 ordered triples of A-D, reverse + pogo (Fig. 9b/c: 19 % for A-C-D to 90 %);
5. density / modulus / Poisson sweeps, three equal rings, reverse + pogo (Tables 2-4);
6. context: the three prototype designs and a crosstalk proxy (ours, not the paper's).

Checks of why we might disagree: amplitude definition, center definition, motor parameters,
the pogo-pin smearing, steady vs transient, mesh refinement, and how the inner ring meets the
motor (``unit.ring_contact``).

Modules: :mod:`.paper` (the published numbers), :mod:`.cases` (the case language and plan),
:mod:`.run` (solving on the shared pool), :mod:`.studies`, :mod:`.checks`, :mod:`.contact`
(report sections), :mod:`.figures`, :mod:`.report` and :mod:`.discussion` (Markdown),
:mod:`.outdir` (the report directory), :mod:`.study` (:func:`reproduce`).

Entry point: :func:`reproduce` (``hapticrom reproduce``).
"""

from .study import Reproduction, reproduce

__all__ = ["Reproduction", "reproduce"]
