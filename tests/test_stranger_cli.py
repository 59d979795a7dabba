"""Issue 20 on the command line: NUMBERMP4111 in a simulation, --werror, --encoding, a folder as MAIN, traces."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from transpiler.cli import main

TIMER = "L I1\nJPF DONE\nPS K96\nCM 9006\nLBL DONE\nL T96\n= O1\nEM\n"
SCENARIO = ('cycles: 5\nmp: {"4111.96": 0.04}\nevents:\n  - cycle: 0\n    set: {I1: 1}\n  - cycle: 1\n'
            '    set: {I1: 0}\nexpect:\n  - cycle: 1\n    values: {O1: 1}\n')


def _run(argv, capsys) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _timer_project(folder: Path) -> None:
    (folder / "main.src").write_text(TIMER)
    (folder / "s.yaml").write_text(SCENARIO)


def test_mp4111_timer_runs_only_with_numbermp4111_from_cfg_or_command_line(tmp_path, capsys):
    _timer_project(tmp_path)
    simulate = ["simulate", tmp_path / "main.src", "--scenario", tmp_path / "s.yaml"]
    code, _, err = _run(simulate, capsys)
    assert code == 1 and "expected 1, actual 0" in err            # NUMBERMP4111 = 0: module error, no timer
    assert _run(simulate + ["-S", "number_mp4111=1"], capsys)[0] == 0
    (tmp_path / "OEM.cfg").write_text("DEFINE NUMBERMP4111 = 1\n")
    assert _run(simulate, capsys)[0] == 0


def test_werror_makes_check_fail_on_a_warning(tmp_path, capsys):
    (tmp_path / "main.src").write_text("DEFINE A = 1\nDEFINE A = 2\nL I1\n= O1\nEM\n")
    assert _run(["check", tmp_path / "main.src"], capsys)[0] == 0
    code, _, err = _run(["check", tmp_path / "main.src", "--werror"], capsys)
    assert code == 2 and "error[E-WERROR]" in err and "warning[E-DEF-REDEFINE]" in err


def test_encoding_option_and_unknown_encoding(tmp_path, capsys):
    (tmp_path / "main.src").write_bytes("L I1 ; Tür\n= O1\nEM\n".encode("cp1252"))
    assert _run(["check", tmp_path / "main.src"], capsys)[0] == 0
    code, _, err = _run(["check", tmp_path / "main.src", "--encoding", "utf-8"], capsys)
    assert code == 2 and "main.src:1:9: error[E-ENCODING]" in err
    code, _, err = _run(["check", tmp_path / "main.src", "--encoding", "klingon"], capsys)
    assert code == 2 and "unknown encoding 'klingon'" in err


def test_check_given_a_folder_checks_its_main_program(tmp_path, capsys):
    (tmp_path / "Main.src").write_text("USES Mod.src\nEXTERN Fn\nCM Fn\nEM\n")
    (tmp_path / "Mod.src").write_text("GLOBAL Fn\nLBL Fn\nEM\n")
    code, out, _ = _run(["check", tmp_path], capsys)
    assert code == 0 and "files          2" in out and "routines       1" in out


def test_traces_get_normal_permissions_and_show_inputs(tmp_path, capsys):
    _timer_project(tmp_path)
    (tmp_path / "s.yaml").write_text("cycles: 3\nevents:\n  - cycle: 0\n    set: {I1: 1}\n")
    old = os.umask(0o022)
    try:
        code, _, err = _run(["simulate", tmp_path / "main.src", "--scenario", tmp_path / "s.yaml", "--trace",
                             tmp_path / "t.csv", "--vcd", tmp_path / "t.vcd"], capsys)
    finally:
        os.umask(old)
    assert code == 0, err
    for name in ("t.csv", "t.vcd"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o644
    header = (tmp_path / "t.csv").read_text().splitlines()[0].split(",")
    assert "I1" in header and "O1" in header
    assert (tmp_path / "t.csv").read_text().splitlines()[1].split(",")[header.index("I1")] == "1"


def test_trace_into_a_missing_folder_names_the_folder(tmp_path, capsys):
    _timer_project(tmp_path)
    for flag in ("--trace", "--vcd"):
        code, _, err = _run(["simulate", tmp_path / "main.src", "--scenario", tmp_path / "s.yaml", flag,
                             tmp_path / "nowhere" / "t.out"], capsys)
        assert code == 2 and f"folder '{tmp_path / 'nowhere'}' does not exist" in err and flag in err
        assert "Traceback" not in err
