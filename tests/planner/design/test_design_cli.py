"""`hapticrom design` through the command line: bad input exits 2 and writes nothing, no
felt design exits 1, and on a tiny case (one unit, one frequency, one FE sweep per unit) the
exit code follows the FE verdict (0 confirmed, 3 refuted) with every output written."""

from __future__ import annotations

import json
import tomllib

import pytest

from fieldspec.toml import dumps
from hapticrom.cli import main
from planner.design.record import check_design_record
from planner.layout import layout_from_dict


def _write(tmp_path, d: dict):
    path = tmp_path / "request.toml"
    path.write_text(dumps(d))
    return path


def test_bad_request_exits_2_and_writes_nothing(tmp_path, tiny_dict, capsys):
    tiny_dict["space"]["n_rings"] = [0, 5]
    out = tmp_path / "out"
    code = main(["design", str(_write(tmp_path, tiny_dict)), "--out-dir", str(out)])
    assert code == 2
    assert "space.n_rings[1]" in capsys.readouterr().err
    assert not out.exists()


def test_missing_out_dir_parent_exits_2(tmp_path, tiny_dict, capsys):
    code = main(["design", str(_write(tmp_path, tiny_dict)), "--out-dir",
                 str(tmp_path / "no" / "such")])
    assert code == 2 and "does not exist" in capsys.readouterr().err


def test_no_felt_design_exits_1(tmp_path, tiny_dict, capsys):
    tiny_dict["criterion"]["drive_level"] = 0.01  # the unit's own amplitude x 0.01: not felt
    code = main(["design", str(_write(tmp_path, tiny_dict)), "--no-verify"])
    assert code == 1
    assert "no design in the space" in capsys.readouterr().out


def test_tiny_case_end_to_end(tmp_path, tiny_dict, capsys):
    tiny_dict["space"]["n_rings"] = [1]
    tiny_dict["space"]["catalogue"] = ["A"]
    out = tmp_path / "out"
    code = main(["design", str(_write(tmp_path, tiny_dict)), "--out-dir", str(out),
                 "--seed", "1"])
    record = json.loads((out / "design.json").read_text())
    assert check_design_record(record) == "sealed"
    v = record["verify"]
    assert code == (0 if v["confirmed"] else 3)
    assert record["search"]["seed"] == 1
    # the FE pitch of the winner is the FE re-ranking's, and the reference was solved too
    assert v["designs"][0]["fe_pitch_mm"] == v["fe"]["pitch_mm"]
    assert [r["design"] for r in v["references"]] == ["unit-bare-forward"]
    assert v["target"]["met"] == (v["designs"][0]["fe_pitch_mm"]
                                  < v["references"][0]["fe_pitch_mm"])
    # the outputs read back: the layout plans, the scene is the unit at its frequency
    layout = layout_from_dict(tomllib.loads((out / "layout.toml").read_text()))
    assert layout.designs[0]["name"] == record["winner"]["name"]
    scene = tomllib.loads((out / "unit.toml").read_text())
    assert scene["unit"]["encapsulation"] == ["ecoflex-00-10"]
    assert scene["analysis"]["frequency_hz"] == 150.0
    assert (out / "design.png").stat().st_size > 10_000
    text = capsys.readouterr().out
    assert "verdict:" in text and ("CONFIRMED" in text) == v["confirmed"]


@pytest.mark.parametrize("option", ["--verify-top", "--seed"])
def test_bad_option_value_exits_2(tmp_path, tiny_dict, option):
    assert main(["design", str(_write(tmp_path, tiny_dict)), option, "-1"]) == 2
