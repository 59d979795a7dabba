"""The condition vectors a decision can see on the paths of the cycle that come to it (verify/cycle_paths.py): a
step chain whose abort sets the step word before its CASE keeps the step subprograms from seeing the abort's
condition, and nothing is claimed where a path, a write or a loop breaks that; every vector a run records from any
memory state is among the ones found."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from transpiler.exec.interp import Machine, compile_program
from transpiler.exec.interp.decisions import decision_table
from transpiler.exec.interp.faults import MachineHalted
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics
from transpiler.verify.cycle_paths import Runner, Word, seen_vectors
from transpiler.verify.mcdc import decision_coverage
from transpiler.verify.simulate import program_operands

ROOT = Path(__file__).resolve().parents[1]

# B10 is a step word: 0 idle, 1 and 2 working, 3 aborted (Idle starts step 1 whatever M2 is). M1: a step is running; M2 (the control voltage, from I5)
# off aborts a running step before the CASE, so Work and Work2 never run with M2 = 0, and neither does the chain
# after the CASE that asks for a working step. {abort} is the abort request, {between} code between it and the CASE.
_STEPS = """L I5
= M2
L B10
<> K0
A[
L B10
<> K3
]
= M1
L I1
ON M2
A M1
{abort}IFT
L K3
= B10
ENDI
{between}CASE B10
CM Idle
CM Work
CM Work2
CM Abort
ENDC
L B10
>= K2
A[
L B10
<= K2
]
A M2
= O3
EM
LBL Idle
L I2
JPF Idle_wait
L K1
= B10
LBL Idle_wait
EM
LBL Work
L M2
A I3
= O1
L I4
JPF Work_wait
L K2
= B10
LBL Work_wait
EM
LBL Work2
L I3
A M2
= O2
L I6
IFT
L K0
= B10
ENDI
EM
LBL Abort
L I2
JPT Abort_wait
L K0
= B10
LBL Abort_wait
EM
"""


def _program(folder: Path, text: str, **semantics):
    (folder / "main.src").write_text(text)
    result = compile_project(ProjectOptions(main=folder / "main.src"), make_semantics("itnc530", semantics))
    assert result.ok
    return result.program


def _items(program) -> dict[tuple[str, str], object]:
    cov = decision_coverage(program, [])
    return {(i.condition.text, i.decision.op.operand.display()): i for i in cov.conditions
            if i.decision.op.operand is not None}


def test_an_abort_before_the_case_keeps_its_condition_from_the_steps(tmp_path: Path) -> None:
    # M2 = 0 with a step running sets B10 to 3 before the CASE: Work (O1), Work2 (O2) and the chain after the CASE
    # that asks for step 2 (O3: only Work sets it) never see M2 = 0. The reason names the start of the paths.
    # Catches: the CASE taken on an entry the step word cannot hold, the IFT's not-taken way losing what it says.
    program = _program(tmp_path, _STEPS.format(abort="", between=""))
    items = _items(program)
    for output in ("O1", "O2", "O3"):
        item = items[("M2", output)]
        assert item.status == "infeasible", (output, item)
        assert "on every path of the cycle to this chain, followed from the start of the main program (main.src:1:1)" in item.reason
        assert output == "O3" or "M2 is always 1" in item.reason
    # the other conditions of those chains are not claimed
    assert items[("I3", "O1")].status == "missing" and items[("I3", "O2")].status == "missing"


@pytest.mark.parametrize("abort, between", [
    ("A I7\n", ""),                     # the abort needs another input too: M2 = 0 may leave the step running
    ("", "L I8\n= M2[X]\n"),            # an indexed marker write between: M2 may be anything at the steps
    ("", "L I8\n= M2\n"),               # M2 written again between
    ("", "L W20\n= B10\n"),             # the step word overwritten from a word the run does not know
    ("", "PS K40\nPS K0\nCM 9040\n"),    # a PLC module that writes to an address it is given
    ("", "LBL Again\nL I9\nJPT Again\n"),   # a loop before the CASE: the run gives up
], ids=["abort_needs_more", "indexed_write", "rewritten", "step_from_word", "module", "loop"])
def test_a_path_or_write_that_breaks_it_leaves_the_condition_missing(tmp_path: Path, abort: str, between: str) -> None:
    # Catches: a claim where M2 = 0 can reach a working step, or where the run cannot know.
    program = _program(tmp_path, _STEPS.format(abort=abort, between=between))
    items = _items(program)
    assert items[("M2", "O1")].status == "missing", items[("M2", "O1")]
    assert items[("M2", "O3")].status == "missing", items[("M2", "O3")]


def test_a_subprogram_not_joined_may_leave_wa_changed(tmp_path: Path) -> None:
    # Sub loads K5 and loops (its paths are not joined); it writes no memory, but the caller stores the WA it returns
    # with: B10 = 5 reaches the chain. Catches: WA kept over a call whose subprogram was not followed.
    program = _program(tmp_path, "L K0\nCM Sub\n= B10\nL B10\n== K5\nA I2\n= O1\nEM\n"
                                 "LBL Sub\nL K5\nLBL Lp\nL M5\nJPT Lp\nEM\n")
    assert _check_recorded(program, _random_memory_runs(program, 10, 30, 3)) >= 1
    assert _items(program)[("B10 == K5", "O1")].status == "missing"


def test_a_negative_value_stored_under_saturation_loads_back_negative(tmp_path: Path) -> None:
    # A-08 saturate: `L K-1` `= B10` stores -1 (within the byte's range), and `L B10` loads -1 again, so the compare
    # is always 1. Catches: the clamped bit pattern (255) kept as the byte's value.
    program = _program(tmp_path, "L K-1\n= B10\nL B10\n== K-1\nA I2\n= O1\nL K-300\n= B12\nL B12\n== K-128\n"
                                 "A I2\n= O2\nEM\n", store_truncation="saturate")
    runner = Runner(program)
    for decision in decision_table(program).decisions:
        assert seen_vectors(runner, decision).vectors == {1, 3}, decision.text()
    assert _check_recorded(program, _random_memory_runs(program, 4, 5, 3)) == 2


def test_a_subprogram_called_from_two_places_starts_its_own_runs(tmp_path: Path) -> None:
    # Work is called by the CASE and once more after it, from code where B10 and M2 are anything: the run starts
    # at the main program's code that makes both calls, and the second call sees M2 = 0.
    program = _program(tmp_path, _STEPS.format(abort="", between="").replace("= O3\nEM\n", "= O3\nCM Work\nEM\n", 1))
    assert _items(program)[("M2", "O1")].status == "missing"


_GROUP = """CM Decode
CM Module
CM Ack
EM
LBL Decode
LN I1
IFT
L K0
W= M100
ENDI
L I1
AN M50
= M51
L I1
= M50
L M51
EMF
L I2
S M101
EM
LBL Module
{done}EM
LBL Ack
L I1
A[
L M100
O M120
]
= O1
EM
"""


@pytest.mark.parametrize("done, claimed", [("L M101\nA I3\n= M120\n", True), ("L I3\n= M120\n", False)],
                         ids=["done_from_pending", "done_from_an_input"])
def test_a_group_cleared_without_the_strobe_is_followed_through_the_modules(tmp_path: Path, done: str,
                                                                             claimed: bool) -> None:
    # Without the strobe I1, Decode clears the pending markers M100..M115 (W=), and Module's done marker M120 is
    # a pending one ANDed with an input: Ack's chain never sees I1 = 0 with M100 OR M120 = 1. Decode and Module
    # cannot reach the chain: they are run with their paths joined, and the path calling Decode splits on I1,
    # which it reads first. A done marker from an input alone breaks it. Catches: W= not followed, a joined
    # subprogram losing the chain's bit, the split made after the call.
    program = _program(tmp_path, _GROUP.format(done=done))
    item = _items(program)[("I1", "O1")]
    assert (item.status == "infeasible") == claimed, item
    if claimed:
        assert "on every path of the cycle to this chain" in item.reason
    assert _check_recorded(program, _random_memory_runs(program, 6, 30, 5)) > 0


def test_words_narrowed_by_compares() -> None:
    word = Word(-128, 127)
    yes, no = word.split("<>", 0)
    assert no == Word(0, 0) and yes.holds(5) and not yes.holds(0)
    low, high = yes.split("<", 3)
    assert (low.lo, low.hi) == (-128, 2) and not low.holds(0) and high == Word(3, 127)
    assert Word(4, 4).split("==", 4) == (Word(4, 4), None)
    assert Word(3, 5, frozenset({4})).split(">=", 4) == (Word(5, 5), Word(3, 3))


def _random_memory_runs(program, runs: int, cycles: int, seed: int) -> list[Machine]:
    """Runs in which every named marker, input, output and word is set at random before each cycle (any state a
    cycle can start from)."""
    used = sorted(program_operands(program)[0], key=lambda r: (r.kind, r.addr))
    bits = [(r.kind, r.addr) for r in used if r.kind in "MIO"]
    words = [(r.kind, r.addr) for r in used if r.kind in "BWD"]
    rng = random.Random(seed)
    compiled = compile_program(program, coverage=True)
    machines = []
    for _ in range(runs):
        machine = Machine(program, compiled=compiled, coverage=True)
        try:
            for cycle in range(cycles):
                writes = [(k, a, rng.randrange(2)) for k, a in bits if rng.random() < 0.5]
                writes += [(k, a, rng.choice((-1, 0, 1, 2, 3, 4, 5, 8, 13, 16, 17, 100, rng.randrange(-3, 30))))
                           for k, a in words if rng.random() < 0.5]
                machine.run_cycle(cycle, writes)
        except MachineHalted:       # a fault the memory provokes: what ran until then counts
            pass
        machines.append(machine)
    return machines


def _check_recorded(program, machines, files: frozenset[str] | None = None) -> int:
    runner = Runner(program)
    checked = 0
    for decision in decision_table(program).decisions:
        if files is not None and Path(program.files[decision.file].path).name not in files:
            continue
        seen = seen_vectors(runner, decision)
        if seen is None:
            continue
        mask = (1 << len(decision.conditions)) - 1
        recorded = {v & mask for m in machines for v in m.coverage.vectors.get(decision.key, ())}
        assert recorded <= seen.vectors, (decision.text(), sorted(recorded - seen.vectors))
        checked += bool(recorded)
    return checked


def test_recorded_vectors_from_any_memory_are_among_the_ones_found(tmp_path: Path) -> None:
    # Soundness on the step chain and its breaking variants: the run assumes nothing about the memory a cycle
    # starts from, so every vector recorded from random memory must be among those it finds.
    for abort, between in (("", ""), ("A I7\n", ""), ("", "L I8\n= M2[X]\n")):
        program = _program(tmp_path, _STEPS.format(abort=abort, between=between))
        assert _check_recorded(program, _random_memory_runs(program, 10, 30, 3)) >= 5


@pytest.mark.parametrize("project", ["basic_program", *sorted(p.name for p in (ROOT / "samples" / "constructs").iterdir()
                                                               if p.is_dir())])
def test_recorded_vectors_of_the_samples_are_among_the_ones_found(project: str) -> None:
    # Catches: any op followed wrongly (stack, brackets, calls, CASE, indexed writes, module calls) on real code.
    folder = ROOT / "samples" / (project if project == "basic_program" else f"constructs/{project}")
    main = folder / ("Main_PGM.src" if project == "basic_program" else "main.src")
    result = compile_project(ProjectOptions(main=main), make_semantics("itnc530", {}))
    if not result.ok:
        pytest.skip("the project needs options this test does not give")
    # the sample: its step chains (every chain of it takes the analysis half a minute)
    files = frozenset({"Toolaut1.src", "Mfunction.src", "Chip_conveyor.src"}) if project == "basic_program" else None
    assert _check_recorded(result.program, _random_memory_runs(result.program, 8, 40, 7), files) > 0 or \
        not decision_table(result.program).decisions
