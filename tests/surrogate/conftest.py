"""Fixtures: a synthetic dataset and models trained on it (shared by the session)."""

from __future__ import annotations

import pytest
from synthetic import make_dataset


@pytest.fixture(scope="session")
def synthetic_dataset(tmp_path_factory):
    return make_dataset(tmp_path_factory.mktemp("data") / "synthetic", 96)


@pytest.fixture(scope="session")
def trained_models(synthetic_dataset, tmp_path_factory):
    """A small NN and GP trained on the synthetic dataset: {kind: (model dir, card)}."""
    from surrogate.train import train

    root = tmp_path_factory.mktemp("models")
    opts = {"nn": {"max_epochs": 400, "n_members": 3, "hidden": (32, 32)}, "gp": {}}
    return {kind: (root / kind, train([synthetic_dataset], kind, root / kind,
                                      options=opts[kind], n_modes=3))
            for kind in ("nn", "gp")}
