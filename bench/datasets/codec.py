"""Storage of sweep datasets: bytes per design, largest error and speed of each candidate form.

    python bench/datasets/codec.py DATASET [--rows N] [--repeat 3] [--json out.json]

DATASET is a sweep dataset (either form; :mod:`surrogate.data.store` decodes it) -- e.g. a copy
of a set being generated. Every candidate stores the same rows (all columns: provenance,
scene_json, parameters, outputs); reported per candidate:

* ``kB/design``: the Parquet file of all rows divided by the rows (the whole row, not only the
  arrays);
* ``max err``: the largest error of any stored value relative to the band maximum of the
  displacement magnitude at its location (centre, edge, each profile distance) in the same row,
  over all rows and columns (0 for a lossless form); the bound is 3e-4;
* ``enc ms`` / ``dec ms``: median over ``--repeat`` runs of the time to encode all rows
  to the file's bytes and to decode them back to the float arrays, per 1,000 designs.

The candidates: float32 lists as stored before (zstd level 1, Arrow's default), fixed-size
lists with BYTE_STREAM_SPLIT and zstd levels, float16 and int16 scaled per row and location,
integer codes on a step chosen from the error bound with a prediction along frequency
(first or second difference) or over frequency and distance (Lorenzo), zfp's fixed-accuracy
mode on the scaled (n_f x n_p) arrays, Blosc2 with its filters, the edge stored as its
difference from profile point 0 (the solver computes both at the same point), and the cost of
the provenance columns (scene_json kept, or dropped because it is rebuilt from the space and
the parameter values and checked against sample_id). The chosen form is
:mod:`surrogate.data.codec` (``codec``), run through the real store path.
"""

from __future__ import annotations

import argparse
import io
import json
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from surrogate.data.codec import (  # noqa: E402
    ARRAY_COLUMNS,
    ORDER,
    ZSTD_LEVEL,
    SweepCodec,
    location_scales,
)
from surrogate.data.columns import COMPONENTS  # noqa: E402
from surrogate.data.store import Store  # noqa: E402

BOUND = 3e-4
TOL = 2.5e-4  # the quantisers' target: below the bound with room for float32 rounding
WHERE = ("center", "edge", "profile")


def load(path: str, rows: int | None) -> tuple[pa.Table, np.ndarray]:
    """(the logical table of the ok rows, the arrays (n, n_f, L, 6) float32 [um], L = 2 + n_p:
    centre, edge, profile points; last axis r re, r im, z re, z im, t re, t im)."""
    table = Store.open(path).read_table()
    ok = np.flatnonzero(np.asarray(table.column("status").to_pylist()) == "ok")[:rows]
    table = table.take(pa.array(ok))
    return table, arrays(table)


def arrays(table: pa.Table) -> np.ndarray:
    """The float32 arrays of a logical sweep table (see :func:`load`)."""
    n = table.num_rows
    n_f = len(table.column("sweep_frequency_hz")[0])
    out = []
    for where in WHERE:
        comps = [np.asarray(table.column(f"sweep_{where}_u{c}_{p}_um").combine_chunks()
                            .flatten().to_numpy(), dtype=np.float32).reshape(n, n_f, -1)
                 for c in COMPONENTS for p in ("re", "im")]
        out.append(np.stack(comps, axis=-1))
    return np.concatenate(out, axis=2)


def max_error(got: np.ndarray, want: np.ndarray) -> float:
    """Largest |got - want| relative to the band maximum magnitude at its location."""
    scale = location_scales(want)  # (n, L)
    err = np.abs(got.astype(float) - want.astype(float)).max(axis=(1, 3))  # (n, L)
    safe = np.where(scale > 0, scale, 1.0)
    return float(np.max(np.where(scale > 0, err / safe, err)))


# --------------------------------------------------------------------------- candidate forms


def _other_columns(table: pa.Table, drop_scene: bool = False) -> pa.Table:
    drop = [c for c in table.column_names if c in ARRAY_COLUMNS]
    if drop_scene:
        drop.append("scene_json")
    return table.drop_columns(drop)


def _parquet(table: pa.Table, **kw: Any) -> bytes:
    buf = io.BytesIO()
    pq.write_table(table, buf, **kw)
    return buf.getvalue()


def _leaves(names: list[str]) -> list[str]:
    """Parquet's paths of the values of list columns (where encodings apply)."""
    return [f"{n}.list.element" for n in names]


def _read(data: bytes) -> pa.Table:
    return pq.read_table(io.BytesIO(data))


