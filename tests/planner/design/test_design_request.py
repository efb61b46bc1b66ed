"""Bad design requests: each refused with the field named (and the allowed values)."""

from __future__ import annotations

import pytest

from planner.design.request import DesignRequestError, design_request_from_dict


def _set(path: str, value):
    def edit(d: dict) -> None:
        table, key = path.split(".")
        d.setdefault(table, {})[key] = value
    return edit


CASES = [
    (_set("space.orientation", ["forward"]), "space.orientation", "did you mean"),
    (_set("space.orientations", ["forward", "sideways"]), "space.orientations[1]",
     "'forward', 'reverse'"),
    (_set("space.orientations", []), "space.orientations", "at least one"),
    (_set("space.n_rings", [0, 4]), "space.n_rings[1]", "[0, 3]"),
    (_set("space.n_rings", [1, 1]), "space.n_rings", "twice"),
    (_set("space.materials", "wood"), "space.materials", "'catalogue', 'continuous'"),
    (_set("space.catalogue", ["dragon-skin-30", "unobtainium"]), "space.catalogue[1]",
     "ecoflex-00-10"),
    (_set("space.catalogue", ["D", "dragon skin 30"]), "space.catalogue[1]", "twice"),
    (_set("search.optimiser", "sgd"), "search.optimiser", "'de'"),
    (_set("search.budget", 3), "search.budget", "8 <= budget <= 20000"),
    (_set("verify.top", 9), "verify.top", "1 <= top <= 8"),
    (_set("drive.band_step_hz", 10.0), "drive.band_step_hz", "not both"),
    (_set("drive.band_step_hz", 0.1), "drive.band_step_hz", "1 <= band_step_hz <= 150"),
    (lambda d: d.update(array={"grid": "free", "positions_mm": [[0, 0], [20, 0]]}),
     "array.grid", "square or hex"),
    (_set("criterion.max_ratio", 2.0), "criterion.max_ratio", "max_ratio <= 1"),
    (_set("reference.scenes", ["no-such-scene.toml"]), "reference.scenes[0]",
     "no-such-scene"),
    (lambda d: d.update(design=[{"name": "x"}]), "design", "allowed keys"),
]


@pytest.mark.parametrize(("edit", "field", "says"), CASES, ids=[c[1] for c in CASES])
def test_bad_request_names_the_field(request_dict, edit, field, says):
    edit(request_dict)
    with pytest.raises(DesignRequestError) as err:
        design_request_from_dict(request_dict)
    assert err.value.field == field
    assert says in str(err.value)


def test_band_replaces_the_frequencies(request_dict):
    request_dict["drive"] = {"band_step_hz": 25.0}
    req = design_request_from_dict(request_dict)
    assert req.band_step_hz == 25.0


def test_the_example_reads_with_the_three_prototypes(request_dict):
    req = design_request_from_dict(request_dict)
    assert [p.name for p in req.references] == ["unit-bare-forward", "unit-double-forward",
                                                "unit-triple-reverse-pogo"]
    triple = req.references[2]
    assert triple.materials == ("ecoflex-00-10", "dragon-skin-10-medium", "dragon-skin-30")
    assert (triple.inputs["orientation"], triple.inputs["attachment"],
            triple.inputs["n_rings"]) == ("reverse", "pogo", 3)
    assert [triple.inputs[f"ring_{k}_E_kPa"] for k in (1, 2, 3)] == [95.0, 260.0, 1016.0]
    assert triple.inputs["ring_density_kg_m3"] == pytest.approx((1040 + 1070 + 1080) / 3)
