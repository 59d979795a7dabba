"""Reference interpreter: instruction semantics beyond the public vectors, faults with locations, jobs, modules, NC, API."""

from __future__ import annotations

import dataclasses
import textwrap
from pathlib import Path
from typing import Any, Iterable, Mapping

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from transpiler.frontend.load import ProjectOptions
from transpiler.exec.interp import Machine, MachineConfigError, MachineHalted, compile_program
from transpiler.exec.interp.faults import CycleReport
from transpiler.exec.interp.gen_exprs import norm
from transpiler.ir import Program
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import Semantics, make_semantics

# ---------------------------------------------------------------------------------------------
# helpers (also used by test_interp_switches.py)


def compile_text(folder: Path, program: str, profile: str = "tv", overrides: Mapping[str, Any] | None = None, *,
                 files: Mapping[str, str] | None = None, semantics: Semantics | None = None) -> Program:
    """Compile `program` as main.src (plus extra files) and return the IR program; fails on compile errors."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "main.src").write_text(textwrap.dedent(program).lstrip("\n"), encoding="latin-1")
    for name, text in (files or {}).items():
        (folder / name).write_text(textwrap.dedent(text).lstrip("\n"), encoding="latin-1")
    semantics = semantics or make_semantics(profile, overrides)
    result = compile_project(ProjectOptions(main=folder / "main.src"), semantics)
    assert not result.diagnostics.has_errors(), "\n".join(d.render() for d in result.diagnostics.errors)
    return result.program


def machine(folder: Path, program: str, profile: str = "tv", overrides: Mapping[str, Any] | None = None, *,
            given: Mapping[str, Any] | None = None, mp: Mapping | None = None, files: Mapping[str, str] | None = None,
            semantics: Semantics | None = None, **kwargs: Any) -> Machine:
    prog = compile_text(folder, program, profile, overrides, files=files, semantics=semantics)
    m = Machine(prog, mp, **kwargs)
    for name, value in (given or {}).items():
        m.write(*ref(name), value)
    return m


def ref(name: str) -> tuple[str, int]:
    if name in ("LA", "WA", "X", "SA"):
        return name, 0
    return name[0], int(name[1:])


def cycles(m: Machine, count: int, inputs: Mapping[str, list] | None = None,
           nc: Mapping[int, list[dict]] | None = None, stop_on_fault: bool = True) -> list[CycleReport]:
    reports = []
    for c in range(m.next_cycle, m.next_cycle + count):
        writes = [(*ref(n), v[c]) for n, v in (inputs or {}).items() if c < len(v)]
        report = m.run_cycle(c, writes, (nc or {}).get(c, []))
        reports.append(report)
        if report.faults and stop_on_fault:
            break
    return reports


def values(m: Machine, *names: str) -> dict[str, Any]:
    return {n: m.read(*ref(n)) for n in names}


def with_setting(program: Program, **values: Any) -> Program:
    """The program with semantic settings replaced after compilation (for run-time-only checks)."""
    sem = program.semantics
    return dataclasses.replace(program, semantics=Semantics(sem.profile, {**sem.values, **values}))


def fault_of(reports: Iterable[CycleReport]):
    faults = [f for r in reports for f in r.faults]
    assert len(faults) == 1, faults
    return faults[0]


# ---------------------------------------------------------------------------------------------
# word memory and arithmetic


def test_word_gates_on_a_w_operand_change_only_16_bits(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   K$12345678
        A   W0
        =   D4
        L   K$12345678
        ON  W0
        =   D8
        L   K$12345678
        XON W0
        =   D12
        EM
    """, given={"W0": 0x0F0F})
    cycles(m, 1)
    assert values(m, "D4", "D8", "D12") == {"D4": 0x12340608, "D8": 0x1234F6F8, "D12": 0x1234A688}


def test_division_edge_cases_and_flags(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   K-2147483648
        /   K-1
        =   D0
        L   M4201
        =   M1
        L   K-2147483648
        MOD K-1
        =   D4
        L   K7
        /   K-2
        =   D8
        L   K-7
        MOD K-2
        =   D12
        L   K5
        x   K-3
        =   D16
        EM
    """)
    cycles(m, 1)
    assert values(m, "D0", "M1", "D4", "D8", "D12", "D16", "M4200", "M4201", "M4202") == {
        "D0": -2147483648, "M1": 0, "D4": 0, "D8": -3, "D12": -1, "D16": -15, "M4200": 0, "M4201": 0, "M4202": 0}


def test_big_endian_words_on_tnc407(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   W10
        =   D20
        L   B12
        =   W24
        EM
    """, profile="tnc407", given={"B10": 0x80, "B11": 0x01, "B12": 0xFE})
    cycles(m, 1)
    assert values(m, "D20", "W24", "B24", "B25") == {"D20": -32767, "W24": -2, "B24": -1, "B25": -2}


def test_unsigned_comparisons_over_the_operand_width(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   K-1
        >   W0
        =   M1
        L   K$1FFFF
        ==  W0
        =   M2
        EM
    """, overrides={"compare_signedness": "unsigned"}, given={"W0": 0x7FFF})
    cycles(m, 1)
    assert values(m, "M1", "M2") == {"M1": 1, "M2": 0}


def test_ld_and_d_equals_move_32_bits(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   K-5
        D=  M100
        LD  M100
        =   D0
        LW  M100
        =   D4
        EM
    """)
    cycles(m, 1)
    assert values(m, "D0", "D4", "M100", "M101", "M102", "M131") == {
        "D0": -5, "D4": -5, "M100": 1, "M101": 1, "M102": 0, "M131": 1}


