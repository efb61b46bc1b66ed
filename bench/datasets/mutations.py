"""Mutation run over a dataset: every alteration must be refused, naming the altered file.

    python bench/datasets/mutations.py              # 3 seeds x every mutation x command
    python bench/datasets/mutations.py --seeds 10

A small synthetic dataset (3 parts, 24 rows, the real format: written through
``surrogate.data.store``) is altered by each mutation of :data:`MUTATIONS` (a row value x1000,
a deleted row, a copied, swapped, renamed, truncated, deleted or damaged part, edits of the
manifest's part records, a broken or stripped manifest), then every reading command runs on it
through the command line (``hapticrom.cli.main``: info, validate, generate, train, refine,
merge). Each outcome is one of:

* refused: exit 2, the altered file named in the output, nothing in the directory changed and
  no output written;
* silent acceptance: exit 0 (the alteration went unnoticed);
* traceback: exit 1 or a Python traceback in the output;
* refused unnamed / wrote: exit 2 without naming the file, or something was written.

The counts are printed; the exit status is 1 unless the silent acceptances and tracebacks are
0 (and every refusal named the file and wrote nothing). Stray files (a note, a copy under
another name) must be ignored by every command: the pristine dataset plus strays is accepted
by info, validate and merge, which report the strays. ``tests/surrogate/data/
test_mutations.py`` runs the same catalogue under hypothesis.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import random
import shutil
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

SPACE_TOML = """
[space]
name = "mutations"
sampler = "sobol"
seed = 7

[base.load]
kind = "unit"

[base.analysis]
kind = "harmonic"

[base.unit]
encapsulation = ["ecoflex-00-10", "dragon-skin-30"]

[[parameter]]
name = "orientation"
type = "categorical"
path = "unit.orientation"
choices = ["forward", "reverse"]

[[parameter]]
name = "skin_E_kPa"
type = "continuous"
path = "tissue.layer[0].E_kPa"
low = 20.0
high = 120.0
scale = "log"

