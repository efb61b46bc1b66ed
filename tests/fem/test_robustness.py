"""Hard cases stay finite and accurate: each is checked against a reference (a finer mesh, a
known limit or an invariance), not merely for the absence of NaN."""

import numpy as np
import pytest

from fem import simulate
from fem.scene import load_scene, scene_from_dict, scene_to_dict

POGO = "examples/unit-triple-reverse-pogo.toml"
FOREARM = "examples/forearm.toml"


def _amplitudes(res):
    return np.linalg.norm(res.U, axis=1)


def _with(example, **tables):
    d = scene_to_dict(load_scene(example))
    for table, values in tables.items():
        d.setdefault(table, {}).update(values)
    return d


def test_thin_layer_split_is_invisible():
    """Splitting the skin into 0.05 mm + 1.85 mm of the same material adds a row of 0.05 mm
    cells (aspect ratio 10) and must not change the answer beyond discretisation error: both
    meshes agree with a twice-finer unsplit reference."""
    split = _with(POGO)
    skin = split["tissue"]["layer"][0]
    split["tissue"]["layer"] = [{**skin, "name": "skin-top", "thickness_mm": 0.05},
                                {**skin, "thickness_mm": 1.85}, *split["tissue"]["layer"][1:]]
    ref = simulate(scene_from_dict(_with(POGO, mesh={"near_size_mm": 0.25,
                                                     "far_size_mm": 1.0})))
    for d in (split, _with(POGO)):
        res = simulate(scene_from_dict(d))
        assert np.allclose(_amplitudes(res), _amplitudes(ref), rtol=0.02)
        assert res.normalized_edge == pytest.approx(ref.normalized_edge, rel=0.02)


def test_thin_stiff_film_converges_under_refinement():
    """A 0.05 mm film 1e4 times stiffer than the skin under it (a stiff coating)."""
    def run(level):
        d = _with(FOREARM, mesh={"near_size_mm": 0.5 * level, "far_size_mm": 2.0 * level})
        skin = d["tissue"]["layer"][0]
        d["tissue"]["layer"].insert(0, {**skin, "name": "film", "thickness_mm": 0.05,
                                        "E_kPa": 4.9e5})
        return _amplitudes(simulate(scene_from_dict(d)))

    assert np.allclose(run(1.0), run(0.6), rtol=0.02)


@pytest.mark.parametrize("nu", [0.49, 0.4999])
def test_near_incompressible_tissue_converges_under_refinement(nu):
    def run(level):
        d = _with(POGO, mesh={"near_size_mm": 0.5 * level, "far_size_mm": 2.0 * level})
        for layer in d["tissue"]["layer"][:3]:
            layer["nu"] = nu
        return simulate(scene_from_dict(d))

    coarse, fine = run(1.0), run(0.6)
    assert np.all(np.isfinite(coarse.U))
    assert np.allclose(_amplitudes(coarse), _amplitudes(fine), rtol=0.03)
    assert coarse.normalized_edge == pytest.approx(fine.normalized_edge, rel=0.03)


def test_dense_rings_converge_under_refinement():
    """Encapsulation at 4000 kg/m3 (Table 2's heaviest)."""
    def run(level):
        d = _with(POGO, mesh={"near_size_mm": 0.5 * level, "far_size_mm": 2.0 * level})
        d["unit"]["encapsulation"] = [{"E_kPa": 355.0, "density_kg_m3": 4000.0, "nu": 0.47}] * 3
        return simulate(scene_from_dict(d))

    coarse, fine = run(1.0), run(0.6)
    assert coarse.edge_amplitude_um == pytest.approx(fine.edge_amplitude_um, rel=0.03)
    assert coarse.center_amplitude_um == pytest.approx(fine.center_amplitude_um, rel=0.03)


def test_bone_a_million_times_stiffer_than_fat_acts_as_a_rigid_base():
    """Bone 1e6 x fat (10 GPa vs 10 kPa) under the muscle: same answer as fixing the muscle's
    underside (the rigid limit)."""
    with_bone = _with(FOREARM)
    with_bone["tissue"]["layer"][3]["E_kPa"] = 1e7
    rigid = _with(FOREARM)
    rigid["tissue"]["layer"] = rigid["tissue"]["layer"][:3]  # base = "fixed" under the muscle
    a = _amplitudes(simulate(scene_from_dict(with_bone)))
    b = _amplitudes(simulate(scene_from_dict(rigid)))
    assert np.allclose(a, b, rtol=0.01)


def test_one_kilohertz_warns_when_under_resolved_and_converges_when_refined():
    coarse = simulate(scene_from_dict(_with(POGO, analysis={"frequency_hz": 1000.0},
                                            mesh={"follow_wavelength": False})))
    assert "under-resolved" in coarse.meta["warnings"][0]
    assert "far_size_mm" in coarse.meta["warnings"][0]
    assert "follow_wavelength" in coarse.meta["warnings"][0]

    def run(level, follow=False, far=0.3):  # a shallow forearm keeps the 1 kHz mesh small
        d = _with(POGO, analysis={"frequency_hz": 1000.0},
                  mesh={"near_size_mm": 0.25 * level, "near_radius_mm": 12.0,
                        "far_size_mm": far * level, "follow_wavelength": follow},
                  tissue={"radius_mm": 15.0},
                  output={"radii_mm": [0.0, 4.0, 8.0], "profile_length_mm": 5.0})
        skin, fat, muscle, _ = d["tissue"]["layer"]
        d["tissue"]["layer"] = [skin, {**fat, "thickness_mm": 4.0},
                                {**muscle, "thickness_mm": 4.0}]
        return simulate(scene_from_dict(d))

    fine, finer = run(1.0), run(0.7)
    assert "warnings" not in fine.meta
    assert np.allclose(_amplitudes(fine), _amplitudes(finer), rtol=0.03)
    # Following the wavelength, a 2 mm far size asked for is capped to what 1 kHz needs.
    followed = run(1.0, follow=True, far=2.0)
    assert "warnings" not in followed.meta
    assert np.allclose(_amplitudes(followed), _amplitudes(finer), rtol=0.03)


def test_default_quadratic_mesh_raises_no_resolution_warning():
    assert "warnings" not in simulate(load_scene(POGO)).meta


def test_low_frequency_unit_tends_to_its_static_response():
    """At 1 Hz inertia is negligible: the harmonic answer approaches the static one (the pogo
    unit is held sideways by its frictionless ring contact, so the static solve is posed)."""
    harmonic = simulate(scene_from_dict(_with(POGO, analysis={"frequency_hz": 1.0})))
    static = simulate(scene_from_dict(_with(POGO, analysis={"kind": "static",
                                                            "frequency_hz": 1.0})))
    assert np.allclose(_amplitudes(harmonic), _amplitudes(static), rtol=0.02)
