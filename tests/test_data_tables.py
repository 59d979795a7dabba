"""PLC data tables (MP_Data.tab, MP_Config.tab): read and checked with their lines, loaded at power-on and at an MP
restart by the reference interpreter and the ST alike, overridden by scenarios, listed in the report."""

from __future__ import annotations

from pathlib import Path

import pytest

from transpiler.backends.st.check import find_iec2c
from transpiler.cli import main

MAIN = """#define /g data.def
L   DG_limit
>   W_torque
=   O_below_limit
L   MG_option
=   O_option
L   I_teach
CMT Teach
EM
LBL Teach
L   K7
=   DG_limit
EM
"""
DEFS = """DG_limit       D 100
MG_option      M 200
W_torque       W 10
BG_small       B 120
O_below_limit  O 1
O_option       O 2
I_teach        I 1
"""
DATA = """BEGIN MP_DATA.TAB
NR   NAME                 VALUE      COMMENT
0    DG_limit             500        torque limit [%]
1    BG_small             200
[END]
"""
CONFIG = "BEGIN MP_CONFIG.TAB\nNR NAME        VALUE\n0  MG_option   1\n[END]\n"
# Torque 400 is below the limit 500 until the program teaches 7 (cycle 5); the MP restart at cycle 12 (M4174 in the
# cycle after the event) loads 500 again.
SCENARIO = """name: tables
cycles: 20
events:
  - {cycle: 1, set: {W_torque: 400}}
  - {cycle: 5, set: {I_teach: 1}}
  - {cycle: 6, set: {I_teach: 0}}
  - {cycle: 12, nc: {restart: machine_parameters}}
expect:
  - {cycle: 2, values: {O_below_limit: 1, O_option: 1, DG_limit: 500, BG_small: -56}}
  - {cycle: 6, values: {O_below_limit: 0, DG_limit: 7}}
  - {cycle: 11, values: {O_below_limit: 0}}
  - {cycle: 14, values: {O_below_limit: 1, DG_limit: 500}}
"""


def _run(args: list, capsys) -> tuple[int, str, str]:
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def _project(tmp_path: Path, data: str = DATA, config: str = CONFIG, folder: str = "MP") -> Path:
    (tmp_path / "main.src").write_text(MAIN)
    (tmp_path / "data.def").write_text(DEFS)
    tables = tmp_path / folder
    tables.mkdir(exist_ok=True)
    (tables / "MP_Data.tab").write_text(data)
    (tables / "MP_Config.tab").write_text(config)
    (tmp_path / "scenario.yaml").write_text(SCENARIO)
    return tmp_path / "main.src"


def test_check_reports_every_bad_row_with_its_place(tmp_path, capsys):
    bad = ("BEGIN MP_DATA.TAB\nNR   NAME                 VALUE      COMMENT\n"
           "0    DG_limt              500\n"          # misspelt
           "1    BG_small             300\n"          # does not fit a byte
           "2    O_below_limit        1\n"            # an output
           "3    DG_limit             5\n"
           "3    MG_option            1\n"            # NR used twice
           "5    DG_limit             6\n"            # second row of DG_limit
           "6    W_torque             12x\n"
           "[END]\n")
    main_src = _project(tmp_path, data=bad, config="BEGIN MP_CONFIG.TAB\nNR NAME  VALUE  UNITS\n[END]\n")
    code, _, err = _run(["check", main_src], capsys)
    assert code == 2
    assert "MP/MP_Data.tab:3:6: error[E-TAB-SYMBOL]: unknown symbol 'DG_limt'" in err and "nearest: DG_limit" in err
    assert "MP/MP_Data.tab:4:27: error[E-TAB-VALUE]: BG_small (B120): 300 does not fit: a byte holds -128..255" in err
    assert "MP/MP_Data.tab:5:6: error[E-TAB-SYMBOL]: 'O_below_limit' is an output (O1)" in err
    assert "MP/MP_Data.tab:7:1: error[E-TAB-DUP]: row number 3 is used already (at MP/MP_Data.tab:6:1)" in err
    assert "MP/MP_Data.tab:8:6: error[E-TAB-DUP]: 'DG_limit' has a row already (at MP/MP_Data.tab:6:6)" in err
    assert "MP/MP_Data.tab:9:27: error[E-TAB-VALUE]: W_torque (W10): '12x' is not a whole number" in err
    assert "MP/MP_Config.tab:2:17: error[E-TAB-SYNTAX]: unknown column 'UNITS' (did you mean UNIT?)" in err


