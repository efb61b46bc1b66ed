"""fieldspec: declarative field specifications for TOML-shaped input files.

One engine validates every user-editable file of the project (FE scenes, dataset parameter
spaces, planner layouts). A table is described by a mapping ``key -> Spec`` (type, default or
:data:`REQUIRED`, allowed interval in math notation whose bounds may name earlier fields,
choices); :func:`read_fields` resolves a raw table against it, :func:`read_table` also rejects
unknown keys (listing the allowed ones), :func:`read_array` reads an array of tables. Every
error is a :class:`FieldError` whose ``.field`` is the dotted path of the offending value
(``unit.encapsulation[1].E_kPa``) and whose message names the field and the allowed range.

Units live in the key names (``thickness_mm``, ``E_kPa``); this package converts nothing.
It imports nothing of the project.
"""

from fieldspec.errors import FieldError, HapticromWarning, WorkError
from fieldspec.spec import (
    REQUIRED,
    Context,
    Spec,
    allowed_text,
    check_interval,
    is_bool,
    read_array,
    read_fields,
    read_number,
    read_table,
    read_value,
    require_table,
    unknown_key,
)

__all__ = [
    "REQUIRED",
    "Context",
    "FieldError",
    "HapticromWarning",
    "Spec",
    "WorkError",
    "allowed_text",
    "check_interval",
    "is_bool",
    "read_array",
    "read_fields",
    "read_number",
    "read_table",
    "read_value",
    "require_table",
    "unknown_key",
]