def test_extended_instructions(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        INC B0
        DEC W2
        INC M5
        L   K5
        INCW
        TWOC
        =   D4
        L   K0
        =   X
        DECX
        L   X
        =   D8
        L   I1
        NOTL
        =   M6
        L   K6
        NOTW
        =   D12
        EM
    """, given={"B0": 255, "W2": -32768, "M5": 1})
    cycles(m, 1)
    assert values(m, "B0", "W2", "M5", "D4", "D8", "M6", "D12") == {
        "B0": 0, "W2": 32767, "M5": 0, "D4": -6, "D8": -1, "M6": 1, "D12": -7}


@pytest.mark.parametrize("width", [16, 32])
@pytest.mark.parametrize("exact", [False, True], ids=["fast", "exact"])
def test_incx_and_decx_wrap_at_the_width_of_x(tmp_path: Path, width: int, exact: bool) -> None:
    top = (1 << (width - 1)) - 1
    prog = compile_text(tmp_path, f"""
        L   K{top}
        =   X
        INCX
        L   X
        =   D0
        DECX
        L   X
        =   D4
        INCX
        INCX
        L   X
        =   D8
        EM
    """, overrides={"index_register_width": width})
    m = Machine(prog, compiled=compile_program(prog, exact=exact))
    cycles(m, 1)
    assert values(m, "D0", "D4", "D8") == {"D0": -top - 1, "D4": top, "D8": -top}


def test_strings_truncate_with_a_warning_and_compare_bytewise(tmp_path: Path) -> None:
    long = "x" * 100
    m = machine(tmp_path, f"""
        L   S"{long}"
        +   S"{long}"
        =   S1
        L   S#E12
        =   S2
        L   S2
        <   S"a"
        =   M1
        EM
    """)
    reports = cycles(m, 2)
    assert m.read("S", 1) == "x" * 128
    assert m.read("S", 2) == "E0012"
    assert m.read("M", 1) == 1
    warnings = [w for r in reports for w in r.warnings]
    assert [(w.code, w.span.line, w.cycle) for w in warnings] == [("E-RT-STRING", 2, 0), ("E-RT-STRING", 2, 1)]
    assert not any(r.faults for r in reports)


# ---------------------------------------------------------------------------------------------
# runtime faults carry file, line and cycle


def test_stack_overflow_is_a_fault_at_the_push(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   K0
        LBL LOOP
        PS  K1
        JP  LOOP
    """, overrides={"data_stack_words": 6})
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line, fault.cycle) == ("E-RT-STACK-OVERFLOW", 3, 0)
    assert m.halted
    with pytest.raises(MachineHalted):
        m.run_cycle(1)


@pytest.mark.parametrize("exact", [False, True], ids=["fast", "exact"])
@pytest.mark.parametrize("program, expected", [
    # the operand of a push is read before the capacity check: its fault comes first
    ("""
        L   K99
        =   X
        PS  K1
        PS  KF TAB[X]
        EM
        KFIELD TAB
        K1
        ENDK
     """, ("E-RT-INDEX", 4, "KF TAB[X] with X = 99 is outside 0..0")),
    ("""
        PS  K1
        PS  M1
        EM
     """, ("E-RT-STACK-OVERFLOW", 2, "data stack overflow (capacity 2 words)")),
    # a run of pushes is checked at once; without room for all of it, the push that overflows faults
    ("""
        PS  M1
        PSL
        PS  M3
        EM
     """, ("E-RT-STACK-OVERFLOW", 3, "data stack overflow (capacity 2 words)")),
    ("""
        PS  M1
        PL  D0
        EM
     """, ("E-RT-STACK-UNDERFLOW", 2, "a 32-bit pull needs 2 words, the data stack holds 1")),
    ("""
        PL  M1
        EM
     """, ("E-RT-STACK-UNDERFLOW", 1, "pull from an empty data stack")),
])
def test_stack_faults_in_both_variants(tmp_path: Path, program: str, expected: tuple, exact: bool) -> None:
    prog = compile_text(tmp_path, program, overrides={"data_stack_words": 2})
    m = Machine(prog, compiled=compile_program(prog, exact=exact))
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line, fault.message) == expected


@pytest.mark.parametrize("exact", [False, True], ids=["fast", "exact"])
def test_a_run_of_pushes_keeps_their_order(tmp_path: Path, exact: bool) -> None:
    prog = compile_text(tmp_path, """
        L   K7
        L   M1
        PS  K5
        PS  M1
        PSW
        PSL
        PSX
        PLX
        PL  M2
        PL  D8
        PL  M3
        PL  D4
        EM
    """)
    m = Machine(prog, compiled=compile_program(prog, exact=exact))
    m.write("M", 1, 1)
    m.write("X", 0, -3)
    assert not cycles(m, 1)[0].faults
    assert values(m, "X", "M2", "D8", "M3", "D4") == {"X": -3, "M2": 1, "D8": 7, "M3": 1, "D4": 5}


