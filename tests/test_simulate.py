"""`hh2iec simulate`: exit codes, messages with file and line, traces (CSV with symbol names, VCD), MPs, profiles."""

from __future__ import annotations

import csv
import re
import textwrap
from pathlib import Path

import pytest

from transpiler.cli import main

PROGRAM = """
    #define /g io.def
    L   I_start
    =   TS_lamp
    L   TR_lamp
    =   O_lamp
    L   M4072           ; acknowledge M functions at once
    =   M4092
    L   W260
    =   WG_code
    EM
"""

DEFS = """
    I_start   I 3
    O_lamp    O 7
    TS_lamp   T 0
    TR_lamp   T 48
    WG_code   W 100
"""


@pytest.fixture
def project(tmp_path: Path) -> Path:
    (tmp_path / "main.src").write_text(textwrap.dedent(PROGRAM).lstrip(), encoding="latin-1")
    (tmp_path / "io.def").write_text(textwrap.dedent(DEFS).lstrip(), encoding="latin-1")
    return tmp_path


def scenario(folder: Path, text: str, name: str = "scn.yaml") -> Path:
    path = folder / name
    path.write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    return path


def simulate(project: Path, scn: Path, *extra: str) -> int:
    return main(["simulate", str(project / "main.src"), "--scenario", str(scn), *extra])


GOOD = """
    name: lamp
    cycles: 6
    profile: tv
    mp: {"4110.0": 2}
    events:
      - cycle: 0
        set: {I_start: 1}
      - cycle: 1
        set: {I_start: 0}
      - cycle: 2
        nc: {m_function: 3}
    observe: [O_lamp, TS_lamp, WG_code]
    expect:
      - cycle: 1
        values: {O_lamp: 1}
      - cycle: 3
        values: {O_lamp: 0, WG_code: 3}
"""


def test_passing_scenario_writes_csv_and_vcd(project: Path, capsys: pytest.CaptureFixture) -> None:
    scn = scenario(project, GOOD)
    out_csv, out_vcd = project / "t.csv", project / "t.vcd"
    assert simulate(project, scn, "--trace", str(out_csv), "--vcd", str(out_vcd)) == 0
    captured = capsys.readouterr()
    assert "6 of 6 cycles" in captured.out and "0 failed" in captured.out
    rows = list(csv.reader(out_csv.open()))
    assert rows[0] == ["cycle", "O_lamp", "TS_lamp", "WG_code"]
    assert [r[1] for r in rows[1:]] == ["0", "1", "1", "0", "0", "0"]     # timer preset 2 cycles
    assert [r[2] for r in rows[1:]] == ["1", "0", "0", "0", "0", "0"]     # start consumed by the service
    assert [r[3] for r in rows[1:]] == ["0", "0", "3", "3", "3", "3"]
    vcd = out_vcd.read_text()
    assert re.search(r"\$var wire 1 \S+ O_lamp \$end", vcd) and re.search(r"\$var wire 16 \S+ WG_code \$end", vcd)
    assert "#20" in vcd and "#40" in vcd                                  # one time step per 20 ms cycle


def test_failed_expectation_exits_1_with_cycle_operand_expected_actual(project: Path,
                                                                        capsys: pytest.CaptureFixture) -> None:
    scn = scenario(project, GOOD.replace("values: {O_lamp: 0, WG_code: 3}", "values: {O_lamp: 1, WG_code: 3}"))
    assert simulate(project, scn) == 1
    err = capsys.readouterr().err
    line = next(i for i, text in enumerate(scn.read_text().splitlines(), 1) if "O_lamp: 1, WG_code" in text)
    assert re.search(rf"scn\.yaml:{line}:\d+: expectation failed: cycle 3: O_lamp: expected 1, actual 0", err), err


@pytest.mark.parametrize("text, line, message", [
    ("cycles: 3\nprofile: tv\nevnts: []\n", 3, "unknown key 'evnts'"),
    ("cycles: 3\nevents:\n  - cycle: 1\n    set: {I_nothing: 1}\n", 4, "unknown name 'I_nothing'"),
    ("cycles: 3\nevents:\n  - cycle: 1\n    set: {O_lamp: 2}\n", 4, "O_lamp"),
    ("cycles: 3\nexpect: [\n", 3, "YAML syntax error"),
    ("cycles: 3\nsemantics:\n  byte_order: middle\n", 2, "byte_order"),
    ("cycles: 3\nprofile: tv\nmodule_results: {9888: [1]}\n", 3, "9888"),
])
def test_malformed_scenario_exits_2_with_file_and_line(project: Path, capsys: pytest.CaptureFixture, text: str,
                                                       line: int, message: str) -> None:
    scn = scenario(project, text)
    assert simulate(project, scn) == 2
    err = capsys.readouterr().err
    assert re.search(rf"scn\.yaml:{line}:\d+: error\[E-SCENARIO\]: .*{re.escape(message)}", err), err
    assert "Traceback" not in err


def test_runtime_fault_exits_2_with_location_and_cycle(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "main.src").write_text("L   I1\nJPF END\nPL  D0\nLBL END\nEM\n", encoding="latin-1")
    scn = scenario(tmp_path, "cycles: 5\nevents:\n  - cycle: 2\n    set: {I1: 1}\n")
    out_csv = tmp_path / "t.csv"
    assert simulate(tmp_path, scn, "--trace", str(out_csv)) == 2
    captured = capsys.readouterr()
    assert re.search(r"main\.src:3:1: error\[E-RT-STACK-UNDERFLOW\]: .*\(cycle 2\)", captured.err), captured.err
    assert "3 of 5 cycles" in captured.out
    assert len(list(csv.reader(out_csv.open()))) == 1 + 3                # the trace up to the faulting cycle


