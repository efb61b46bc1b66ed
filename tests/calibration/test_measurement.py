"""Measurement files: the format, the unit conversions to the model's quantity, and every bad
row named with its column and the allowed values."""

from __future__ import annotations

import math

import pytest

from calibration.measurement import (
    G_M_S2,
    Measurement,
    MeasurementError,
    measurement_from_rows,
    read_measurement,
    to_amplitude_m,
    write_measurement,
)

HEADER = "reference,distance_mm,frequency_hz,quantity,unit,statistic,component,value,uncertainty"


def _write(tmp_path, rows, meta=("# design.n_rings = 0",)):
    path = tmp_path / "m.csv"
    path.write_text("\n".join([*meta, HEADER, *rows]) + "\n")
    return path


def test_conversions_to_peak_displacement():
    w = 2 * math.pi * 150.0
    assert to_amplitude_m(10.0, "displacement", "um", "peak", 150.0) == pytest.approx(1e-5)
    assert to_amplitude_m(10.0, "displacement", "um", "peak-to-peak", 150.0) == \
        pytest.approx(5e-6)
    assert to_amplitude_m(3.0, "velocity", "mm/s", "peak", 150.0) == pytest.approx(3e-3 / w)
    assert to_amplitude_m(2.0, "velocity", "m/s", "rms", 150.0) == \
        pytest.approx(2.0 * math.sqrt(2) / w)
    assert to_amplitude_m(1.0, "acceleration", "g", "rms", 150.0) == \
        pytest.approx(G_M_S2 * math.sqrt(2) / w ** 2)
    assert to_amplitude_m(5.0, "acceleration", "m/s^2", "peak", 150.0) == \
        pytest.approx(5.0 / w ** 2)


def test_read_file_metadata_and_relative_uncertainty(tmp_path):
    path = _write(tmp_path, ["centre,0,150,acceleration,g,rms,magnitude,1.2,5%",
                             "edge,4,150,velocity,mm/s,peak,normal,4.5,0.3"],
                  meta=("# format = hapticrom-measurement 1", "# subject = arm",
                        "# design.orientation = forward", "# design.n_rings = 2",
                        "# site.fat_thickness_mm = 9.5", "# a plain comment"))
    m = read_measurement(path)
    assert m.design == {"orientation": "forward", "n_rings": 2}
    assert m.site == {"fat_thickness_mm": 9.5}
    assert m.meta["subject"] == "arm"
    a, b = m.points
    assert (a.row, b.row) == (8, 9)  # line numbers in the file
    assert a.uncertainty == pytest.approx(0.06)
    assert a.relative_sigma == pytest.approx(0.05)
    assert b.relative_sigma == pytest.approx(0.3 / 4.5)
    assert b.distance_m == pytest.approx(4e-3) and b.component == "normal"
    assert a.amplitude_m == pytest.approx(to_amplitude_m(1.2, "acceleration", "g", "rms", 150))
    assert m.frequencies_hz == (150.0,)


def test_every_bad_row_is_named_with_column_and_allowed_values(tmp_path):
    path = _write(tmp_path, ["centre,0,150,displacement,um,peak,magnitude,3,0.1",
                             "middle,0,150,displacement,um,peak,magnitude,3,0.1",
                             "edge,2,150,velocity,g,peak,magnitude,3,0.1",
                             "edge,2,-5,displacement,um,peak,magnitude,3,0.1",
                             "edge,2,150,displacement,um,mean,sideways,3,0.1",
                             "edge,2,150,displacement,um,peak,magnitude,-1,0.1",
                             "edge,2,150,displacement,um,peak,magnitude,3,4",
                             "edge,2,150"])
    with pytest.raises(MeasurementError) as err:
        read_measurement(path)
    text = str(err.value)
    assert err.value.field == "row 4: reference"
    for piece in ("row 4, column reference: 'middle' is not one of centre, edge",
                  "row 5, column unit: 'g' is not a unit of velocity (allowed: mm/s, m/s)",
                  "row 6, column frequency_hz", "row 7, column statistic",
                  "row 7, column component: 'sideways' is not one of normal, magnitude",
                  "row 8, column value", "row 9, column uncertainty", "row 10: 3 cells"):
        assert piece in text
    assert "8 bad value(s)" in text


def test_header_and_metadata_errors(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("reference,distance_mm,frequency_hz\nedge,1,150\n")
    with pytest.raises(MeasurementError, match="column 'quantity' is missing"):
        read_measurement(path)
    with pytest.raises(MeasurementError, match="unknown key 'colour'"):
        read_measurement(_write(tmp_path, ["edge,1,150,displacement,um,peak,magnitude,3,5%"],
                                meta=("# colour = red",)))
    with pytest.raises(MeasurementError, match="no measurement rows"):
        read_measurement(_write(tmp_path, []))
    with pytest.raises(MeasurementError, match="cannot read"):
        read_measurement(tmp_path / "absent.csv")


def test_python_rows_and_round_trip(tmp_path):
    rows = [{"reference": "edge", "distance_mm": 3, "frequency_hz": 120.0,
             "quantity": "velocity", "unit": "mm/s", "statistic": "rms",
             "component": "magnitude", "value": 2.5, "uncertainty": "10%"}]
    m = measurement_from_rows(rows, design={"n_rings": 1}, site={"skin_E_kPa": 60.0})
    assert isinstance(m, Measurement) and m.points[0].row == 1
    path = tmp_path / "out.csv"
    write_measurement(m, path)
    back = read_measurement(path)
    assert back.design == m.design and back.site == m.site
    assert back.points[0].amplitude_m == pytest.approx(m.points[0].amplitude_m, rel=1e-5)
    assert back.points[0].sigma_m == pytest.approx(m.points[0].sigma_m, rel=1e-5)
    bad = [dict(rows[0], quantity="force")]
    with pytest.raises(MeasurementError, match="row 1, column quantity: 'force'"):
        measurement_from_rows(bad)


def test_runtime_path_imports_no_solver_or_training_stack():
    """The calibration library runs on numpy, onnxruntime and emcee; the planner's tissue hook
    reads a calibration without even emcee."""
    import subprocess
    import sys

    code = ("import sys, calibration, calibration.plot, planner.tissue; "
            "bad = [m for m in ('fem', 'torch', 'sklearn', 'scipy', 'emcee') "
            "if m in sys.modules]; print(' '.join(bad))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == []
