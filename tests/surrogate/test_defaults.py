"""The default models (surrogate.runtime.defaults): the first installed candidate of a role
that has the role's outputs serves, so installing a sweep model switches every command."""

from __future__ import annotations

import json
import tomllib

import pytest

from planner import LayoutError, layout_from_dict
from surrogate.runtime import defaults
from surrogate.runtime.card import ModelFileError, read_card
from surrogate.runtime.defaults import default_model, default_model_path, is_sweep_model
from surrogate.runtime.models import MODEL_PATH_ENV

SWEEP = "nn-sweep-fixture"  # the directory name of the sweep_model fixture


@pytest.fixture
def with_sweep(monkeypatch, sweep_model):
    """The sweep fixture installed (on the model path) in place of every sweep candidate
    (``nn-sweep``, ``nn-sweep-normal``, ``gp-sweep``), as the trained models are."""
    monkeypatch.setenv(MODEL_PATH_ENV, str(sweep_model.parent))
    _sweep_candidates_as(monkeypatch, SWEEP)
    return sweep_model


@pytest.fixture
def without_sweep(monkeypatch):
    """The sweep candidate absent (a name no model root holds): the single-frequency models
    serve, as before the sweep models are trained."""
    monkeypatch.delenv(MODEL_PATH_ENV, raising=False)
    _sweep_candidates_as(monkeypatch, "no-such-sweep-model")


def _sweep_candidates_as(monkeypatch, name: str) -> None:
    """Every sweep candidate of every role (``nn-sweep``, ``nn-sweep-normal``, ``gp-sweep``)
    renamed ``name``, the other candidates kept in their order."""
    monkeypatch.setattr(defaults, "DEFAULT_MODELS",
                        {role: tuple(name if "sweep" in n else n for n in names)
                         for role, names in defaults.DEFAULT_MODELS.items()})


def test_every_harmonic_role_takes_the_installed_sweep_model(with_sweep):
    for role in ("harmonic", "normal"):
        assert default_model_path(role).resolve() == with_sweep.resolve()


def test_the_envelope_keeps_a_model_of_the_motors_whole_speed_range(with_sweep):
    # the spin-up passes 20-100 Hz, below the sweep models' 100-250 Hz band
    card = read_card(default_model_path("envelope_harmonic"))
    band = next(i for i in card["inputs"] if i["name"] == "frequency_hz")
    assert not is_sweep_model(card)
    assert band["low"] <= 20.0 and band["high"] >= 250.0


def test_before_the_sweep_models_the_single_frequency_ones_serve(without_sweep):
    assert default_model("harmonic") == "models/nn-default"  # relative to the checkout root
    assert default_model("normal") == "models/nn-normal"
    assert default_model("envelope_harmonic") == "models/nn-wide"


def test_a_candidate_without_the_roles_outputs_is_passed_over(monkeypatch):
    monkeypatch.setattr(defaults, "DEFAULT_MODELS", {"normal": ("nn-default", "nn-normal")})
    assert "profile_normal_um" not in json.dumps(read_card("models/nn-default")["outputs"])
    assert default_model("normal") == "models/nn-normal"


def test_no_candidate_or_an_unknown_role_names_the_model_field(monkeypatch):
    monkeypatch.setattr(defaults, "DEFAULT_MODELS", {"normal": ("nn-default",)})
    with pytest.raises(ModelFileError, match="no default normal model installed: tried "
                       r"nn-default \(with outputs profile_normal_um\)") as err:
        default_model("normal")
    assert err.value.field == "model"
    with pytest.raises(ModelFileError, match="no default model for 'thermal'; roles: normal"):
        default_model("thermal")


def test_the_card_says_which_contract(sweep_model):
    assert is_sweep_model(read_card(sweep_model))
    assert not is_sweep_model(read_card("models/nn-default"))


def _forearm(**model):
    d = tomllib.loads(open("examples/forearm-layout.toml").read())
    d["model"] = {k: v for k, v in d["model"].items() if k != "path"} | model
    return d


def test_a_layout_without_a_model_path_plans_on_the_default(with_sweep):
    assert layout_from_dict(_forearm()).model == str(with_sweep.resolve())
    assert layout_from_dict(_forearm(path="models/nn-default")).model == "models/nn-default"


def test_a_layout_without_a_model_path_and_no_default_is_refused(monkeypatch):
    monkeypatch.setattr(defaults, "DEFAULT_MODELS", {"harmonic": ("no-such-model",)})
    with pytest.raises(LayoutError, match=r"model\.path is not given and no default harmonic "
                       "model installed") as err:
        layout_from_dict(_forearm())
    assert err.value.field == "model.path"


def test_predict_without_a_model_uses_the_default(with_sweep, capsys):
    from hapticrom.cli import main

    sets = ["--set", "orientation=forward", "--set", "attachment=glued", "--set", "n_rings=0",
            "--set", "ring_1_E_kPa=95", "--set", "ring_2_E_kPa=95", "--set", "ring_3_E_kPa=95",
            "--set", "ring_density_kg_m3=1070", "--set", "ring_nu=0.47",
            "--set", "ring_loss_factor=0.1", "--set", "skin_E_kPa=49",
            "--set", "fat_thickness_mm=14", "--set", "tissue_loss_factor=0.3",
            "--set", "frequency_hz=150"]
    assert main(["predict", *sets]) == 0
    out = capsys.readouterr().out
    assert f"model {with_sweep.resolve()} (the default harmonic model)" in out
    assert "centre (unit face) magn." in out