def test_fault_inside_a_module_file_names_that_file(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        USES mod.src
        EXTERN Fn
        L   I1
        CMT Fn
        EM
    """, files={"mod.src": """
        GLOBAL Fn
        LBL Fn
        L   K99
        =   X
        L   KF TAB[X]
        EM
        KFIELD TAB
        K1
        ENDK
    """})
    reports = cycles(m, 3, inputs={"I1": [0, 0, 1]})
    fault = fault_of(reports)
    assert (fault.code, Path(fault.span.file).name, fault.span.line, fault.cycle) == ("E-RT-INDEX", "mod.src", 5, 2)
    assert "main.src" not in fault.render() and ":5:" in fault.render() and "cycle 2" in fault.render()


def test_runtime_call_depth_limit(tmp_path: Path) -> None:
    prog = compile_text(tmp_path, """
        CM  A1
        EM
        LBL A1
        CM  B1
        EM
        LBL B1
        EM
    """)
    m = Machine(with_setting(prog, call_depth=1))
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line) == ("E-RT-CALL-DEPTH", 4)
    ok = Machine(with_setting(prog, call_depth=2))
    assert not cycles(ok, 1)[0].faults


WATCHDOG_LOOP = """
    L   K0
    =   W0
    LBL LOOP
    L   W0
    +   K1
    =   W0
    JP  LOOP
"""


@pytest.mark.parametrize("coverage", [False, True])
def test_watchdog_faults_at_the_instruction_that_exceeds_the_budget(tmp_path: Path, coverage: bool) -> None:
    # 2 + 4 per turn: instruction 11 is the 'L W0' of the third turn; the label does not count
    m = machine(tmp_path, WATCHDOG_LOOP, overrides={"max_instructions_per_cycle": 10}, coverage=coverage)
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line, fault.cycle) == ("E-RT-WATCHDOG", 4, 0)
    assert m.read("W", 0) == 2           # the first 10 instructions ran, the 11th did not


def test_a_cycle_may_execute_exactly_the_budget(tmp_path: Path) -> None:
    program = """
        L   K1
        =   W0
        LBL X1
        L   I1
        JPT X1
        EM
    """
    # 5 counted instructions (LBL excluded)
    assert not cycles(machine(tmp_path / "a", program, overrides={"max_instructions_per_cycle": 5}), 2)[-1].faults
    fault = fault_of(cycles(machine(tmp_path / "b", program, overrides={"max_instructions_per_cycle": 4}), 1))
    assert (fault.code, fault.span.line) == ("E-RT-WATCHDOG", 6)


def test_watchdog_rerun_keeps_the_state_of_the_cycle_exact(tmp_path: Path) -> None:
    # The fast code counts whole blocks in advance; a block that would pass the budget is re-run
    # exactly, so the outputs written before the faulting instruction are there, and no later ones.
    m = machine(tmp_path, """
        L   M4172
        =   O1
        =   O2
        =   O3
        =   O4
        EM
    """, overrides={"max_instructions_per_cycle": 3})
    fault = fault_of(cycles(m, 1))
    assert fault.span.line == 4
    assert values(m, "O1", "O2", "O3", "O4") == {"O1": 1, "O2": 1, "O3": 0, "O4": 0}


@pytest.mark.parametrize("coverage", [False, True])
def test_a_fault_after_the_budget_is_passed_gives_way_to_the_watchdog(tmp_path: Path, coverage: bool) -> None:
    # The fast code checks its count at jumps back, calls and module calls only: here it runs on past the
    # budget into the stack underflow of PL. The watchdog fault of the 4th instruction is what happened first.
    m = machine(tmp_path, """
        L   M4172
        =   O1
        =   O2
        =   O3
        PL  W0
        EM
    """, overrides={"max_instructions_per_cycle": 3}, coverage=coverage)
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line) == ("E-RT-WATCHDOG", 4)
    assert len(m.faults) == 1
    assert values(m, "O1", "O2", "O3") == {"O1": 1, "O2": 1, "O3": 0}


def test_module_calls_are_not_repeated_by_the_exact_rerun(tmp_path: Path) -> None:
    # The fast code runs the module calls, then its pre-count of the next block passes the budget, and
    # the cycle is re-run exactly from a snapshot. 9036 doubles status 10 (the jog-increment limit, any value) each time it runs: the re-run
    # must replay the logged module results instead of calling the modules a second time.
    m = machine(tmp_path, """
        PS  K10
        CM  9035
        PL  D0
        L   D0
        x   K2
        =   D0
        PS  K10
        PS  D0
        CM  9036
        PL  D4
        L   M0
        JPT END
        L   M4172
        =   O1
        =   O2
        LBL END
        EM
    """, overrides={"max_instructions_per_cycle": 14, "module_context": "ignore"})  # 9035 is submit-only (A-46q)
    m.sys.set_status(10, 21)
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line) == ("E-RT-WATCHDOG", 15)
    assert values(m, "D0", "O1", "O2") == {"D0": 42, "O1": 1, "O2": 0}
    assert m.sys.call(9035, [10])[0] == [42]


# ---------------------------------------------------------------------------------------------
# data stack, modules


def test_leftover_stack_is_a_warning_at_the_final_em(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        PS  K1
        CM  SUB
        EM
        LBL SUB
        EM
    """)
    report = cycles(m, 1)[0]
    assert not report.faults
    assert [(w.code, w.span.line, w.severity) for w in report.warnings] == [("E-RT-STACK-LEFTOVER", 3, "warning")]


def test_module_results_errors_and_overrides(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        PS  K4110
        PS  K7
        CM  9032
        PL  D0
        L   M4203
        =   M1
        L   W1022
        =   W10
        CM  9195
        PL  D20
        PS  K-3
        CM  9192
        PL  D24
        EM
    """, module_results={9192: [3600]}, overrides={"module_context": "ignore"})  # 9032/9192 are submit-only
    cycles(m, 51)
    # MP4110.7 is not set: 9032 fails with the module error marker and code
    assert values(m, "D0", "M1", "W10", "M4203") == {"D0": 0, "M1": 1, "W10": 1, "M4203": 0}
    assert m.read("D", 20) == 1          # whole seconds of simulated time in cycle 50 (1.0 s)
    assert m.read("D", 24) == 3600       # scenario override of module 9192


def test_unknown_module_is_a_compile_error_naming_the_nearest(tmp_path: Path) -> None:
    (tmp_path / "main.src").write_text("PS  K1\nCM  9888\nPL  D0\nEM\n", encoding="latin-1")
    result = compile_project(ProjectOptions(main=tmp_path / "main.src"), make_semantics("tv"))
    [diag] = result.diagnostics.errors
    assert (diag.code, diag.span.line) == ("E-MODULE-UNKNOWN", 2)
    assert "nearest known: 9263, 9264, 9429" in diag.message


def test_module_9006_starts_an_additional_timer(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   I1
        JPF DONE
        PS  K96
        CM  9006
        LBL DONE
        L   T96
        =   O1
        EM
    """, mp={"4111.96": 2}, number_mp4111=1)
    trace = []
    for c in range(5):
        assert not m.run_cycle(c, [("I", 1, 1 if c == 0 else 0)]).faults
        trace.append(m.read("O", 1))
    assert trace == [0, 1, 1, 0, 0]