def _value_lists(u: np.ndarray, dtype: Any, fixed: bool) -> dict[str, pa.Array]:
    """Columns per (where, component, part) of ``u`` (n, n_f, L, 6) as (fixed-size) lists."""
    n, L = u.shape[0], u.shape[2]
    cols = {}
    spans = {"center": slice(0, 1), "edge": slice(1, 2), "profile": slice(2, L)}
    for where, s in spans.items():
        for k, (c, p) in enumerate((c, p) for c in COMPONENTS for p in ("re", "im")):
            flat = np.ascontiguousarray(u[:, :, s, k], dtype=dtype).reshape(-1)
            size = flat.size // n
            vals = pa.array(flat)
            cols[f"sweep_{where}_u{c}_{p}"] = (pa.FixedSizeListArray.from_arrays(vals, size)
                                               if fixed else
                                               pa.ListArray.from_arrays(
                                                   pa.array(np.arange(n + 1) * size,
                                                            type=pa.int32()), vals))
    return cols


def _unlists(t: pa.Table, n: int, n_f: int, L: int) -> np.ndarray:
    out = np.empty((n, n_f, L, 6), dtype=np.float64)
    spans = {"center": slice(0, 1), "edge": slice(1, 2), "profile": slice(2, L)}
    for where, s in spans.items():
        for k, (c, p) in enumerate((c, p) for c in COMPONENTS for p in ("re", "im")):
            col = t.column(f"sweep_{where}_u{c}_{p}").combine_chunks()
            vals = np.asarray(col.flatten().to_numpy(zero_copy_only=False), dtype=float)
            out[:, :, s, k] = vals.reshape(n, n_f, -1)
    return out


class Form:
    """A candidate: ``encode(table, u) -> bytes``, ``decode(bytes) -> u (n, n_f, L, 6)``."""

    def __init__(self, name: str, encode: Callable[[pa.Table, np.ndarray], bytes],
                 decode: Callable[[bytes, tuple[int, ...]], np.ndarray]) -> None:
        self.name, self.encode, self.decode = name, encode, decode


def plain_float32(fixed: bool, bss: bool, level: int | None) -> Form:
    def enc(table: pa.Table, u: np.ndarray) -> bytes:
        t = _other_columns(table)
        for name, arr in _value_lists(u, np.float32, fixed).items():
            t = t.append_column(name, arr)
        kw: dict[str, Any] = {"compression": "zstd", "compression_level": level}
        if bss:
            names = [c for c in t.column_names if c.startswith("sweep_")
                     and pa.types.is_fixed_size_list(t.schema.field(c).type)]
            kw.update(use_byte_stream_split=_leaves(names), use_dictionary=[
                c for c in t.column_names if c not in names])
        return _parquet(t, **kw)

    def dec(data: bytes, shape: tuple[int, ...]) -> np.ndarray:
        return _unlists(_read(data), *shape[:3])

    what = ("fixed-size lists" if fixed else "lists") + (", BYTE_STREAM_SPLIT" if bss else "")
    return Form(f"float32 {what}, zstd {level or 'default'}", enc, dec)


def scaled(kind: str, level: int = 9) -> Form:
    """float16 of u / M or int16 of u / M * 32767 (M: band max at the location)."""
    def enc(table: pa.Table, u: np.ndarray) -> bytes:
        scale = location_scales(u).astype(np.float32)
        safe = np.where(scale > 0, scale, 1.0)[:, None, :, None]
        z = u / safe
        q = z.astype(np.float16) if kind == "float16" else np.rint(z * 32767).astype(np.int16)
        t = _other_columns(table)
        for name, arr in _value_lists(q, q.dtype, True).items():
            t = t.append_column(name, arr)
        t = t.append_column("scale_um", pa.FixedSizeListArray.from_arrays(
            pa.array(scale.reshape(-1)), scale.shape[1]))
        names = [c for c in t.column_names if c.startswith("sweep_") and "_u" in c]
        return _parquet(t, compression="zstd", compression_level=level,
                        use_byte_stream_split=_leaves(names) if kind == "float16" else False,
                        use_dictionary=[c for c in t.column_names if c not in names])

    def dec(data: bytes, shape: tuple[int, ...]) -> np.ndarray:
        t = _read(data)
        n, n_f, L = shape[:3]
        scale = np.asarray(t.column("scale_um").combine_chunks().flatten(), float).reshape(n, L)
        z = _unlists(t, n, n_f, L)
        if kind == "int16":
            z /= 32767
        return (z * scale[:, None, :, None]).astype(np.float32)

    return Form(f"{kind} scaled per row and location, zstd {level}", enc, dec)


