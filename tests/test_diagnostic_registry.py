"""Severity has one home: every code the library reports is registered, and only the registry sets its severity."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from transpiler.diagnostics import CODES, Diagnostic, Diagnostics, Severity, Span

PACKAGE = Path(__file__).resolve().parents[1] / "transpiler"
REPORTING_CALLS = {"report", "of"}


def _reported_codes() -> dict[str, list[str]]:
    """Literal codes passed first to `.report(...)` / `Diagnostic.of(...)` anywhere in the package, with their places."""
    found: dict[str, list[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in REPORTING_CALLS
                    and node.args and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)):
                found.setdefault(node.args[0].value, []).append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno}")
    return found


def test_every_reported_code_is_registered():
    found = _reported_codes()
    assert len(found) > 35, "the scan found too few report calls: has the reporting API changed?"
    unregistered = {code: places for code, places in found.items() if code not in CODES}
    assert unregistered == {}


def test_no_call_site_chooses_a_severity():
    """The collector has no per-call severity: a site that passes one (or calls warning()/error()) fails here."""
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
                continue
            if node.func.attr == "report" and any(k.arg == "severity" for k in node.keywords):
                offenders.append(f"{path.name}:{node.lineno}")
            if (node.func.attr in {"warning", "error", "note"} and node.args and isinstance(node.args[0], ast.Constant)
                    and str(node.args[0].value).startswith("E-")):
                offenders.append(f"{path.name}:{node.lineno}")
    assert offenders == []


@pytest.mark.parametrize("code", sorted(CODES))
def test_reported_severity_is_the_registry_severity(code):
    diags = Diagnostics()
    diags.report(code, Span("x.src", 1, 1), "message")
    assert diags.items[0].severity is CODES[code].severity


def test_an_allowed_error_becomes_a_warning_and_only_allowable_codes_may_be_allowed():
    allowable = [c for c, info in CODES.items() if info.allowable]
    assert "E-UNSUPPORTED" in allowable
    diags = Diagnostics(allowed={"E-UNSUPPORTED"})
    diags.report("E-UNSUPPORTED", Span("x.src", 3, 1), "not translated")
    diags.report("E-SYNTAX", Span("x.src", 4, 1), "bad")
    assert [(d.code, d.severity) for d in diags.items] == [("E-UNSUPPORTED", Severity.WARNING), ("E-SYNTAX", Severity.ERROR)]
    with pytest.raises(ValueError):
        Diagnostics(allowed={"E-SYNTAX"})


def test_unregistered_code_is_refused():
    with pytest.raises(KeyError):
        Diagnostic.of("E-NO-SUCH-CODE", Span("x.src", 1, 1), "m")
