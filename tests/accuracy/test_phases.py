"""A progress bar per phase of the study, on stderr, only on a terminal; seconds per phase."""

import io
import sys

from clothsim.accuracy.phases import PHASES, Phases, advance


class Terminal(io.StringIO):
    def isatty(self):
        return True


def run(monkeypatch, stream, units=3):
    monkeypatch.setattr(sys, "stderr", stream)
    phases = Phases()
    with phases.phase("references", units, "step"):
        for _ in range(units):
            advance()
    advance()  # no phase open: nothing happens
    return phases


def test_a_phase_draws_its_bar_on_a_terminal_and_records_its_seconds(monkeypatch):
    monkeypatch.delenv("TQDM_DISABLE", raising=False)
    phases = run(monkeypatch, Terminal())
    text = sys.stderr.getvalue()
    assert "references: 100%" in text and "3/3" in text
    assert set(phases.seconds) == {"references"} and "references" in PHASES
    assert phases.seconds["references"]["wall"] >= 0 and phases.seconds["references"]["cpu"] >= 0


def test_no_bar_off_a_terminal_or_under_tqdm_disable(monkeypatch):
    monkeypatch.delenv("TQDM_DISABLE", raising=False)
    run(monkeypatch, io.StringIO())
    assert sys.stderr.getvalue() == ""
    monkeypatch.setenv("TQDM_DISABLE", "1")
    phases = run(monkeypatch, Terminal())
    assert sys.stderr.getvalue() == "" and "references" in phases.seconds


def test_off_a_terminal_a_phase_logs_its_progress(monkeypatch, caplog):
    import logging

    import clothsim.accuracy.phases as phases_module

    monkeypatch.delenv("TQDM_DISABLE", raising=False)
    monkeypatch.setattr(phases_module, "LOG_EVERY", 0.0)   # a line per unit
    with caplog.at_level(logging.INFO, logger="clothsim.accuracy.phases"):
        run(monkeypatch, io.StringIO())
    lines = [r.getMessage() for r in caplog.records]
    assert "references: 1/3 step(s) done, 0 s" in lines[0]
    assert any(line.startswith("references: 3/3 step(s) done") for line in lines)
    assert lines[-1].startswith("phase references:")
    assert sys.stderr.getvalue() == ""      # no bar drawn


def test_an_interrupted_phase_keeps_its_seconds_and_logs_no_end_line(caplog):
    """A signal inside a phase: its seconds are recorded, but the command's one-line error
    stays the only line (no "phase ...: s wall" line for a phase that did not end)."""
    import logging

    import pytest

    phases = Phases(enabled=False)
    with caplog.at_level(logging.INFO, logger="clothsim.accuracy.phases"):
        with pytest.raises(KeyboardInterrupt):
            with phases.phase("recording", total=2, unit="step"):
                raise KeyboardInterrupt
        with phases.phase("references", total=1, unit="step"):
            pass
    assert "recording" in phases.seconds and "references" in phases.seconds
    lines = [r.getMessage() for r in caplog.records]
    assert not any(line.startswith("phase recording") for line in lines)
    assert any(line.startswith("phase references") for line in lines)
