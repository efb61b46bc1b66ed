"""The output choices: what a learner is trained to predict from a design's band response.

Every choice turns training designs (:class:`.data.Sweeps`) into rows (features X, targets Y),
turns test designs into query rows, and decodes the predicted targets into :class:`Answers`
(magnitudes [um] at every band frequency, and the profile's magnitudes when the data has one):

* :class:`Point` (``magnitude@f``, today's dataset layout): one row per (design, frequency),
  inputs = design + frequency scaled to [0, 1], targets = ln |centre|, ln |edge| and the POD
  coefficients of ln |profile(r)| at that frequency;
* :class:`LnMagBand` (``ln-magnitude band``): one row per design, targets = POD coefficients
  of ln |centre(f)|, ln |edge(f)| over the band (and of ln |profile(f, r)|, its own basis);
* :class:`ComplexBand` (``complex band``): one row per design, targets = ln of the band's RMS
  centre amplitude (the scale) and POD coefficients of the complex components of centre and
  edge over the band divided by the scale, real and imaginary parts (and of the complex profile
  over frequency and radius, its own basis); magnitudes come from the decoded components.

Magnitudes are ``sqrt(|u_r|^2 + |u_z|^2 + |u_t|^2)`` of the complex amplitudes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .data import Sweeps

__all__ = ["CHOICES", "Answers", "Choice", "ComplexBand", "LnMagBand", "Pod", "Point",
           "magnitude"]

#: Smallest magnitude [um] a logarithm is taken of (the data's float32 floor, far below any
#: displacement of the band).
_FLOOR_UM = 1e-12


def magnitude(u: np.ndarray) -> np.ndarray:
    """|u| over the last axis of complex components (r, z, t)."""
    return np.sqrt(np.sum(np.abs(u) ** 2, axis=-1))


def _ln(a: np.ndarray) -> np.ndarray:
    return np.log(np.maximum(a, _FLOOR_UM))


@dataclass(frozen=True)
class Answers:
    """Magnitudes [um] of n designs at every band frequency: ``center``, ``edge`` (n, n_f),
    ``profile`` (n, n_f, n_p) or None."""

    center: np.ndarray
    edge: np.ndarray
    profile: np.ndarray | None

    @classmethod
    def of(cls, sw: Sweeps) -> Answers:
        """The FE answers of ``sw``."""
        return cls(magnitude(sw.center), magnitude(sw.edge),
                   None if sw.profile is None else magnitude(sw.profile))


class Pod:
    """Proper orthogonal decomposition of rows (n, k): the mean row and the leading ``modes``
    right singular vectors (None: every mode of the data's numerical rank)."""

    def __init__(self, modes: int | None) -> None:
        if modes is not None and modes < 1:
            raise ValueError(f"modes = {modes}: allowed >= 1 or None (all)")
        self.modes = modes

    def fit(self, y: np.ndarray) -> Pod:
        self.mean_ = y.mean(axis=0)
        _, s, vt = np.linalg.svd(y - self.mean_, full_matrices=False)
        rank = int(np.sum(s > s[0] * 1e-12)) if s.size and s[0] > 0 else 1
        k = max(1, rank if self.modes is None else min(self.modes, rank))
        self.basis_ = vt[:k]
        self.energy_ = float(np.sum(s[:k] ** 2) / max(np.sum(s**2), 1e-300))
        return self

    def transform(self, y: np.ndarray) -> np.ndarray:
        return (y - self.mean_) @ self.basis_.T

    def inverse_transform(self, a: np.ndarray) -> np.ndarray:
        return a @ self.basis_ + self.mean_


class Choice:
    """One choice of outputs. ``training`` fits its bases on the training designs and returns
    their rows; ``query`` gives the rows to predict for test designs; ``decode`` turns the
    predicted targets of those rows into :class:`Answers`."""

    name = ""

    def training(self, sw: Sweeps, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def query(self, sw: Sweeps) -> np.ndarray:
        return sw.x

    def decode(self, pred: np.ndarray, sw: Sweeps) -> Answers:
        raise NotImplementedError

    def targets(self, sw: Sweeps) -> np.ndarray:
        """The exact targets of the query rows of ``sw`` in the fitted bases: decoding them
        gives the choice's own floor (POD truncation), whatever the learner."""
        raise NotImplementedError


class Point(Choice):
    """Today's layout: (design, frequency) rows, ln magnitudes out (``per_design`` random
    band frequencies per training design; 1 is today's dataset)."""

    def __init__(self, per_design: int = 1, profile_modes: int = 8) -> None:
        self.per_design = per_design
        self.profile_modes = profile_modes
        self.name = f"magnitude@f x{per_design}"

    def _f01(self, sw: Sweeps) -> np.ndarray:
        return (sw.band - sw.band[0]) / (sw.band[-1] - sw.band[0])

    def training(self, sw: Sweeps, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        n_f = sw.band.size
        if not 1 <= self.per_design <= n_f:
            raise ValueError(f"frequencies per design {self.per_design}: allowed 1..{n_f}")
        cols = np.stack([rng.choice(n_f, self.per_design, replace=False)
                         for _ in range(len(sw))]).reshape(-1)
        rows = np.repeat(np.arange(len(sw)), self.per_design)
        x = np.column_stack([sw.x[rows], self._f01(sw)[cols]])
        y = [_ln(magnitude(sw.center[rows, cols]))[:, None],
             _ln(magnitude(sw.edge[rows, cols]))[:, None]]
        self.pod_ = None
        if sw.profile is not None:
            lp = _ln(magnitude(sw.profile[rows, cols]))
            self.pod_ = Pod(self.profile_modes).fit(lp)
            y.append(self.pod_.transform(lp))
        return x, np.column_stack(y)

    def query(self, sw: Sweeps) -> np.ndarray:
        n_f = sw.band.size
        return np.column_stack([np.repeat(sw.x, n_f, axis=0), np.tile(self._f01(sw), len(sw))])

    def decode(self, pred: np.ndarray, sw: Sweeps) -> Answers:
        n, n_f = len(sw), sw.band.size
        prof = None
        if self.pod_ is not None:
            prof = np.exp(self.pod_.inverse_transform(pred[:, 2:])).reshape(n, n_f, -1)
        return Answers(np.exp(pred[:, 0]).reshape(n, n_f), np.exp(pred[:, 1]).reshape(n, n_f),
                       prof)

    def targets(self, sw: Sweeps) -> np.ndarray:
        y = [_ln(magnitude(sw.center)).reshape(-1, 1), _ln(magnitude(sw.edge)).reshape(-1, 1)]
        if self.pod_ is not None and sw.profile is not None:
            lp = _ln(magnitude(sw.profile)).reshape(len(sw) * sw.band.size, -1)
            y.append(self.pod_.transform(lp))
        return np.column_stack(y)


class LnMagBand(Choice):
    """Whole ln |u(f)| curves out, through POD (``modes``; ``profile_modes`` for ln |profile|
    over frequency and radius)."""

    name = "ln-magnitude band"

    def __init__(self, modes: int | None = 24, profile_modes: int | None = 24) -> None:
        self.modes = modes
        self.profile_modes = profile_modes

    def training(self, sw: Sweeps, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        y = np.column_stack([_ln(magnitude(sw.center)), _ln(magnitude(sw.edge))])
        self.pod_ = Pod(self.modes).fit(y)
        self.profile_pod_ = None
        if sw.profile is not None:
            lp = _ln(magnitude(sw.profile)).reshape(len(sw), -1)
            self.profile_pod_ = Pod(self.profile_modes).fit(lp)
        return sw.x, self.targets(sw)

    def targets(self, sw: Sweeps) -> np.ndarray:
        y = np.column_stack([_ln(magnitude(sw.center)), _ln(magnitude(sw.edge))])
        out = [self.pod_.transform(y)]
        if self.profile_pod_ is not None and sw.profile is not None:
            out.append(self.profile_pod_.transform(_ln(magnitude(sw.profile)).reshape(len(sw),
                                                                                      -1)))
        return np.column_stack(out)

    def decode(self, pred: np.ndarray, sw: Sweeps) -> Answers:
        k = self.pod_.basis_.shape[0]
        out = np.exp(self.pod_.inverse_transform(pred[:, :k]))
        n, n_f = len(sw), sw.band.size
        prof = None
        if self.profile_pod_ is not None:
            prof = np.exp(self.profile_pod_.inverse_transform(pred[:, k:])).reshape(n, n_f, -1)
        return Answers(out[:, :n_f], out[:, n_f:], prof)


def _re_im(z: np.ndarray) -> np.ndarray:
    """Complex (n, ...) -> real (n, 2 * size): real parts, then imaginary parts."""
    z = z.reshape(len(z), -1)
    return np.concatenate([z.real, z.imag], axis=1)


def _complex(a: np.ndarray) -> np.ndarray:
    half = a.shape[1] // 2
    return a[:, :half] + 1j * a[:, half:]


class ComplexBand(Choice):
    """Complex components over the band out, normalised by the band's RMS centre level
    (targets: ln scale, POD of centre and edge, POD of the profile; ``None`` modes: all)."""

    name = "complex band"

    def __init__(self, modes: int | None = 24, profile_modes: int | None = 24) -> None:
        self.modes = modes
        self.profile_modes = profile_modes

    @staticmethod
    def scale(center: np.ndarray) -> np.ndarray:
        """The band's RMS centre amplitude of each design (n,) [um]."""
        return np.sqrt(np.mean(magnitude(center) ** 2, axis=1))

    def encode(self, center: np.ndarray, edge: np.ndarray,
               profile: np.ndarray | None = None) -> np.ndarray:
        """Targets of designs (fitting the bases on the first call): ln scale, shape POD
        coefficients (and profile POD coefficients)."""
        s = self.scale(center)
        shape = _re_im(np.concatenate([center, edge], axis=1) / s[:, None, None])
        if not hasattr(self, "pod_"):
            self.pod_ = Pod(self.modes).fit(shape)
            self.profile_pod_ = None
            if profile is not None:
                self.profile_pod_ = Pod(self.profile_modes).fit(
                    _re_im(profile / s[:, None, None, None]))
        out = [np.log(s)[:, None], self.pod_.transform(shape)]
        if self.profile_pod_ is not None and profile is not None:
            out.append(self.profile_pod_.transform(_re_im(profile / s[:, None, None, None])))
        return np.column_stack(out)

    def decode_complex(self, pred: np.ndarray, n_f: int
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """(centre, edge (n, n_f, 3), profile (n, n_f, n_p, 3) or None) complex [um] of
        predicted targets."""
        n, k = len(pred), self.pod_.basis_.shape[0]
        s = np.exp(pred[:, 0])
        z = _complex(self.pod_.inverse_transform(pred[:, 1:1 + k])).reshape(n, 2 * n_f, 3)
        z = z * s[:, None, None]
        prof = None
        if self.profile_pod_ is not None:
            p = _complex(self.profile_pod_.inverse_transform(pred[:, 1 + k:]))
            prof = p.reshape(n, n_f, -1, 3) * s[:, None, None, None]
        return z[:, :n_f], z[:, n_f:], prof

    def training(self, sw: Sweeps, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        if hasattr(self, "pod_"):
            del self.pod_
        return sw.x, self.encode(sw.center, sw.edge, sw.profile)

    def targets(self, sw: Sweeps) -> np.ndarray:
        return self.encode(sw.center, sw.edge, sw.profile)

    def decode(self, pred: np.ndarray, sw: Sweeps) -> Answers:
        c, e, p = self.decode_complex(pred, sw.band.size)
        return Answers(magnitude(c), magnitude(e), None if p is None else magnitude(p))


#: Choice name on the command line -> its class.
CHOICES = {"point": Point, "lnmag": LnMagBand, "complex": ComplexBand}
