"""fieldspec: the shared field-spec engine (types, intervals with relative bounds, choices,
unknown keys, arrays, one error class with .field)."""

import pytest

from fieldspec import REQUIRED, Context, FieldError, Spec, read_array, read_table

SPECS = {
    "length_mm": Spec(float, REQUIRED, "(0, 100]"),
    "inner_mm": Spec(float, 1.0, "[0, .length_mm)"),
    "count": Spec(int, 3, "[1, 10]"),
    "mode": Spec(str, "a", choices=("a", "b")),
    "flag": Spec(bool, None),
    "radii_mm": Spec(tuple, (0.0,), "[0, .length_mm]"),
    "step_mm": Spec(float, 1.0, "(0, .length_mm]"),
}


class BoxError(FieldError):
    pass


def _read(raw):
    return read_table(raw, SPECS, "box", Context(BoxError))


def test_defaults_and_conversion():
    out = _read({"length_mm": 5, "radii_mm": [1, 2]})
    assert out == {"length_mm": 5.0, "inner_mm": 1.0, "count": 3, "mode": "a", "flag": None,
                   "radii_mm": (1.0, 2.0), "step_mm": 1.0}
    assert isinstance(out["length_mm"], float)


@pytest.mark.parametrize(("raw", "field", "text"), [
    ({}, "box.length_mm", "0 < length_mm <= 100"),
    ({"length_mm": 0.0}, "box.length_mm", "out of range: allowed 0 < length_mm <= 100"),
    ({"length_mm": float("nan")}, "box.length_mm", "out of range"),
    ({"length_mm": True}, "box.length_mm", "true/false is not a number"),
    ({"length_mm": 5, "inner_mm": 5}, "box.inner_mm", "inner_mm < box.length_mm (= 5)"),
    ({"length_mm": 0.5}, "box.inner_mm", "(the default) is out of range"),
    ({"length_mm": 5, "count": 2.0}, "box.count", "expected an integer"),
    ({"length_mm": 5, "mode": "c"}, "box.mode", "choose one of 'a', 'b'"),
    ({"length_mm": 5, "flag": 1}, "box.flag", "leave the key out for auto"),
    ({"length_mm": 5, "radii_mm": [1, 9]}, "box.radii_mm[1]", "radii_mm <= box.length_mm"),
    ({"length_mm": 5, "step_mm": 6}, "box.step_mm", "step_mm <= box.length_mm (= 5)"),
    ({"length_mm": 5, "lenght_mm": 5}, "box.lenght_mm", "did you mean 'length_mm'"),
    ({"length_mm": 5, "zzz": 5}, "box.zzz", "allowed keys: length_mm, inner_mm, count"),
])
def test_errors_name_field_and_range(raw, field, text):
    with pytest.raises(BoxError) as info:
        _read(raw)
    assert info.value.field == field
    assert isinstance(info.value, ValueError)
    assert text in str(info.value)
    assert field.split("[")[0] in str(info.value)


def test_array_of_tables_paths_and_count():
    ctx = Context()
    items = read_array([{"length_mm": 2}, {"length_mm": 3}], "box", ctx,
                       lambda item, where, i: read_table(item, SPECS, where, ctx))
    assert [item["length_mm"] for item in items] == [2.0, 3.0]
    assert ctx["box[1].inner_mm"] == 1.0
    with pytest.raises(FieldError, match=r"inner_mm < box\[0\].length_mm \(= 1\)"):
        read_array([{"length_mm": 1, "inner_mm": 1}], "box", ctx,
                   lambda item, where, i: read_table(item, SPECS, where, ctx))
    with pytest.raises(FieldError) as info:
        read_array([{"length_mm": 2}, {"length_mm": -1}], "box", ctx,
                   lambda item, where, i: read_table(item, SPECS, where, ctx))
    assert info.value.field == "box[1].length_mm"
    with pytest.raises(FieldError, match="allowed 1 <= number of boxes <= 2"):
        read_array([], "box", ctx, lambda *a: None, count=(1, 2), noun="boxes")
    with pytest.raises(FieldError, match="expected an array of tables"):
        read_array({}, "box", ctx, lambda *a: None)


def test_toml_writer_round_trips_through_tomllib():
    import tomllib

    from fieldspec.toml import dumps, toml_value

    tables = {"box": {"name": 'a "q"\n\x01', "n": 3, "x": 1e-05, "ok": True, "xs": [1.0, 2.5],
                      "inner": {"k": 1}, "item": [{"a": 1}, {"a": 2}]}}
    text = dumps(tables, {"box": "item"}, header="written by a test")
    assert text.startswith("# written by a test\n")
    assert tomllib.loads(text) == tables
    with pytest.raises(ValueError, match="non-finite"):
        toml_value(float("inf"))
    with pytest.raises(TypeError):
        toml_value(object())


def test_read_toml_file_names_the_file_on_every_failure(tmp_path):
    from fieldspec import FieldError
    from fieldspec.toml import read_toml_file

    class PatternError(FieldError):
        pass

    good = tmp_path / "ok.toml"
    good.write_bytes(b"\xef\xbb\xbf[a]\nx = 1\n")  # a byte-order mark is accepted
    assert read_toml_file(good, PatternError, "pattern file") == {"a": {"x": 1}}
    bad = tmp_path / "bad.toml"
    bad.write_text("[a]\nx = \n")
    with pytest.raises(PatternError, match=r"bad.toml: invalid TOML.*line 2") as err:
        read_toml_file(bad, PatternError, "pattern file")
    assert err.value.field == "<file>"
    with pytest.raises(PatternError, match=r"cannot read pattern file .*missing\.toml"):
        read_toml_file(tmp_path / "missing.toml", PatternError, "pattern file")
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(PatternError, match="invalid TOML"):
        read_toml_file(binary, PatternError, "pattern file")
