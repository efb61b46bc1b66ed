"""Dataset subcommands of the ``hapticrom`` CLI: ``generate``, ``dataset``, ``ingest``.

``hapticrom.cli`` calls :func:`register` with its subparsers; every subcommand stores a
``func(args) -> int`` handler in the namespace (``args.func``). Exit codes: 0 success,
1 the run failed or validation found problems, 2 bad input (nothing written), 130
interrupted. Heavy modules (pyarrow, dask, the solver) load only when a command runs.

Examples::

    hapticrom generate --space datasets/spaces/default.toml --n 4096 --out datasets/default
    hapticrom generate --space S.toml --n 100000 --out D --scheduler tcp://10.0.0.5:8786
    hapticrom dataset info datasets/default
    hapticrom dataset validate datasets/default --rehash
    hapticrom dataset merge --out datasets/all datasets/laptop datasets/cluster
    hapticrom ingest results.csv --out datasets/default
    hapticrom ingest job1.rpt --out D --distance-unit mm --amplitude-unit m \\
        --set skin_E_kPa=49 --set fat_thickness_mm=14 ...
"""

from __future__ import annotations

import argparse
import contextlib
import json
import shlex
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from typing import Any

__all__ = ["main", "register"]


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not >= 1")
    return value


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not 0 < value <= 3600:
        raise argparse.ArgumentTypeError(f"{value} is not in (0, 3600]")
    return value


def _column_pair(text: str) -> tuple[int, int]:
    parts = text.split(",")
    try:
        a, b = (int(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected two column indices I,J "
                                         "(0-based), e.g. 0,1") from None
    if a < 0 or b < 0 or a == b:
        raise argparse.ArgumentTypeError(f"{text!r}: need two different indices >= 0")
    return a, b


def register(subparsers: Any) -> None:
    """Add ``generate``, ``dataset`` (info | validate | merge) and ``ingest`` to an argparse
    subparsers object."""
    _add_generate(subparsers)
    _add_dataset(subparsers)
    _add_ingest(subparsers)


def _add_generate(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "generate", help="generate a dataset from a parameter space (resumable)",
        description="Sample a parameter space, solve every scene with the FE solver and store "
        "the results as Parquet parts. Rerun the same command after an interruption to "
        "resume; raise --n to extend along the same design sequence.")
    p.add_argument("--space", required=True, help="parameter space TOML file")
    p.add_argument("--n", required=True, type=_positive_int,
                   help="total number of samples the dataset should hold")
    p.add_argument("--out", required=True, help="dataset directory (created if missing)")
    p.add_argument("--scheduler", help="Dask scheduler address tcp://HOST:PORT (default: a "
                   "local process pool)")
    p.add_argument("--workers", type=_positive_int, help="local worker processes "
                   "(default: all cores)")
    p.add_argument("--chunk", type=_positive_int, help="samples per task (default adaptive)")
    p.add_argument("--flush-every", type=_positive_int, default=256,
                   help="write a part after this many samples (default 256)")
    p.add_argument("--flush-seconds", type=_positive_float, default=10.0,
                   help="... or after this many seconds (default 10)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--allow-solver-change", action="store_true",
                   help="extend a dataset computed by another solver version (recorded)")
    p.set_defaults(func=cmd_generate)


def _add_dataset(subparsers: Any) -> None:
    p = subparsers.add_parser("dataset", help="inspect, validate or merge datasets")
    sub = p.add_subparsers(dest="dataset_command", required=True, metavar="{info,validate,merge}")
    info = sub.add_parser("info", help="summary of a dataset")
    info.add_argument("path")
    info.add_argument("--json", action="store_true", help="print JSON")
    info.set_defaults(func=cmd_dataset_info)
    val = sub.add_parser("validate", help="check parts, schema, provenance and ranges")
    val.add_argument("path")
    val.add_argument("--rehash", action="store_true",
                     help="also recompute every sample_id from its scene")
    val.set_defaults(func=cmd_dataset_validate)
    merge = sub.add_parser("merge", help="union of datasets into a new one")
    merge.add_argument("inputs", nargs="+", help="input dataset directories")
    merge.add_argument("--out", required=True, help="new dataset directory")
    merge.add_argument("--allow-mixed-solvers", action="store_true",
                       help="merge results of different solver versions")
    merge.set_defaults(func=cmd_dataset_merge)


def _add_ingest(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "ingest", help="import external simulation results (CSV table or ABAQUS/COMSOL "
        "profile)", description="Import a CSV of parameters and amplitudes, or one "
        "amplitude-vs-distance export (ABAQUS/COMSOL), validated against the space.")
    p.add_argument("file", help="table CSV or profile export")
    p.add_argument("--out", required=True, help="dataset directory (created if missing)")
    p.add_argument("--space", help="space TOML (required when --out does not exist yet)")
    p.add_argument("--kind", choices=("auto", "table", "profile"), default="auto",
                   help="auto: a table when the header names amplitude/profile columns")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="parameter value for all rows (repeatable)")
    p.add_argument("--center-amplitude-um", type=float, help="centre amplitude of a profile")
    p.add_argument("--distance-unit", help="unit of profile distances (mm, m, cm, um, in)")
    p.add_argument("--amplitude-unit", help="unit of profile amplitudes (um, nm, mm, m)")
    p.add_argument("--columns", type=_column_pair, default=(0, 1), metavar="I,J",
                   help="profile columns of distance and amplitude (default 0,1)")
    p.add_argument("--source", help="source label (default: the file name)")
    p.set_defaults(func=cmd_ingest)


