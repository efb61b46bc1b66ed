"""The case language: shipped scenes, dotted-path edits, the quick plan, sweep points."""

import itertools
from pathlib import Path

import pytest

from fem.scene import SceneError, scene_from_dict
from studies.guo2025 import cases, paper

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize("name", [cases.BARE, cases.DOUBLE, cases.TRIPLE])
def test_shipped_scenes_are_the_examples(name):
    """The package ships its own copy of the prototype scenes; in a checkout they must equal
    the examples users read."""
    if not EXAMPLES.is_dir():
        pytest.skip("not a checkout")
    assert (cases.SCENES_DIR / name).read_text() == (EXAMPLES / name).read_text()


def test_edits_set_dotted_paths_and_validate():
    d = cases.scene_dict(cases.triple_case("DCA", cases.contact_edit("bonded")))
    assert d["unit"]["ring_contact"] == "bonded"
    # the paper's model is undamped: each ring is its material with the loss pinned to 0
    assert d["unit"]["encapsulation"] == [{"material": paper.LETTERS[c], "loss_factor": 0.0}
                                          for c in "DCA"]
    assert d["output"]["profile_step_mm"] == cases.PROFILE_STEP_MM
    assert d["effects"]["preload"] is True  # pins: report whether they keep contact
    scene_from_dict(d)
    bad = cases.Case(cases.BARE, (("unit.motor.mass_g", -1.0),))
    with pytest.raises(SceneError) as err:
        scene_from_dict(cases.scene_dict(bad))
    assert "mass_g" in err.value.field


def test_a_transient_case_runs_from_rest_at_constant_speed():
    d = cases.scene_dict(cases.transient_case())
    assert d["analysis"]["kind"] == "transient"
    assert d["analysis"]["duration_ms"] == cases.TRANSIENT_MS
    assert d["effects"]["spin_up"] is False
    assert d["unit"]["ring_contact"] == cases.TRANSIENT_CONTACT


def test_the_quick_plan_is_a_subset_of_the_full_plan():
    quick, full = cases.plan(quick=True), cases.plan()
    assert set(quick.cases) < set(full.cases)
    assert all(quick.cases[n] == full.cases[n] for n in quick.cases)
    assert quick.triples == ("AAA", "ACD", "DCA", "DDD")
    assert full.triples == tuple("".join(t) for t in itertools.product("ABCD", repeat=3))
    assert "transient/ACD" in full.cases and "transient/ACD" not in quick.cases
    assert {k: v for k, v in quick.sweeps.items()} == {
        k: (v[0], v[-1]) for k, v in full.sweeps.items()}
    for p in (quick, full):
        assert set(p.follow.needs) <= set(p.cases)


def test_sweep_points_vary_one_value_from_the_common_point():
    assert cases.sweep_point("density", 4000.0) == (4000.0, *paper.COMMON[1:])
    assert cases.sweep_point("E", 15.0) == (paper.COMMON[0], 15.0, paper.COMMON[2])
    assert cases.sweep_point("nu", 0.2) == (*paper.COMMON[:2], 0.2)
    assert cases.common_value("E") == paper.COMMON[1]
    assert cases.uniform_name(1000.0, 355.0, 0.47) == "uniform/rho1000/E355/nu0.47"


def test_names_that_are_one_scene_share_a_hash():
    """The default contact's case is the plain triple: the run solves it once."""
    from fem.scene import scene_hash

    default = cases.default_contact()
    a = cases.scene_dict(cases.triple_case("ACD"))
    b = cases.scene_dict(cases.triple_case("ACD", cases.contact_edit(default)))
    assert scene_hash(scene_from_dict(a)) == scene_hash(scene_from_dict(b))
