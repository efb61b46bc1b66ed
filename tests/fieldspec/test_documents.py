"""Size and nesting limits on every TOML and JSON document the tool reads (issue 21, item 4):
a clear error naming the file, exit 2, never a RecursionError."""

from __future__ import annotations

import json

import pytest

from fieldspec import FieldError
from fieldspec.documents import (
    MAX_DEPTH,
    check_depth,
    loads_json,
    loads_toml,
    read_json_file,
    read_toml_file,
)
from hapticrom.cli import main

DEEP_TOML = "x = " + "[" * 5000 + "]" * 5000 + "\n"
DEEP_JSON = "[" * 1000 + "]" * 1000


class DocError(FieldError):
    pass


def test_deep_toml_and_json_are_refused_by_name():
    with pytest.raises(DocError, match=r"a\.toml: nested deeper than the limit") as err:
        loads_toml(DEEP_TOML, "a.toml", DocError)
    assert err.value.field == "<file>"
    with pytest.raises(DocError, match=r"b\.json: nested deeper"):
        loads_json(DEEP_JSON, "b.json", DocError)
    table = "[" + "a." * 40 + "b]\nx = 1\n"  # dotted tables nest without brackets
    with pytest.raises(DocError, match="nested deeper"):
        loads_toml(table, "c.toml", DocError)
    ok = "[" * (MAX_DEPTH - 1) + "]" * (MAX_DEPTH - 1)
    assert loads_json(ok, "d.json", DocError)
    with pytest.raises(DocError, match="nested deeper"):
        check_depth({"a": [[[1]]]}, "e", DocError, max_depth=3)


def test_brackets_inside_strings_do_not_count():
    text = 'x = "' + "[" * 500 + '"\ny = \'' + "{" * 500 + "'\n"
    assert loads_toml(text, "s.toml", DocError)["x"] == "[" * 500
    assert loads_json(json.dumps({"k": "[" * 500}), "s.json", DocError)["k"] == "[" * 500


def test_size_limit_and_non_json_numbers(tmp_path):
    big = tmp_path / "big.json"
    big.write_text("[" + "1," * 600 + "1]")
    with pytest.raises(DocError, match=r"big\.json: .*larger than the limit of 1000 bytes"):
        read_json_file(big, DocError, "plan", max_bytes=1000)
    nan = tmp_path / "nan.json"
    nan.write_text('{"a": NaN}')
    with pytest.raises(DocError, match=r"nan\.json: invalid JSON: NaN"):
        read_json_file(nan, DocError, "plan")
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"\xff\xfe")
    with pytest.raises(DocError, match="invalid TOML: the scene is not UTF-8"):
        read_toml_file(bad, DocError, "scene")


@pytest.mark.parametrize("command", ["simulate", "generate", "plan"])
def test_every_command_refuses_a_deep_document_with_exit_2(tmp_path, capsys, command):
    """Before: RecursionError, exit 1, in simulate, generate and plan (play: see
    tests/hardware/test_play_outputs.py)."""
    deep = tmp_path / "deep.toml"
    deep.write_text(DEEP_TOML)
    argv = {"simulate": ["simulate", str(deep)],
            "generate": ["generate", "--space", str(deep), "--n", "2", "--out",
                         str(tmp_path / "d")],
            "plan": ["plan", str(deep)]}[command]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "nested deeper than the limit" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["deep.toml"]


def test_train_options_nested_deep_are_refused(tmp_path, capsys):
    """Before: RecursionError, exit 1."""
    deep = "[" * 5000 + "]" * 5000
    assert main(["train", "--data", str(tmp_path), "--kind", "gp", "--out",
                 str(tmp_path / "m"), "--options", deep]) == 2
    err = capsys.readouterr().err
    assert "--options" in err and "nested deeper" in err and "Traceback" not in err
