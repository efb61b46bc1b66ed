"""Single-frequency datasets store the complex amplitudes (centre, edge, profile; r, z, t)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from test_generate import SPACE

from fem import simulate
from fem.scene import scene_from_dict
from hapticrom.commands.dataset import format_info
from surrogate.data.columns import COMPLEX_FIELDS, COMPONENTS
from surrogate.data.digests import part_entry
from surrogate.data.generate import generate
from surrogate.data.inspect import dataset_info, validate_dataset
from surrogate.data.integrity import manifest_digest
from surrogate.data.plan import plan_samples
from surrogate.data.space import space_from_dict
from surrogate.data.store import MANIFEST_NAME, Store

SHIPPED = Path(__file__).resolve().parents[3] / "datasets" / "default"


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("cx") / "ds"
    generate(space_from_dict(SPACE), 3, out, workers=1, progress=False)
    return out


def test_rows_hold_the_solvers_complex_amplitudes(generated):
    df = Store.open(generated).read().sort_values("sample_index").reset_index(drop=True)
    planned, _ = plan_samples(space_from_dict(SPACE), 3)
    res = simulate(scene_from_dict(planned[1].scene))
    row = df.loc[1]
    for i, c in enumerate(COMPONENTS):
        assert row[f"center_u{c}_re_um"] == res.center[i].real * 1e6
        assert row[f"center_u{c}_im_um"] == res.center[i].imag * 1e6
        assert row[f"edge_u{c}_im_um"] == res.edge[i].imag * 1e6
        np.testing.assert_array_equal(row[f"profile_u{c}_re_um"], res.profile[:, i].real * 1e6)
        np.testing.assert_array_equal(row[f"profile_u{c}_im_um"], res.profile[:, i].imag * 1e6)
    parts = np.array([row[f"center_u{c}_{p}_um"] for c in COMPONENTS for p in ("re", "im")])
    assert np.sqrt((parts ** 2).sum()) == pytest.approx(row["center_amplitude_um"], rel=1e-12)
    assert abs(row["center_uz_im_um"]) > 0  # a damped harmonic response has a phase
    assert validate_dataset(generated) == []
    info = dataset_info(generated)
    assert "complex amplitudes" in info["outputs"]
    assert "complex amplitudes" in format_info(info)


def _reseal_part(path: Path, part: Path) -> None:
    m = json.loads((path / MANIFEST_NAME).read_text())
    m["parts"][part.name] = part_entry(part)
    m["digest"] = manifest_digest(m)
    (path / MANIFEST_NAME).write_text(json.dumps(m))


def test_validate_finds_complex_values_that_disagree_with_the_magnitudes(generated, tmp_path):
    work = tmp_path / "w"
    shutil.copytree(generated, work)
    part = sorted(work.glob("part-*.parquet"))[0]
    t = pq.read_table(part)
    i = t.schema.get_field_index("center_uz_im_um")
    values = t.column(i).to_numpy().copy()
    values[0] *= 2.0
    pq.write_table(t.set_column(i, t.schema.field(i), pa.array(values)), part)
    _reseal_part(work, part)  # a consistent envelope: only the physics check can see it
    assert any("complex center amplitudes do not give their center_amplitude_um" in p
               for p in validate_dataset(work))


def test_a_dataset_without_complex_columns_stays_readable_and_extendable(tmp_path):
    """Datasets written before the complex columns keep their columns; new rows written to
    them are stored without the complex values."""
    out = tmp_path / "old"
    generate(space_from_dict(SPACE), 2, out, workers=1, progress=False)
    # make it look like a dataset of the previous version: no complex columns recorded
    names = {f.name for f in COMPLEX_FIELDS}
    m = json.loads((out / MANIFEST_NAME).read_text())
    m["columns"] = [c for c in m["columns"] if c["name"] not in names]
    for part in sorted(out.glob("part-*.parquet")):
        t = pq.read_table(part)
        pq.write_table(t.drop_columns(sorted(names)), part, compression="zstd")
        m["parts"][part.name] = part_entry(part)
    m["digest"] = manifest_digest(m)
    (out / MANIFEST_NAME).write_text(json.dumps(m))
    assert validate_dataset(out) == []
    assert "magnitudes only" in dataset_info(out)["outputs"]
    rep = generate(space_from_dict(SPACE), 4, out, workers=1, progress=False)
    assert rep.new_ok == 2
    df = Store.open(out).read()
    assert len(df) == 4 and not names & set(df.columns)
    assert validate_dataset(out) == []


def test_the_shipped_dataset_reads_as_before():
    df = Store.open(SHIPPED).read(columns=["center_amplitude_um", "profile_magnitude_um"])
    assert len(df) == 4096 and df["center_amplitude_um"].notna().all()
    assert "magnitudes only" in dataset_info(SHIPPED)["outputs"]
