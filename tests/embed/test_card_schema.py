"""The model card's JSON Schema (hapticrom/schemas/model-card.json): every shipped card, once
sealed, conforms to it; broken cards do not; the schema ships with the package."""

from __future__ import annotations

import copy
import importlib.util
import json

import pytest
from embed_cases import REPO, seal_copy

from hapticrom.documents import schema

_spec = importlib.util.spec_from_file_location("schema_check",
                                               REPO / "tests/hapticrom/schema_check.py")
schema_check = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(schema_check)
SHIPPED = sorted(p.name for p in (REPO / "models").iterdir() if (p / "card.json").is_file())


@pytest.fixture(scope="module")
def cards(tmp_path_factory) -> dict[str, dict]:
    dest = tmp_path_factory.mktemp("cards")
    return {m: json.loads((seal_copy(m, dest) / "card.json").read_text()) for m in SHIPPED}


@pytest.mark.parametrize("model", SHIPPED)
def test_every_shipped_card_conforms(cards, model):
    assert schema_check.problems(cards[model], schema("model-card")) == []


BREAKS = {
    "unsealed": lambda c: c.pop("card_sha256"),
    "bad digest": lambda c: c["files"].update({"model.onnx": "abc"}),
    "unknown input type": lambda c: c["inputs"][0].update(type="boolean"),
    "numeric input without a range": lambda c: c["inputs"][3].pop("low"),
    "unknown scale": lambda c: c["inputs"][3].update(scale="sqrt"),
    "graph dtype": lambda c: c["graph"].update(dtype="float16"),
    "no graph": lambda c: c.pop("graph"),
    "other format": lambda c: c.update(format="onnx"),
    "edge radius method": lambda c: c["edge_radius"].update(method="formula"),
    "output column": lambda c: c["log_output_columns"].append("profile_um[x]"),
}


@pytest.mark.parametrize("damage", BREAKS)
def test_broken_cards_do_not_conform(cards, damage):
    card = copy.deepcopy(cards["nn-default"])
    BREAKS[damage](card)
    assert schema_check.problems(card, schema("model-card"))

