"""Vibrotactile detection threshold against frequency, for the perceptual crosstalk criterion.

A :class:`ThresholdCurve` is a tabulated curve (frequency [Hz], peak displacement threshold
[um]) interpolated linearly in log(frequency)-log(threshold), with its source, skin site and
contactor area. Frequencies outside the table are refused (a threshold curve is not
extrapolated). The threshold falls with the contact area in the Pacinian range by 3 dB per
doubling of area (Verrillo 1966, below): ``at_area`` rescales a curve by (A / A_ref)^-0.5.

The default, :data:`VERRILLO_1966_FOREARM`, is the hairy skin of the volar forearm with a
2.9 cm^2 contactor (Verrillo, R. T. (1966) Vibrotactile thresholds for hairy skin. J. Exp.
Psychol. 72(1), 47-50). Its abstract states the curve's shape: U-shaped, falling at 12 dB per
octave at the lower frequencies and rising at 9 dB per octave above 220 Hz, and thresholds
falling 3 dB per doubling of contactor area. The table is built from that shape: a minimum at
220 Hz and the stated slopes between 80 and 500 Hz. Its absolute level, 0.3 um (-10 dB re
1 um) at 220 Hz, is the anchor read from the paper's figure for the 2.9 cm^2 contactor; it
was not checked against a digitised table in this project (caveats in docs/planner.md). A
request can replace the curve by its own table and source (``[criterion] threshold_hz``,
``threshold_um``, ``threshold_source``).

Caveats: thresholds are for a rigid contactor with a surround, 1 s bursts, young adults,
peak displacement normal to the skin; a wearable unit's contact, static preload and adaptation
differ, and thresholds rise with age (about 0.2 dB per year above 25 in the Pacinian range).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["VERRILLO_1966_FOREARM", "ThresholdCurve", "verrillo_1966_forearm"]

DB_PER_AREA_DOUBLING = 3.0  # Verrillo 1966: thresholds fall 3 dB per doubling of area


@dataclass(frozen=True)
class ThresholdCurve:
    """Detection threshold [um, peak displacement] at tabulated frequencies [Hz]."""

    frequency_hz: tuple[float, ...]
    threshold_um: tuple[float, ...]
    source: str
    site: str = ""
    contactor_area_cm2: float | None = None

    def __post_init__(self) -> None:
        f = np.asarray(self.frequency_hz, dtype=float)
        t = np.asarray(self.threshold_um, dtype=float)
        if f.ndim != 1 or f.size < 2 or t.shape != f.shape:
            raise ValueError("threshold_hz and threshold_um: need two equal-length lists of at "
                             "least 2 values")
        if not (np.all(np.isfinite(f)) and np.all(f > 0) and np.all(np.diff(f) > 0)):
            raise ValueError("threshold_hz: frequencies must be > 0 Hz and strictly increasing")
        if not (np.all(np.isfinite(t)) and np.all(t > 0)):
            raise ValueError("threshold_um: thresholds must be finite and > 0 um")

    @property
    def range_hz(self) -> tuple[float, float]:
        return float(self.frequency_hz[0]), float(self.frequency_hz[-1])

    def __call__(self, frequency_hz: ArrayLike) -> NDArray:
        """Threshold [um] at ``frequency_hz`` (log-log interpolation inside the table)."""
        f = np.asarray(frequency_hz, dtype=float)
        lo, hi = self.range_hz
        if np.any(f < lo) or np.any(f > hi) or not np.all(np.isfinite(f)):
            raise ValueError(f"frequency {f.tolist()} Hz is outside the threshold curve's "
                             f"range [{lo:g}, {hi:g}] Hz ({self.source})")
        return np.exp(np.interp(np.log(f), np.log(self.frequency_hz),
                                np.log(self.threshold_um)))

    def at_area(self, area_cm2: float) -> ThresholdCurve:
        """The curve for another contactor area (3 dB lower per doubling of area)."""
        if self.contactor_area_cm2 is None:
            raise ValueError("this threshold curve has no reference contactor area")
        if not area_cm2 > 0:
            raise ValueError(f"contactor_area_cm2 = {area_cm2!r}: must be > 0")
        db = -DB_PER_AREA_DOUBLING * math.log2(area_cm2 / self.contactor_area_cm2)
        scale = 10.0 ** (db / 20.0)
        return ThresholdCurve(self.frequency_hz, tuple(t * scale for t in self.threshold_um),
                              f"{self.source}; rescaled to {area_cm2:g} cm^2 at "
                              f"{DB_PER_AREA_DOUBLING:g} dB per doubling of area", self.site,
                              area_cm2)


def verrillo_1966_forearm(freqs_hz: tuple[float, ...] = (80.0, 100.0, 120.0, 160.0, 220.0,
                                                          250.0, 320.0, 400.0, 500.0),
                          ) -> ThresholdCurve:
    """Volar-forearm (hairy skin) threshold, 2.9 cm^2 contactor, from the shape stated by
    Verrillo (1966): -12 dB per octave up to the 220 Hz minimum, +9 dB per octave above,
    anchored at -10 dB re 1 um at 220 Hz (see the module docstring for the caveats)."""
    f_min, anchor_db = 220.0, -10.0
    levels = [anchor_db + (-12.0 if f < f_min else 9.0) * math.log2(f / f_min) for f in freqs_hz]
    return ThresholdCurve(tuple(freqs_hz), tuple(10.0 ** (db / 20.0) for db in levels),
                          "Verrillo 1966, J Exp Psychol 72:47 (hairy skin, volar forearm; "
                          "slopes from the paper, 0.3 um anchor at 220 Hz)",
                          "volar forearm (hairy skin)", 2.9)


VERRILLO_1966_FOREARM = verrillo_1966_forearm()
