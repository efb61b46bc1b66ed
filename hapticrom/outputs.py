"""Writing outputs so that a failure never leaves a half-written one behind, and so that
nothing hapticrom did not write is ever replaced.

Files go through :func:`atomic_path`. Directories (``play --out``; models through
:func:`surrogate.registry.write_model`, which follows the same rules) are built in a fresh
temporary sibling and renamed into place (:func:`write_dir`); an existing directory is
replaced only when hapticrom wrote it as the same kind of output -- recognised by its own
marker (:func:`written_kind`: a model card, a dataset manifest, :data:`MARKER`) -- and only
with ``--overwrite``; anything else is refused naming the path and what it holds, and an
input being read is never an output (:func:`check_dir_output`).
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import figstyle
from fieldspec import FieldError
from fieldspec.documents import read_json_file


def check_output_file(option: str, target: str | os.PathLike, overwrite: bool = False) -> None:
    """Raise ValueError naming ``option`` unless ``target`` can be written as a file: its
    directory exists, it is not itself a directory, and an existing file there is one
    hapticrom wrote (:func:`written_file`) or ``overwrite`` says to replace it. Called before
    any work starts."""
    path = Path(target)
    if path.is_dir():
        raise ValueError(f"{option} {target}: is a directory; give a file name")
    if not path.resolve().parent.is_dir():
        raise ValueError(f"{option} {target}: the directory {path.parent} does not exist")
    if (path.exists() or path.is_symlink()) and not overwrite and not written_file(path):
        raise ValueError(f"{option} {target}: exists and hapticrom did not write it "
                         f"({path.stat().st_size if path.exists() else 0} bytes); refusing to "
                         "replace it: choose another name, or pass --overwrite")


def written_file(path: str | os.PathLike) -> bool:
    """Whether hapticrom wrote the file ``path``: a JSON document whose ``kind`` starts with
    ``hapticrom.`` (every document it writes), a PNG carrying figstyle's ``Software`` text
    chunk, a VTK file naming hapticrom's fields (``magnitude_um``). Anything else is the
    user's."""
    path = Path(path)
    if not path.is_file() or path.is_symlink():
        return False
    with open(path, "rb") as fh:
        head = fh.read(1 << 16)
    if head.startswith(b"\x89PNG"):
        return b"Software\x00" + figstyle.SOFTWARE.encode() in head
    if head.lstrip().startswith(b"{"):  # the kind is among the first keys of every document
        return re.search(rb'"kind"\s*:\s*"hapticrom\.', head) is not None
    return b"<VTKFile" in head[:4096] and b'Name="magnitude_um"' in head


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


# --------------------------------------------------------------------------- whole directories

#: The marker file of an output directory written by a command (play, ...): JSON with
#: ``kind`` ("hapticrom.play") and ``files`` (what the command wrote beside it).
MARKER = ".hapticrom-output.json"
_DATASET_MANIFEST = "_manifest.json"
_DATASET_FORMAT = "hapticrom-dataset"
_REPRODUCE_MARKER = ".hapticrom-reproduce"


def _listing(path: Path, limit: int = 5) -> str:
    names = sorted(p.name + ("/" if p.is_dir() and not p.is_symlink() else "")
                   for p in path.iterdir())
    shown = ", ".join(names[:limit])
    return shown + (f" and {len(names) - limit} more" if len(names) > limit else "")


def _json_kind(path: Path, key: str) -> Any:
    try:
        data = read_json_file(path, FieldError, "marker", max_bytes=1 << 20)
    except FieldError:
        return None
    return data.get(key) if isinstance(data, dict) else None


def written_kind(path: str | os.PathLike) -> str | None:
    """What hapticrom wrote ``path`` as, recognised by its own marker: "model" (a model card
    listing every file of the directory), "dataset" (a dataset manifest), "reproduce" (a
    report), the ``kind`` of a :data:`MARKER` whose ``files`` cover the directory ("play");
    None for anything else (the user's)."""
    path = Path(path)
    if not path.is_dir() or path.is_symlink():
        return None
    # Lazy: surrogate.registry loads onnxruntime through surrogate.runtime, 0.16 s of the
    # 0.4 s of `hapticrom --help` (python -X importtime); only a model directory needs it.
    from surrogate.registry import model_dir_files

    if (path / "card.json").is_file() and model_dir_files(path) is not None:
        return "model"
    if _json_kind(path / _DATASET_MANIFEST, "format") == _DATASET_FORMAT:
        return "dataset"
    if (path / _REPRODUCE_MARKER).is_file():
        return "reproduce"
    kind = _json_kind(path / MARKER, "kind")
    files = _json_kind(path / MARKER, "files")
    if isinstance(kind, str) and kind.startswith("hapticrom.") and isinstance(files, list):
        if all(p.name == MARKER or p.name in files for p in path.iterdir()):
            return kind.removeprefix("hapticrom.")
    return None


