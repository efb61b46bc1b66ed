"""The one error base class of user input validation."""

from __future__ import annotations


class FieldError(ValueError):
    """Invalid user input. ``field`` is the dotted path of the offending value, e.g.
    ``unit.encapsulation[1].E_kPa`` (``"<file>"`` for a file that cannot be parsed); the
    message names the field and the allowed range or choices.

    Subclasses (``SceneError``, ``SpaceError``, ...) only rename the kind of input, so callers
    (the CLI: exit code 2) can catch ``FieldError`` for all of them."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field