[[parameter]]
name = "frequency_hz"
type = "continuous"
path = "analysis.frequency_hz"
low = 100.0
high = 250.0
"""
GRID_MM = np.linspace(0.0, 20.0, 11)
MANIFEST = "_manifest.json"
Draw = Callable[[int], int]  # draw(n) -> an integer in [0, n)


def build_dataset(path: Path, space_file: Path, rows: int = 24, parts: int = 3) -> Path:
    """A dataset of ``rows`` synthetic rows in ``parts`` parts, written by hapticrom."""
    from surrogate.data.provenance import solver_info
    from surrogate.data.space import load_space
    from surrogate.data.store import Store, new_manifest

    space = load_space(space_file, check_scenes=False)
    pts = space.points(0, rows)
    store = Store.create(path, space, **{**new_manifest(space, solver_info(git=False)),
                                         "profile_grid_mm": GRID_MM.tolist()})
    out = []
    for i in range(rows):
        values = {k: (v[i].item() if hasattr(v[i], "item") else v[i]) for k, v in pts.items()}
        center = 10.0 * (values["skin_E_kPa"] / 50.0) ** -0.3
        profile = 0.8 * center * np.exp(-GRID_MM / 6.0)
        out.append({"sample_id": hashlib.sha256(f"s{i}".encode()).hexdigest(),
                    "sample_index": i, "status": "ok", "source": "hapticrom-fem",
                    "scene_json": json.dumps(space.resolve(values)), **values,
                    "center_amplitude_um": center, "edge_amplitude_um": profile[0],
                    "normalized_edge": profile[0] / center, "edge_radius_mm": 6.0,
                    "profile_distance_mm": GRID_MM.tolist(),
                    "profile_uz_um": profile.tolist(), "profile_magnitude_um": profile.tolist()})
    with store.lock():
        for k in range(parts):
            store.write_part(out[k * rows // parts: (k + 1) * rows // parts])
    return path


# --------------------------------------------------------------------------- mutations


def _parts(d: Path) -> list[Path]:
    return sorted(d.glob("part-*.parquet"))


def _manifest(d: Path) -> dict:
    return json.loads((d / MANIFEST).read_text())


def _write_manifest(d: Path, m: dict, reseal: bool = True) -> None:
    from surrogate.data.integrity import manifest_digest

    if reseal and "digest" in m:
        m["digest"] = manifest_digest(m)
    (d / MANIFEST).write_text(json.dumps(m))


def _rewrite(part: Path, change: Callable) -> None:
    """Rewrite a part with ``change(table) -> table`` (keeping its key-value metadata)."""
    import pyarrow.parquet as pq

    t = pq.read_table(part)
    pq.write_table(change(t).replace_schema_metadata(t.schema.metadata), part,
                   compression="zstd")


def edit_value(d: Path, draw: Draw, fix_file_hash: bool = False) -> str:
    """One value of one row x1000 (a numeric output or parameter column)."""
    import pyarrow as pa

    part = _parts(d)[draw(3)]
    col = ["center_amplitude_um", "edge_amplitude_um", "skin_E_kPa", "frequency_hz",
           "wall_s"][draw(5)]

    def change(t):
        values = t.column(col).to_numpy(zero_copy_only=False).astype(float).copy()
        row = draw(len(values))
        values[row] = (values[row] if np.isfinite(values[row]) else 1.0) * 1000.0 + 1.0
        return t.set_column(t.schema.get_field_index(col), col, pa.array(values))

    _rewrite(part, change)
    if fix_file_hash:  # the file's own hash and size updated, as a careful editor would
        from surrogate.data.digests import file_sha256

        m = _manifest(d)
        m["parts"][part.name].update(file_sha256=file_sha256(part), bytes=part.stat().st_size)
        _write_manifest(d, m)
    return part.name


def edit_profile(d: Path, draw: Draw) -> str:
    """One profile value of one row changed."""
    import pyarrow as pa

    part = _parts(d)[draw(3)]

    def change(t):
        rows = t.column("profile_magnitude_um").to_pylist()
        r = draw(len(rows))
        rows[r][draw(len(rows[r]))] *= 1000.0
        i = t.schema.get_field_index("profile_magnitude_um")
        return t.set_column(i, t.schema.field(i), pa.array(rows, t.schema.field(i).type))

    _rewrite(part, change)
    return part.name


def drop_row(d: Path, draw: Draw) -> str:
    part = _parts(d)[draw(3)]
    row = draw(8)  # every part holds 8 rows
    _rewrite(part, lambda t: t.take([i for i in range(t.num_rows) if i != row]))
    return part.name


def copy_part(d: Path, draw: Draw) -> str:
    src = _parts(d)[draw(3)]
    dst = d / f"part-{4 + draw(50):06d}.parquet"
    shutil.copy(src, dst)
    return dst.name


def overwrite_part(d: Path, draw: Draw) -> str:
    parts = _parts(d)
    i = draw(3)
    j = (i + 1 + draw(2)) % 3
    shutil.copy(parts[i], parts[j])
    return parts[j].name


def rename_part(d: Path, draw: Draw) -> str:
    src = _parts(d)[draw(3)]
    src.rename(d / f"part-{10 + draw(50):06d}.parquet")
    return src.name


def delete_part(d: Path, draw: Draw) -> str:
    part = _parts(d)[draw(3)]
    part.unlink()
    return part.name


def truncate_part(d: Path, draw: Draw) -> str:
    part = _parts(d)[draw(3)]
    data = part.read_bytes()
    part.write_bytes(data[: draw(len(data) - 1) + 1 if len(data) > 1 else 0])
    return part.name


def damage_pages(d: Path, draw: Draw) -> str:
    """Bytes flipped inside the data pages (between the magic and the footer)."""
    part = _parts(d)[draw(3)]
    data = bytearray(part.read_bytes())
    footer = int.from_bytes(data[-8:-4], "little")
    end = max(5, len(data) - 8 - footer)
    for _ in range(1 + draw(8)):
        data[4 + draw(end - 4)] ^= 1 + draw(255)
    part.write_bytes(bytes(data))
    return part.name


def manifest_rows(d: Path, draw: Draw) -> str:
    m = _manifest(d)
    name = sorted(m["parts"])[draw(3)]
    m["parts"][name]["rows"] += 1 + draw(5)
    _write_manifest(d, m, reseal=False)
    return MANIFEST


def manifest_forget_part(d: Path, draw: Draw) -> str:
    """A part's record deleted from the manifest, digest recomputed: the part is unrecorded."""
    m = _manifest(d)
    name = sorted(m["parts"])[draw(3)]
    del m["parts"][name]
    _write_manifest(d, m)
    return name


def manifest_strip(d: Path, draw: Draw) -> str:
    """Part records and digest removed (looks like an old, unsealed dataset)."""
    m = _manifest(d)
    del m["parts"], m["digest"]
    _write_manifest(d, m)
    return "manifest"


def manifest_break(d: Path, draw: Draw) -> str:
    text = (d / MANIFEST).read_text()
    (d / MANIFEST).write_text(text[: draw(len(text))])
    return MANIFEST


def manifest_drop_digest(d: Path, draw: Draw) -> str:
    m = _manifest(d)
    del m["digest"]
    _write_manifest(d, m)
    return MANIFEST


MUTATIONS: dict[str, Callable[[Path, Draw], str]] = {
    "row value x1000": edit_value,
    "row value x1000, file hash updated": lambda d, draw: edit_value(d, draw, True),
    "profile value x1000": edit_profile,
    "row deleted": drop_row,
    "part copied": copy_part,
    "part overwritten by another": overwrite_part,
    "part renamed": rename_part,
    "part deleted": delete_part,
    "part truncated": truncate_part,
    "data pages damaged": damage_pages,
    "manifest row count edited": manifest_rows,
    "manifest part record deleted (resealed)": manifest_forget_part,
    "manifest part records stripped": manifest_strip,
    "manifest truncated": manifest_break,
    "manifest digest deleted": manifest_drop_digest,
}