# ---------------------------------------------------------------------------------------------
# submit jobs


def test_submit_job_states_and_own_registers(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   M4172
        JPF LATER
        L   K7
        SUBM JOB
        =   W0
        RPLY W0
        =   W2
        LBL LATER
        RPLY W0
        =   W4
        EM
        LBL JOB
        =   W6          ; the job's own WA starts at 0
        RPLY W0
        =   W8          ; running
        SUBM JOB
        =   W10         ; no nesting: 0
        L   K1
        x   K-2147483648
        x   K2          ; overflow sets the job's own multiplication marker
        EM
    """, given={"W6": 99, "W10": 99})
    cycles(m, 2)
    assert values(m, "W0", "W2", "W4", "W6", "W8", "W10", "M4200") == {
        "W0": 1, "W2": 2, "W4": 0, "W6": 0, "W8": 1, "W10": 0, "M4200": 0}
    assert m.read("WA") == 0             # main's WA (RPLY 0), not the job's


def test_submit_queue_holds_eight_jobs_and_ids_count_up(tmp_path: Path) -> None:
    body = "\n".join(f"SUBM JOB\n=   W{2 * i}" for i in range(9))
    m = machine(tmp_path, body + "\nEM\nLBL JOB\nEM\n")
    cycles(m, 2)
    assert [m.read("W", 2 * i) for i in range(9)] == [9, 10, 11, 12, 13, 14, 15, 16, 0]


def test_can_removes_a_queued_job(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        SUBM JOB
        =   W0
        CAN W0
        RPLY W0
        =   W2
        EM
        LBL JOB
        L   K5
        =   W4
        EM
    """, given={"W2": 9})
    cycles(m, 1)
    assert values(m, "W0", "W2", "W4") == {"W0": 1, "W2": 0, "W4": 0}


# ---------------------------------------------------------------------------------------------
# timers, counters, machine parameters


def test_timer_preset_in_seconds_rounds_up_exactly(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   I1
        =   T3
        L   T51
        =   O1
        EM
    """, profile="itnc530", mp={(4110, 3): "0.125"})
    trace = []
    for c in range(10):
        m.run_cycle(c, [("I", 1, 1 if c == 0 else 0)])
        trace.append(m.read("O", 1))
    assert trace == [0, 1, 1, 1, 1, 1, 1, 1, 0, 0]       # ceil(125 / 20) = 7 cycles


def test_non_integer_preset_in_a_cycles_profile_is_rejected(tmp_path: Path) -> None:
    prog = compile_text(tmp_path, "L I1\n= T0\nEM\n")
    with pytest.raises(MachineConfigError) as info:
        Machine(prog, {(4110, 0): "1.5"})
    assert [d.code for d in info.value.diagnostics] == ["E-MP-VALUE"]


# ---------------------------------------------------------------------------------------------
# NC model


def test_tool_call_markers_and_handshake(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   M4073
        =   M4093
        EM
    """)
    nc = {0: [{"tool_call": {"tool": 0, "pocket": 3}}], 1: [{"tool_call": {"tool": 4, "pocket": -1}}]}
    seen = []
    for c in range(5):
        m.run_cycle(c, [], nc.get(c, []))
        seen.append(values(m, "M4073", "W264", "W262", "M4521", "M4522", "M4523"))
    assert seen[0] == {"M4073": 1, "W264": 0, "W262": 3, "M4521": 1, "M4522": 0, "M4523": 0}
    assert seen[1]["M4073"] == 0 and seen[1]["W264"] == 0
    assert seen[2] == {"M4073": 1, "W264": 4, "W262": -1, "M4521": 0, "M4522": 0, "M4523": 1}


def test_unacknowledged_strobe_times_out_after_10_s(tmp_path: Path) -> None:
    m = machine(tmp_path, "L K0\n= W0\nEM\n")
    reports = cycles(m, 600, nc={3: [{"m_function": 5}]})
    fault = fault_of(reports)
    # started in cycle 3; (k - 3) * 20 ms > 10 000 ms first for k = 504
    assert (fault.code, fault.cycle, fault.span) == ("E-SIM-HANDSHAKE-TIMEOUT", 504, None)
    assert len(reports) == 505


def test_first_cycle_marker_and_operating_mode(tmp_path: Path) -> None:
    m = machine(tmp_path, "L M4172\n= M1\nEM\n")
    cycles(m, 1)
    assert values(m, "M1", "W272") == {"M1": 1, "W272": 1}
    cycles(m, 1)
    assert values(m, "M1", "M4172") == {"M1": 0, "M4172": 0}


# ---------------------------------------------------------------------------------------------
# machine API and phases


