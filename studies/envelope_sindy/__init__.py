"""Does SINDy identify the envelope model's dynamic remainder better than today's fit? (Issue 39.)

The grey-box envelope model (``models/rom-default``, :mod:`surrogate.runtime.rom`) is kept as
the known part: the motor law's speed, the harmonic model's steady response A at the
instantaneous speed and the one rotating-frame mode whose envelope m(t) it gives. SINDy with
control (pysindy) then identifies what that model lacks as a residual state

    r = (e_FE - m) / s,    dr/dt = Theta(r, u) xi,    e = m + s r,

with s the run's largest steady level (the model's own, known at run time) and the control
u from the motor law and the known mode: the mode's lag d = (m - A) / s, the speed
w = omega / (2 pi 130 Hz), its rate of change w' (per 10 ms), A / s and m / s. The candidate
libraries carry what the one-mode model is measured to lack (docs/transient-model.md): a second,
slower state beside the mode (r itself), damping that depends on speed or amplitude (r w,
r m, r A), and the speed's rate of change (w', w' m). Every library is affine in r, so the
identified residual is integrated exactly between samples by numpy
(:func:`residual_response`), as the run time would have to.

Variants (:data:`VARIANTS`): sparse regression by pysindy's STLSQ and SR3, coefficients per
attachment (one set for glued, one for pogo units, as today's design map is grouped) or
affine in the design features (SINDyCP, ``ParameterizedLibrary``, the same encoded features
as today's map). Each is fitted on the training runs of ``datasets/transient`` and scored with
the card's metrics (:mod:`surrogate.envelope.metrics`) on the same 56 held-out runs as today's
model, in one table. Entry point: ``bench/surrogate/envelope_sindy.py``. pysindy is not a
dependency of the project (this measurement removed it): ``pip install "pysindy==2.1.0"``
to re-run it.
"""

from .study import VARIANTS, residual_response, run, table

__all__ = ["VARIANTS", "residual_response", "run", "table"]
