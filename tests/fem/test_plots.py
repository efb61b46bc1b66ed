"""`simulate --plot`: the figure of each analysis kind says the design, the frequency and what
is plotted; the transient one shows centre and edge histories with envelopes and the peaks."""

from __future__ import annotations

import pytest

import figstyle
from fem import simulate
from fem.plots import plot_result
from fem.scene import load_scene, scene_from_dict, scene_to_dict

COARSE = {"order": 1, "near_size_mm": 1.0, "far_size_mm": 4.0}


def _scene(path, **analysis):
    d = scene_to_dict(load_scene(path))
    d["mesh"].update(COARSE)
    d["tissue"]["radius_mm"] = 20.0
    d["analysis"].update(analysis)
    return scene_from_dict(d)


@pytest.fixture
def drawn(monkeypatch):
    """The figures plot_result draws, kept instead of closed (and the file still written)."""
    figs = []

    def keep(fig, path, **kw):
        figs.append(fig)
        fig.savefig(path)

    monkeypatch.setattr(figstyle, "save", keep)
    yield figs
    import matplotlib.pyplot as plt

    for f in figs:
        plt.close(f)


def _texts(fig):
    caption = " ".join(t.get_text() for t in fig.texts)
    titles = [ax.get_title() for ax in fig.axes]
    labels = [line.get_label() for ax in fig.axes for line in ax.get_lines()]
    return fig._suptitle.get_text(), caption, titles, labels


@pytest.mark.parametrize(("kind", "freq"), [("harmonic", "Frequency: 120 Hz"),
                                            ("static", "Frequency: n/a (static)")])
def test_steady_plot_says_design_frequency_and_quantity(tmp_path, drawn, kind, freq):
    res = simulate(_scene("examples/forearm.toml", kind=kind))
    plot_result(str(tmp_path / "p.png"), res, "forearm.toml")
    title, caption, _, labels = _texts(drawn[0])
    assert title == f"forearm.toml: {kind} surface response"
    assert "Design: tangential patch r = 2 mm" in caption and freq in caption
    assert "Plotted:" in caption and "um" in caption
    assert any(lbl.startswith("edge, r = 2 mm") for lbl in labels)
    assert (tmp_path / "p.png").stat().st_size > 1000


def test_transient_plot_has_centre_and_edge_histories_envelopes_and_peak_panel(tmp_path,
                                                                                drawn):
    res = simulate(_scene("examples/unit-transient.toml", duration_ms=6.0, time_step_ms=0.2))
    plot_result(str(tmp_path / "t.png"), res, "unit-transient.toml")
    title, caption, titles, labels = _texts(drawn[0])
    assert title == "unit-transient.toml: transient"
    assert "Design: unit: reverse, pogo" in caption and "ERM spin-up" in caption
    assert "peak amplitude against radius" in titles
    assert any(lbl.startswith("centre") and "(t)" in lbl for lbl in labels)
    assert any(lbl.startswith("edge") and "envelope" in lbl for lbl in labels)
    assert any(lbl.startswith("peak") for lbl in labels)