@pytest.mark.parametrize("text, where, message", [
    ("NR NAME VALUE\n[END]\n", "1:1", "a table starts with a line `BEGIN <table name>`"),
    ("BEGIN MP_DATA.TAB\nNR NAME VALUE\n0 DG_limit 1\n", "3:1", "the table does not end with a line [END]"),
    ("BEGIN MP_DATA.TAB\nNR NAME\n[END]\n", "2:1", "the column header lacks the column VALUE"),
    ("BEGIN MP_DATA.TAB\nNR NAME VALUE\n[END]\n0 DG_limit 1\n", "4:1", "text after [END]"),
])
def test_malformed_tables_are_errors_at_their_line(tmp_path, capsys, text, where, message):
    main_src = _project(tmp_path, data=text)
    code, _, err = _run(["check", main_src], capsys)
    assert code == 2 and f"MP/MP_Data.tab:{where}: error[E-TAB-SYNTAX]: {message}" in err
    assert "Traceback" not in err


def test_the_tables_become_retained_globals_loaded_by_the_program(tmp_path, capsys):
    main_src = _project(tmp_path)
    code, _, _ = _run(["transpile", main_src, "--out", tmp_path / "out"], capsys)
    assert code == 0
    st = (tmp_path / "out" / "project.st").read_text()
    retained = st[st.index("VAR_GLOBAL RETAIN (* PLC data tables"):]
    assert "DG_limit_table : DINT := 500;" in retained and "BG_small_table : SINT := -56;" in retained
    assert "MG_option_table : BOOL := TRUE;" in retained
    assert "IF NOT HH_data_loaded OR M4174 THEN" in st and "DG_limit := DG_limit_table;" in st
    report = (tmp_path / "out" / "report.md").read_text()
    assert "| MP/MP_Data.tab:3 | 0 | DG_limit | D100 | 500 | `DG_limit_table` (DINT) | `DG_limit` |" in report
    assert "| MP/MP_Config.tab:3 | 0 | MG_option | M200 | 1 | `MG_option_table` (BOOL) | `MG_option` |" in report
    assert "MP_Data.tab:BG_small,BG_small_table,,SINT,parameter" in (tmp_path / "out" / "io_map.csv").read_text()
    # A changed row changes one initial value and nothing else.
    (tmp_path / "MP" / "MP_Data.tab").write_text(DATA.replace("500 ", "650 "))
    code, _, _ = _run(["transpile", main_src, "--out", tmp_path / "out2"], capsys)
    changed = (tmp_path / "out2" / "project.st").read_text()
    before, after = st.splitlines(), changed.splitlines()
    assert len(before) == len(after)
    assert [(a, b) for a, b in zip(before, after) if a != b] == [
        (line, line.replace(":= 500;", ":= 650;")) for line in before if "DG_limit_table : DINT := 500;" in line]


def test_tables_given_on_the_command_line_and_beside_the_main_program(tmp_path, capsys):
    main_src = _project(tmp_path, folder="elsewhere")
    code, _, _ = _run(["transpile", main_src, "--out", tmp_path / "none", "--format", "st"], capsys)
    assert code == 0 and "DG_limit_table" not in (tmp_path / "none" / "project.st").read_text()
    code, _, _ = _run(["transpile", main_src, "--out", tmp_path / "given", "--format", "st", "--mp-data",
                       tmp_path / "elsewhere" / "MP_Data.tab"], capsys)
    st = (tmp_path / "given" / "project.st").read_text()
    assert code == 0 and "DG_limit_table : DINT := 500;" in st and "MG_option_table" not in st
    (tmp_path / "MP_Config.tab").write_text(CONFIG)
    code, _, _ = _run(["transpile", main_src, "--out", tmp_path / "beside", "--format", "st"], capsys)
    assert code == 0 and "MG_option_table : BOOL := TRUE;" in (tmp_path / "beside" / "project.st").read_text()
    code, _, err = _run(["check", main_src, "--mp-config", tmp_path / "missing.tab"], capsys)
    assert code == 2 and "--mp-config file" in err