def test_handshake_timeout_points_at_the_nc_event(project: Path, capsys: pytest.CaptureFixture) -> None:
    (project / "main.src").write_text("L   K0\n=   W0\nEM\n", encoding="latin-1")
    scn = scenario(project, "cycles: 600\nevents:\n  - cycle: 4\n    nc: {m_function: 8}\n")
    assert simulate(project, scn) == 2
    err = capsys.readouterr().err
    assert re.search(r"scn\.yaml:4:\d+: error\[E-SIM-HANDSHAKE-TIMEOUT\]: .*\(cycle 505\)", err), err


def test_machine_parameter_file_and_errors(project: Path, capsys: pytest.CaptureFixture) -> None:
    (project / "machine.mp").write_text("MP4110.0 : 0.1  ; lamp\n", encoding="latin-1")
    scn = scenario(project, """
        cycles: 8
        machine_parameters: machine.mp
        events:
          - cycle: 0
            set: {I_start: 1}
          - cycle: 1
            set: {I_start: 0}
        expect:
          - cycle: 5
            values: {O_lamp: 1}
          - cycle: 6
            values: {O_lamp: 0}
    """)
    assert simulate(project, scn) == 0          # itnc530: 0.1 s at 20 ms = 5 cycles
    (project / "machine.mp").write_text("MP4110.0 : 0.1\nMP4110.1 : fast\n", encoding="latin-1")
    assert simulate(project, scn) == 2
    assert re.search(r"machine\.mp:2:\d+: error\[E-MP-VALUE\]", capsys.readouterr().err)
    (project / "machine.mp").write_text("MP4110.0 : 0.1\n", encoding="latin-1")
    assert simulate(project, scn, "--profile", "tv") == 2          # cycles profile: 0.1 is not a whole number
    assert re.search(r"machine\.mp:1:\d+: error\[E-MP-VALUE\]", capsys.readouterr().err)


def test_profile_from_scenario_and_command_line(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "main.src").write_text("L   K$1234\n=   W10\nEM\n", encoding="latin-1")
    big = scenario(tmp_path, "cycles: 1\nprofile: tnc407\nexpect:\n  - cycle: 0\n    values: {B10: 0x12}\n")
    assert simulate(tmp_path, big) == 0
    assert simulate(tmp_path, big, "--profile", "itnc530") == 1      # the flag wins: little-endian
    assert "B10: expected 18, actual 52" in capsys.readouterr().err


def test_nc_action_unknown_to_the_profile_is_a_scenario_error(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "main.src").write_text("L   K0\n=   W0\nEM\n", encoding="latin-1")
    scn = scenario(tmp_path, "cycles: 3\nprofile: tnc407\nevents:\n  - cycle: 1\n"
                             "    nc: {tool_call: {tool: 1, pocket: 1}}\n")
    assert simulate(tmp_path, scn) == 2
    assert re.search(r"scn\.yaml:5:\d+: error\[E-SCENARIO\]: .*tool_call", capsys.readouterr().err)


def test_compile_errors_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "main.src").write_text("L   I_undefined\n=   O1\nEM\n", encoding="latin-1")
    scn = scenario(tmp_path, "cycles: 1\n")
    assert simulate(tmp_path, scn) == 2
    assert re.search(r"main\.src:1:\d+: error\[E-SYM-UNDEF\]", capsys.readouterr().err)


def test_runtime_warnings_are_reported_once_with_a_count(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "main.src").write_text("PS  K1\nEM\n", encoding="latin-1")
    scn = scenario(tmp_path, "cycles: 4\n")
    assert simulate(tmp_path, scn) == 0
    err = capsys.readouterr().err
    assert len(re.findall(r"main\.src:2:1: warning\[E-RT-STACK-LEFTOVER\]", err)) == 1
    assert "4 times in total" in err


def test_default_observation_is_inputs_written_operands_and_outputs(project: Path) -> None:
    scn = scenario(project, "cycles: 2\nprofile: tv\n")
    out_csv = project / "t.csv"
    assert simulate(project, scn, "--trace", str(out_csv)) == 0
    header = next(csv.reader(out_csv.open()))
    assert header == ["cycle", "I_start", "O_lamp", "M4092", "TS_lamp", "WG_code"]


def test_plc_error_messages_are_listed(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "main.src").write_text("L   I1\nS   M4805\nEM\n", encoding="latin-1")
    scn = scenario(tmp_path, "cycles: 4\nevents:\n  - cycle: 2\n    set: {I1: 1}\n")
    assert simulate(tmp_path, scn) == 0
    assert "PLC error message 5 (M4805) was set, first after cycle 2" in capsys.readouterr().err


SAMPLE = Path(__file__).resolve().parents[1] / "samples" / "basic_program"
SAMPLE_SCENARIOS = sorted((SAMPLE / "scenarios").glob("*.yaml")) if (SAMPLE / "scenarios").is_dir() else []


def _short(path: Path) -> bool:
    # the long-running scenarios (e.g. minutes of lubrication) are left to `make demo`
    import yaml
    return int((yaml.safe_load(path.read_text(encoding="utf-8")) or {}).get("cycles", 0)) <= 2000


@pytest.mark.skipif(not SAMPLE_SCENARIOS, reason="the sample project has no scenarios")
@pytest.mark.parametrize("path", [p for p in SAMPLE_SCENARIOS if _short(p)], ids=lambda p: p.stem)
def test_sample_project_scenarios_meet_their_expectations(path: Path, capsys: pytest.CaptureFixture) -> None:
    code = main(["simulate", str(SAMPLE / "Main_PGM.src"), "--scenario", str(path)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert " 0 failed" in captured.out
