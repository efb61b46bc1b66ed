"""The dataset layer's input errors: each a :class:`fieldspec.FieldError` carrying ``.field``.

``SpaceError``: an invalid parameter space or design point (``field`` such as
``parameter[2] (skin_E_kPa).low``). ``DatasetError``: a bad dataset, dataset argument or
dataset state (not a dataset, locked, incompatible space or solver; ``field`` names the
argument or manifest key, e.g. ``out`` or ``manifest.sampling.seed``). The command line maps
both to exit code 2.
"""

from __future__ import annotations

from fieldspec import FieldError

__all__ = ["DatasetError", "SpaceError"]


class SpaceError(FieldError):
    """Invalid parameter space, design point or generation argument."""


class DatasetError(FieldError):
    """Bad dataset input or state; ``field`` names the argument or manifest entry."""