def _overlaps(target: Path, reads: Sequence[str | os.PathLike]) -> Path | None:
    """The first input that ``target`` is, contains, or lies inside (resolved paths)."""
    t = target.resolve()
    for r in reads:
        p = Path(r).resolve()
        if t == p or t in p.parents or p in t.parents:
            return Path(r)
    return None


def check_not_input(option: str, target: str | os.PathLike,
                    reads: Sequence[str | os.PathLike]) -> None:
    """Raise ValueError naming ``option`` when the output ``target`` is, contains or lies
    inside one of the inputs ``reads`` (it would delete or alter what the command reads)."""
    inside = _overlaps(Path(target), reads)
    if inside is not None:
        raise ValueError(f"{option} {target}: overlaps the input {inside} the command reads; "
                         "refusing (it would be deleted or altered); choose another directory")


def check_dir_output(option: str, target: str | os.PathLike, *, kind: str, overwrite: bool,
                     reads: Sequence[str | os.PathLike] = ()) -> None:
    """Raise ValueError (FileExistsError without ``overwrite``) naming ``option``, the path and
    what it holds, unless ``target`` may become a ``kind`` output directory: it does not
    exist, or is empty, or (with ``overwrite``) is a ``kind`` directory hapticrom wrote
    (:func:`written_kind`). An input being read (``reads``) is never the output, nor inside
    it, nor holds it. Called before any work starts, and again just before the swap."""
    path = Path(target)
    check_not_input(option, target, reads)
    if path.is_symlink() or (path.exists() and not path.is_dir()):
        raise ValueError(f"{option} {target}: exists and is not a directory; refusing to "
                         "replace it")
    if not path.resolve().parent.is_dir():
        raise ValueError(f"{option} {target}: the directory {path.parent} does not exist")
    if not path.exists() or not any(path.iterdir()):
        return
    found = written_kind(path)
    if found != kind:
        what = (f"a hapticrom {found}" if found else "files hapticrom did not write")
        raise ValueError(f"{option} {target}: the directory holds {_listing(path)} "
                         f"({what}); only a {kind} directory hapticrom wrote is replaced "
                         "(with --overwrite); choose a new or empty directory")
    if not overwrite:
        raise FileExistsError(f"{option} {target}: exists and holds an earlier {kind} output; "
                              "pass --overwrite to replace it")


@contextlib.contextmanager
def write_dir(option: str, target: str | os.PathLike, *, kind: str, overwrite: bool,
              reads: Sequence[str | os.PathLike] = ()) -> Iterator[Path]:
    """Yield a fresh temporary sibling of ``target``; when the block succeeds, add the
    :data:`MARKER` (kind ``hapticrom.<kind>``, the files written) and rename the directory
    into place, replacing ``target`` only as :func:`check_dir_output` allows (checked again
    just before the swap). When the block raises, nothing is left and ``target`` is as it
    was."""
    target = Path(target)
    check_dir_output(option, target, kind=kind, overwrite=overwrite, reads=reads)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.resolve().parent))
    old: Path | None = None
    try:
        os.chmod(tmp, _dir_mode())  # mkdtemp makes it private; an output is not
        yield tmp
        files = sorted(p.name for p in tmp.iterdir())
        (tmp / MARKER).write_text(json.dumps({"kind": f"hapticrom.{kind}", "files": files,
                                              "written_by": f"hapticrom {kind}"}) + "\n")
        for f in tmp.iterdir():
            os.chmod(f, _file_mode())
        check_dir_output(option, target, kind=kind, overwrite=overwrite, reads=reads)
        if target.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-",
                                        dir=target.resolve().parent))
            os.replace(target, old / target.name)
        os.replace(tmp, target)
    except BaseException:
        if old is not None and not target.exists():
            os.replace(old / target.name, target)  # put the previous output back
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)


def _dir_mode() -> int:
    """The mode a plain ``mkdir`` would give: 0777 less the process umask."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o777 & ~umask