def test_inputs_are_latched_and_program_writes_to_inputs_are_lost(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   I1
        =   M1
        L   M4172
        =   I1
        EM
    """)
    m.write("I", 1, 0)
    cycles(m, 1)
    assert m.read("M", 1) == 0 and m.read("I", 1) == 1   # the program wrote I1 ...
    cycles(m, 1)
    assert m.read("M", 1) == 0                           # ... and the latch restored the process value


def test_read_write_api_and_registers(tmp_path: Path) -> None:
    m = machine(tmp_path, "L W0\n+ K1\n= X\nEM\n")
    m.write("B", 0, 0xFF)
    m.write("B", 1, 0x7F)
    assert m.read("W", 0) == 0x7FFF and m.read("B", 0) == -1
    m.write("D", 4, 0xFFFFFFFF)
    assert m.read("D", 4) == -1
    m.write("S", 3, "y" * 200)
    assert m.read("S", 3) == "y" * 128
    cycles(m, 1)
    assert m.registers == {"LA": 0, "WA": 32768, "X": 32768, "SA": ""}
    with pytest.raises(ValueError):
        m.read("W", 1)
    with pytest.raises(ValueError):
        m.read("M", 10**6)


def test_shared_bit7_accumulator(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   K$100
        L   I1
        =   M1
        PSW
        PL  D0
        L   K$7F
        =   M2
        EM
    """, overrides={"accumulator_model": "shared_bit7"}, given={"I1": 1})
    cycles(m, 1)
    # the logic result went into bit 7 of WA; K$7F has bit 7 = 0
    assert values(m, "M1", "D0", "M2") == {"M1": 1, "D0": 0x180, "M2": 0}


def test_coverage_records_ops_and_branch_outcomes(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   I1
        JPT SKIP
        CASE B0
        CM  C0
        CM  C1
        ENDC
        LBL SKIP
        EM
        LBL C0
        EM
        LBL C1
        EM
    """, coverage=True, given={"B0": 1})
    cycles(m, 3, inputs={"I1": [0, 1, 0]})
    m.write("B", 0, 7)
    cycles(m, 1)
    cov = m.coverage
    ops = m.program.files[0].ops
    lines = {ops[i].span.line for f, i in cov.executed}
    assert lines == {1, 2, 3, 6, 8, 12}          # C0 (lines 9-10) never ran; labels are not executed ops
    by_line = {ops[i].span.line: outcomes for (f, i), outcomes in cov.branches.items()}
    assert by_line == {2: frozenset({0, 1}), 3: frozenset({1, -1})}


def test_fast_and_exact_code_agree(tmp_path: Path) -> None:
    program = """
        L   I1
        A[
        L   W0
        <   K3
        ]
        JPF NEXT
        L   W0
        +   K1
        =   W0
        LBL NEXT
        L   W0
        x   K1000
        -[
        L   B2
        MOD K7
        ]
        =   D4
        PS  D4
        PL  W8
        EM
    """
    fast = machine(tmp_path / "fast", program)
    exact = machine(tmp_path / "exact", program, coverage=True)
    for m in (fast, exact):
        for c in range(6):
            m.run_cycle(c, [("I", 1, c % 2), ("B", 2, c * 37)])
    assert values(fast, "W0", "D4", "W8", "LA", "WA") == values(exact, "W0", "D4", "W8", "LA", "WA")
    assert not fast._primary.exact and exact._primary.exact


def test_compiled_program_can_be_shared(tmp_path: Path) -> None:
    prog = compile_text(tmp_path, "L W0\n+ K1\n= W0\nEM\n")
    code = compile_program(prog)
    a, b = Machine(prog, compiled=code), Machine(prog, compiled=code)
    cycles(a, 3)
    cycles(b, 1)
    assert (a.read("W", 0), b.read("W", 0)) == (3, 1)


# ---------------------------------------------------------------------------------------------
# indexed operands and less common operand kinds


def test_indexed_bits_strings_and_bit_groups(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   K3
        =   X
        L   M10[X]
        =   O1[X]
        L   K$A5
        B=  M20[X]
        LB  M20[X]
        =   W0
        L   S"abc"
        =   S1[X]
        L   S4
        ==  S"abc"
        =   M2
        INC B10[X]
        L   X
        +   X
        =   D4
        L   K9
        A   X
        =   W2
        EM
    """, given={"M13": 1, "B13": 0x7F})
    cycles(m, 1)
    assert values(m, "O4", "M23", "M24", "M30", "W0", "S4", "M2", "B13", "D4", "W2") == {
        "O4": 1, "M23": 1, "M24": 0, "M30": 1, "W0": -91, "S4": "abc", "M2": 1, "B13": -128, "D4": 6, "W2": 1}


def test_indexed_bit_group_is_range_checked_as_a_whole(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   K9995
        =   X
        L   K0
        B=  M0[X]
        EM
    """)
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line) == ("E-RT-INDEX", 4)
    assert "M9995..M10002" in fault.message


def test_big_endian_double_words_in_generated_code(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   D0
        +   K1
        =   D4
        L   K$0102
        =   W8
        L   B8
        =   W10
        EM
    """, profile="tnc407", given={"B0": 0x12, "B1": 0x34, "B2": 0x56, "B3": 0x78})
    cycles(m, 1)
    assert values(m, "D4", "B4", "B7", "W10") == {"D4": 0x12345679, "B4": 0x12, "B7": 0x79, "W10": 1}


