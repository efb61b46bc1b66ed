"""The actuators: one class per ``load.kind`` in one module of this package.

Every module here is imported at start (below), and each registers its class with
:func:`fem.actuators.base.register`; adding an actuator is adding one module (the LRA,
``lra.py``, is the worked example). The scene's ``LoadKind`` and its schema's choices, and
every solver question about a load, come from :data:`ACTUATORS`.
"""

from __future__ import annotations

import importlib
import pkgutil

from .base import ACTUATORS, Actuator, actuator, register

__all__ = ["ACTUATORS", "Actuator", "actuator", "register"]

for _module in pkgutil.iter_modules(__path__):
    if _module.name != "base":
        importlib.import_module(f"{__name__}.{_module.name}")
