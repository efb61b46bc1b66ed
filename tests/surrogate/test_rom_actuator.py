"""The envelope model knows its actuator: a model that does not record one was trained on the
coin ERM (the shipped one), it refuses another actuator naming the field, and coefficients
naming an actuator its form cannot follow (an LRA, driven with a carrier) are refused."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import pytest

from fieldspec import FieldError
from surrogate.runtime.card import ModelFileError, seal_card
from surrogate.runtime.rom import RomInputError, load_envelope_model, model_from_parts

SHIPPED = Path(__file__).resolve().parents[2] / "models" / "rom-default"


@pytest.fixture(scope="module")
def parts():
    card = json.loads((SHIPPED / "card.json").read_text())
    coefficients = json.loads((SHIPPED / card["coefficients"]).read_text())
    hcard = json.loads((SHIPPED / card["harmonic"]["card"]).read_text())
    return coefficients, hcard, SHIPPED / card["harmonic"]["graph"]


def test_the_shipped_model_is_the_erms_and_refuses_an_lra(parts):
    model = load_envelope_model(SHIPPED)
    assert model.meta["actuator"] == "unit" and model.actuator == "unit"
    coefficients, hcard, graph = parts  # a model trained before the key: the coin ERM
    legacy = model_from_parts({k: v for k, v in coefficients.items() if k != "actuator"},
                              hcard, graph)
    assert "actuator" not in legacy.meta and legacy.actuator == "unit"
    model.check_actuator("unit")
    with pytest.raises(RomInputError) as err:
        model.check_actuator("lra")
    assert isinstance(err.value, FieldError) and err.value.field == "actuator"
    assert "'lra': this envelope model was trained for the actuator 'unit' (coin ERM)" in \
        str(err.value)


def test_recorded_actuator_is_read_and_a_carrier_drive_refused(parts):
    coefficients, hcard, graph = parts
    same = model_from_parts({**coefficients, "actuator": "unit"}, hcard, graph)
    assert same.actuator == "unit" and same.motor == load_envelope_model(SHIPPED).motor
    with pytest.raises(ValueError, match=r"actuator: 'lra' \(coin LRA\) is driven with a "
                       r"carrier"):
        model_from_parts({**coefficients, "actuator": "lra"}, hcard, graph)
    with pytest.raises(ValueError, match=r"'voice_coil' has no drive law"):
        model_from_parts({**coefficients, "actuator": "voice_coil"}, hcard, graph)


def test_a_model_directory_naming_an_lra_is_a_model_file_error(tmp_path, parts):
    coefficients, _, _ = parts
    shutil.copytree(SHIPPED, tmp_path / "m")
    card = json.loads((tmp_path / "m" / "card.json").read_text())
    body = (json.dumps({**coefficients, "actuator": "lra"}) + "\n").encode()
    (tmp_path / "m" / card["coefficients"]).write_bytes(body)
    card["files"][card["coefficients"]] = hashlib.sha256(body).hexdigest()
    card.pop("card_sha256", None)
    (tmp_path / "m" / "card.json").write_text(json.dumps(seal_card(card)))
    with pytest.raises(ModelFileError, match=r"malformed coefficients.*actuator: 'lra'"):
        load_envelope_model(tmp_path / "m")
