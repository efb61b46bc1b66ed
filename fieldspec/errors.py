"""The two error bases of the project: bad input (:class:`FieldError`) and work that failed
on valid input (:class:`WorkError`). The command line maps them to its exit codes in one place
(``hapticrom/cli.py``: 2 and 1). And the base of the project's own warnings
(:class:`HapticromWarning`), the only ones the command line shows without ``--verbose``."""

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


class WorkError(RuntimeError):
    """The work failed although its input was valid: a solver breakdown, a worker process that
    died, a device link that went away. The message says what failed and what was kept (the
    CLI: exit code 1, the message without a traceback). The one sibling of
    :class:`FieldError`; an unexpected error of any other type is a bug, and the CLI prints
    its traceback."""


class HapticromWarning(UserWarning):
    """A warning of the project itself (e.g. ``DatasetWarning``: stray files in a dataset).
    The command line shows these always, and third-party warnings (deprecations of torch's
    exporter, ...) only with ``--verbose``."""
