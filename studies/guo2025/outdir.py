"""The report directory: refuse to overwrite what we did not write, replace our own as a whole.

A directory written by :func:`write_report_dir` holds a marker file; only such a directory (or
an empty one, or none) is replaced. Anything else is the user's and an error names it.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

MARKER = ".hapticrom-reproduce"
MARKER_TEXT = ("Written by `hapticrom reproduce`: the next run replaces this directory as a "
               "whole.\n")


def check_out_dir(out: str | os.PathLike) -> Path:
    """``out`` resolved, if a report may be written there: its parent exists, and ``out`` is
    missing, empty, or a report directory (it holds :data:`MARKER`).

    Raises:
        ValueError: naming ``out`` and why nothing will be written there.
    """
    path = Path(out).resolve()
    if not path.parent.is_dir():
        raise ValueError(f"out = {out}: the parent directory {path.parent} does not exist")
    if path.exists() and not path.is_dir():
        raise ValueError(f"out = {out}: exists and is not a directory")
    if path.is_dir() and not (path / MARKER).is_file() and any(path.iterdir()):
        raise ValueError(f"out = {out}: the directory is not empty and was not written by "
                         f"`hapticrom reproduce` (no {MARKER} file); choose a new or empty "
                         "directory, the report replaces its directory as a whole")
    return path


def write_report_dir(out: Path, fill: Callable[[Path], None]) -> None:
    """Build the report with ``fill(tmp)`` in a temporary sibling directory, add the marker,
    then swap it into place; on any failure the previous ``out`` is left as it was."""
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    old = None
    try:
        umask = os.umask(0)
        os.umask(umask)
        tmp.chmod(0o777 & ~umask)  # mkdtemp makes it private; the report is not
        fill(tmp)
        (tmp / MARKER).write_text(MARKER_TEXT)
        check_out_dir(out)  # the user may have filled it since the run started
        if out.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
            os.replace(out, old / out.name)
        os.replace(tmp, out)
    except BaseException:
        if old is not None and not out.exists():
            os.replace(old / out.name, out)  # put the previous report back
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