# --------------------------------------------------------------------------- handlers


def _input_errors() -> tuple[type[BaseException], ...]:
    from fem.scene import SceneError
    from surrogate.space import SpaceError
    from surrogate.store import DatasetError

    return SpaceError, DatasetError, SceneError


def _guard(name: str, body: Callable[[], int]) -> int:
    errors = _input_errors()
    from surrogate.generate import RunnerError

    try:
        return body()
    except errors as err:
        print(f"hapticrom {name}: error: {err}", file=sys.stderr)
        return 2
    except RunnerError as err:
        print(f"hapticrom {name}: failed: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"hapticrom {name}: interrupted; completed samples are saved, rerun to resume",
              file=sys.stderr)
        return 130


@contextlib.contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM flushes completed samples like Ctrl-C does."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def cmd_generate(args: argparse.Namespace) -> int:
    """``hapticrom generate``."""

    def body() -> int:
        from surrogate.generate import generate

        with _sigterm_as_interrupt():
            rep = generate(args.space, args.n, args.out, scheduler=args.scheduler,
                           workers=args.workers, chunk=args.chunk,
                           flush_every=args.flush_every, flush_seconds=args.flush_seconds,
                           progress=not args.no_progress,
                           allow_solver_change=args.allow_solver_change,
                           command=shlex.join(sys.argv))
        if rep.new == 0:
            print(f"{rep.path}: already holds the {rep.requested} requested samples")
        else:
            print(f"{rep.path}: {rep.new} new samples ({rep.new_ok} ok, {rep.new_failed} "
                  f"failed) in {rep.wall_s:.1f} s = {rep.rate_per_min:.0f} samples/min on "
                  f"{rep.workers} workers ({rep.backend}); {rep.already_done + rep.new} of "
                  f"{rep.requested} done")
        return 0

    return _guard("generate", body)


def cmd_dataset_info(args: argparse.Namespace) -> int:
    """``hapticrom dataset info``."""

    def body() -> int:
        from surrogate.store import dataset_info

        info = dataset_info(args.path)
        if args.json:
            print(json.dumps(info, indent=1))
            return 0
        print(_format_info(info))
        return 0

    return _guard("dataset info", body)


