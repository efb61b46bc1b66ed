"""The compact codec of sweep lists: round trips within the bound, the recorded and provable
errors, nulls, and the inputs it refuses."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from surrogate.data.codec import (
    ARRAY_COLUMNS,
    BOUND,
    STEP_COLUMN,
    CodecError,
    SweepCodec,
    code_column,
    location_scales,
)

WHERE = {"center": slice(0, 1), "edge": slice(1, 2), "profile": slice(2, None)}


def _table(u: np.ndarray, valid: np.ndarray | None = None) -> pa.Table:
    """A logical sweep table of u (n, n_f, L, 6) [um] (float32 lists; rows not ``valid``
    null), with one non-array column."""
    n = u.shape[0]
    valid = np.ones(n, bool) if valid is None else valid
    cols: dict[str, pa.Array] = {"sample_index": pa.array(np.arange(n))}
    for i, name in enumerate(ARRAY_COLUMNS):
        block = u[:, :, WHERE[name.split("_")[1]], i % 6].astype(np.float32).reshape(n, -1)
        cols[name] = pa.array([b.tolist() if ok else None for b, ok in zip(block, valid,
                                                                          strict=True)],
                              pa.list_(pa.float32()))
    cols["sweep_error_estimate"] = pa.array(np.full(n, 1e-4))
    return pa.table(cols)


def _arrays(table: pa.Table, n_f: int) -> np.ndarray:
    n = table.num_rows
    blocks = []
    for where in WHERE:
        names = [c for c in ARRAY_COLUMNS if c.split("_")[1] == where]
        blocks.append(np.stack([np.asarray(table.column(c).to_pylist(), float).reshape(
            n, n_f, -1) for c in names], axis=-1))
    return np.concatenate(blocks, axis=2)


def _column_errors(got: np.ndarray, want: np.ndarray) -> dict[str, float]:
    m = location_scales(want.astype(np.float32).astype(float))
    err = np.abs(got - want.astype(np.float32)).max(axis=1)
    rel = np.where(m[..., None] > 0, err / np.where(m > 0, m, 1)[..., None], err)
    return {name: float(rel[:, WHERE[name.split("_")[1]], i % 6].max())
            for i, name in enumerate(ARRAY_COLUMNS)}


def _smooth(rng: np.random.Generator, n: int, n_f: int, n_p: int) -> np.ndarray:
    """Resonance-like responses whose level spans decades between locations and rows."""
    f = np.linspace(0.0, 1.0, n_f)
    out = np.empty((n, n_f, 2 + n_p, 6))
    for i in range(n):
        h = 1.0 / (1.0 - (f / (0.3 + rng.random())) ** 2 + 0.05j)
        level = 10.0 ** rng.uniform(-3, 2, size=2 + n_p)
        comp = rng.normal(size=(2 + n_p, 3)) + 1j * rng.normal(size=(2 + n_p, 3))
        z = h[:, None, None] * comp[None] * level[None, :, None]
        out[i] = np.stack([z.real, z.imag], axis=-1).reshape(n_f, 2 + n_p, 6)
    return out


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(1, 4), n_f=st.integers(2, 24),
       n_p=st.integers(1, 6), order=st.integers(0, 4), noise=st.sampled_from([0.0, 1e-3, 1.0]),
       zero_location=st.booleans())
def test_round_trip_within_the_tolerance_and_the_errors_recorded(seed, n, n_f, n_p, order,
                                                                 noise, zero_location):
    rng = np.random.default_rng(seed)
    u = _smooth(rng, n, n_f, n_p)
    u += noise * rng.normal(size=u.shape) * np.abs(u).max(axis=(1, 3), keepdims=True)
    if zero_location:
        u[:, :, -1] = 0.0  # a location at rest (e.g. the centre's u_z on the axis)
    codec = SweepCodec(order=order)
    table = _table(u)
    stored, recorded = codec.encode(table)
    assert stored.schema == codec.stored_schema(table.schema)
    back = codec.decode(stored, table.schema)
    assert back.schema == table.schema
    assert back.column("sample_index").to_pylist() == list(range(n))
    measured = _column_errors(_arrays(back, n_f), u)
    assert measured == pytest.approx(recorded, abs=1e-12)
    assert max(recorded.values()) <= codec.tolerance + 2.0**-23  # + float32 rounding
    proven = codec.proven(stored)
    assert all(recorded[c] <= proven[c] <= BOUND for c in ARRAY_COLUMNS)
    if zero_location:
        assert np.all(_arrays(back, n_f)[:, :, -1] == 0.0)


def test_codes_are_small_integers_distance_major():
    rng = np.random.default_rng(1)
    u = _smooth(rng, 2, 76, 21)
    stored, _ = SweepCodec().encode(_table(u))
    assert stored.schema.field(code_column("sweep_profile_uz_re_um")).type == \
        pa.list_(pa.int16())
    assert len(stored.column(STEP_COLUMN)[0]) == 23
    q = np.asarray(stored.column("sweep_profile_uz_re_q")[0].as_py()).reshape(21, 76)
    # rows of q are the distances: undoing the differences along each gives its codes
    codes = np.cumsum(np.cumsum(np.cumsum(q, axis=1), axis=1), axis=1)
    step = np.asarray(stored.column(STEP_COLUMN)[0].as_py())[2:]
    np.testing.assert_allclose(codes * step[:, None], u[0, :, 2:, 2].T,
                               atol=2.5e-4 * location_scales(u)[0, 2:].max())


def test_null_rows_stay_null():
    u = _smooth(np.random.default_rng(2), 3, 8, 2)
    valid = np.array([True, False, True])
    codec = SweepCodec()
    stored, _ = codec.encode(_table(u, valid))
    assert stored.column(STEP_COLUMN).is_null().to_pylist() == [False, True, False]
    back = codec.decode(stored)
    for name in ARRAY_COLUMNS:
        assert back.column(name).is_null().to_pylist() == [False, True, False]


def test_non_finite_values_are_refused_by_column():
    u = _smooth(np.random.default_rng(3), 2, 8, 2)
    u[1, 3, 2, 3] = np.nan  # profile point 0, u_z imaginary
    with pytest.raises(CodecError, match="non-finite values in sweep_profile_uz_im_um"):
        SweepCodec().encode(_table(u))


@pytest.mark.parametrize("kw, words", [
    ({"tolerance": 3e-4}, "allowed below the bound"),
    ({"tolerance": 0.0}, "allowed 0 < tolerance"),
    ({"bound": float("nan")}, "allowed 0 < bound"),
    ({"order": 5}, "allowed 0, 1, 2, 3, 4"),
    ({"order": True}, "allowed 0, 1, 2, 3, 4"),
    ({"tolerance": 1e-4, "bound": 2e-4, "order": 4}, "would not fit int16"),
])
def test_bad_codec_parameters_are_refused_by_name(kw, words):
    with pytest.raises(CodecError, match=words):
        SweepCodec(**kw)


def test_an_unknown_codec_record_is_refused():
    with pytest.raises(CodecError, match="is not known"):
        SweepCodec.from_dict({**SweepCodec().to_dict(), "version": 99})
    assert SweepCodec.from_dict(SweepCodec(order=2).to_dict()) == SweepCodec(order=2)


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.drop_columns([STEP_COLUMN]), "sweep_step_um missing"),
    (lambda t: t.set_column(t.schema.get_field_index("sweep_edge_ur_re_q"),
                            "sweep_edge_ur_re_q",
                            pa.array([[1, 2, 3]] * t.num_rows, pa.list_(pa.int16()))),
     "list lengths"),
    (lambda t: t.set_column(t.schema.get_field_index(STEP_COLUMN), STEP_COLUMN,
                            pa.array([[-1.0] * 4] * t.num_rows, pa.list_(pa.float32()))),
     "finite and >= 0"),
])
def test_stored_lists_that_do_not_fit_together_do_not_decode(edit, words):
    stored, _ = SweepCodec().encode(_table(_smooth(np.random.default_rng(4), 2, 8, 2)))
    with pytest.raises(CodecError, match=words):
        SweepCodec().decode(edit(stored))