def test_conditional_module_call_and_em_forms(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        L   I1
        CMF 9195
        CMF SUB
        L   I1
        EMF
        L   K5
        =   W0
        EM
        LBL SUB
        PL  D4
        L   K1
        =   W2
        L   I2
        EMT
        L   K2
        =   W2
        EM
    """, given={"D4": 77})
    cycles(m, 1, inputs={"I1": [0], "I2": [1]})
    assert values(m, "D4", "W2", "W0") == {"D4": 0, "W2": 1, "W0": 0}
    cycles(m, 1, inputs={"I1": [0, 1], "I2": [1, 1]})
    assert values(m, "W0") == {"W0": 5}


def test_case_with_a_word_selector_and_nested_calls(tmp_path: Path) -> None:
    m = machine(tmp_path, """
        CASE W0
        CM  C0
        CM  C1
        ENDC
        L   W2
        +   K100
        =   W2
        EM
        LBL C0
        L   K1
        =   W2
        EM
        LBL C1
        CM  C0
        L   W2
        +   K10
        =   W2
        EM
    """, given={"W0": 1})
    cycles(m, 1)
    assert m.read("W", 2) == 111


# ---------------------------------------------------------------------------------------------
# the fast code (block pre-counts, dispatch) and the exact code agree on random programs

_SIMPLE = st.one_of(
    st.sampled_from(["L", "LN", "A", "AN", "O", "ON", "XO", "XON"]).flatmap(
        lambda m: st.sampled_from([f"{m} I{i}" for i in range(3)] + [f"{m} M{i}" for i in range(4)])),
    st.sampled_from(["=", "S", "R", "SN", "RN"]).flatmap(lambda m: st.sampled_from([f"{m} M{i}" for i in range(4)])),
    st.sampled_from(["L", "+", "-", "x", "/", "MOD", "A", "O", "XO", "==", "<", ">=", "<<", ">>", "BS", "BC", "BT"]
                    ).flatmap(lambda m: st.sampled_from([f"{m} K{k}" for k in (-3, 0, 1, 2, 7, 300)]
                                                        + [f"{m} W{a}" for a in (0, 2)] + [f"{m} B5"])),
    st.sampled_from(["= W0", "= W2", "= B5", "= D8", "PS W0", "PS M1", "PL D8", "PL M3", "PSW", "PLW",
                     "CM SUB0", "CMT SUB1", "CMF SUB0", "EMT", "EMF", "L X", "= X", "INCW", "NOTL"]),
)
_COMPOSITE = st.sampled_from([
    ["L W0", "+[", "L K3", "x W2", "]"],
    ["L I0", "A[", "L M1", "O I2", "]"],
    ["L W2", "==[", "L W0", "MOD K3", "]"],
    ["L M2", "ON[", "L I1", "XO M0", "]"],
])


@st.composite
def _programs(draw: st.DrawFn) -> str:
    units = draw(st.lists(st.one_of(_SIMPLE.map(lambda s: [s]), _COMPOSITE), min_size=1, max_size=25))
    labels = draw(st.integers(min_value=1, max_value=4))
    for i in range(labels):
        units.insert(draw(st.integers(min_value=0, max_value=len(units))), [f"LBL L{i}"])
    jumps = draw(st.lists(st.tuples(st.sampled_from(["JP", "JPT", "JPF"]), st.integers(0, labels - 1)), max_size=4))
    for mnemonic, target in jumps:
        units.insert(draw(st.integers(min_value=0, max_value=len(units))), [f"{mnemonic} L{target}"])
    lines = [line for unit in units for line in unit] + ["EM"]
    lines += ["LBL SUB0", "L W2", "+ K1", "= W2", "EM", "LBL SUB1", "PS W0", "PL D12", "EM"]
    return "\n".join(lines) + "\n"


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(source=_programs(), inputs=st.lists(st.integers(0, 7), min_size=3, max_size=3))
def test_random_programs_run_the_same_in_fast_and_exact_code(tmp_path: Path, source: str, inputs: list) -> None:
    prog = compile_text(tmp_path, source, overrides={"max_instructions_per_cycle": 120})
    fast, exact = Machine(prog), Machine(prog, coverage=True)
    covered = Machine(prog, compiled=compile_program(prog, coverage=True, exact=False), coverage=True)
    for cycle, bits in enumerate(inputs):
        writes = [("I", i, (bits >> i) & 1) for i in range(3)]
        outcomes = []
        for m in (fast, exact, covered):
            report = m.run_cycle(cycle, writes)
            # a cycle ended by a fault counts its last block whole in the fast code, so counts compare without one
            count = None if report.faults else report.instructions
            outcomes.append(([(f.code, f.op, f.cycle) for f in report.faults],
                             [(w.code, w.op) for w in report.warnings], count,
                             bytes(m.state.M[:8]), bytes(m.state.mem[:16]), m.registers))
        assert outcomes[0] == outcomes[1] == outcomes[2], source
        if fast.halted:
            break
    # the fast code's coverage marks (per stretch, implied by branch marks) are the exact code's per-op marks
    assert covered.coverage.branches == exact.coverage.branches, source
    assert covered.coverage.executed <= exact.coverage.executed, source
    if not covered.halted:
        assert covered.coverage.executed == exact.coverage.executed, source


_LOGIC = st.sampled_from(["L", "LN", "A", "AN", "O", "ON", "XO", "XON"]).flatmap(
    lambda m: st.sampled_from([f"{m} M{i}" for i in range(6)] + [f"{m} I{i}" for i in range(3)]))
_LOGIC_OR_STORE = st.one_of(_LOGIC, _LOGIC, _LOGIC, st.sampled_from(["= M0", "= M5", "SN M3", "S M1", "R M2",
                                                                     "RN M4", "PSL", "PLL", "= O1"]))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(ops=st.lists(_LOGIC_OR_STORE, min_size=1, max_size=90), bits=st.integers(0, 511))
def test_runs_of_bit_logic_give_the_exact_codes_results(tmp_path: Path, ops: list, bits: int) -> None:
    # the fast code folds runs of bit logic into one expression of LA (long runs in pieces)
    source = "\n".join(["PSL", *ops, "PLL", "EM"]) + "\n"
    prog = compile_text(tmp_path, source)
    fast = Machine(prog, compiled=compile_program(prog, exact=False))
    exact = Machine(prog, compiled=compile_program(prog, exact=True))
    results = []
    for m in (fast, exact):
        for i in range(6):
            m.write("M", i, (bits >> i) & 1)
        for i in range(3):
            m.write("I", i, (bits >> (6 + i)) & 1)
        report = m.run_cycle(0)
        # a cycle ended by a fault (a pull from the empty stack) counts its last block whole in the fast code
        count = report.instructions if report.ok else None
        results.append(([f.code for f in report.faults], count, bytes(m.state.M[:8]), m.state.O[1], m.registers))
    assert results[0] == results[1], source


@pytest.mark.parametrize("coverage", [False, True])
def test_many_forward_jumps_in_one_block_stay_within_the_nesting_limit(tmp_path: Path, coverage: bool) -> None:
    # each jump to the next block nests the rest of its block one level deeper, up to a cap
    source = "\n".join(["L K0", "= W0"] + ["L W0", "+ K1", "= W0", "< K40", "JPF END"] * 150 + ["LBL END", "EM"])
    prog = compile_text(tmp_path, source + "\n")
    fast = Machine(prog, compiled=compile_program(prog, coverage=coverage, exact=False), coverage=coverage)
    exact = Machine(prog, compiled=compile_program(prog, coverage=coverage, exact=True), coverage=coverage)
    for m in (fast, exact):
        report = m.run_cycle(0)
        assert not report.faults and m.read("W", 0) == 40
    assert fast.instructions == exact.instructions
    if coverage:
        assert fast.coverage == exact.coverage


# ---------------------------------------------------------------------------------------------
# the fast code against hand-computed values (not against the exact code): each expected value follows from the
# rules of the language description by hand, and the comment says which wrong implementation it rules out.


@given(value=st.integers(-(1 << 40), 1 << 40))
def test_the_int32_wrap_of_the_generated_code(value: int) -> None:
    # a value in range is taken as it is, any other wraps; for a name and for an expression evaluated once
    for expr in ("v", "v + 0"):
        assert eval(norm(expr), {"v": value}) == ((value + (1 << 31)) % (1 << 32)) - (1 << 31)  # noqa: S307


def fast_machine(folder: Path, program: str, **kwargs: Any) -> Machine:
    m = machine(folder, program, **kwargs)
    assert not m._primary.exact, "this test is about the fast (compiled) code path"
    return m


def fast_trace(m: Machine, count: int, names: tuple[str, ...], inputs: Mapping[str, list] | None = None) -> dict:
    trace: dict[str, list] = {n: [] for n in names}
    for c in range(count):
        report = m.run_cycle(c, [(*ref(n), v[c]) for n, v in (inputs or {}).items() if c < len(v)])
        assert not report.faults, report.faults
        for n in names:
            trace[n].append(m.read(*ref(n)))
    return trace


def test_fast_code_word_arithmetic_wraps_and_sets_the_flags_by_hand(tmp_path: Path) -> None:
    m = fast_machine(tmp_path, """
        L   D0
        +   K1
        =   D4
        L   K65536
        x   K65536
        =   D8
        L   M4200
        =   O1
        L   K-7
        /   K2
        =   D12
        L   M4201
        =   O2
        L   K5
        /   K0
        =   D16
        L   M4201
        =   O3
        L   K-7
        MOD K2
        =   D20
        L   D0
        -   K-1
        x   K1
        =   D24
        L   M4200
        =   O4
        L   K300
        =   B28
        EM
    """, given={"D0": 2147483647})
    cycles(m, 1)
    assert values(m, "D4", "D8", "O1", "D12", "O2", "D16", "O3", "D20", "D24", "O4", "B28") == {
        "D4": -2147483648,  # 2^31-1 + 1 wraps mod 2^32 (6.5, no flag); saturation gives 2^31-1, Python ints 2^31
        "D8": 0,            # 65536*65536 = 2^32: low 32 bits are 0 (6.5, A-10); saturation gives 2^31-1
        "O1": 1,            # ... and MUL_ERR (M4200) is set because 2^32 is outside int32
        "D12": -3,          # -7/2 truncates toward zero; floor division gives -4
        "O2": 0,            # a division that succeeds resets DIV_ERR (M4201)
        "D16": 5,           # division by zero leaves WA unchanged: 0 or an exception would be wrong
        "O3": 1,            # ... and sets DIV_ERR
        "D20": -1,          # MOD takes the sign of the dividend: -7 - 2*trunc(-7/2) = -1; Python's % gives 1
        "D24": -2147483648,  # (2^31-1) - (-1) wraps to -2^31; x K1 of an int32 value fits
        "O4": 0,            # so the second x resets MUL_ERR: the flag is written by every execution
        "B28": 44,          # 300 stored into a byte keeps the low 8 bits: 300 - 256 = 44, not 300 or 127
    }


def test_fast_code_byte_word_overlap_is_little_endian_by_hand(tmp_path: Path) -> None:
    m = fast_machine(tmp_path, """
        L   K$1234
        =   W30
        L   K$12345678
        =   D40
        L   K-1
        =   B50
        L   K0
        =   B51
        L   B60
        =   D64
        L   W50
        =   D68
        EM
    """, given={"B60": 0x80})
    cycles(m, 1)
    assert values(m, "B30", "B31", "W40", "W42", "B43", "W50", "D64", "D68") == {
        "B30": 0x34, "B31": 0x12,   # a word's low byte is at its own address (5.2, little-endian `tv`): not $12/$34
        "W40": 0x5678, "W42": 0x1234, "B43": 0x12,  # the same for the words and bytes inside D40
        "W50": 255,     # B50 = $FF and B51 = $00 make W50 = $00FF = 255: separate byte and word stores give -1 or 0
        "D64": -128,    # L B60 sign-extends $80: -128; zero extension gives 128
        "D68": 255,     # L W50 sign-extends from bit 15, which is 0 here: 255, not -1
    }


def test_fast_code_shifts_by_hand(tmp_path: Path) -> None:
    m = fast_machine(tmp_path, """
        L   K$3E
        <<  K4
        =   D0
        L   K-16
        >>  K2
        =   D4
        L   K1
        <<  K33
        =   D8
        L   K$40000000
        <<  K1
        =   D12
        L   K$7FFFFFFF
        <<  K4
        =   D16
        EM
    """)
    cycles(m, 1)
    assert values(m, "D0", "D4", "D8", "D12", "D16") == {
        "D0": 0x3E0,         # the description's own example (6.7)
        "D4": -4,            # >> is arithmetic: -16 >> 2 = -4; a logical shift gives 1073741820
        "D8": 2,             # the count is taken mod 32 (6.7): << 33 is << 1; a 64-bit shift gives 0 or 2^33
        "D12": -2147483648,  # the result is the low 32 bits as int32: $80000000; an unbounded int gives 2^31
        "D16": -16,          # $7FFFFFFF << 4 = $7FFFFFFF0, low 32 bits $FFFFFFF0 = -16; saturation gives 2^31-1
    }


def test_fast_code_brackets_by_hand(tmp_path: Path) -> None:
    m = fast_machine(tmp_path, """
        L   I1
        A[
        L   I2
        O   I3
        ]
        =   O1
        L   K15000
        -[
        L   K4000
        +   K6000
        ]
        =   W0
        L   D12
        ==[
        L   K100
        x   D16
        ]
        =   O15
        L   K$FF00
        A[
        L   K$0FF0
        ]
        =   W2
        L   K10
        -[
        L   K1
        +[
        L   K2
        x   K3
        ]
        ]
        =   W4
        EM
    """, given={"I1": 0, "I2": 0, "I3": 1, "D12": 500, "D16": 5})
    cycles(m, 1)
    assert values(m, "O1", "W0", "O15", "W2", "W4") == {
        "O1": 0,        # 0 AND (0 OR 1) = 0: a bracket that drops the saved LA (I1) gives 1
        "W0": 5000,     # 15000 - (4000 + 6000) (6.9 example): reversed operands give -5000, no bracket 10000
        "O15": 1,       # 500 == 100 * 5 (6.9 example): the saved WA is the left side of the comparison
        "W2": 0x0F00,   # word-mode A[ ANDs saved $FF00 with inner $0FF0 over 32 bits; no bracket gives $0FF0
        "W4": 3,        # nested: 10 - (1 + (2 * 3)) = 3; flattening the brackets gives 10 - 1 + 6 or 6
    }


def test_fast_code_timer_runs_exactly_its_preset_by_hand(tmp_path: Path) -> None:
    m = fast_machine(tmp_path, """
        L   I1
        =   T2
        L   T50
        =   O1
        L   T2
        =   O2
        L   I1
        =   T3
        L   T51
        =   O3
        EM
    """, mp={"4110.2": 2, "4110.3": 0})
    trace = fast_trace(m, 5, ("O1", "O2", "O3"), {"I1": [1, 0, 0, 0, 0]})
    assert trace == {
        # T2 is set in cycle 0; the service of cycles 1..P (P = MP4110.2 = 2 cycles in `tv`) keeps T50 at 1 (9.2):
        # a timer that starts in the cycle it is set gives [1, 1, 0, ...], one that counts P+1 gives [0, 1, 1, 1, 0]
        "O1": [0, 1, 1, 0, 0],
        # the start operand reads back as 1 in the cycle the program set it and is then consumed (9.2)
        "O2": [1, 0, 0, 0, 0],
        # preset 0: the running operand never becomes 1 (9.2)
        "O3": [0, 0, 0, 0, 0],
    }


@pytest.mark.parametrize("coverage", [False, True])
def test_dispatch_without_the_tests_that_always_hold_by_hand(tmp_path: Path, coverage: bool) -> None:
    # IF/ELSE by jumps (the ELSE block is tested, the join after it is not: b can only be its number there),
    # a forward jump over two blocks, a loop; every path checked against values worked out by hand
    program = """
        L   K0
        =   W0
        L   I1
        JPF ELSE
        L   K1
        =   W0
        JP  JOIN
        LBL ELSE
        L   K2
        =   W0
        LBL JOIN
        L   W0
        +   K10
        =   W2
        L   I2
        JPT OVER
        L   K100
        =   W4
        LBL SKIPPED
        L   K200
        =   W6
        LBL OVER
        L   K0
        =   X
        =   W8
        LBL LOOP
        L   W8
        +   K3
        =   W8
        INCX
        L   X
        <   K4
        JPT LOOP
        EM
    """
    prog = compile_text(tmp_path, program)
    code = compile_program(prog, coverage=coverage, exact=False)
    assert code.source.count("if b == ") < 6            # 6 blocks (the start and 5 labels): some tests went
    for i1, i2, expected in ((1, 0, (1, 11, 100, 200, 12)), (0, 0, (2, 12, 100, 200, 12)),
                             (0, 1, (2, 12, 0, 0, 12))):
        m = Machine(prog, compiled=code, coverage=coverage)
        assert not cycles(m, 1, {"I1": [i1], "I2": [i2]})[0].faults
        assert tuple(values(m, "W0", "W2", "W4", "W6", "W8").values()) == expected
