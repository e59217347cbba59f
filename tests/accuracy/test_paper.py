"""``accuracy --paper --out DIR``: its table and figure on disk, progress while it runs, and
a table that does not move with the machine's speed."""

import csv
import io
import json
import logging
import re
import sys

import clothsim.accuracy.paper as paper
import clothsim.accuracy.phases as phases_module
from clothsim.cli import main
from clothsim.io.folders import folder_kind


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_paper_out_writes_table_csv_figure_and_record(tmp_path):
    text = paper.paper_report(n=5, frames=2, repeats=1, cap=300, out=tmp_path / "p")
    out = tmp_path / "p"
    assert (out / "paper.md").read_text() == text + "\n"
    rows = list(csv.DictReader((out / "paper.csv").open()))
    assert [float(r["level"]) for r in rows] == [10.0 ** -p for p in range(1, 9)]
    assert (out / "paper.png").read_bytes().startswith(b"\x89PNG")
    record = json.loads((out / "paper.json").read_text())
    assert record["paper"]["cap"] == 300 and folder_kind(out) == "paper"
    assert record["status"] == "complete"
    # again into its own folder: allowed; into an accuracy study's: refused by name
    paper.paper_report(n=5, frames=2, repeats=1, cap=300, out=out)
    (tmp_path / "q").mkdir()
    (tmp_path / "q" / "notes.txt").write_text("mine")
    assert main(["accuracy", "--paper", "--paper-size", "5", "--repeats", "1", "--out",
                 str(tmp_path / "q")]) == 2
    assert not (tmp_path / "q" / "paper.md").exists()


def test_the_iteration_counts_do_not_depend_on_the_machine(monkeypatch):
    """The local/global trace is cut by a count: a machine 10x slower per iteration moves
    the milliseconds, not the iterations nor where the trace ends."""
    counts = []
    for seconds in (1e-4, 1e-3):
        monkeypatch.setattr(paper, "_seconds_per_iteration", lambda *a, s=seconds: s)
        text = paper.paper_report(n=6, frames=3, repeats=1, cap=60)
        lg = re.findall(r"^\| (1e-\d\d) \| ([^|]+) \|", text, re.M)
        counts.append([(lev, re.sub(r",\s*[\d.e+]+$|≈ [\d.e+]+ ms", "", cell))
                       for lev, cell in lg])
        assert "local/global traced for" in text
    assert counts[0] == counts[1] and len(counts[0]) == 8
    assert any("extrapolated" in cell for _, cell in counts[0])   # 60 iterations: beyond


def test_paper_shows_progress_bars_on_a_terminal_and_log_lines_otherwise(monkeypatch,
                                                                           caplog, tmp_path):
    monkeypatch.delenv("TQDM_DISABLE", raising=False)
    monkeypatch.setattr(sys, "stderr", Terminal())
    paper.paper_report(n=5, frames=2, repeats=1, cap=100)
    bars = sys.stderr.getvalue()
    for name in ("converged steps", "reference", "local/global trace", "timing"):
        assert f"{name}: 100%" in bars, bars
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    monkeypatch.setattr(phases_module, "LOG_EVERY", 0.0)
    with caplog.at_level(logging.INFO, logger="clothsim.accuracy.phases"):
        paper.paper_report(n=5, frames=2, repeats=1, cap=100)
    lines = [r.getMessage() for r in caplog.records]
    assert sys.stderr.getvalue() == ""
    for name in ("converged steps: 2/2 step(s)", "local/global trace:", "timing: 1/1"):
        assert any(line.startswith(name) for line in lines), (name, lines[:5])


def test_the_command_line_shows_progress_lines_off_a_terminal(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(phases_module, "LOG_EVERY", 0.0)
    assert main(["accuracy", "--paper", "--paper-size", "5", "--repeats", "1", "--out",
                 str(tmp_path / "p")]) == 0
    captured = capsys.readouterr()
    assert "| 1e-01 |" in captured.out and (tmp_path / "p" / "paper.png").exists()
    assert "clothsim: INFO: local/global trace:" in captured.err
    assert "clothsim: INFO: timing: 1/1 repeat(s) done" in captured.err
