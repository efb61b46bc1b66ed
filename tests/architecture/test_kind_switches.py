"""Kinds asked, not named (issue 35): outside the registries no module compares a surrogate
kind's name to a string, except to validate a loaded card, each place listed here with why.
Counted by bench/structure/count_structure.py."""

from __future__ import annotations

from bench.structure.count_structure import kind_switches
from surrogate import kinds

#: (file, kind) -> why the name is written there: each checks or writes a card.
CARD_CHECKS = {
    ("surrogate/runtime/card.py", "rom"):
        "the envelope model's card has keys of its own (REQUIRED_KEYS)",
    ("surrogate/runtime/rom.py", "rom"): "load_envelope refuses a card of another kind",
    ("surrogate/envelope/fit.py", "nn"):
        "the harmonic model the fit reads must be an NN card with frequency_hz",
    ("surrogate/sweep/gp_export.py", "gp"): "the card's training.gp entry (a key, no branch)",
}


def test_kind_names_are_compared_only_to_validate_a_card():
    assert {(path, kind) for path, _, kind in kind_switches()} == set(CARD_CHECKS)


def test_the_registry_says_which_kinds_train_on_sweeps_and_their_quick_options():
    assert kinds.SWEEP_KINDS == ("gp", "nn")
    assert all(kinds.KINDS[name].estimator is not None for name in kinds.SWEEP_KINDS)
    assert [name for name, k in kinds.KINDS.items() if k.row_cap is not None] == ["gp"]
    assert kinds.KINDS["nn"].quick_options == {"max_epochs": 30, "n_members": 2}
