"""Progress bars of long runs (transients, generation, the reproduction): tqdm on stderr with
the rate and the ETA, shown only when stderr is a terminal and the user did not ask for quiet."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Callable, Iterator

__all__ = ["progress_bar", "wanted"]


def wanted(quiet: bool = False) -> bool:
    """True when a bar should be drawn: not ``--quiet`` and stderr is a terminal."""
    return not quiet and sys.stderr.isatty()


@contextlib.contextmanager
def progress_bar(enabled: bool, unit: str, desc: str
                 ) -> Iterator[Callable[[int, int], None] | None]:
    """Yield a ``report(done, total)`` callback driving a tqdm bar (rate and ETA), or None
    when disabled or stderr is not a terminal (nothing is imported then)."""
    if not (enabled and wanted()):
        yield None
        return
    # lazy: a progress bar, drawn only on a terminal
    from tqdm import tqdm

    bar = tqdm(total=None, unit=unit.split()[-1], desc=desc, file=sys.stderr,
               dynamic_ncols=True, smoothing=0.1)

    def report(done: int, total: int) -> None:
        if bar.total != total:
            bar.total = total
        bar.update(done - bar.n)

    try:
        yield report
    finally:
        bar.close()
