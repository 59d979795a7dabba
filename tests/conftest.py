"""Skipped tests are never silent: every skip is listed with its reason at the end of the run, and when
HH2IEC_SKIP_ALLOWANCE_FILE names an allowance file (`make test` sets it to tests/skip_allowance.txt) the session
fails if more tests were skipped than that file allows."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

ALLOWANCE_ENV = "HH2IEC_SKIP_ALLOWANCE_FILE"
_RESULT_KEY = pytest.StashKey[tuple[int, int | None, str]]()   # (skipped, allowance or None, message)


def _reason(report: pytest.TestReport) -> str:
    longrepr = report.longrepr
    if isinstance(longrepr, tuple) and len(longrepr) == 3:
        path, line, reason = longrepr
        reason = str(reason).removeprefix("Skipped: ")
        return f"{reason}  [{path}:{line}]" if reason else f"(no reason given)  [{path}:{line}]"
    return str(longrepr or "(no reason given)")


def _skipped(config: pytest.Config) -> list[pytest.TestReport]:
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    if reporter is None:
        return []
    return [r for r in reporter.stats.get("skipped", []) if getattr(r, "nodeid", None) is not None]


def read_allowance(path: Path) -> int:
    """The allowance: the sum of the numbers that start the non-comment lines (one line per group of skips)."""
    total, groups = 0, 0
    for line in path.read_text(encoding="utf-8").splitlines():
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        match = re.match(r"(\d+)\b", text)
        if not match:
            raise ValueError(f"{path}: a group line must start with its number of allowed skips: {line!r}")
        total += int(match.group(1))
        groups += 1
    if groups == 0:
        raise ValueError(f"{path}: no group of allowed skips")
    return total


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    skipped = len(_skipped(session.config))
    name = os.environ.get(ALLOWANCE_ENV)
    if not name:
        session.config.stash[_RESULT_KEY] = (skipped, None, "")
        return
    path = Path(name)
    try:
        allowance = read_allowance(path)
    except (OSError, ValueError) as exc:
        session.config.stash[_RESULT_KEY] = (skipped, None, f"FAILED: cannot read the skip allowance {path}: {exc}")
        session.exitstatus = pytest.ExitCode.TESTS_FAILED if exitstatus == 0 else exitstatus
        return
    if skipped > allowance:
        message = (f"FAILED: {skipped} tests were skipped, more than the allowance of {allowance} in {path}: "
                   f"make the new skips run, or add a documented group to the allowance file")
        if exitstatus == pytest.ExitCode.OK:
            session.exitstatus = pytest.ExitCode.TESTS_FAILED
    elif skipped < allowance:
        message = f"ok: {skipped} skipped, allowance {allowance} ({path}; it could be lowered to {skipped})"
    else:
        message = f"ok: {skipped} skipped, allowance {allowance} ({path})"
    session.config.stash[_RESULT_KEY] = (skipped, allowance, message)


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    reports = _skipped(config)
    skipped, _, message = config.stash.get(_RESULT_KEY, (len(reports), None, ""))
    if reports:
        terminalreporter.section(f"not run: {len(reports)} skipped tests", sep="=", yellow=True)
        for report in sorted(reports, key=lambda r: r.nodeid):
            terminalreporter.write_line(f"not run: {report.nodeid}: {_reason(report)}")
    terminalreporter.write_line(f"skipped: {skipped}")
    if message:
        terminalreporter.write_line(f"skip allowance: {message}", red=message.startswith("FAILED"),
                                    bold=message.startswith("FAILED"))
