"""Single output files: hapticrom replaces a file only if it wrote it (its JSON documents, its
figures) or when told to with --overwrite; a user's file is refused by name, exit 2, untouched."""

from __future__ import annotations

import json

import matplotlib

import figstyle
from hapticrom.cli import main
from hapticrom.outputs import written_file

matplotlib.use("Agg")

SCENE = """
[tissue]
radius_mm = 30.0
[mesh]
order = 1
near_size_mm = 1.5
far_size_mm = 4.0
[analysis]
kind = "static"
"""


def test_files_hapticrom_wrote_are_recognised(tmp_path):
    fig, _ = figstyle.figure()
    figstyle.save(fig, tmp_path / "fig.png")
    (tmp_path / "doc.json").write_text(json.dumps({"schema_version": 1,
                                                   "kind": "hapticrom.plan"}))
    (tmp_path / "other.json").write_text(json.dumps({"kind": "something else"}))
    (tmp_path / "notes.txt").write_text("my notes")
    assert written_file(tmp_path / "fig.png") and written_file(tmp_path / "doc.json")
    assert not written_file(tmp_path / "other.json")
    assert not written_file(tmp_path / "notes.txt")


def test_a_users_file_is_refused_and_left_alone(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE)
    mine = tmp_path / "notes.json"
    mine.write_text('{"my": "data"}')
    assert main(["simulate", str(scene), "--json", str(mine)]) == 2
    err = capsys.readouterr().err
    assert "--json" in err and "hapticrom did not write it" in err and "--overwrite" in err
    assert mine.read_text() == '{"my": "data"}'
    # its own output is replaced on a second run; a user's file only when told
    out = tmp_path / "out.json"
    assert main(["simulate", str(scene), "--json", str(out)]) == 0
    assert main(["simulate", str(scene), "--json", str(out)]) == 0
    assert main(["simulate", str(scene), "--json", str(mine), "--overwrite"]) == 0
    assert json.loads(mine.read_text())["kind"] == "hapticrom.simulate.static"