def test_the_reference_loads_the_tables_at_power_on_and_at_an_mp_restart(tmp_path, capsys):
    main_src = _project(tmp_path)
    code, out, err = _run(["simulate", main_src, "--scenario", tmp_path / "scenario.yaml"], capsys)
    assert code == 0, out + err
    assert "expectation failed" not in err


@pytest.mark.parametrize("backend", ["builtin", pytest.param("matiec", marks=pytest.mark.skipif(
    find_iec2c() is None, reason="iec2c not found ($MATIEC_HOME/iec2c or PATH): the matiec backend is skipped"))])
def test_tables_and_their_scenario_overrides_co_simulate_equal(tmp_path, capsys, backend):
    main_src = _project(tmp_path)
    code, out, err = _run(["equiv", main_src, "--scenario", tmp_path / "scenario.yaml", "--backend", backend], capsys)
    assert code == 0 and "hh2iec equiv: EQUIVALENT" in out, out + err
    # The scenario's rows reach both sides: with a limit of 300, torque 400 is above it from the start.
    text = SCENARIO.replace("cycles: 20\n", "cycles: 20\nmp_data: {DG_limit: 300, MG_option: 0}\n")
    text = text.replace("O_below_limit: 1, O_option: 1, DG_limit: 500", "O_below_limit: 0, O_option: 0, DG_limit: 300")
    text = text.replace("{O_below_limit: 1, DG_limit: 500}", "{O_below_limit: 0, DG_limit: 300}")
    (tmp_path / "override.yaml").write_text(text)
    code, out, err = _run(["equiv", main_src, "--scenario", tmp_path / "override.yaml", "--backend", backend], capsys)
    assert code == 0 and "hh2iec equiv: EQUIVALENT" in out, out + err


def test_a_scenario_row_the_tables_do_not_have_is_an_error_at_its_line(tmp_path, capsys):
    main_src = _project(tmp_path)
    (tmp_path / "bad.yaml").write_text("cycles: 5\nmp_data:\n  DG_limt: 3\n  MG_option: 2\n")
    code, _, err = _run(["simulate", main_src, "--scenario", tmp_path / "bad.yaml"], capsys)
    assert code == 2
    assert "bad.yaml:3:3: error[E-SCENARIO]: mp_data: unknown row 'DG_limt'" in err and "'DG_limit'" in err
    assert "bad.yaml:4:14: error[E-SCENARIO]: mp_data: MG_option (M200): a bit operand expects 0 or 1" in err


def test_an_st_shipped_with_other_table_values_is_refused(tmp_path, capsys):
    main_src = _project(tmp_path)
    code, _, _ = _run(["transpile", main_src, "--out", tmp_path / "out"], capsys)
    st = tmp_path / "out" / "project.st"
    st.write_text(st.read_text().replace("DG_limit_table : DINT := 500;", "DG_limit_table : DINT := 501;"))
    code, out, err = _run(["equiv", main_src, "--scenario", tmp_path / "scenario.yaml", "--backend", "builtin",
                           "--st", st], capsys)
    assert code == 2 and "error[E-MP-TRANSLATION]" in err
    assert "MP_Data.tab:DG_limit: 500 in the data table (MP/MP_Data.tab:3), 501 in the translated program" in err
    assert "EQUIVALENT" not in out.replace("NOT EQUIVALENT", "")


def test_an_st_made_before_the_tables_existed_is_refused_without_a_traceback(tmp_path, capsys):
    main_src = _project(tmp_path, folder="later")
    code, _, _ = _run(["transpile", main_src, "--out", tmp_path / "out", "--format", "st"], capsys)
    assert code == 0
    (tmp_path / "later").rename(tmp_path / "MP")
    (tmp_path / "out" / "io_map.csv").unlink()          # the fresh translation's map names the tables' globals
    code, out, err = _run(["equiv", main_src, "--scenario", tmp_path / "scenario.yaml", "--backend", "builtin",
                           "--st", tmp_path / "out" / "project.st"], capsys)
    assert code == 2 and "error[E-MP-TRANSLATION]" in err and "E-TOOL" not in err
    assert "MP_Data.tab:DG_limit: the translated program holds no value of this data-table row" in err
