"""``hapticrom dataset info|validate|merge|seal|compact``: inspect, check, combine, seal and
compact datasets.

Exit codes (the policy of :mod:`hapticrom.cli`): ``validate`` exits 0 for a valid dataset and
2 (bad input) with the list of problems; ``info`` exits 2 for a damaged or missing dataset,
like every command given bad input. Files that are not part of a dataset are listed (``note:``)
and ignored. ``seal`` records the part digests of a dataset written before hapticrom recorded
them (after validating it); every reader refuses an unsealed dataset. ``compact`` re-encodes
a sweep dataset stored as float32 lists into the compact form (:mod:`surrogate.data.compact`):
a new dataset, written atomically; an existing ``--out`` only with ``--overwrite``.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from hapticrom.commands._args import positive_int
from hapticrom.documents import dataset_info_document
from hapticrom.outputs import check_not_input


def register(subparsers: Any) -> None:
    """Add the ``dataset`` sub-parser and its three sub-commands."""
    p = subparsers.add_parser("dataset", help="inspect, validate or merge datasets")
    sub = p.add_subparsers(dest="dataset_command", required=True,
                           metavar="{info,validate,merge,seal,compact}")
    info = sub.add_parser("info", help="summary of a dataset")
    info.add_argument("path")
    info.add_argument("--json", action="store_true", help="print JSON")
    info.set_defaults(func=run_info)
    val = sub.add_parser("validate", help="check parts, schema, provenance and ranges")
    val.add_argument("path")
    val.add_argument("--rehash", action="store_true",
                     help="also recompute every sample_id from its scene")
    val.set_defaults(func=run_validate)
    merge = sub.add_parser("merge", help="union of datasets into a new one")
    merge.add_argument("inputs", nargs="+", help="input dataset directories")
    merge.add_argument("--out", required=True, help="new dataset directory")
    merge.add_argument("--allow-mixed-solvers", action="store_true",
                       help="merge results of different solver versions")
    merge.set_defaults(func=run_merge)
    seal = sub.add_parser("seal", help="record the part digests of a dataset written before "
                          "they were recorded (validates it first)")
    seal.add_argument("path")
    seal.set_defaults(func=run_seal)
    compact = sub.add_parser("compact", help="re-encode a sweep dataset into the compact form "
                             "(a new dataset)")
    compact.add_argument("src", help="sweep dataset stored as float32 lists")
    compact.add_argument("--out", required=True, help="new dataset directory")
    compact.add_argument("--overwrite", action="store_true",
                         help="replace --out if it is a dataset (atomically)")
    compact.add_argument("--rows-per-part", type=positive_int, default=1024,
                         help="rows per Parquet part (default 1024; every part costs about "
                         "15 kB of footer)")
    compact.set_defaults(func=run_compact)


def run_info(args: argparse.Namespace) -> int:
    """Print the dataset summary (text or JSON)."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.data.inspect import dataset_info

    info = dataset_info(args.path)
    if args.json:
        print(json.dumps(dataset_info_document(info), indent=1))
    else:
        print(format_info(info))
    return 0


def format_info(info: dict[str, Any]) -> str:
    """The text form of :func:`surrogate.data.inspect.dataset_info`."""
    s = info.get("sampling") or {}
    solver = info.get("solver") or {}
    lines = [
        f"dataset   {info['path']}",
        f"space     {info['space']} (hash {(info['space_hash'] or 'none: merged')[:12]})",
        f"params    {', '.join(info['parameters'])}",
        f"sampling  {s.get('sampler')} seed {s.get('seed')}, target {s.get('target_n')}, "
        f"scanned {s.get('scanned')} (rejected {s.get('rejected')}, repeated scenes "
        f"{s.get('duplicates')})",
        f"solver    {solver.get('version')} ({solver.get('hash')}) git "
        f"{solver.get('git_revision')}; all: {', '.join(info['solver_versions'])}",
        f"analysis  {info.get('analysis_kind')}; mesh {info.get('mesh')}",
        f"outputs   {info.get('outputs')}",
        f"rows      {info['rows']} ({info['ok']} ok, {info['failed']} failed) in "
        f"{info['parts']} parts, {info['bytes'] / 1e6:.2f} MB",
        f"sources   {', '.join(f'{k}: {v}' for k, v in info['by_source'].items()) or '-'}",
        f"runs      {info['runs']} ({info['interrupted_runs']} interrupted)",
    ]
    codec = info.get("codec")
    if codec:
        worst = codec.get("max_error")
        lines.append(f"storage   compact: {codec['name']} v{codec['version']} (bound "
                     f"{codec['bound']:g} of the band maximum), largest codec error "
                     f"{'-' if worst is None else f'{worst:.2e}'}")
    if info.get("stray_files"):
        lines.append(f"note      ignored (not part of the dataset): "
                     f"{', '.join(info['stray_files'])}")
    if info["temp_files"]:
        lines.append(f"note      {info['temp_files']} unfinished temp parts (ignored; removed "
                     "by the next generate)")
    return "\n".join(lines)


def run_validate(args: argparse.Namespace) -> int:
    """Exit 0 when valid, 2 (an invalid input dataset) with the list of problems."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.data.inspect import validate_dataset

    notes: list[str] = []
    problems = validate_dataset(args.path, rehash=args.rehash, notes=notes)
    for n in notes:
        print(f"note: {n}")
    for p in problems:
        print(f"problem: {p}")
    if problems:
        print(f"hapticrom dataset validate: {args.path}: {len(problems)} problems",
              file=sys.stderr)
        return 2
    print(f"{args.path}: valid")
    return 0


def run_merge(args: argparse.Namespace) -> int:
    """Merge the inputs into a new dataset."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.data.inspect import merge_datasets

    check_not_input("--out", args.out, args.inputs)
    res = merge_datasets(args.out, args.inputs, args.allow_mixed_solvers)
    print(f"{args.out}: {res['rows_out']} rows from {res['rows_in']} "
          f"({res['duplicates_dropped']} duplicates dropped), {res['parts']} parts")
    return 0


def run_compact(args: argparse.Namespace) -> int:
    """Write the compact form of a sweep dataset."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.data.compact import compact_dataset

    res = compact_dataset(args.src, args.out, overwrite=args.overwrite,
                          rows_per_part=args.rows_per_part)
    print(f"{args.out}: {res['rows']} rows in {res['parts_out']} parts, "
          f"{res['bytes_out'] / 1e6:.2f} MB ({res['bytes_out'] / max(res['rows'], 1) / 1e3:.1f}"
          f" kB a row; source {res['bytes_in'] / 1e6:.2f} MB in {res['parts_in']} parts); "
          f"largest codec error {res['max_error']:.2e} of the band maximum")
    return 0


def run_seal(args: argparse.Namespace) -> int:
    """Record part digests (exit 2 with the problems if the dataset is not valid)."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.data.inspect import seal_dataset

    res = seal_dataset(args.path)
    what = "sealed" if res["sealed"] else "already sealed, verified"
    print(f"{args.path}: {what}: {res['parts']} parts, {res['rows']} rows")
    return 0
