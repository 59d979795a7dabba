"""Assumption switches that the public vectors cannot tell apart: each one changes the result of an own program."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.test_interp import compile_text, cycles, fault_of, machine, ref, values, with_setting
from transpiler.exec.interp import Machine, MachineConfigError
from transpiler.language.semantics import make_semantics


def _trace(m: Machine, count: int, names: tuple[str, ...], inputs: dict[str, list] | None = None) -> dict[str, list]:
    trace: dict[str, list] = {n: [] for n in names}
    for c in range(count):
        writes = [(*ref(n), v[c]) for n, v in (inputs or {}).items()]
        assert not m.run_cycle(c, writes).faults
        for n in names:
            trace[n].append(m.read(*ref(n)))
    return trace


def _after_one_cycle(folder: Path, program: str, names: tuple[str, ...], **kwargs: Any) -> dict[str, Any]:
    """Values of `names` after cycle 0 of `program` on a machine built with `kwargs` (see test_interp.machine)."""
    m = machine(folder, program, **kwargs)
    cycles(m, 1)
    return values(m, *names)


TIMER_SET_ONCE = """
    L   I1
    S   T0          ; set once, never reset by the program
    L   T0
    =   M1          ; read-back of the start operand
    L   T48
    =   O1
    EM
"""


@pytest.mark.parametrize("consumed, m1, o1", [
    (True, [1, 0, 0, 0, 0], [0, 1, 1, 0, 0]),
    (False, [1, 1, 1, 1, 1], [0, 1, 1, 1, 1]),     # a level start restarts the timer every cycle
])
def test_timer_start_consumed(tmp_path: Path, consumed: bool, m1: list, o1: list) -> None:
    m = machine(tmp_path, TIMER_SET_ONCE, overrides={"timer_start_consumed": consumed}, mp={"4110.0": 2})
    assert _trace(m, 5, ("M1", "O1"), {"I1": [1, 0, 0, 0, 0]}) == {"M1": m1, "O1": o1}


COUNTER_SET_ONCE = """
    L   I1
    S   C0
    LN  M0
    =   C96         ; released in every cycle
    L   C0
    =   M1
    L   C48
    =   O1
    EM
