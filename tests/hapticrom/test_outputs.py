"""Output files: checked before any work, written atomically with the usual permissions."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from hapticrom.cli import main
from hapticrom.outputs import atomic_path, check_output_file

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "forearm.toml"


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def test_atomic_files_get_the_umask_permissions_not_private_ones(tmp_path, umask_022):
    target = tmp_path / "out.json"
    with atomic_path(target) as tmp:
        tmp.write_text("{}")
    assert stat.S_IMODE(target.stat().st_mode) == 0o644


def test_a_failed_block_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError), atomic_path(tmp_path / "x.json") as tmp:
        tmp.write_text("half")
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []


def test_a_directory_or_a_missing_parent_is_refused_by_name(tmp_path):
    with pytest.raises(ValueError, match=r"--json .*: is a directory"):
        check_output_file("--json", tmp_path)
    with pytest.raises(ValueError, match=r"--plot .*: the directory .* does not exist"):
        check_output_file("--plot", tmp_path / "no" / "p.png")


def test_simulate_refuses_a_directory_before_solving(tmp_path, capsys):
    assert main(["simulate", str(EXAMPLE), "--json", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert "is a directory" in captured.err
    assert "center" not in captured.out  # nothing was solved
    assert list(tmp_path.iterdir()) == []


def test_a_reader_that_stops_early_is_not_an_error():
    """`hapticrom ... | head`: the closed pipe ends the command quietly with exit code 0."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[2]
    code = ("import sys; from hapticrom.cli import main; "
            "sys.exit(main(['models', 'show', 'models/gp-default']))")
    proc = subprocess.Popen([sys.executable, "-c", code], cwd=root, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    proc.stdout.close()  # before the interpreter has started: its first write hits EPIPE
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 0, err
    assert "Broken pipe" not in err and "Traceback" not in err
