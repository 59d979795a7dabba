"""`hh2iec --version`, `hh2iec explain CODE` for every diagnostic code and assumption, and `explain --list`."""

from __future__ import annotations

import re
from importlib import metadata

import pytest

from transpiler import __version__
from transpiler.cli.app import main
from transpiler.diagnostics import CODES
from transpiler.language.semantics import ASSUMPTIONS, PROFILES


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_version_prints_the_package_metadata_version(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = _run(["--version"], capsys)
    assert code == 0 and err == ""
    assert out == f"hh2iec {metadata.version('hh2iec')}\n"
    assert metadata.version("hh2iec") == __version__  # pyproject reads the version from the package


@pytest.mark.parametrize("code", sorted(CODES))
def test_explain_every_diagnostic_code(code: str, capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = _run(["explain", code.lower()], capsys)
    assert rc == 0 and err == ""
    info = CODES[code]
    assert out.startswith(f"{code} ({info.severity.value}): {info.summary}\n")


@pytest.mark.parametrize("assumption", ASSUMPTIONS, ids=lambda a: a.id)
def test_explain_every_assumption(assumption, capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = _run(["explain", assumption.id], capsys)
    assert rc == 0 and err == ""
    assert out.startswith(f"{assumption.id} {assumption.key}: {assumption.topic}\n")
    assert f"-S {assumption.key}=" in out
    for name, profile in PROFILES.items():
        value = profile.defaults[assumption.key]
        assert f"{name}: {value if value != '' else '(empty)'}" in out
    for alternative in assumption.alternatives:
        assert str(alternative) in out
    assert "docs/assumptions.md" in out


def test_explain_takes_an_assumption_key_too(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = _run(["explain", "add_overflow"], capsys)
    assert rc == 0 and out.startswith("A-09 add_overflow:")


def test_explain_list_names_every_code_and_assumption_with_its_summary(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = _run(["explain", "--list"], capsys)
    assert rc == 0 and err == ""
    lines = out.splitlines()
    assert len(lines) == len(CODES) + len(ASSUMPTIONS)
    for line, info in zip(lines, CODES.values()):
        assert re.match(rf"{re.escape(info.code)} +{info.severity.value} +{re.escape(info.summary)}$", line), line
    for line, a in zip(lines[len(CODES):], ASSUMPTIONS):
        assert re.match(rf"{re.escape(a.id)} +assume +{a.key}: {re.escape(a.topic)}$", line), line


@pytest.mark.parametrize("argv, message", [
    (["explain", "E-NO-SUCH"], "unknown diagnostic code or assumption E-NO-SUCH"),
    (["explain", "A-99"], "unknown diagnostic code or assumption A-99"),
    (["explain"], "explain needs a diagnostic code"),
    (["explain", "--list", "E-SYNTAX"], "either a CODE or --list"),
])
def test_explain_bad_usage_is_e_usage_exit_2(argv: list[str], message: str,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = _run(argv, capsys)
    assert rc == 2 and out == ""
    assert "error[E-USAGE]" in err and message in err, err
