"""``hapticrom generate``: sample a parameter space and solve every scene (resumable).

Examples::

    hapticrom generate --space datasets/spaces/default.toml --n 4096 --out datasets/default
    (the default space file and the README give the same --n 4096: the shipped dataset)
    hapticrom generate --space S.toml --n 100000 --out D --scheduler tcp://HOST:8786
"""

from __future__ import annotations

import argparse
import contextlib
import shlex
import signal
import sys
import threading
from collections.abc import Iterator
from typing import Any

from hapticrom.commands._args import positive_int, seconds


def register(subparsers: Any) -> None:
    """Add the ``generate`` sub-parser."""
    p = subparsers.add_parser(
        "generate", help="generate a dataset from a parameter space (resumable)",
        description="Sample a parameter space, solve every scene with the FE solver and store "
        "the results as Parquet parts. Rerun the same command after an interruption to "
        "resume; raise --n to extend along the same design sequence.")
    p.add_argument("--space", required=True, help="parameter space TOML file")
    p.add_argument("--n", required=True, type=positive_int,
                   help="total number of samples the dataset should hold")
    p.add_argument("--out", required=True, help="dataset directory (created if missing)")
    p.add_argument("--scheduler", help="Dask scheduler address tcp://HOST:PORT (default: a "
                   "local process pool)")
    p.add_argument("--workers", type=positive_int, help="local worker processes "
                   "(default: all cores)")
    p.add_argument("--chunk", type=positive_int, help="samples per task (default adaptive)")
    p.add_argument("--flush-every", type=positive_int, default=256,
                   help="write a part after this many samples (default 256)")
    p.add_argument("--flush-seconds", type=seconds, default=10.0,
                   help="... or after this many seconds (default 10)")
    p.add_argument("--quiet", "--no-progress", dest="quiet", action="store_true",
                   help="no progress bar on stderr (it is shown only on a terminal anyway)")
    p.add_argument("--allow-solver-change", action="store_true",
                   help="extend a dataset computed by another solver version (recorded)")
    p.set_defaults(func=run)


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


def run(args: argparse.Namespace) -> int:
    """Generate, then print what was done and the rate."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.data.generate import generate

    try:
        with _sigterm_as_interrupt():
            rep = generate(args.space, args.n, args.out, scheduler=args.scheduler,
                           workers=args.workers, chunk=args.chunk,
                           flush_every=args.flush_every, flush_seconds=args.flush_seconds,
                           progress=not args.quiet,
                           allow_solver_change=args.allow_solver_change,
                           command=shlex.join(sys.argv))
    except KeyboardInterrupt:
        print("hapticrom generate: completed samples are saved; rerun the same command to "
              "resume", file=sys.stderr)
        raise
    if rep.new == 0:
        print(f"{rep.path}: already holds the {rep.requested} requested samples")
    else:
        answers = (f" = {rep.answers_per_min:.0f} design-frequency answers/min "
                   f"({rep.frequencies} frequencies per sample)" if rep.frequencies > 1 else "")
        print(f"{rep.path}: {rep.new} new samples ({rep.new_ok} ok, {rep.new_failed} "
              f"failed) in {rep.wall_s:.1f} s = {rep.rate_per_min:.0f} samples/min{answers} "
              f"on {rep.workers} workers ({rep.backend}); {rep.already_done + rep.new} of "
              f"{rep.requested} done")
    return 0
