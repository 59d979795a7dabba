"""transpile writes the HH_Sys interface library as files of its own (hh_sys.st, hh_sys.xml); report.md names them."""

from __future__ import annotations

from transpiler.backends.plcopen.writer import extract_st_bodies
from transpiler.backends.st.writer import extract_pou_bodies
from transpiler.cli import main

PROGRAM = "PS K0\nPS K0\nCM 9038\nPL W102\nPS K7280\nPS K0\nCM 9032\nPL W104\nL S\"12\"\n= S0\nPS K0\nCM 9052\nPL D12\nPL D16\nEM\n"


def test_library_files_hold_the_hh_sys_blocks_only(tmp_path, capsys) -> None:
    src = tmp_path / "main.src"
    src.write_text(PROGRAM, encoding="latin-1")
    assert main(["transpile", str(src), "--out", str(tmp_path / "out")]) == 0
    out = tmp_path / "out"
    assert "hh_sys.st, hh_sys.xml" in capsys.readouterr().out
    lib_st = (out / "hh_sys.st").read_text()
    project_st = (out / "project.st").read_text()
    lib = extract_pou_bodies(lib_st)
    assert len(lib) == 2, lib.keys()
    assert "HH_ReadMP" in lib and "HH_StringToNum" not in lib and "CONFIGURATION" not in lib_st
    # The same declarations as in project.st: the integrator's implementation replaces exactly these.
    project = extract_pou_bodies(project_st)
    assert all(project[name] == body for name, body in lib.items())
    xml = extract_st_bodies((out / "hh_sys.xml").read_bytes())
    assert set(xml) == set(lib)
    report = (out / "report.md").read_text()
    assert "`hh_sys.st` (ST) and `hh_sys.xml` (PLCopen XML)" in report


def test_no_library_files_without_hh_sys_modules(tmp_path, capsys) -> None:
    src = tmp_path / "main.src"
    src.write_text("L I1\n= O1\nEM\n", encoding="latin-1")
    assert main(["transpile", str(src), "--out", str(tmp_path / "out")]) == 0
    assert not (tmp_path / "out" / "hh_sys.st").exists() and not (tmp_path / "out" / "hh_sys.xml").exists()
    assert "hh_sys.st" not in (tmp_path / "out" / "report.md").read_text()