def quantised(predictor: str, bss: bool, level: int, edge_from_profile: bool = False,
              drop_scene: bool = False, lib: str = "parquet") -> Form:
    """Integer codes of u on the step 2 TOL M, predicted along frequency ("f": first
    difference, "f2": second difference) or by the Lorenzo predictor over frequency and
    distance ("lorenzo"), stored as int16 in Parquet (or as one Blosc2 frame per column)."""
    def codes(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        step = (2 * TOL * location_scales(u)).astype(np.float32)
        safe = np.where(step > 0, step, 1.0)[:, None, :, None]
        q = np.rint(u / safe).astype(np.int32)
        if edge_from_profile:
            q[:, :, 1] -= q[:, :, 2]
        r = np.diff(q, axis=1, prepend=0)
        for _ in range({"f2": 1, "f3": 2}.get(predictor, 0)):
            r = np.diff(r, axis=1, prepend=0)
        if predictor == "lorenzo":
            r[:, :, 2:] = np.diff(r[:, :, 2:], axis=2, prepend=0)
        return r.astype(np.int16), step

    def enc(table: pa.Table, u: np.ndarray) -> bytes:
        r, step = codes(u)
        t = _other_columns(table, drop_scene)
        if lib == "blosc2":
            import blosc2

            head = _parquet(t, compression="zstd", compression_level=level)
            body = blosc2.compress2(np.ascontiguousarray(r.transpose(2, 3, 0, 1)).tobytes(),
                                    typesize=2, clevel=9, codec=blosc2.Codec.ZSTD,
                                    filters=[blosc2.Filter.BYTEDELTA])
            return (len(head).to_bytes(8, "little") + len(body).to_bytes(8, "little") + head
                    + body + step.tobytes())
        for name, arr in _value_lists(r, np.int16, True).items():
            t = t.append_column(name, arr)
        t = t.append_column("step_um", pa.FixedSizeListArray.from_arrays(
            pa.array(step.reshape(-1)), step.shape[1]))
        names = [c for c in t.column_names if c.startswith("sweep_") and "_u" in c]
        return _parquet(t, compression="zstd", compression_level=level,
                        column_encoding=dict.fromkeys(_leaves(names), "BYTE_STREAM_SPLIT")
                        if bss else None,
                        use_dictionary=[c for c in t.column_names if c not in names])

    def dec(data: bytes, shape: tuple[int, ...]) -> np.ndarray:
        n, n_f, L = shape[:3]
        if lib == "blosc2":
            import blosc2

            a, b = (int.from_bytes(data[i:i + 8], "little") for i in (0, 8))
            body = np.frombuffer(blosc2.decompress2(data[16 + a:16 + a + b]), np.int16)
            r = body.reshape(L, 6, n, n_f).transpose(2, 3, 0, 1).astype(np.int64)
            step = np.frombuffer(data[16 + a + b:], np.float32).reshape(n, L).astype(float)
        else:
            t = _read(data)
            step = np.asarray(t.column("step_um").combine_chunks().flatten(),
                              float).reshape(n, L)
            r = _unlists(t, n, n_f, L)
        if predictor == "lorenzo":
            r[:, :, 2:] = np.cumsum(r[:, :, 2:], axis=2)
        for _ in range({"f2": 1, "f3": 2}.get(predictor, 0)):
            r = np.cumsum(r, axis=1)
        q = np.cumsum(r, axis=1)
        if edge_from_profile:
            q[:, :, 1] += q[:, :, 2]
        return (q * step[:, None, :, None]).astype(np.float32)

    what = {"f": "1st difference in f", "f2": "2nd difference in f",
            "f3": "3rd difference in f", "lorenzo": "Lorenzo (f, distance)"}[predictor]
    extra = (", edge - profile[0]" if edge_from_profile else "") + \
        (", no scene_json" if drop_scene else "")
    store = "Blosc2 bytedelta+zstd 9" if lib == "blosc2" else \
        f"int16{' BSS' if bss else ''}, zstd {level}"
    return Form(f"codes on 2*{TOL:g}*M, {what}{extra}, frequency-major: {store}", enc, dec)


def zfp_form(tol: float) -> Form:
    """zfp fixed-accuracy on u / M: per row and component, the (n_f, 2) centre/edge array and
    the (n_f, n_p) profile array; one binary column per (where, component, part)."""
    def enc(table: pa.Table, u: np.ndarray) -> bytes:
        import zfpy

        scale = location_scales(u).astype(np.float32)
        z = u / np.where(scale > 0, scale, 1.0)[:, None, :, None]
        t = _other_columns(table)
        for k in range(6):
            for name, s in (("ce", slice(0, 2)), ("profile", slice(2, None))):
                blobs = [zfpy.compress_numpy(np.ascontiguousarray(z[i, :, s, k], np.float64),
                                             tolerance=tol) for i in range(len(z))]
                t = t.append_column(f"{name}_{k}", pa.array(blobs, pa.binary()))
        t = t.append_column("scale_um", pa.FixedSizeListArray.from_arrays(
            pa.array(scale.reshape(-1)), scale.shape[1]))
        return _parquet(t, compression="zstd", compression_level=9)

    def dec(data: bytes, shape: tuple[int, ...]) -> np.ndarray:
        import zfpy

        n, n_f, L = shape[:3]
        t = _read(data)
        out = np.empty((n, n_f, L, 6))
        for k in range(6):
            for name, s in (("ce", slice(0, 2)), ("profile", slice(2, None))):
                for i, b in enumerate(t.column(f"{name}_{k}").to_pylist()):
                    out[i, :, s, k] = zfpy.decompress_numpy(b)
        scale = np.asarray(t.column("scale_um").combine_chunks().flatten(), float).reshape(n, L)
        return (out * scale[:, None, :, None]).astype(np.float32)

    return Form(f"zfp fixed-accuracy {tol:g} on u/M (n_f x n_p per component), zstd 9", enc,
                dec)


def blosc2_trunc(bits: int) -> Form:
    """Blosc2 on the float32 values with its TRUNC_PREC filter (``bits`` mantissa bits kept),
    shuffle and zstd: a bound relative to each value, not to the location's maximum."""
    def enc(table: pa.Table, u: np.ndarray) -> bytes:
        import blosc2

        head = _parquet(_other_columns(table), compression="zstd", compression_level=9)
        body = blosc2.compress2(np.ascontiguousarray(u.transpose(2, 3, 0, 1),
                                                     np.float32).tobytes(),
                                typesize=4, clevel=9, codec=blosc2.Codec.ZSTD,
                                filters=[blosc2.Filter.TRUNC_PREC, blosc2.Filter.SHUFFLE],
                                filters_meta=[bits, 0])
        return len(head).to_bytes(8, "little") + head + body

    def dec(data: bytes, shape: tuple[int, ...]) -> np.ndarray:
        import blosc2

        n, n_f, L = shape[:3]
        head = int.from_bytes(data[:8], "little")
        body = np.frombuffer(blosc2.decompress2(data[8 + head:]), np.float32)
        return body.reshape(L, 6, n, n_f).transpose(2, 3, 0, 1)

    return Form(f"Blosc2 float32 TRUNC_PREC {bits} bits + shuffle + zstd 9", enc, dec)


def store_codec(order: int = ORDER, level: int = ZSTD_LEVEL) -> Form:
    """:class:`surrogate.data.codec.SweepCodec` (what the store writes: the whole part file,
    provenance and parameters included) with differences of ``order``, zstd ``level``."""
    codec = SweepCodec(order=order)

    def enc(table: pa.Table, u: np.ndarray) -> bytes:
        stored, _ = codec.encode(table)
        return _parquet(stored, **{**codec.parquet_options(stored.schema),
                                   "compression_level": level})

    def dec(data: bytes, shape: tuple[int, ...]) -> np.ndarray:
        return arrays(codec.decode(_read(data)))

    chosen = "chosen: " if (order, level) == (ORDER, ZSTD_LEVEL) else ""
    return Form(f"{chosen}codes on 2*{codec.tolerance:g}*M, order-{order} difference in f, "
                f"distance-major: int16, zstd {level}", enc, dec)


def forms() -> list[Form]:
    out = [plain_float32(False, False, None)]
    out += [plain_float32(True, True, lv) for lv in (3, 9, 19)]
    out += [scaled("float16"), scaled("int16")]
    out += [quantised("f", False, 9), quantised("f", True, 9), quantised("f2", False, 9),
            quantised("f2", False, 19),
            quantised("lorenzo", False, 9), quantised("lorenzo", False, 19),
            quantised("f", False, 9, edge_from_profile=True),
            quantised("f", False, 9, edge_from_profile=True, drop_scene=True),
            quantised("f", False, 9, lib="blosc2"), quantised("f3", False, 9, lib="blosc2")]
    out += [zfp_form(TOL), zfp_form(TOL / 2), blosc2_trunc(12)]
    out += [store_codec(2), store_codec(4), store_codec(level=9), store_codec()]
    return out


def provenance_costs(table: pa.Table) -> list[tuple[str, float]]:
    """Bytes per design of the non-array columns, each alone in a zstd 9 Parquet file."""
    n = table.num_rows
    other = _other_columns(table)
    rows = [("all non-array columns", len(_parquet(other, compression="zstd",
                                                   compression_level=9)) / n)]
    for name in ("scene_json", "sample_id", "warnings", "solver_hash"):
        if name in other.column_names:
            rows.append((name, len(_parquet(other.select([name]), compression="zstd",
                                            compression_level=9)) / n))
    rows.append(("all non-array columns but scene_json",
                 len(_parquet(other.drop_columns(["scene_json"]), compression="zstd",
                              compression_level=9)) / n))
    return rows


def run(path: str, rows: int | None, repeat: int) -> dict[str, Any]:
    table, u = load(path, rows)
    n = table.num_rows
    results = []
    for form in forms():
        enc_t, dec_t = [], []
        for _ in range(repeat):
            t0 = time.perf_counter()
            data = form.encode(table, u)
            t1 = time.perf_counter()
            got = form.decode(data, u.shape)
            enc_t.append(t1 - t0)
            dec_t.append(time.perf_counter() - t1)
        results.append({"form": form.name, "kB_per_design": len(data) / n / 1e3,
                        "max_error": max_error(got, u),
                        "encode_ms_per_1000": 1e6 * statistics.median(enc_t) / n,
                        "decode_ms_per_1000": 1e6 * statistics.median(dec_t) / n})
    return {"dataset": path, "designs": n, "shape": list(u.shape), "bound": BOUND,
            "forms": results, "provenance_bytes": provenance_costs(table),
            "rows_per_part": part_sizes(path, table)}


def part_sizes(path: str, table: pa.Table) -> list[tuple[int, float]]:
    """(rows per part, kB a design) of the chosen form written through the store (each part
    with its footer and metadata), for parts of 1, 4, 16, 64, 256 and all rows."""
    source = Store.open(path)
    keep = {k: v for k, v in source.manifest.items()
            if k in ("sampling", "solver", "solver_history", "mesh", "analysis_kind",
                     "profile_grid_mm", "band")}
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for rows in sorted({1, 4, 16, 64, 256, table.num_rows}):
            if rows > table.num_rows:
                continue
            store = Store.create(Path(tmp) / f"r{rows}", source.space, **keep,
                                 codec=SweepCodec().to_dict())
            with store.lock():
                for start in range(0, table.num_rows, rows):
                    store.write_part(table.slice(start, rows), {"source": "bench"})
            size = sum(p.stat().st_size for p in store.parts())
            out.append((rows, size / table.num_rows / 1e3))
    return out


def print_table(res: dict[str, Any]) -> None:
    print(f"{res['dataset']}: {res['designs']} designs, arrays {res['shape']} "
          f"(n, n_f, locations, re/im x 3)")
    print(f"{'form':<78} {'kB/design':>9} {'max err':>9} {'enc ms':>8} {'dec ms':>8}")
    for r in res["forms"]:
        err = "-" if r["max_error"] is None else f"{r['max_error']:.2e}"
        dec = "-" if r["decode_ms_per_1000"] is None else f"{r['decode_ms_per_1000']:.0f}"
        flag = " FAILS" if r["max_error"] is not None and r["max_error"] > res["bound"] else ""
        print(f"{r['form']:<78} {r['kB_per_design']:9.2f} {err:>9} "
              f"{r['encode_ms_per_1000']:8.0f} {dec:>8}{flag}")
    print("(times per 1,000 designs; max err relative to the band maximum magnitude at the "
          f"location, bound {res['bound']:g})")
    print("non-array columns, bytes per design (zstd 9):")
    for name, b in res["provenance_bytes"]:
        print(f"  {name:<40} {b:8.0f}")
    print("chosen form through the store, by rows per part (footers included):")
    for rows, kb in res["rows_per_part"]:
        print(f"  {rows:6d} rows a part: {kb:6.2f} kB a design")


def print_markdown(res: dict[str, Any]) -> None:
    """The table as docs/datasets.md shows it."""
    print("| form | kB/design | largest error | encode ms/1000 | decode ms/1000 |")
    print("|---|---|---|---|---|")
    for r in res["forms"]:
        flag = " (above the bound)" if r["max_error"] > res["bound"] else ""
        print(f"| {r['form']} | {r['kB_per_design']:.2f} | {r['max_error']:.2e}{flag} | "
              f"{r['encode_ms_per_1000']:,.0f} | {r['decode_ms_per_1000']:,.0f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dataset")
    ap.add_argument("--rows", type=int, default=None, help="first N ok rows only")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", default=None)
    ap.add_argument("--markdown", action="store_true", help="also print the markdown table")
    args = ap.parse_args()
    res = run(args.dataset, args.rows, args.repeat)
    print_table(res)
    if args.markdown:
        print_markdown(res)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
