"""Coverage recorded by the interpreter's fast variant (marks per straight-line stretch, pre-counted watchdog)
is the exact variant's (a mark per op, counted per instruction), and Machine's public accessors of branch
outcomes agree with its coverage."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from transpiler.exec.interp import Machine, compile_program
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics

ROOT = Path(__file__).resolve().parents[1]
PROJECTS = [ROOT / "samples" / "basic_program" / "Main_PGM.src",
            ROOT / "samples" / "constructs" / "indexed" / "main.src",
            ROOT / "samples" / "constructs" / "jumps_loop" / "main.src",
            ROOT / "samples" / "constructs" / "case_chain" / "main.src",
            ROOT / "samples" / "constructs" / "calls_cmt_cmf" / "main.src",
            ROOT / "samples" / "constructs" / "submit_jobs" / "main.src"]


def _program(main: Path):
    result = compile_project(ProjectOptions(main=main), make_semantics("itnc530", {}))
    assert result.ok
    return result.program


def _run(program, exact: bool, seed: int, cycles: int) -> Machine:
    machine = Machine(program, compiled=compile_program(program, coverage=True, exact=exact), coverage=True)
    rng = random.Random(seed)
    for cycle in range(cycles):
        writes = [("I", rng.randrange(64), rng.randrange(2)) for _ in range(3)]
        report = machine.run_cycle(cycle, writes)
        if report.faults:
            break
    return machine


@pytest.mark.parametrize("main", PROJECTS, ids=lambda p: p.parent.name)
def test_fast_coverage_is_the_exact_coverage(main: Path) -> None:
    program = _program(main)
    for seed in (1, 2):
        fast, exact = _run(program, False, seed, 300), _run(program, True, seed, 300)
        assert fast.coverage.branches == exact.coverage.branches
        # a faulting cycle may leave the ops of its last stretch unmarked in the fast variant, never more
        assert fast.coverage.executed <= exact.coverage.executed
        if not fast.halted:
            assert fast.coverage.executed == exact.coverage.executed
        assert fast.coverage.executed, "nothing recorded"


def test_branch_outcome_accessors_follow_the_run() -> None:
    program = _program(PROJECTS[0])
    machine = Machine(program, compiled=compile_program(program, coverage=True, exact=False), coverage=True)
    counts = []
    for cycle in range(50):
        machine.run_cycle(cycle, [("I", cycle % 64, cycle & 1)])
        counts.append(machine.branch_outcome_count)
    assert counts == sorted(counts) and counts[-1] > 0

    outcomes = machine.branch_outcomes()
    assert len(outcomes) == counts[-1]
    index = compile_program(program, coverage=True).op_index
    assert {(index[op], outcome) for op, outcome in outcomes} == \
        {(at, outcome) for at, seen in machine.coverage.branches.items() for outcome in seen}

def test_coverage_alone_still_means_the_exact_variant() -> None:
    program = _program(PROJECTS[2])
    assert compile_program(program, coverage=True).exact
    assert not compile_program(program, coverage=True, exact=False).exact


def test_boundaries_mark_compares_whose_operands_come_out_equal_or_one_apart(tmp_path: Path) -> None:
    # Catches: a wrong slot for a difference (off by one), a signed compare marked on the unsigned values, marks
    # without coverage, a branch figure that counts them, compares counted by the value profile twice.
    (tmp_path / "main.src").write_text("L     W10\n>     K100\n=     M1\nL     B20\n<     K-5\n=     M2\nEM\n")
    program = _program(tmp_path / "main.src")
    plain = Machine(program, compiled=compile_program(program, coverage=True, exact=False), coverage=True)
    machine = Machine(program, compiled=compile_program(program, coverage=True, exact=False, value_profile=True),
                      coverage=True)
    bare = Machine(program, compiled=compile_program(program), coverage=False)
    seen = []
    for cycle, (w10, b20) in enumerate([(0, 0), (101, 0), (100, -6), (99, -5), (102, -4)]):
        for m in (plain, machine, bare):
            m.write("W", 10, w10)
            m.write("B", 20, b20)
            m.run_cycle(cycle, [])
        seen.append(machine.boundary_outcomes())
        assert plain.boundary_outcomes() == seen[-1]
    cmp_w, cmp_b = 1, 4                       # op ids of the two compares
    assert seen[0] == frozenset()
    assert seen[1] == {(cmp_w, 1)}
    assert seen[2] == {(cmp_w, 1), (cmp_w, 0), (cmp_b, -1)}
    assert seen[4] == {(cmp_w, d) for d in (-1, 0, 1)} | {(cmp_b, d) for d in (-1, 0, 1)}
    assert machine.boundary_outcome_count == 6 and bare.boundary_outcome_count == 0
    assert machine.value_outcome_count == 0
    assert machine.branch_outcome_count == plain.branch_outcome_count


def test_value_profile_marks_the_pairs_a_bit_gate_combines(tmp_path: Path) -> None:
    # Catches: the mark of the wrong op, LA taken after the gate instead of before, an inverted operand (ON) marked
    # before its inversion, pairs marked on which AND and OR agree.
    (tmp_path / "main.src").write_text("L     I1\nA     I2\n=     O1\nL     I1\nON    I2\n=     O2\nEM\n")
    program = _program(tmp_path / "main.src")
    machine = Machine(program, compiled=compile_program(program, coverage=True, exact=False, value_profile=True),
                      coverage=True)
    for cycle, (i1, i2) in enumerate([(1, 0), (0, 0)]):
        machine.run_cycle(cycle, [("I", 1, i1), ("I", 2, i2)])
    and_op, or_op = 1, 4
    # (1, 0): AND sees LA 1 and I2 0 (they differ: marked); ON sees LA 1 and NOT I2 = 1 (equal). (0, 0): AND 0/0
    # (equal); ON sees LA 0 and 1 (marked).
    assert machine.value_outcomes() == {(and_op, 1), (or_op, 0)}


def test_value_profile_marks_zero_and_non_zero_divisors(tmp_path: Path) -> None:
    # The translation checks a run-time divisor for 0 where the original has no branch: the profile makes both
    # outcomes features. Catches: the dividend marked instead of the divisor.
    (tmp_path / "main.src").write_text("L     W10\n/     W12\n=     W14\nL     W10\nMOD   W12\n=     W16\nEM\n")
    program = _program(tmp_path / "main.src")
    machine = Machine(program, compiled=compile_program(program, coverage=True, exact=False, value_profile=True),
                      coverage=True)
    seen = []
    for cycle, (w10, w12) in enumerate([(5, 0), (0, 3)]):
        machine.write("W", 10, w10)
        machine.write("W", 12, w12)
        machine.run_cycle(cycle, [])
        seen.append(machine.value_outcomes())
    div_op, mod_op = 1, 4
    assert seen == [{(div_op, 0), (mod_op, 0)}, {(div_op, 0), (mod_op, 0), (div_op, 1), (mod_op, 1)}]
