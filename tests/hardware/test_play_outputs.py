"""``play --out`` never replaces files it did not write (issue 21, item 1): the output
directory is built beside the target and renamed into place; an earlier play output is
replaced only with --overwrite; any other directory is refused naming what it holds."""

from __future__ import annotations

import json

from hw_cases import line_plan, sealed

from hapticrom.cli import main


def _inputs(tmp_path):
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(sealed(line_plan())))
    pattern = tmp_path / "p.toml"
    pattern.write_text("[[step]]\nsites = [0, 2]\nduration_ms = 60.0\n")
    return plan, pattern


def test_play_refuses_to_overwrite_user_files(tmp_path, capsys):
    """Before: commands.jsonl (and field.gif, field-peak.png) in DIR were overwritten."""
    plan, pattern = _inputs(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "commands.jsonl").write_text("my notes\n")
    for extra in ([], ["--overwrite"]):
        assert main(["play", str(plan), str(pattern), "--device", "log", "--out", str(out),
                     *extra]) == 2
        err = capsys.readouterr().err
        assert str(out) in err and "commands.jsonl" in err and "did not write" in err
        assert (out / "commands.jsonl").read_text() == "my notes\n"
        assert sorted(p.name for p in out.iterdir()) == ["commands.jsonl"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "p.toml", "plan.json"]


def test_play_replaces_its_own_output_only_with_overwrite(tmp_path, capsys):
    plan, pattern = _inputs(tmp_path)
    out = tmp_path / "out"
    argv = ["play", str(plan), str(pattern), "--device", "log", "--out", str(out)]
    assert main(argv) == 0
    first = (out / "commands.jsonl").read_text()
    assert main(argv) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert main([*argv, "--overwrite"]) == 0
    assert (out / "commands.jsonl").read_text().count("\n") == first.count("\n")
    (out / "mine.txt").write_text("x")  # a user file put into the output: no longer ours
    assert main([*argv, "--overwrite"]) == 2
    assert "mine.txt" in capsys.readouterr().err
    assert (out / "mine.txt").read_text() == "x"


def test_play_never_writes_over_its_inputs(tmp_path, capsys):
    plan, pattern = _inputs(tmp_path)
    assert main(["play", str(plan), str(pattern), "--device", "log", "--out",
                 str(tmp_path), "--overwrite"]) == 2
    assert "overlaps the input" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.toml", "plan.json"]


def test_play_refuses_a_deep_plan_or_pattern_with_exit_2(tmp_path, capsys):
    """Before: RecursionError, exit 1."""
    plan, pattern = _inputs(tmp_path)
    deep_plan = tmp_path / "deep.json"
    deep_plan.write_text('{"x": ' + "[" * 1000 + "]" * 1000 + "}")
    deep_pattern = tmp_path / "deep.toml"
    deep_pattern.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    for p, q in ((deep_plan, pattern), (plan, deep_pattern)):
        out = tmp_path / "out"
        assert main(["play", str(p), str(q), "--device", "log", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert "nested deeper than the limit" in err and "Traceback" not in err
        assert not out.exists()
