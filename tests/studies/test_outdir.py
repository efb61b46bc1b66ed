"""The report directory is never a user's: a foreign non-empty directory is refused by name and
left untouched, our own is replaced as a whole, a failure keeps the previous report."""

import pytest

from hapticrom.cli import main
from studies.guo2025.outdir import MARKER, check_out_dir, write_report_dir


def _names(path):
    return sorted(p.name for p in path.iterdir())


def test_a_foreign_non_empty_directory_is_refused_and_left_untouched(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "thesis.tex").write_text("precious")
    with pytest.raises(ValueError, match=r"out = .*mine.*not empty.*not written by") as err:
        check_out_dir(out)
    assert MARKER in str(err.value)
    with pytest.raises(ValueError, match="not empty"):
        write_report_dir(out, lambda d: (d / "README.md").write_text("report"))
    assert _names(out) == ["thesis.tex"] and (out / "thesis.tex").read_text() == "precious"
    assert _names(tmp_path) == ["mine"]  # no temporary left behind


def test_the_cli_refuses_a_foreign_directory_with_exit_2_before_solving(tmp_path, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep")
    assert main(["reproduce", "--out", str(out), "--quick", "--workers", "1"]) == 2
    assert "not written by" in capsys.readouterr().err
    assert _names(out) == ["notes.txt"]


def test_new_and_empty_directories_are_written_with_the_marker(tmp_path):
    for out in (tmp_path / "new", tmp_path / "empty"):
        if out.name == "empty":
            out.mkdir()
        write_report_dir(check_out_dir(out), lambda d: (d / "README.md").write_text("r"))
        assert _names(out) == [MARKER, "README.md"]


def test_our_own_report_is_replaced_as_a_whole_and_kept_on_failure(tmp_path):
    out = tmp_path / "rep"
    write_report_dir(out, lambda d: (d / "stale.md").write_text("old"))
    write_report_dir(check_out_dir(out), lambda d: (d / "new.md").write_text("new"))
    assert _names(out) == [MARKER, "new.md"]

    def fail(d):
        (d / "half.md").write_text("half")
        raise RuntimeError("boom")

    with pytest.raises(RuntimeError):
        write_report_dir(out, fail)
    assert _names(out) == [MARKER, "new.md"]
    assert _names(tmp_path) == ["rep"]


def test_a_file_or_a_missing_parent_is_refused(tmp_path):
    (tmp_path / "f").write_text("x")
    with pytest.raises(ValueError, match="not a directory"):
        check_out_dir(tmp_path / "f")
    with pytest.raises(ValueError, match="does not exist"):
        check_out_dir(tmp_path / "no" / "rep")
