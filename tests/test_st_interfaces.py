"""Subprogram interfaces from the data stack: the analysis (transpiler/backends/st/interfaces.py) and the ST it
gives: VAR_INPUT/VAR_OUTPUT where every call site and path moves the stack the same way, the emulated stack (and a
reason for the report) where the depth depends on run time; both co-simulated against the original."""

from __future__ import annotations

from pathlib import Path

import pytest

from transpiler import api
from transpiler.diagnostics import Diagnostics
from transpiler.backends.st.backend import StBackend
from transpiler.backends.st.interfaces import StackAnalysis

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "samples" / "basic_program" / "Main_PGM.src"


def _project(tmp_path: Path, text: str):
    (tmp_path / "main.src").write_text(text)
    return api.load_project(api.project_options(tmp_path / "main.src"))


def _st(project) -> tuple[str, object]:
    result = StBackend(project.program, Diagnostics()).build()
    from transpiler.backends.st.writer import render_st
    return render_st(result.project), result


def _equivalent(tmp_path: Path, project, cycles: int = 300) -> bool:
    eq = api.check_equivalence(project, random_cycles=cycles, backend="builtin")
    return eq.equivalent


PASSING = """L     I0
PS    I0
PS    I1
L     K7
PSW
CM    Sub
PLW
=     W10
PL    O0
EM
LBL Sub
PL    D20
PL    M_b
PL    M_a
L     M_a
A     M_b
PSL
L     D20
+     K1
PSW
EM
"""


def test_sample_clamp_axis_has_inputs_and_outputs_and_no_emulated_stack():
    project = api.load_project(api.project_options(SAMPLE))
    st, result = _st(project)
    head = st.split("FUNCTION_BLOCK Clamp_axis\n", 1)[1].split("VAR_EXTERNAL", 1)[0]
    assert "VAR_INPUT\n    inpos : BOOL;" in head and "clamped_fb : BOOL;" in head
    assert "VAR_OUTPUT\n    clamp_cmd : BOOL;" in head and "release : BOOL;" in head
    assert "Clamp_axis_1(inpos := ML_inpos_X, clamp_start := TS_clamp_X" in st
    assert "MG_axis.release_X := Clamp_axis_1.release;" in st
    assert "HH_SP" not in st and "HH_STACK" not in st
    assert result.dynamic_stack == ()


def test_parameters_and_results_of_mixed_kinds(tmp_path):
    project = _project(tmp_path, PASSING.replace("M_b", "M2").replace("M_a", "M1"))
    analysis = StackAnalysis(project.program)
    sub = next(r.key for r in project.program.routines if r.label == "Sub")
    iface = analysis.interfaces[sub]
    assert [k for _, k in iface.params] == ["bit", "bit", "val"]
    assert [k for _, k in iface.results] == ["bit", "val"]
    st, result = _st(project)
    assert "HH_SP" not in st and "VAR_INPUT" in st and "VAR_OUTPUT" in st
    assert _equivalent(tmp_path, project)


def test_conditional_call_of_a_stack_passing_routine_keeps_the_emulated_stack(tmp_path):
    text = "L     I0\nPS    I1\nCMT   Sub\nEM\nLBL Sub\nPL    M1\nL     M1\n=     O1\nEM\n"
    project = _project(tmp_path, text)
    analysis = StackAnalysis(project.program)
    sub = next(r.key for r in project.program.routines if r.label == "Sub")
    assert sub not in analysis.interfaces
    assert "conditionally" in analysis.dynamic[(0, 0)].reason or "conditionally" in analysis.dynamic[sub].reason
    st, result = _st(project)
    assert "HH_SP" in st
    assert result.dynamic_stack and all(reason for _, reason, _ in result.dynamic_stack)
    assert _equivalent(tmp_path, project)


def test_depth_that_depends_on_the_path_is_dynamic(tmp_path):
    text = "L     I0\nJPF   Skip\nPS    I1\nLBL Skip\nCM    Sub\nEM\nLBL Sub\nEM\n"
    project = _project(tmp_path, text)
    analysis = StackAnalysis(project.program)
    assert (0, 0) in analysis.dynamic and "path" in analysis.dynamic[(0, 0)].reason


def test_interface_survives_branches_inside_the_callee(tmp_path):
    text = ("PS    I0\nPS    I1\nCM    Sub\nPL    O0\nEM\n"
            "LBL Sub\nPL    M1\nPL    M2\nL     M1\nJPF   Other\nL     M2\nPSL\nEM\nLBL Other\nLN    M2\nPSL\nEM\n")
    project = _project(tmp_path, text)
    st, result = _st(project)
    assert "HH_SP" not in st
    assert _equivalent(tmp_path, project)


@pytest.mark.parametrize("pull", ["PL    W4", "PLW"])
def test_kind_mismatch_keeps_the_emulated_stack(tmp_path, pull):
    text = f"PS    I0\nCM    Sub\nEM\nLBL Sub\n{pull}\nEM\n"
    project = _project(tmp_path, text)
    analysis = StackAnalysis(project.program)
    sub = next(r.key for r in project.program.routines if r.label == "Sub")
    assert sub not in analysis.interfaces or (0, 0) in analysis.dynamic


def test_report_lists_the_places_that_keep_the_emulated_stack(tmp_path):
    text = "L     I0\nPS    I1\nCMT   Sub\nEM\nLBL Sub\nPL    M1\nL     M1\n=     O1\nEM\n"
    project = _project(tmp_path, text)
    report = api.transpile(project, formats=("st",)).files["report.md"].decode()
    section = report.split("### Data stack", 1)[1].split("##", 1)[0]
    assert "`Sub_2`" in section and "conditionally" in section  # SUB is a standard function: renamed
    sample = api.transpile(api.load_project(api.project_options(SAMPLE)), formats=("st",)).files["report.md"].decode()
    assert "No POU emulates the data stack" in sample
