"""The published numbers of the study we reproduce, each with where it comes from.

W. Guo et al., "Optimization Design of Haptic Units for Perception Feedback Interfaces Based on
Vibrotactile Amplitude Modulation", Biomimetics 10 (2025) 597, doi:10.3390/biomimetics10090597.

Only what the paper states is here; every choice of ours (tolerances, extra cases, motor and
pin parameters it does not give) lives with the code that makes it (:mod:`.cases`,
:mod:`.text`). Fractions are plain numbers (0.19 = 19 %).
"""

from __future__ import annotations

CITATION = ("W. Guo et al., Optimization Design of Haptic Units for Perception Feedback "
            "Interfaces Based on Vibrotactile Amplitude Modulation, Biomimetics 10 (2025) 597, "
            "doi:10.3390/biomimetics10090597")

#: The paper's encapsulation silicones A-D (layer letters as in its Figs. 9-13), mapped to our
#: material library names.
LETTERS: dict[str, str] = {
    "A": "ecoflex-00-10",
    "B": "ecoflex-00-50",
    "C": "dragon-skin-10-medium",
    "D": "dragon-skin-30",
}

#: Fig. 8b: pogo pins cut the edge amplitude to about half.
PAPER_POGO_RATIO = 0.5
#: Fig. 9a: the normalized edge amplitude (edge / center) of a single layer, by material.
PAPER_SINGLE_RANGE = (0.50, 0.58)
#: Fig. 9b/c: the most restraining triple (A, C, D as layers 1, 2, 3) and the most enhancing.
PAPER_TRIPLE_MIN = 0.19
PAPER_TRIPLE_MIN_DESIGN = "ACD"
PAPER_TRIPLE_MAX = 0.90
#: The FE model against a laser Doppler vibrometer on a forearm phantom (coefficient of
#: determination over amplitudes 0-20 mm from the motor edge).
PAPER_R2 = 0.9831
#: Two-point discrimination of the optimized unit, successive stimuli (mm, edge to edge).
PAPER_TPD_MM = 8.6
#: The vibrometer signals' Butterworth band-pass (Hz).
LDV_BAND_HZ = (40.0, 200.0)
#: The encapsulation sweeps, three equal rings: Table 2 (density, kg/m3), Table 3 (Young's
#: modulus, kPa), Table 4 (Poisson's ratio); each varies one value from the common point.
TABLE2_DENSITY = (1000.0, 2000.0, 4000.0)
TABLE3_E_KPA = (15.0, 100.0, 268.0, 355.0, 900.0, 1200.0, 3600.0)
TABLE4_NU = (0.2, 0.33, 0.47)
#: The point all three tables share: density kg/m3, E kPa, nu.
COMMON = (1000.0, 355.0, 0.47)
