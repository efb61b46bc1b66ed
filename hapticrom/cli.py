"""The ``hapticrom`` command line: parses, calls the library, prints.

Every subcommand lives in its own module of :mod:`hapticrom.commands` (see its docstring for
the pattern); this module builds the parser from :data:`hapticrom.commands.COMMANDS` and
applies the one exit-code policy of the project, the same for every command:

====  =====================================================================================
0     success (``--help``, ``--version``; a check that finds nothing wrong)
1     the work failed: a :class:`fieldspec.WorkError` (a solver or worker failure, a lost
      device link: the message, no traceback) or an unexpected error (with its traceback)
2     bad input: any :class:`fieldspec.FieldError` (the message names the field and the
      allowed range), a ``ValueError`` from the library, an unreadable input or unwritable
      output file, a usage error; nothing is written. A check that finds its input broken
      is bad input too: ``dataset validate`` with problems, ``dataset info`` of a damaged
      dataset, ``models list`` with a model that fails verification all exit 2.
130   interrupted (Ctrl-C or SIGTERM); work completed so far is kept where it can be resumed
====  =====================================================================================

Progress bars (transients, ``generate``, ``refine``, ``reproduce``) go to stderr with the rate
and the ETA, only when stderr is a terminal; ``--quiet`` turns them off.

Warnings: the project's own (:class:`fieldspec.HapticromWarning`) are always shown; those of
the libraries it uses (torch's exporter notices and deprecations, ...) and their log messages
below ERROR only with ``--verbose`` (accepted before or after any command name). What a result
itself warns about (a model's coverage, a plan's criterion) is printed by its command.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import signal
import sys
import threading
import traceback
import warnings
from collections.abc import Iterator, Sequence
from importlib.metadata import PackageNotFoundError, version

from fem import SOLVER_VERSION  # cheap: fem loads its modules lazily
from fieldspec import FieldError, HapticromWarning, WorkError
from hapticrom.commands import COMMANDS

__all__ = ["EXIT_FAILED", "EXIT_INPUT", "EXIT_INTERRUPTED", "EXIT_OK", "build_parser", "main",
           "quiet_libraries", "version_text"]

EXIT_OK, EXIT_FAILED, EXIT_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130


class _Parser(argparse.ArgumentParser):
    """argparse exits with 2 on usage errors already, which matches the policy."""


def version_text() -> str:
    """``hapticrom X (solver Y)``: the installed package version (its metadata) and
    :data:`fem.SOLVER_VERSION`, the version recorded with every result."""
    try:
        package = version("hapticrom")
    except PackageNotFoundError:  # run from a source tree that is not installed
        package = "(not installed)"
    return f"hapticrom {package} (solver {SOLVER_VERSION})"


def build_parser() -> argparse.ArgumentParser:
    """The full parser: one sub-parser per module of :data:`COMMANDS`."""
    parser = _Parser(prog="hapticrom",
                     description="Reduced-order surrogate modelling of wearable vibrotactile "
                     "arrays. Exit codes: 0 ok, 1 failed, 2 bad input, 130 interrupted.")
    parser.add_argument("--version", action="version", version=version_text(),
                        help="print the package and solver versions and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        module = importlib.import_module(f"hapticrom.commands.{name}")
        module.register(sub)
    _add_verbose(parser, argparse.SUPPRESS)
    parser.set_defaults(verbose=False)
    return parser


def _add_verbose(parser: argparse.ArgumentParser, default: object) -> None:
    """``--verbose`` on ``parser`` and every sub-command under it (``default`` SUPPRESS, so that
    a sub-command's parser does not reset what was given before its name)."""
    parser.add_argument("--verbose", action="store_true", default=default,
                        help="also show the warnings and log notices of the libraries used "
                        "(torch, scikit-learn, ...); the project's own are always shown")
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in set(action.choices.values()):
                _add_verbose(child, argparse.SUPPRESS)


@contextlib.contextmanager
def quiet_libraries(quiet: bool = True) -> Iterator[None]:
    """While it lasts, keep the libraries' warnings and log messages below ERROR off the
    terminal (``quiet``); the project's own warnings (:class:`fieldspec.HapticromWarning`) stay
    on. The project logs nothing itself (it prints), so the logging switch only touches
    libraries; it is global because torch re-initialises its loggers' levels whenever it is
    imported. Both are restored on exit (``main`` may run in a caller's process)."""
    if not quiet:
        yield
        return
    before = logging.root.manager.disable
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        warnings.simplefilter("default", HapticromWarning)
        logging.disable(logging.WARNING)
        try:
            yield
        finally:
            logging.disable(before)


def _interruptible() -> None:
    """Ctrl-C stops every command (exit 130, below). A process started in the background by a
    script inherits SIGINT ignored, and Python then leaves it so: the long-running commands
    (emulate, play, generate) could be stopped only by SIGTERM or SIGKILL. Restored here, in
    the main thread only (a handler can be set nowhere else), and only where it is ignored."""
    if (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) == signal.SIG_IGN):
        signal.signal(signal.SIGINT, signal.default_int_handler)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # usage error (2, message printed) or --help (0): return, not exit
        return int(exc.code or EXIT_OK)
    name = args.command
    _interruptible()
    try:
        with quiet_libraries(not getattr(args, "verbose", False)):
            return int(args.func(args) or EXIT_OK)
    except KeyboardInterrupt:
        print(f"hapticrom {name}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except (FieldError, ValueError, FloatingPointError) as exc:  # bad input, or a model it makes
        print(f"hapticrom {name}: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except WorkError as exc:  # valid input, the work failed: say what, no traceback
        print(f"hapticrom {name}: failed: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except BrokenPipeError:  # the reader went away (`... | head`): stop quietly, as cat does
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # so that the final flush does not fail again
        return EXIT_OK
    except OSError as exc:  # unreadable input file, unwritable output
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"hapticrom {name}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_INPUT
    except Exception as exc:  # a failure of the work itself: say what and where
        traceback.print_exc(file=sys.stderr)
        print(f"hapticrom {name}: failed: {type(exc).__name__}: {exc}", file=sys.stderr)
        return EXIT_FAILED


if __name__ == "__main__":
    sys.exit(main())
