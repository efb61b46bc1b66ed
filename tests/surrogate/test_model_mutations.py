"""Property tests (issue 21, item 6): any alteration of a model directory -- a flipped byte in
a model file, an edited card value, a listed name leaving the directory, a symlink, a stray
file -- is refused with a :class:`ModelFileError` naming a file, and loading writes nothing.
An alteration whose digests were all recomputed ("re-sealed") may load (integrity cannot tell
it from a model trained that way); it is then refused by name or works, never a traceback."""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from model_dirs import copy_model, read, reseal, tree, write

from surrogate.registry import check_model
from surrogate.runtime import ModelFileError, RomBlowUpError

KINDS = st.sampled_from(["gp", "nn", "rom"])
SETTINGS = settings(max_examples=40, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])
JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-10**6, 10**6) | st.floats(allow_nan=False)
    | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=4), inner,
                                                                 max_size=3),
    max_leaves=6)


def _leaves(obj, path=()):
    """Every (path, value) of a JSON value, containers included."""
    yield path, obj
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _leaves(v, (*path, i))


def _set(obj, path, value):
    for k in path[:-1]:
        obj = obj[k]
    obj[path[-1]] = value


def _refused(d: Path, *names: str) -> ModelFileError:
    before = tree(d.parent)
    try:
        check_model(d)
    except ModelFileError as err:
        assert tree(d.parent) == before  # nothing written
        assert any(n in str(err) for n in names), (names, str(err))
        return err
    raise AssertionError(f"an altered model was accepted ({names})")


def _refused_or_works(d: Path) -> None:
    """A re-sealed alteration: a named refusal, or a model that loads and answers."""
    try:
        check_model(d)
    except (ModelFileError, RomBlowUpError) as err:
        assert str(err)
        return


def _tmp() -> tempfile.TemporaryDirectory:
    return tempfile.TemporaryDirectory(prefix="mut-")


@SETTINGS
@given(kind=KINDS, where=st.floats(0, 1, exclude_max=True), bit=st.integers(0, 7),
       resealed=st.booleans())
def test_a_flipped_bit_in_a_model_file(kind, where, bit, resealed):
    with _tmp() as t:
        d = copy_model(kind, Path(t) / "m")
        name = next(iter(read(d)["files"]))
        data = bytearray((d / name).read_bytes())
        data[int(where * len(data))] ^= 1 << bit
        (d / name).write_bytes(bytes(data))
        if not resealed:
            _refused(d, name)
            return
        reseal(d)
        _refused_or_works(d)


@SETTINGS
@given(kind=KINDS, pick=st.integers(0, 10**6), value=JSON_VALUES, resealed=st.booleans())
def test_an_edited_card_value(kind, pick, value, resealed):
    with _tmp() as t:
        d = copy_model(kind, Path(t) / "m")
        card = read(d)
        paths = [p for p, _ in _leaves(card) if p and p[0] != "card_sha256"]
        path = paths[pick % len(paths)]
        old = card
        for k in path:
            old = old[k]
        if old == value:
            return
        _set(card, path, value)
        write(d, card)
        if not resealed:
            _refused(d, "card.json")
            return
        reseal(d, card)
        _refused_or_works(d)


@SETTINGS
@given(kind=KINDS, name=st.sampled_from(["../m.bin", "/tmp/m.bin", "sub/m.bin", "..", ".",
                                         "card.json", "a\\b", ""]),
       role=st.booleans())
def test_a_listed_name_leaving_the_directory(kind, name, role):
    with _tmp() as t:
        d = copy_model(kind, Path(t) / "m")
        card = read(d)
        old = next(iter(card["files"]))
        card["files"] = {name: card["files"][old]}
        if role:  # the graph / coefficients entry points there too
            if kind == "rom":
                card["coefficients"] = name
            else:
                card["graph"]["file"] = name
        reseal(d, card)
        _refused(d, repr(name), "card.json", "graph.file", "coefficients")


@SETTINGS
@given(kind=KINDS, what=st.sampled_from(["symlink-file", "stray-file", "stray-dir",
                                         "stray-symlink", "symlink-card"]))
def test_symlinks_and_stray_entries(kind, what):
    with _tmp() as t:
        d = copy_model(kind, Path(t) / "m")
        name = next(iter(read(d)["files"]))
        if what == "symlink-file":
            shutil.copy(d / name, Path(t) / "outside")
            (d / name).unlink()
            os.symlink(Path(t) / "outside", d / name)
            _refused(d, name)
        elif what == "symlink-card":
            shutil.copy(d / "card.json", Path(t) / "card-outside.json")
            (d / "card.json").unlink()
            os.symlink(Path(t) / "card-outside.json", d / "card.json")
            _refused(d, "card.json")
        else:
            target = d / "extra"
            if what == "stray-file":
                target.write_text("x")
            elif what == "stray-dir":
                target.mkdir()
            else:
                os.symlink(d / name, target)
            _refused(d, "extra")


@SETTINGS
@given(kind=KINDS, cut=st.floats(0, 1, exclude_max=True), junk=st.binary(max_size=16))
def test_a_damaged_card_file(kind, cut, junk):
    with _tmp() as t:
        d = copy_model(kind, Path(t) / "m")
        raw = (d / "card.json").read_bytes()
        damaged = raw[:int(cut * len(raw))] + junk
        assume(not _same_json(damaged, raw))  # a dropped trailing newline alters nothing
        (d / "card.json").write_bytes(damaged)
        _refused(d, "card.json")


def _same_json(a: bytes, b: bytes) -> bool:
    try:
        return json.loads(a) == json.loads(b)
    except ValueError:
        return False


def test_a_resealed_model_that_loads_still_answers():
    """The one thing integrity cannot see: a consistent, re-sealed edit. It is used as a
    model would be, never a crash (the shipped rom's motor constants, say)."""
    with _tmp() as t:
        d = copy_model("nn", Path(t) / "m")
        card = read(d)
        card["metrics"] = {}
        reseal(d, card)
        assert check_model(d)["metrics"] == {}
        assert json.loads((d / "card.json").read_text())["card_sha256"]
        assert np.isfinite(len(card["inputs"]))
