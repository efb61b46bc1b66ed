"""Small design requests built from the forearm example (tests stay fast: a few designs)."""

from __future__ import annotations

import pytest
from design_requests import example_dict


@pytest.fixture
def request_dict() -> dict:
    """The forearm example's tables (reference scenes made absolute), to be edited."""
    return example_dict()


@pytest.fixture
def tiny_dict(request_dict: dict) -> dict:
    """One unit (reverse, pogo, bare) at one frequency, the bare-motor prototype beside it,
    the FE check of the winner alone: one FE sweep per unit."""
    d = request_dict
    d["drive"] = {"frequencies_hz": [150.0]}
    d["space"] = {"orientations": ["reverse"], "attachments": ["pogo"], "n_rings": [0]}
    d["search"] = {"budget": 8}
    d["verify"] = {"top": 1}
    d["reference"] = {"scenes": [d["reference"]["scenes"][0]]}
    return d