"""


@pytest.mark.parametrize("consumed, m1, o1", [
    (True, [1, 0, 0, 0, 0], [0, 1, 1, 0, 0]),
    (False, [1, 1, 1, 1, 1], [0, 1, 1, 1, 1]),
])
def test_counter_start_consumed(tmp_path: Path, consumed: bool, m1: list, o1: list) -> None:
    m = machine(tmp_path, COUNTER_SET_ONCE, overrides={"counter_start_consumed": consumed}, mp={"4120.0": 2})
    assert _trace(m, 5, ("M1", "O1"), {"I1": [1, 0, 0, 0, 0]}) == {"M1": m1, "O1": o1}


def test_index_scaling(tmp_path: Path) -> None:
    program = """
        L   K2
        =   X
        L   K$1234
        =   W10[X]
        L   K1
        =   X
        L   K7
        =   D0[X]
        EM
    """
    m = machine(tmp_path / "bytes", program)
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line) == ("E-RT-ALIGN", 8)     # D0 + 1 byte is misaligned
    assert values(m, "W12", "W14") == {"W12": 0x1234, "W14": 0}
    m = machine(tmp_path / "elements", program, overrides={"index_scaling": "elements"})
    assert not cycles(m, 1)[0].faults
    assert values(m, "W12", "W14", "D4") == {"W12": 0, "W14": 0x1234, "D4": 7}


def test_index_read_check(tmp_path: Path) -> None:
    program = """
        L   K10000
        =   X
        L   B0[X]
        =   W2
        EM
    """
    m = machine(tmp_path / "checked", program, given={"W2": 5})
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line) == ("E-RT-INDEX", 3)
    m = machine(tmp_path / "unchecked", program, overrides={"index_read_check": False}, given={"W2": 5})
    assert not cycles(m, 1)[0].faults
    assert m.read("W", 2) == 0


def test_store_saturation(tmp_path: Path) -> None:
    program = """
        L   K300
        =   B0
        L   K-40000
        =   W2
        L   K-200
        =   B4
        EM
    """
    names = ("B0", "W2", "B4")
    assert _after_one_cycle(tmp_path / "truncate", program, names) == {"B0": 44, "W2": 25536, "B4": 56}
    assert _after_one_cycle(tmp_path / "saturate", program, names, overrides={"store_truncation": "saturate"}) == {
        "B0": 127, "W2": -32768, "B4": -128}


def test_bracket_width(tmp_path: Path) -> None:
    program = """
        L   K$1FF
        ==[
        L   B0
        ]
        =   M1
        L   K$1200
        O[
        L   B0
        ]
        =   D4
        EM
    """
    names = ("M1", "D4")
    assert _after_one_cycle(tmp_path / "32", program, names, given={"B0": 0xFF}) == {"M1": 0, "D4": -1}
    # make_semantics rejects 'operand' for this integer-typed key, so the setting is placed directly
    sem = make_semantics("tv")
    sem = type(sem)(sem.profile, {**sem.values, "bracket_width": "operand"})
    assert _after_one_cycle(tmp_path / "operand", program, names, semantics=sem, given={"B0": 0xFF}) == {
        "M1": 1, "D4": 0x12FF}


def test_index_register_width(tmp_path: Path) -> None:
    program = """
        L   K$12345
        =   X
        L   X
        =   D0
        L   K$18000
        =   X
        L   X
        =   D4
        EM
    """
    assert _after_one_cycle(tmp_path / "32", program, ("D0", "D4")) == {"D0": 0x12345, "D4": 0x18000}
    m = machine(tmp_path / "16", program, overrides={"index_register_width": 16})
    cycles(m, 1)
    assert values(m, "D0", "D4") == {"D0": 0x2345, "D4": -32768}
    m.write("X", 0, 0x18001)             # a write from outside wraps like one by the program
    assert m.read("X") == -32767


def test_psx_width(tmp_path: Path) -> None:
    program = """
        L   K7
        =   X
        PSX
        PSX
        PL  D0
        EM
    """
    m = machine(tmp_path / "32", program)
    report = cycles(m, 1)[0]
    assert m.read("D", 0) == 7 and [w.code for w in report.warnings] == ["E-RT-STACK-LEFTOVER"]
    m = machine(tmp_path / "16", program, overrides={"psx_width": 16})
    report = cycles(m, 1)[0]
    assert m.read("D", 0) == 0x00070007 and not report.warnings


def test_div_min_by_minus_one(tmp_path: Path) -> None:
    program = """
        L   K-2147483648
        /   K-1
        =   D0
        L   M4201
        =   M1
        L   K-2147483648
        MOD K-1
        =   D4
        L   M4202
        =   M2
        EM
    """
    names = ("D0", "M1", "D4", "M2")
    assert _after_one_cycle(tmp_path / "no_flag", program, names) == {"D0": -2147483648, "M1": 0, "D4": 0, "M2": 0}
    assert _after_one_cycle(tmp_path / "flag", program, names, overrides={"div_min_by_minus_one": "flag"}) == {
        "D0": -2147483648, "M1": 1, "D4": 0, "M2": 1}


@pytest.mark.parametrize("line, program", [
    (2, "L   K1\n<<  K33\n=   D0\nEM\n"),
    (2, "L   K$40000000\n<<  K1\n=   D0\nEM\n"),
    (2, "L   K-16\n>>  K-1\n=   D0\nEM\n"),
])
def test_shift_fault(tmp_path: Path, line: int, program: str) -> None:
    assert not cycles(machine(tmp_path / "mod32", program), 1)[0].faults
    m = machine(tmp_path / "fault", program, overrides={"shift_semantics": "fault"})
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line) == ("E-RT-SHIFT", line)


def test_add_overflow_flag_only_on_overflow(tmp_path: Path) -> None:
    program = """
        L   K-2147483648
        -   K1
        =   D0
        L   M4200
        =   M1
        L   K5
        +   K1
        =   D4
        EM
    """
    assert _after_one_cycle(tmp_path / "wrap", program, ("D0", "M1", "M4200")) == {
        "D0": 2147483647, "M1": 0, "M4200": 0}
    assert _after_one_cycle(tmp_path / "flag", program, ("D0", "M1", "D4", "M4200"),
                            overrides={"add_overflow": "flag"}) == {"D0": 2147483647, "M1": 1, "D4": 6, "M4200": 1}


def test_case_out_of_range_fault(tmp_path: Path) -> None:
    program = """
        CASE B0
        CM  C0
        ENDC
        EM
        LBL C0
        EM
    """
    for selector in (0, -1):
        m = machine(tmp_path / f"skip{selector}", program, given={"B0": selector})
        assert not cycles(m, 1)[0].faults
    m = machine(tmp_path / "fault", program, overrides={"case_out_of_range": "fault"}, given={"B0": -1})
    fault = fault_of(cycles(m, 1))
    assert (fault.code, fault.span.line) == ("E-RT-INDEX", 1)


def test_timer_unit(tmp_path: Path) -> None:
    program = "L   I1\n=   T0\nL   T48\n=   O1\nEM\n"
    seconds = machine(tmp_path / "s", program, profile="itnc530", mp={"4110.0": "0.06"})
    assert _trace(seconds, 5, ("O1",), {"I1": [1, 0, 0, 0, 0]})["O1"] == [0, 1, 1, 1, 0]
    cycles_unit = machine(tmp_path / "c", program, profile="itnc530", overrides={"timer_unit": "cycles"},
                          mp={"4110.0": 2})
    assert _trace(cycles_unit, 5, ("O1",), {"I1": [1, 0, 0, 0, 0]})["O1"] == [0, 1, 1, 0, 0]
    prog = compile_text(tmp_path / "bad", program, "itnc530", {"timer_unit": "cycles"})
    with pytest.raises(MachineConfigError):
        Machine(prog, {"4110.0": "0.06"})


def test_submit_model_next_cycle_reply_states(tmp_path: Path) -> None:
    program = """
        L   M4172
        JPF LATER
        SUBM JOB
        =   W0
        LBL LATER
        RPLY W0
        =   W2
        EM
        LBL JOB
        L   W4
        +   K1
        =   W4
        EM
    """
    same = machine(tmp_path / "same", program)
    assert _trace(same, 3, ("W2", "W4")) == {"W2": [2, 0, 0], "W4": [1, 1, 1]}
    later = machine(tmp_path / "next", program, overrides={"submit_model": "next_cycle"})
    assert _trace(later, 3, ("W2", "W4")) == {"W2": [2, 2, 0], "W4": [0, 1, 1]}


def test_cycle_time_from_semantics_and_machine(tmp_path: Path) -> None:
    program = "L   I1\n=   T0\nL   T48\n=   O1\nEM\n"
    prog = compile_text(tmp_path, program, "itnc530", {"cycle_time_ms": 40})
    slow = Machine(prog, {"4110.0": "0.08"})                    # 80 ms / 40 ms = 2 cycles
    assert _trace(slow, 4, ("O1",), {"I1": [1, 0, 0, 0]})["O1"] == [0, 1, 1, 0]
    fast = Machine(prog, {"4110.0": "0.08"}, cycle_time_ms=20)  # the scenario's cycle time wins: 4 cycles
    assert _trace(fast, 6, ("O1",), {"I1": [1, 0, 0, 0, 0, 0]})["O1"] == [0, 1, 1, 1, 1, 0]


def test_call_depth_is_checked_at_run_time(tmp_path: Path) -> None:
    prog = compile_text(tmp_path, "CM  A1\nEM\nLBL A1\nEM\n")
    assert not cycles(Machine(prog), 1)[0].faults
    fault = fault_of(cycles(Machine(with_setting(prog, call_depth=0)), 1))
    assert (fault.code, fault.span.line) == ("E-RT-CALL-DEPTH", 1)