def _format_info(info: dict[str, Any]) -> str:
    s = info.get("sampling") or {}
    solver = info.get("solver") or {}
    lines = [
        f"dataset   {info['path']}",
        f"space     {info['space']} (hash {(info['space_hash'] or 'none: merged')[:12]})",
        f"params    {', '.join(info['parameters'])}",
        f"sampling  {s.get('sampler')} seed {s.get('seed')}, target {s.get('target_n')}, "
        f"scanned {s.get('scanned')} (rejected {s.get('rejected')}, repeated scenes "
        f"{s.get('duplicates')})",
        f"solver    {solver.get('version')} source {solver.get('hash')} git "
        f"{solver.get('git_revision')}; all: {', '.join(info['solver_versions'])}",
        f"analysis  {info.get('analysis_kind')}; mesh {info.get('mesh')}",
        f"rows      {info['rows']} ({info['ok']} ok, {info['failed']} failed) in "
        f"{info['parts']} parts, {info['bytes'] / 1e6:.2f} MB",
        f"sources   {', '.join(f'{k}: {v}' for k, v in info['by_source'].items()) or '-'}",
        f"runs      {info['runs']} ({info['interrupted_runs']} interrupted)",
    ]
    if info["temp_files"]:
        lines.append(f"note      {info['temp_files']} unfinished temp parts (ignored; removed "
                     "by the next generate)")
    return "\n".join(lines)


def cmd_dataset_validate(args: argparse.Namespace) -> int:
    """``hapticrom dataset validate``: exit 0 when valid, 1 with a list of problems."""

    def body() -> int:
        from surrogate.store import validate_dataset

        problems = validate_dataset(args.path, rehash=args.rehash)
        for p in problems:
            print(f"problem: {p}")
        if problems:
            return 1
        print(f"{args.path}: valid")
        return 0

    return _guard("dataset validate", body)


def cmd_dataset_merge(args: argparse.Namespace) -> int:
    """``hapticrom dataset merge``."""

    def body() -> int:
        from surrogate.store import merge_datasets

        res = merge_datasets(args.out, args.inputs, args.allow_mixed_solvers)
        print(f"{args.out}: {res['rows_out']} rows from {res['rows_in']} "
              f"({res['duplicates_dropped']} duplicates dropped), {res['parts']} parts")
        return 0

    return _guard("dataset merge", body)


def cmd_ingest(args: argparse.Namespace) -> int:
    """``hapticrom ingest``."""

    def body() -> int:
        from surrogate.ingest import (
            ingest_profile,
            ingest_table,
            looks_like_table,
            parse_assignments,
        )

        values = parse_assignments(args.set)
        kind = args.kind
        if kind == "auto":
            kind = "table" if looks_like_table(args.file) else "profile"
        units = {"distance_unit": args.distance_unit, "amplitude_unit": args.amplitude_unit,
                 "columns": args.columns, "source": args.source}
        if kind == "table":
            if args.center_amplitude_um is not None:
                print("hapticrom ingest: error: --center-amplitude-um applies to a profile; "
                      "a table has a center_amplitude_um column", file=sys.stderr)
                return 2
            rep = ingest_table(args.file, args.out, args.space, values=values, **units)
        else:
            rep = ingest_profile(args.file, args.out, values, args.space,
                                 center_amplitude_um=args.center_amplitude_um, **units)
        print(f"{rep.path}: {rep.added} rows added from {rep.source} ({rep.rows_read} read, "
              f"{rep.skipped_existing} already present)")
        return 0

    return _guard("ingest", body)


def main(argv: Sequence[str] | None = None) -> int:
    """Stand-alone entry (``python -m surrogate.cli ...``) with just these subcommands."""
    parser = argparse.ArgumentParser(prog="hapticrom", description="hapticrom datasets")
    sub = parser.add_subparsers(dest="command", required=True)
    register(sub)
    args = parser.parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
