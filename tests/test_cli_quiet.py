"""Quiet by default: equiv and mutate print one summary (what went wrong, coverage, reports, verdict); the per-run
lines and the uncovered places come with -v; a progress line only where stderr is a terminal."""

from __future__ import annotations

import io
from pathlib import Path

from transpiler.cli import main
from transpiler.cli.progress import ProgressLine, format_seconds, render_bar

ROOT = Path(__file__).resolve().parents[1]
CASE_CHAIN = ROOT / "samples" / "constructs" / "case_chain"
GAP = "L I0\nJPF Skip\nL I1\n= O1\nLBL Skip\nL I2\n= O2\nEM\n"        # I0 never set: the jump is always taken


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_line_draws_on_a_terminal_and_nothing_elsewhere():
    tty = _Terminal()
    line = ProgressLine("equiv", "cycles", stream=tty, delay=0.0)
    line.update(25, 100, "spindle")
    drawn = tty.getvalue()
    assert drawn.startswith("\requiv: [######..................] 25/100 cycles") and "left (spindle)" in drawn
    line.update(100, 100)
    line.close()
    assert tty.getvalue().endswith("\r")                   # the line is wiped: the results follow on a clean line
    log = io.StringIO()
    quiet = ProgressLine("equiv", "cycles", stream=log, delay=0.0)
    quiet.update(50, 100)
    quiet.close()
    assert log.getvalue() == ""


def test_progress_helpers():
    assert render_bar(0, 10, 4) == "[....]" and render_bar(10, 10, 4) == "[####]" and render_bar(3, 0, 4) == "[....]"
    assert format_seconds(42.4) == "42 s" and format_seconds(125) == "2 min 05 s" and format_seconds(3725) == "1 h 02 min"


def test_equiv_is_quiet_by_default_and_tells_everything_with_v(tmp_path, capsys):
    scenario = CASE_CHAIN / "scenario.yaml"
    report = tmp_path / "equiv.json"
    args = ["equiv", str(CASE_CHAIN), "--scenario", str(scenario), "--random-cycles", "200", "--report", str(report)]
    assert main(args) == 0
    quiet = capsys.readouterr().out.splitlines()
    assert not any(line.startswith("equivalent: ") for line in quiet)
    assert quiet[-1].startswith("hh2iec equiv: EQUIVALENT (") and " cycles, backend " in quiet[-1]
    assert f"reports: {report}" in quiet and any(line.startswith("coverage: ") for line in quiet)
    assert len(quiet) <= 4
    assert main(args + ["-v"]) == 0
    loud = capsys.readouterr().out.splitlines()
    runs = [line for line in loud if line.startswith("equivalent: ")]
    assert len(runs) >= 2 and loud[-1] == quiet[-1]


def test_uncovered_places_are_counted_quietly_and_listed_with_v(tmp_path, capsys):
    (tmp_path / "main.src").write_text(GAP)
    (tmp_path / "s.yaml").write_text("cycles: 5\nevents:\n  - cycle: 1\n    set: {I1: 1}\n")
    args = ["equiv", str(tmp_path / "main.src"), "--scenario", str(tmp_path / "s.yaml")]
    assert main(args) == 0
    quiet = capsys.readouterr().out
    assert "1 branch outcomes or CASE entries no run took (-v lists them)" in quiet and "not covered:" not in quiet
    assert main(args + ["-v"]) == 0
    assert "  not covered: main.src:2:1: JPF always jumps" in capsys.readouterr().out.splitlines()
