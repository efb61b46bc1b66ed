"""The shared figure style: captions that state design, frequency and what is plotted, PNGs
written with the style, and the envelope of the transient plots."""

from __future__ import annotations

import numpy as np
import pytest

import figstyle
from fem.plots import envelope

PNG = b"\x89PNG\r\n\x1a\n"


def test_caption_names_design_frequency_and_what_is_plotted():
    text = figstyle.caption_text(design="reverse, pogo", frequency="120 Hz",
                                 plotted="|u_z| in um")
    assert text == "Design: reverse, pogo | Frequency: 120 Hz | Plotted: |u_z| in um"
    static = figstyle.caption_text(design=None, frequency=None, plotted="x", note="n")
    assert "Design: n/a" in static and "Frequency: n/a (static)" in static
    assert static.endswith("\nn")


def test_annotated_figure_is_saved_with_title_and_caption(tmp_path):
    fig, ax = figstyle.figure()
    ax.plot([0, 1], [1, 2])
    figstyle.annotate(fig, "Title", design="d", frequency="1 Hz", plotted="p")
    texts = [t.get_text() for t in fig.texts]
    assert fig._suptitle.get_text() == "Title"
    assert any("Plotted: p" in t for t in texts)
    figstyle.save(fig, tmp_path / "f.png")
    assert (tmp_path / "f.png").read_bytes()[:8] == PNG


def test_the_style_does_not_leak_into_other_figures():
    import matplotlib

    before = matplotlib.rcParams["font.size"]
    fig, _ = figstyle.figure()
    figstyle.save(fig, "/dev/null", format="png")
    assert matplotlib.rcParams["font.size"] == before


def test_envelope_of_a_growing_sine_follows_its_amplitude():
    t = np.linspace(0.0, 1.0, 20001)
    amp = 1.0 + 2.0 * t
    x = amp * np.sin(2 * np.pi * 40.0 * t)
    env = envelope(t, x)
    inner = (t > 0.05) & (t < 0.95)
    # peaks sit at most a quarter period from any point: amplitude slope 2/s * 1/160 s
    assert np.max(np.abs(env[inner] - amp[inner])) < 2.0 / 160 + 1e-3
    assert np.all(env >= np.abs(x) - 2.0 / 160)


@pytest.mark.parametrize("n", [0, 1, 2])
def test_envelope_of_very_short_series(n):
    t = np.arange(n, dtype=float)
    assert envelope(t, -np.ones(n)).tolist() == [1.0] * n
