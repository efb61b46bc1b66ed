"""One error base (issue 22): every error class that names an input is a FieldError, every
"the work failed" class a WorkError, and the CLI maps both in one place (2 and 1)."""

from __future__ import annotations

import argparse

import pytest

import hapticrom.cli as cli
from bench.structure.count_structure import own_field_errors
from fieldspec import FieldError, WorkError

#: ValueError subclasses left in files another change owns right now (the motor-law rework):
#: each becomes a FieldError there.
LEFT = {"TimingError", "RomInputError"}


def test_no_error_class_derives_from_valueerror_beside_fielderror():
    assert {name for _, _, name, _ in own_field_errors()} <= LEFT


def test_input_and_work_errors_derive_from_the_two_bases():
    from fem.domain import CellPlanError
    from fem.materials import UnknownMaterialError
    from fem.pardiso import PardisoError
    from hardware.device import DeviceError
    from surrogate.data.generate import RunnerError
    from surrogate.runtime.card import ModelFileError
    from surrogate.runtime.encoding import PredictorInputError

    for cls in (CellPlanError, UnknownMaterialError, ModelFileError, PredictorInputError):
        assert issubclass(cls, FieldError), cls
    for cls in (PardisoError, DeviceError, RunnerError):
        assert issubclass(cls, WorkError) and issubclass(cls, RuntimeError), cls
    err = UnknownMaterialError("unobtainium")
    assert err.field == "material" and isinstance(err, KeyError)
    assert str(err).startswith("unknown material 'unobtainium'")
    assert CellPlanError("r", "too few").field == "cells_r"


@pytest.mark.parametrize(("exc", "code", "text"), [
    (FieldError("x.y", "x.y = 3: allowed 0..1"), cli.EXIT_INPUT, "error: x.y = 3"),
    (WorkError("the solver broke down"), cli.EXIT_FAILED, "failed: the solver broke down"),
    (KeyError("bug"), cli.EXIT_FAILED, "failed: KeyError"),
])
def test_the_cli_maps_each_base_to_its_exit_code(monkeypatch, capsys, exc, code, text):
    def raise_it(args: argparse.Namespace) -> int:
        raise exc

    class Parser:
        def parse_args(self, argv: list[str]) -> argparse.Namespace:
            return argparse.Namespace(command="probe", func=raise_it)

    monkeypatch.setattr(cli, "build_parser", Parser)
    assert cli.main(["probe"]) == code
    err = capsys.readouterr().err
    assert text in err
    assert ("Traceback" in err) == (code == cli.EXIT_FAILED and not isinstance(exc, WorkError))
