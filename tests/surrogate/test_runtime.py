"""Run-time predictor: input validation, extrapolation flag, import isolation."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from surrogate.runtime import PredictorInputError, load_predictor


def _row(**over):
    row = {"orientation": np.array(["forward"]), "n_rings": np.array([1]),
           "skin_E_kPa": np.array([50.0]), "frequency_hz": np.array([150.0])}
    row.update({k: np.atleast_1d(v) for k, v in over.items()})
    return row


@pytest.fixture(scope="module")
def predictor(trained_models):
    return load_predictor(trained_models["nn"][0])


def test_interface(predictor):
    assert predictor.input_names == ("orientation", "n_rings", "skin_E_kPa", "frequency_hz")
    assert predictor.input_ranges["skin_E_kPa"] == (20.0, 120.0)
    assert predictor.input_ranges["orientation"] == (0.0, 1.0)
    assert "profile_um" in predictor.output_names


def test_array_and_mapping_agree(predictor):
    a = predictor.predict(np.array([[1.0, 2.0, 40.0, 200.0], [0.0, 0.0, 90.0, 110.0]]))
    b = predictor.predict({"orientation": np.array(["reverse", "forward"]),
                           "n_rings": np.array([2, 0]), "skin_E_kPa": np.array([40.0, 90.0]),
                           "frequency_hz": np.array([200.0, 110.0])})
    for k in a:
        np.testing.assert_array_equal(a[k], b[k])


@pytest.mark.parametrize("over, field, match", [
    ({"skin_E_kPa": np.nan}, "skin_E_kPa", "not finite"),
    ({"skin_E_kPa": 500.0}, "skin_E_kPa", "outside the trained range"),
    ({"orientation": "sideways"}, "orientation", "not allowed"),
    ({"n_rings": 1.5}, "n_rings", "not an integer"),
    ({"n_rings": 7}, "n_rings", "outside the trained range"),
])
def test_bad_inputs_name_the_field(predictor, over, field, match):
    with pytest.raises(PredictorInputError, match=match) as err:
        predictor.predict(_row(**over))
    assert err.value.field == field


def test_shape_and_names_checked(predictor):
    with pytest.raises(PredictorInputError, match="shape"):
        predictor.predict(np.zeros((2, 3)))
    with pytest.raises(PredictorInputError, match="missing input"):
        predictor.predict({k: v for k, v in _row().items() if k != "n_rings"})
    with pytest.raises(PredictorInputError, match="unknown input"):
        predictor.predict({**_row(), "mass_g": np.array([1.0])})


def test_extrapolation_is_explicit(predictor):
    out = predictor.predict({k: np.concatenate([v, v]) for k, v in _row().items()} |
                            {"frequency_hz": np.array([150.0, 300.0])}, extrapolate=True)
    np.testing.assert_array_equal(out["extrapolated"], [False, True])
    assert np.all(np.isfinite(out["center_amplitude_um"]))
    with pytest.raises(PredictorInputError, match="outside"):  # categoricals never extrapolate
        predictor.predict(_row(orientation=5), extrapolate=True)


def test_runtime_imports_no_training_stack(trained_models):
    """A fresh interpreter: import the run time, load, predict; no torch/sklearn/solver."""
    code = textwrap.dedent(f"""
        import sys
        import numpy as np
        from surrogate.runtime import load_predictor
        for path in {[str(p) for p, _ in trained_models.values()]!r}:
            out = load_predictor(path).predict(np.array([[0.0, 1.0, 50.0, 150.0]]))
            assert np.isfinite(out["center_amplitude_um"]).all()
        banned = [m for m in ("torch", "sklearn", "fem", "skl2onnx", "onnx")
                  if m in sys.modules]
        assert not banned, banned
        print("isolated")
    """)
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 0, res.stderr
    assert "isolated" in res.stdout