def commands(d: Path, space: Path, scratch: Path) -> dict[str, list[str]]:
    """The reading commands, each writing (if at all) under ``scratch``."""
    return {
        "info": ["dataset", "info", str(d)],
        "validate": ["dataset", "validate", str(d)],
        "generate": ["generate", "--space", str(space), "--n", "26", "--out", str(d),
                     "--workers", "1", "--quiet"],
        "train": ["train", "--data", str(d), "--kind", "gp", "--out", str(scratch / "model")],
        "refine": ["refine", str(d), "--batch", "2", "--workers", "1", "--quiet"],
        "merge": ["dataset", "merge", str(d), "--out", str(scratch / "merged")],
    }


def snapshot(d: Path) -> dict[str, str]:
    """Name -> sha256 of every file under ``d`` (what a refusal must leave as it was)."""
    if not d.exists():
        return {}
    return {str(p.relative_to(d)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(d.rglob("*")) if p.is_file()}


def run_cli(argv: list[str]) -> tuple[int, str]:
    """``hapticrom.cli.main(argv)`` in this process: (exit code, stdout + stderr)."""
    import warnings

    from hapticrom.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = lambda msg, cat, *a, **k: print(f"{cat.__name__}: {msg}",
                                                              file=sys.stderr)
        try:
            code = main(argv)
        except SystemExit as exc:
            code = int(exc.code or 0)
        except BaseException as exc:
            import traceback

            traceback.print_exc(file=err)
            code = 1 if not isinstance(exc, KeyboardInterrupt) else 130
    return code, out.getvalue() + err.getvalue()


def classify(code: int, text: str, named: str, before: dict, after: dict,
             wrote: bool) -> str:
    """One outcome (see the module docstring)."""
    if "Traceback (most recent call last)" in text or code == 1:
        return "traceback"
    if code == 0:
        return "silent"
    if before != after or wrote:
        return "wrote"
    return "refused" if named in text else "unnamed"


def run(seeds: int, verbose: bool) -> dict[str, int]:
    counts = {"refused": 0, "silent": 0, "traceback": 0, "unnamed": 0, "wrote": 0}
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        space = root / "space.toml"
        space.write_text(SPACE_TOML)
        pristine = build_dataset(root / "pristine", space)
        for seed in range(seeds):
            for mname, mutate in MUTATIONS.items():
                for cname in commands(pristine, space, root):
                    rng = random.Random(f"{seed}-{mname}")
                    work, scratch = root / "work", root / "scratch"
                    shutil.rmtree(work, ignore_errors=True)
                    shutil.rmtree(scratch, ignore_errors=True)
                    shutil.copytree(pristine, work)
                    scratch.mkdir()
                    named = mutate(work, rng.randrange)
                    before = snapshot(work)
                    code, text = run_cli(commands(work, space, scratch)[cname])
                    outcome = classify(code, text, named, before, snapshot(work),
                                       any(scratch.iterdir()))
                    counts[outcome] += 1
                    if verbose or outcome != "refused":
                        print(f"[{outcome}] seed {seed} {mname} / {cname} (exit {code}, "
                              f"expected {named}): {text.strip()[-300:]}")
        counts.update(_strays(root, space, pristine))
    return counts


def _strays(root: Path, space: Path, pristine: Path) -> dict[str, int]:
    """Strays (a note, a copied part under another name, a directory) are ignored and
    reported by info, validate and merge."""
    work = root / "strays"
    shutil.rmtree(work, ignore_errors=True)
    shutil.copytree(pristine, work)
    (work / "notes.txt").write_text("mine")
    shutil.copy(_parts(work)[0], work / "copy of part-000001.parquet")
    (work / "sub").mkdir()
    ok = bad = 0
    for cname in ("info", "validate", "merge"):
        scratch = root / f"scratch-{cname}"
        code, text = run_cli(commands(work, space, scratch)[cname])
        good = code == 0 and "notes.txt" in text and "copy of part-000001.parquet" in text
        ok, bad = ok + good, bad + (not good)
        if not good:
            print(f"[strays] {cname}: exit {code}: {text.strip()[-300:]}")
    return {"strays ignored and reported": ok, "strays mishandled": bad}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3, help="draws per mutation (default 3)")
    ap.add_argument("--verbose", action="store_true", help="print every outcome")
    args = ap.parse_args()
    counts = run(args.seeds, args.verbose)
    total = sum(counts[k] for k in ("refused", "silent", "traceback", "unnamed", "wrote"))
    print(f"{total} altered datasets x commands ({len(MUTATIONS)} mutations x 6 commands x "
          f"{args.seeds} seeds)")
    for k, v in counts.items():
        print(f"  {k:32s} {v}")
    failed = counts["silent"] + counts["traceback"] + counts["unnamed"] + counts["wrote"] \
        + counts["strays mishandled"]
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
