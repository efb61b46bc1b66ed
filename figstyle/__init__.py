"""The one figure style of hapticrom: every PNG of the project is drawn through this package.

Bottom layer (imports nothing of the project; matplotlib only inside the functions, so importing
``figstyle`` costs nothing). Each figure states, in its title and caption, the design, the
frequency and what is plotted (quantity, unit, where on the body)::

    fig, ax = figstyle.figure()
    ...
    figstyle.annotate(fig, "Surface amplitude against radius",
                      design="reverse, pogo, rings A C D", frequency="120 Hz",
                      plotted="|u_z| and the displacement magnitude, um, skin surface")
    figstyle.save(fig, "out.png")
"""

from __future__ import annotations

import io
import math
import os
import textwrap
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["OKABE_ITO", "RC", "annotate", "caption_text", "color", "figure", "plain_log_ticks",
           "save", "style"]

#: matplotlib rcParams of every figure: small sans-serif text, light grid, colour-blind safe
#: cycle (Okabe & Ito 2008, "Color Universal Design", https://jfly.uni-koeln.de/color/).
RC: dict[str, Any] = {
    "figure.dpi": 100,
    "savefig.dpi": 100,
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.6,
    "lines.linewidth": 1.4,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.prop_cycle": None,  # filled in by style(): needs matplotlib's cycler
    "legend.frameon": False,
}
OKABE_ITO = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442",
             "#000000")


def color(i: int) -> str:
    """The i-th colour of the project's cycle (use instead of matplotlib's "C0", "C1", ...,
    which name the default palette wherever a figure is drawn)."""
    return OKABE_ITO[i % len(OKABE_ITO)]


def _pyplot():
    # lazy: matplotlib takes 1.9 s to import, and only a figure needs it
    import matplotlib

    if "MPLBACKEND" not in os.environ:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


@contextmanager
def style() -> Iterator[None]:
    """Apply :data:`RC` for the duration of the block (figures keep the style when saved)."""
    # lazy: matplotlib takes 1.9 s to import, and only a figure needs it
    import matplotlib
    from cycler import cycler

    # eight colours solid, then the same eight dashed: 16 lines stay distinguishable
    rc = {**RC, "axes.prop_cycle": cycler(linestyle=["-", "--"]) * cycler(color=list(OKABE_ITO))}
    with matplotlib.rc_context(rc):
        yield


def figure(nrows: int = 1, ncols: int = 1, *, width_in: float = 6.4,
           height_in: float = 4.2, **kwargs: Any):
    """A new (figure, axes) in the project style; close it with :func:`save`."""
    plt = _pyplot()
    with style():
        return plt.subplots(nrows, ncols, figsize=(width_in, height_in), **kwargs)


def caption_text(*, design: str | None, frequency: str | None, plotted: str,
                 note: str | None = None) -> str:
    """The caption: 'Design: ... | Frequency: ... | Plotted: ...' (+ note); a part that does
    not apply is given as None and says so."""
    parts = [f"Design: {design or 'n/a'}", f"Frequency: {frequency or 'n/a (static)'}",
             f"Plotted: {plotted}"]
    text = " | ".join(parts)
    return text if not note else f"{text}\n{note}"


def annotate(fig: Any, title: str, *, design: str | None, frequency: str | None,
             plotted: str, note: str | None = None) -> None:
    """Put the title on top and the caption (design, frequency, what is plotted) below."""
    fig.suptitle(title, fontsize=11, fontweight="bold")
    cap = caption_text(design=design, frequency=frequency, plotted=plotted, note=note)
    width = max(60, int(fig.get_figwidth() * 15))
    lines = [w for para in cap.split("\n") for w in textwrap.wrap(para, width)]
    fig.text(0.01, 0.01, "\n".join(lines), ha="left", va="bottom", fontsize=7.5, color="0.25")
    bottom = min(0.4, 0.05 + 0.035 * len(lines) * 4.2 / fig.get_figheight())
    with style():
        fig.tight_layout(rect=(0, bottom, 1, 0.95))


def plain_log_ticks(ax: Any) -> None:
    """Label a log y axis with plain numbers (2, 5, 10) instead of 2x10^0 and 5x10^0; minor
    ticks are labelled only when the axis spans less than two decades (call after plotting)."""
    # lazy: matplotlib takes 1.9 s to import, and only a figure needs it
    from matplotlib.ticker import FuncFormatter, NullFormatter

    fmt = FuncFormatter(lambda v, _: f"{v:g}")
    ax.yaxis.set_major_formatter(fmt)
    lo, hi = ax.get_ylim()
    narrow = lo > 0 and math.log10(hi / lo) < 2
    ax.yaxis.set_minor_formatter(fmt if narrow else NullFormatter())


def save(fig: Any, path: str | os.PathLike, **kwargs: Any) -> None:
    """Write the figure (PNG unless the suffix says otherwise) and close it. ``format`` is
    taken from the suffix of ``path`` when it has one, so temporary names work too."""
    plt = _pyplot()
    fmt = kwargs.get("format") or os.path.splitext(os.fspath(path))[1].lstrip(".").lower()
    with style():
        if fmt in ("", "png"):
            _save_png(fig, path, kwargs)
        else:
            fig.savefig(path, **kwargs)
    plt.close(fig)


#: The PNG ``Software`` text of every figure (hapticrom.outputs recognises its own files by it).
SOFTWARE = "hapticrom"


def _save_png(fig: Any, path: str | os.PathLike, kwargs: dict[str, Any]) -> None:
    """A 256-colour palette PNG without dithering: line plots hold far fewer colours, so it
    looks the same at a third of the size (README figures stay well under 150 kB)."""
    # lazy: matplotlib takes 1.9 s to import, and only a figure needs it
    from PIL import Image, PngImagePlugin

    buf = io.BytesIO()
    fig.savefig(buf, **{**kwargs, "format": "png"})
    buf.seek(0)
    with Image.open(buf) as im:
        rgb = im.convert("RGB")
    pal = rgb.quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    info = PngImagePlugin.PngInfo()
    info.add_text("Software", SOFTWARE)  # how hapticrom recognises its own figures
    pal.save(path, format="PNG", optimize=True, pnginfo=info)
