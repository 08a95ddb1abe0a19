"""Progress output: a bar on a terminal only; in a log, plain lines where asked, never carriage returns."""

from __future__ import annotations

import io
import sys

import pytest

from handsim import progress
from handsim.progress import is_terminal, progress_bar, progress_line


def _count(bar) -> None:
    with bar:
        for _ in range(50):
            bar.set_postfix_str("running")  # refreshes the bar each time, as the CoACD wait does
            bar.update(1)


def test_a_progress_bar_writes_nothing_when_stderr_is_not_a_terminal(capsys):
    _count(progress_bar(total=50, desc="trials"))
    assert capsys.readouterr() == ("", "")


def test_a_progress_bar_is_drawn_in_place_on_a_terminal(capsys, monkeypatch):
    monkeypatch.setattr(progress, "is_terminal", lambda: True)
    _count(progress_bar(total=50, desc="trials", mininterval=0))
    err = capsys.readouterr().err
    assert err.count("\r") > 1 and "trials: 100%" in err


def test_a_progress_bar_not_asked_for_is_not_drawn_on_a_terminal(capsys, monkeypatch):
    monkeypatch.setattr(progress, "is_terminal", lambda: True)
    _count(progress_bar(enabled=False, total=50, desc="trials"))
    assert capsys.readouterr() == ("", "")


@pytest.mark.parametrize(("terminal", "enabled", "written"), [(False, True, "step: done\n"), (True, True, ""),
                                                             (False, False, "")])  # fmt: skip
def test_a_progress_line_is_written_only_where_no_bar_is_drawn(
    capsys, monkeypatch, terminal, enabled, written
):
    monkeypatch.setattr(progress, "is_terminal", lambda: terminal)
    progress_line("step: done", enabled=enabled)
    assert capsys.readouterr() == ("", written)


def test_a_closed_or_replaced_stderr_is_no_terminal(monkeypatch):
    closed = io.StringIO()
    closed.close()
    monkeypatch.setattr(sys, "stderr", closed)
    assert is_terminal() is False
    monkeypatch.setattr(sys, "stderr", object())
    assert is_terminal() is False
