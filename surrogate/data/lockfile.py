"""The advisory write lock of a dataset directory, deleted when released."""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
from collections.abc import Iterator
from pathlib import Path

from surrogate.data.errors import DatasetError

__all__ = ["exclusive"]


@contextlib.contextmanager
def exclusive(path: Path, owner: Path) -> Iterator[None]:
    """Hold an exclusive ``flock`` on ``path`` (released by the OS even on kill -9) or raise
    :class:`DatasetError` naming ``owner`` when another process holds it. The file is deleted
    on release, success or failure, so no lock file is left behind; a lock taken on a file
    that its previous holder deleted meanwhile is retaken on the new file."""
    while True:
        fh = open(path, "a+")
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            fh.close()
            if err.errno in (errno.EAGAIN, errno.EACCES):
                raise DatasetError(str(owner), f"{owner} is being written by another "
                                   "process (lock held); wait for it to finish") from None
            raise
        try:
            same = os.stat(path).st_ino == os.fstat(fh.fileno()).st_ino
        except FileNotFoundError:  # the holder before us deleted it as we opened it
            same = False
        if same:
            break
        fh.close()
    try:
        yield
    finally:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()  # while still locked: nobody can hold a lock on this inode
        fh.close()
