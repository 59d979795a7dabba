"""Tests of the independent ST checkers (tree-sitter, blark, matiec) on emitted and on deliberately broken ST."""

from __future__ import annotations

import dataclasses
import os
import re
import stat
from pathlib import Path

import pytest
from test_st_writer import rich_project

from transpiler.backends.st import check as st_check
from transpiler.backends.plcopen.writer import extract_st_bodies, render_xml
from transpiler.backends.st.writer import extract_pou_bodies, render_st

BROKEN_PROGRAM = """\
PROGRAM P
VAR
    x : INT;
END_VAR
    (* ü ß: non-ASCII before the error must not shift the column *) x := x + ;
END_PROGRAM
"""
CONFIG = """
CONFIGURATION Config0
    RESOURCE Res0 ON PLC
        TASK T1(INTERVAL := T#20ms, PRIORITY := 0);
        PROGRAM inst0 WITH T1 : P;
    END_RESOURCE
END_CONFIGURATION
"""


def _error_column(text: str, line_no: int, needle: str) -> int:
    return text.split("\n")[line_no - 1].index(needle) + 1


@pytest.fixture(scope="module")
def rich_st() -> str:
    return render_st(rich_project())


@pytest.fixture()
def iec2c() -> Path:
    found = st_check.find_iec2c()
    if found is None:
        pytest.skip("iec2c not found ($MATIEC_HOME/iec2c or PATH): matiec compile checks skipped")
    return found


# --- tree-sitter ----------------------------------------------------------------------------


def test_tree_sitter_accepts_the_rich_project(rich_st: str) -> None:
    assert st_check.check_tree_sitter(rich_st, "project.st") == []


def test_tree_sitter_locates_errors_in_characters() -> None:
    errors = st_check.check_tree_sitter(BROKEN_PROGRAM + CONFIG, "bad.st")
    assert errors, "a dangling '+' must be reported"
    match = re.match(r"bad\.st:(\d+):(\d+): error: ", errors[0])
    assert match, errors
    line, column = int(match.group(1)), int(match.group(2))
    assert line == 5
    # the fault sits between '+' and ';' (tree-sitter reports the missing operand there)
    assert _error_column(BROKEN_PROGRAM, 5, "+") <= column <= _error_column(BROKEN_PROGRAM, 5, ";")


def test_tree_sitter_rejects_a_broken_configuration() -> None:
    broken = BROKEN_PROGRAM.replace("x + ;", "x + 1;") + CONFIG.replace("PRIORITY := 0);", "PRIORITY := 0;")
    assert st_check.check_tree_sitter(BROKEN_PROGRAM.replace("x + ;", "x + 1;") + CONFIG, "ok.st") == []
    errors = st_check.check_tree_sitter(broken, "bad.st")
    assert errors and all(e.startswith("bad.st:") for e in errors)


# --- blark ----------------------------------------------------------------------------------


def test_blark_accepts_the_rich_project(rich_st: str) -> None:
    assert st_check.check_blark(rich_st, "project.st") == []


def test_blark_reports_errors_with_original_line_numbers() -> None:
    # configuration first, so a wrong strip would shift the reported line
    text = CONFIG + BROKEN_PROGRAM
    errors = st_check.check_blark(text, "bad.st")
    assert len(errors) == 1
    expected_line = text.split("\n").index("    (* ü ß: non-ASCII before the error must not shift the column *) x := x + ;") + 1
    assert errors[0].startswith(f"bad.st:{expected_line}:"), errors


def test_blark_rejects_ampersand_as_and() -> None:
    text = BROKEN_PROGRAM.replace("x := x + ;", "x := x; b := TRUE & FALSE;").replace("x : INT;", "x : INT;\n    b : BOOL;")
    assert st_check.check_blark(text, "amp.st")


def test_strip_configuration_keeps_line_numbers() -> None:
    text = BROKEN_PROGRAM + CONFIG + "\nTYPE\n    T : INT;\nEND_TYPE\n"
    stripped, problems = st_check.strip_configuration(text)
    assert problems == []
    assert stripped.count("\n") == text.count("\n")
    assert "CONFIGURATION" not in stripped and "RESOURCE" not in stripped and "END_TYPE" in stripped
    assert stripped.split("\n")[:6] == text.split("\n")[:6]


