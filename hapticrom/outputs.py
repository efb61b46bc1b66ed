"""Writing output files so that a failure never leaves a half-written one behind."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path


def check_output_file(option: str, target: str | os.PathLike) -> None:
    """Raise ValueError naming ``option`` unless ``target`` can be written as a file: its
    directory exists and it is not itself a directory. Called before any work starts."""
    path = Path(target)
    if path.is_dir():
        raise ValueError(f"{option} {target}: is a directory; give a file name")
    if not path.resolve().parent.is_dir():
        raise ValueError(f"{option} {target}: the directory {path.parent} does not exist")


def _file_mode() -> int:
    """The mode a plain ``open(..., "w")`` would give: 0666 less the process umask."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``target`` (same suffix); rename it onto ``target`` when the
    block succeeds, delete it when the block raises. The file gets the permissions of a normal
    write (mkstemp alone would leave it private, 0600)."""
    target = Path(target)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=target.suffix, dir=target.parent)
    os.fchmod(fd, _file_mode())
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.replace(tmp_path, target)
    finally:
        tmp_path.unlink(missing_ok=True)


def check_output_dir(option: str, target: str | os.PathLike) -> None:
    """Raise ValueError naming ``option`` unless ``target`` can be an output directory: it is
    a directory already, or it does not exist and its parent does."""
    path = Path(target)
    if path.exists() and not path.is_dir():
        raise ValueError(f"{option} {target}: exists and is not a directory")
    if not path.resolve().parent.is_dir():
        raise ValueError(f"{option} {target}: the directory {path.parent} does not exist")


@contextlib.contextmanager
def atomic_dir(target: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary directory beside ``target``; when the block succeeds, create
    ``target`` if needed and move every file into it (each by an atomic rename); when the block
    raises, delete the temporary directory and leave ``target`` as it was."""
    import shutil

    target = Path(target)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.resolve().parent))
    try:
        yield tmp
        target.mkdir(exist_ok=True)
        for f in sorted(tmp.iterdir()):
            os.chmod(f, _file_mode())
            os.replace(f, target / f.name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
