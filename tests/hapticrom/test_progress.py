"""Progress bars: rate and ETA on a terminal, nothing when stderr is not one or with --quiet."""

from __future__ import annotations

import io
import sys

from hapticrom.progress import progress_bar


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_bar_on_a_terminal_shows_count_rate_and_eta(monkeypatch):
    err = _Tty()
    monkeypatch.setattr(sys, "stderr", err)
    with progress_bar(True, "time steps", "scene.toml") as report:
        assert report is not None
        for done in (10, 50, 100):
            report(done, 100)
    text = err.getvalue()
    assert "scene.toml" in text and "100/100" in text
    assert "steps/s" in text or "s/steps" in text  # the rate
    assert "<" in text  # elapsed<remaining: the ETA


def test_no_bar_when_quiet_or_not_a_terminal(monkeypatch):
    err = io.StringIO()  # not a tty: logs and pipes stay clean
    monkeypatch.setattr(sys, "stderr", err)
    with progress_bar(True, "time steps", "x") as report:
        assert report is None
    monkeypatch.setattr(sys, "stderr", _Tty())
    with progress_bar(False, "time steps", "x") as report:
        assert report is None
    assert err.getvalue() == ""
