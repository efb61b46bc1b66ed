"""The public API of ``fem``: names importable from the package root, a cheap ``import fem``,
one error base class, load kinds as a string enum."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import fem
from fieldspec import FieldError


def test_import_fem_is_cheap_and_lazy():
    code = ("import sys, fem; heavy = [m for m in ('numpy', 'scipy', 'matplotlib', 'meshio') "
            "if m in sys.modules]; fem.load_scene; print(heavy, callable(fem.simulate))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[] True"


@pytest.mark.parametrize("name", fem.__all__)
def test_root_names_resolve(name):
    assert getattr(fem, name) is not None
    with pytest.raises(AttributeError):
        fem.no_such_name  # noqa: B018


def test_scene_error_is_the_field_error():
    assert issubclass(fem.SceneError, FieldError) and issubclass(fem.SceneError, ValueError)
    with pytest.raises(FieldError) as info:
        fem.scene_from_dict({"unit": {"encapsulation": [{"E_kPa": -1.0}]},
                             "load": {"kind": "unit"}})
    assert info.value.field == "unit.encapsulation[0].E_kPa"
    assert "0.001 <= E_kPa <= 1e9" in str(info.value)


def test_load_kind_is_a_string_enum_in_files_and_json():
    scene = fem.scene_from_dict({"load": {"kind": "point_force"}})
    assert scene.load.kind is fem.LoadKind.POINT_FORCE and scene.load.kind == "point_force"
    assert fem.scene_to_dict(scene)["load"]["kind"] == "point_force"
    assert type(fem.scene_to_dict(scene)["load"]["kind"]) is str
    assert json.loads(json.dumps(fem.scene_to_dict(scene)))["load"]["kind"] == "point_force"
    assert 'kind = "point_force"' in fem.dump_scene_toml(scene)
