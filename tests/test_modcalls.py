"""Module calls in the ST: HH_Sys FB calls with named arguments, the error marker/word, and co-simulation of the
documented model on both executors (the translated side runs its own copy of the interpreter's system context)."""

from __future__ import annotations

from pathlib import Path

import pytest

from transpiler.backends.st.check import find_iec2c
from transpiler.backends.st.hh_sys import fb_pou, interface
from transpiler.cli import main
from transpiler.exec.compiled.sysfb import SysBinding, patch_pous
from transpiler.exec.interp.sysmodel import SysContext

# 9038 axis info (data, anywhere), 9032 MP read (submit-only: code 20 in the cyclic program), 9162/9161 drives.
PROGRAM = """L I1
= O1
PS K0
PS K0
CM 9038
PL W102
PS K7280
PS K0
CM 9032
PL W104
L M4203
= O2
L W1022
= W106
PS B10
CM 9161
CM 9162
PL W108
EM
"""


def _run(args: list, capsys) -> tuple[int, str]:
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out + err


@pytest.fixture()
def project(tmp_path: Path) -> Path:
    (tmp_path / "main.src").write_text(PROGRAM, encoding="latin-1")
    return tmp_path / "main.src"


def test_module_calls_are_fb_calls_with_named_arguments(project: Path, tmp_path: Path, capsys) -> None:
    code, out = _run(["transpile", project, "--out", tmp_path / "out"], capsys)
    assert code == 0, out
    assert "0 not translated" in out
    st = (tmp_path / "out" / "project.st").read_text()
    assert "FUNCTION_BLOCK HH_ReadMP" in st and "FUNCTION_BLOCK HH_EnableDrives" in st
    assert "(NUMBER := 7280, INDEX := 0, IN_JOB := HH_IN_JOB); (* CM 9032 HH_ReadMP  main.src:9 *)" in st
    assert "(AXIS := 0, INFO := 0, IN_JOB := HH_IN_JOB);" in st
    assert "W104 := DINT_TO_INT(" in st and ".VALUE);" in st
    # The error word follows only a failed call, the marker every call.
    assert "M4203 := " in st and ".FAULT THEN" in st and "HH_STACK" not in st
    report = (tmp_path / "out" / "report.md").read_text()
    section = report.split("## What the target must provide")[1].split("\n## ")[0]
    assert "### HH_ReadMP (module 9032, data)" in section and "- Called at: main.src:9" in section
    assert "### HH_EnableDrives (module 9161, machine)" in section and "24 called in a submit or spawn job" in section


@pytest.mark.parametrize("backend", ["builtin", "matiec"])
def test_module_calls_cosimulate(project: Path, backend: str, capsys, monkeypatch) -> None:
    if backend == "matiec" and find_iec2c() is None:
        pytest.skip("iec2c not available (MATIEC_HOME)")
    code, out = _run(["equiv", project, "--random-cycles", "40", "--backend", backend], capsys)
    assert code == 0 and "hh2iec equiv: EQUIVALENT" in out, out


def test_fb_stub_applies_the_context_rule_and_reports_not_provided() -> None:
    pou = fb_pou(9032)
    assert "IF NOT IN_JOB THEN" in pou.body and "FAULT_CODE := 20;" in pou.body and "FAULT_CODE := 1;" in pou.body
    assert "Assumption A-46a" in pou.comment and "submit/spawn jobs only" in pou.comment
    itf = interface(9192)
    assert itf.outputs == ("TIME_VALUE",)         # 'time' is an IEC keyword


class _Machine:
    def __init__(self, sys: SysContext):
        self.sys = sys
        self.cycle_time_ms = 20
        self.semantics = {"module_context": "enforce"}


def test_binding_runs_an_independent_copy_of_the_system_context() -> None:
    source = SysContext(20)
    source.set_drives(0b111)
    binding = SysBinding("FUNCTION_BLOCK HH_EnableDrives\nEND_FUNCTION_BLOCK\nFUNCTION_BLOCK HH_DrivesReady\n")
    binding.attach(_Machine(source))
    binding.call(9161, [0b101], in_job=False)
    assert binding.call(9162, [], in_job=False)[0] == [0b101]
    assert source.call(9162, [])[0] == [0]          # the interpreter's own copy is untouched
    assert binding.call(9161, [1], in_job=True)[2] == 24      # cyclic-only module in a job
    state = {"mask": 3, "in_job": False}
    binding.externals()["HH_EnableDrives"](state)
    assert state["fault"] is False and state["fault_code"] == 0


def test_patch_pous_inserts_the_model_call_into_the_fb_body() -> None:
    text = "void HH_READMP_body__(HH_READMP *data__) {\n  // ST body\n}\nvoid OTHER_body__(OTHER *data__) {\n}\n"
    patched = patch_pous(text, SysBinding("FUNCTION_BLOCK HH_ReadMP\n").c_bodies())
    assert "hh_sysfb_call(9032," in patched and patched.count("hh_sysfb_call(") == 2    # declaration + one body
    assert "goto __end;" in patched.split("OTHER_body__")[0]


CONDITIONAL = """L I0
PS K4310
PS K0
CMT 9032
L I1
PS K0
PS K2
CMF 9049
L I2
CMT 9162
PL D20
PL D24
PL D28
EM
"""


def test_conditional_module_calls_run_inside_an_if_and_cosimulate(tmp_path: Path, capsys) -> None:
    # Catches: CMT/CMF of a module refused, called unconditionally, or called on the wrong value of LA (the
    # parameters a call that does not happen leaves on the stack are pulled later: the values show it).
    (tmp_path / "main.src").write_text(CONDITIONAL, encoding="latin-1")
    (tmp_path / "s.yaml").write_text(
        "name: cmt\ncycles: 8\nmachine: {axes: {0: {position: 4242}}, drives: {available: 3}}\n"
        "initial: {I0: 1, I1: 0, I2: 1}\nevents:\n  - {cycle: 2, set: {I0: 0, I1: 1}}\n"
        "  - {cycle: 4, set: {I0: 1, I2: 0}}\n", encoding="utf-8")
    code, out = _run(["transpile", tmp_path / "main.src", "--out", tmp_path / "out"], capsys)
    assert code == 0 and "0 not translated" in out, out
    st = (tmp_path / "out" / "project.st").read_text()
    assert "IF HH_LA THEN (* CMT main.src:4 *)" in st and "IF NOT HH_LA THEN (* CMF main.src:8 *)" in st
    code, out = _run(["equiv", tmp_path / "main.src", "--scenario", tmp_path / "s.yaml", "--random-cycles", "200",
                      "--backend", "builtin"], capsys)
    assert code == 0 and "hh2iec equiv: EQUIVALENT" in out, out