def test_unterminated_configuration_is_reported() -> None:
    text = BROKEN_PROGRAM.replace("x + ;", "x + 1;") + "CONFIGURATION C\n    RESOURCE R ON PLC\n"
    errors = st_check.check_blark(text, "cut.st")
    assert errors == [f"cut.st:{BROKEN_PROGRAM.count(chr(10)) + 1}:1: error: CONFIGURATION without END_CONFIGURATION"]


# --- matiec ---------------------------------------------------------------------------------


def test_find_iec2c_prefers_matiec_home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    fake = tmp_path / "iec2c"
    fake.write_text("#!/bin/sh\nexit 0\n")
    fake.chmod(fake.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("MATIEC_HOME", str(tmp_path))
    assert st_check.find_iec2c() == fake
    monkeypatch.setenv("MATIEC_HOME", str(tmp_path / "missing"))
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    assert st_check.find_iec2c() is None
    monkeypatch.setenv("PATH", str(tmp_path))
    assert st_check.find_iec2c() == fake


def test_compile_without_iec2c_is_a_clear_error(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MATIEC_HOME", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(st_check.MatiecUnavailable, match="iec2c not found"):
        st_check.compile_with_matiec("", tmp_path)


@pytest.mark.parametrize("flags", [st_check.STRICT_FLAGS, st_check.BEREMIZ_FLAGS, st_check.OPENPLC_FLAGS],
                         ids=["strict", "beremiz", "openplc"])
def test_rich_project_compiles_with_matiec(iec2c: Path, rich_st: str, tmp_path: Path, flags: tuple[str, ...]) -> None:
    assert st_check.compile_with_matiec(rich_st, tmp_path, flags=flags) == []
    assert (tmp_path / "Config0.o").is_file() and (tmp_path / "Res0.o").is_file()


def test_xml_bodies_assembled_compile_with_matiec(iec2c: Path, tmp_path: Path) -> None:
    """The ST taken back out of the XML, put in place of the ST bodies, is the same program matiec accepts."""
    project = rich_project()
    from_xml = extract_st_bodies(render_xml(project))
    rebuilt = dataclasses.replace(project, pous=tuple(dataclasses.replace(p, body=from_xml[p.name]) for p in project.pous))
    text = render_st(rebuilt)
    assert extract_pou_bodies(text) == {p.name: p.body for p in project.pous}
    assert st_check.compile_with_matiec(text, tmp_path) == []


def test_matiec_semantic_error_is_reported(iec2c: Path, tmp_path: Path) -> None:
    text = BROKEN_PROGRAM.replace("x := x + ;", "x := DINT#70000;") + CONFIG
    errors = st_check.compile_with_matiec(text, tmp_path)
    assert errors and all(e.startswith("iec2c (exit 1): ") for e in errors)
    assert any("project.st:5" in e for e in errors), errors


def test_matiec_c_fail_is_caught_by_gcc(iec2c: Path, tmp_path: Path) -> None:
    # targets.md: a global passed to a FUNCTION's VAR_IN_OUT passes iec2c but the C does not compile
    text = """\
FUNCTION Bump : INT
VAR_IN_OUT
    v : INT;
END_VAR
    v := v + 1;
    Bump := v;
END_FUNCTION
PROGRAM P
VAR_EXTERNAL
    g : INT;
END_VAR
VAR
    r : INT;
END_VAR
    r := Bump(v := g);
END_PROGRAM
CONFIGURATION Config0
    VAR_GLOBAL
        g : INT;
    END_VAR
    RESOURCE Res0 ON PLC
        TASK T1(INTERVAL := T#20ms, PRIORITY := 0);
        PROGRAM inst0 WITH T1 : P;
    END_RESOURCE
END_CONFIGURATION
"""
    errors = st_check.compile_with_matiec(text, tmp_path)
    assert errors and any("C-FAIL" in e and "Res0.c" in e for e in errors), errors


def test_matiec_without_configuration_is_an_error(iec2c: Path, tmp_path: Path) -> None:
    errors = st_check.compile_with_matiec(BROKEN_PROGRAM.replace("x + ;", "x + 1;"), tmp_path)
    assert errors == ["iec2c wrote no configuration C file (is there a CONFIGURATION?)"]


def test_matiec_home_from_environment(iec2c: Path) -> None:
    home = st_check.matiec_home(iec2c)
    assert (home / "lib" / "ieclib.txt").is_file()
    if os.environ.get("MATIEC_HOME"):
        assert home == Path(os.environ["MATIEC_HOME"])
