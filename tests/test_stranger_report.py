"""Issue 20, part 5: the report a porting engineer needs (IEC addresses, configuration, next steps, check --json)."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

from transpiler import api
from transpiler.cli import main

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "basic_program" / "Main_PGM.src"


def _sample(**options):
    project = api.load_project(api.project_options(SAMPLE, **options))
    return api.transpile(project, formats=("st",), validate_xml=False)


def test_io_map_carries_the_iec_address_the_st_declares():
    out = _sample()
    rows = list(csv.DictReader(io.StringIO(out.files["io_map.csv"].decode())))
    located = [r for r in rows if r["iec_address"]]
    assert {r["operand"][0] for r in located} == {"I", "O"} and len(located) > 50
    for r in located:
        assert f"{r['iec_variable']} AT {r['iec_address']} :" in out.st_text, r
    i5 = next(r for r in rows if r["operand"] == "I5")
    assert i5["iec_address"] == "%IX0.5"
    assert all(not r["iec_address"] for r in rows if r["operand"][0] not in "IO")


def test_report_and_io_map_name_the_configuration_and_the_d_values():
    out = _sample(defines={"CFG_Coolant": '"active"'})
    report = out.files["report.md"].decode()
    assert "Configuration: OEM.cfg; -D CFG_Coolant='active'." in report
    rows = list(csv.DictReader(io.StringIO(out.files["io_map.csv"].decode())))
    assert rows[-1]["operand"] == "CONFIG" and rows[-1]["comment"] == "OEM.cfg; -D CFG_Coolant='active'"
    report_io = report.split("## I/O map", 1)[1].split("\n## ", 1)[0]
    assert "| IEC address |" in report_io and "| %IX0.5 |" in report_io


def test_report_ends_with_next_steps_for_this_program():
    report = _sample().files["report.md"].decode()
    steps = report.split("## Next steps", 1)[1]
    assert "Wire the process image" in steps and "%IX" in steps
    assert "NC interface" in steps and "cyclic task of 20 ms" in steps
    assert "A-24" in steps and "A-34a" in steps             # the sample has CASE step chains and timers


def test_next_steps_ask_only_what_the_program_needs(tmp_path):
    (tmp_path / "main.src").write_text("L I0\n= O0\nEM\n")
    report = api.transpile(api.load_project(api.project_options(tmp_path / "main.src")), formats=("st",),
                           validate_xml=False).files["report.md"].decode()
    steps = report.split("## Next steps", 1)[1]
    assert "1 inputs" in steps and "1 outputs" in steps
    assert "Confirm on the machine" not in steps and "no configuration file" in report


def test_check_json_lists_every_diagnostic(tmp_path, capsys):
    (tmp_path / "main.src").write_text("DEFINE A = 1\n  DEFINE A = 2\nL I_nope\n= O1\nEM\n")
    assert main(["check", str(tmp_path / "main.src"), "--json"]) == 2
    data = json.loads(capsys.readouterr().out)
    assert data["errors"] == 1 and data["warnings"] == 1
    assert data["diagnostics"] == [
        {"code": "E-DEF-REDEFINE", "severity": "warning", "file": "main.src", "line": 2, "col": 3,
         "message": data["diagnostics"][0]["message"], "notes": []},
        {"code": "E-SYM-UNDEF", "severity": "error", "file": "main.src", "line": 3, "col": 1,
         "message": data["diagnostics"][1]["message"], "notes": []}]
    assert "I_nope" in data["diagnostics"][1]["message"]
