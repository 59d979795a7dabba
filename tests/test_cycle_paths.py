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
from transpiler.verify.cycle_paths import Runner, Word, seen_vectors, start_relations
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
    ("", "LBL Again\nL I9\n= M2\nL I8\nJPT Again\n"),   # a loop before the CASE that writes M2
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
    recorded: dict = {}
    for machine in machines:
        for key, found in machine.coverage.vectors.items():
            recorded.setdefault(key, set()).update(found)
    return _check_vectors(program, recorded, files)


def _check_vectors(program, recorded: dict, files: frozenset[str] | None = None, runner: Runner | None = None) -> int:
    """Asserts that every vector `recorded` (decision key -> vectors) of a decision in `files` (None: all) is among
    those the run finds; the number of decisions checked with at least one vector."""
    runner = runner or Runner(program)
    checked = 0
    for decision in decision_table(program).decisions:
        if files is not None and Path(program.files[decision.file].path).name not in files:
            continue
        seen = seen_vectors(runner, decision)
        if seen is None:
            continue
        mask = (1 << len(decision.conditions)) - 1
        got = {v & mask for v in recorded.get(decision.key, ())}
        assert got <= seen.vectors, (decision.text(), sorted(got - seen.vectors))
        checked += bool(got)
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


# B10 is a step word (0 idle, 1 orient) that only Steps writes; Steps recomputes M1 = (B10 <> 0) at its end, in
# every cycle, and nothing writes B10 or M1 after that. Spin runs before Steps: the spindle O1 runs only with no step
# active (AN M1), so in Orient (step 1) O1 is 0 in every cycle but the first (M1 there is what the last cycle left:
# B10 <> 0). In the first cycle (M4172) Init sets the step to 0 first: {first} is the first-cycle code, {after} code
# after Steps.
_FLAG = """{first}CM Spin
CM Steps
{after}EM
LBL Init
L K0
= B10
EM
LBL Spin
L I1
AN M1
= O1
EM
LBL Steps
CASE B10
CM Idle
CM Orient
ENDC
{skip}L B10
<> K0
= M1
EM
LBL Idle
L I2
JPF Idle_w
L K1
= B10
LBL Idle_w
EM
LBL Orient
L I3
AN O1
= O2
L I4
JPF Or_w
L K0
= B10
LBL Or_w
EM
"""
_INIT = "L M4172\nCMT Init\n"


def _flag_program(tmp_path: Path, first: str = _INIT, after: str = "", skip: str = ""):
    return _program(tmp_path, _FLAG.format(first=first, after=after, skip=skip))


def test_a_flag_the_step_chain_recomputes_every_cycle_holds_at_the_next_start(tmp_path: Path) -> None:
    # Catches: the relation not found, not assumed at the main program's start, or not named in the reason.
    program = _flag_program(tmp_path)
    relations = start_relations(program, set())
    assert [(r.flag, r.word, r.rel, r.constant) for r in relations] == [(("M", 1), ("B", 10), "<>", 0)]
    item = _items(program)[("O1", "O2")]
    assert item.status == "infeasible", item
    assert "M1 = (B10 <> 0) at the start of every cycle but the first" in item.reason
    assert "the first cycle followed from any memory with the first-cycle marker M4172 = 1" in item.reason
    assert "O1 is always 0" in item.reason
    assert _items(program)[("I3", "O2")].status == "missing"
    # an operand a scenario sets only at power-on does not break it; one set later does
    assert decision_coverage(program, [], driven={("M", 1), ("B", 10)}, power_on={("M", 1), ("B", 10)}
                             ).conditions and _status(program, {("M", 1), ("B", 10)}, {("M", 1), ("B", 10)}) == \
        "infeasible"
    assert _status(program, {("M", 1)}, set()) == "missing"
    assert _status(program, {("W", 10)}, set()) == "missing"     # a word sharing the step word's byte


def _status(program, driven: set, power_on: set) -> str:
    cov = decision_coverage(program, [], driven=driven, power_on=power_on)
    return next(i.status for i in cov.conditions if i.condition.text == "O1" and
                i.decision.op.operand is not None and i.decision.op.operand.display() == "O2")


@pytest.mark.parametrize("first, after, skip", [
    ("", "", ""),                               # no first-cycle reset: the power-on step word reaches Orient
    ("L M4172\nA I7\nCMT Init\n", "", ""),      # a reset only under another input in the first cycle
    ("CM Steps\n" + _INIT, "", ""),             # the step chain runs before the first cycle's reset
    (_INIT, "L I5\n= M1\n", ""),                # the flag written after its store
    (_INIT, "L I5\nIFT\nL K1\n= B10\nENDI\n", ""),   # the step word written after the flag's store
    (_INIT, "", "L I6\nEMT\n"),                 # the flag's store skipped on a path
    (_INIT, "L I5\n= M4172\n", ""),             # the program writes the first-cycle marker
], ids=["no_reset", "conditional_reset", "read_before_reset", "flag_rewritten", "word_rewritten", "store_skipped",
        "marker_written"])
def test_what_breaks_the_flag_relation_leaves_the_condition_missing(tmp_path: Path, first: str, after: str,
                                                                    skip: str) -> None:
    # Catches: a claim where a state the relation does not cover reaches Orient with O1 = 1.
    program = _flag_program(tmp_path, first, after, skip)
    assert _items(program)[("O1", "O2")].status == "missing"


def test_recorded_vectors_of_runs_are_among_the_ones_found_with_the_relations(tmp_path: Path) -> None:
    # Soundness: runs from random power-on memory (step word, flag, outputs) with random inputs every cycle, restarts
    # (M4172 again later) included: every vector recorded is among those the run from the relations finds.
    program = _flag_program(tmp_path)
    relations = start_relations(program, set())
    assert relations
    runner = Runner(program, relations)
    rng = random.Random(11)
    compiled = compile_program(program, coverage=True)
    recorded: dict = {}
    for _ in range(40):
        machine = Machine(program, compiled=compiled, coverage=True)
        for cycle in range(30):
            writes = [("I", n, rng.randrange(2)) for n in range(1, 8)]
            if cycle == 0:
                writes += [("B", 10, rng.choice((0, 1, 2))), ("M", 1, rng.randrange(2)), ("O", 1, rng.randrange(2))]
            elif rng.random() < 0.1:
                writes.append(("M", 4172, 1))       # the first-cycle code again (a restart without power-on)
            elif cycle > 1:
                writes.append(("M", 4172, 0))
            machine.run_cycle(cycle, writes)
        for key, found in machine.coverage.vectors.items():
            recorded.setdefault(key, set()).update(found)
    assert _check_vectors(program, recorded, runner=runner) >= 3


_LOOPED_INIT = """LBL Init
L K0
= B10
L K0
= X
LBL Again
L M0
= M200[X]
{inside}INCX
L X
< K4
JPT Again
EM
"""


@pytest.mark.parametrize("inside, claimed", [("", True), ("L X\n= B10\n", False), ("L I9\n= M1\n", True)],
                         ids=["loop_writes_markers", "loop_writes_the_step_word", "loop_writes_the_flag"])
def test_a_loop_in_a_joined_subprogram_forgets_only_what_it_writes(tmp_path: Path, inside: str,
                                                                   claimed: bool) -> None:
    # The first cycle's Init sets the step word to 0 and then clears markers in a loop: the run goes on after the
    # loop knowing B10 = 0 unless the loop writes B10. A loop that writes the flag M1 breaks the relation (a
    # restart, M4172 again, runs Init before Spin reads M1) but not the claim: that cycle's CASE runs Idle (B10 = 0),
    # and the states at the cycles' starts (cycle_states) show it. Catches: a loop run once only (its later passes
    # not covered), the whole subprogram forgotten.
    text = _FLAG.format(first=_INIT, after="", skip="").replace("LBL Init\nL K0\n= B10\nEM\n",
                                                                _LOOPED_INIT.format(inside=inside))
    program = _program(tmp_path, text)
    assert (_items(program)[("O1", "O2")].status == "infeasible") == claimed
    assert _check_recorded(program, _random_memory_runs(program, 6, 20, 4)) > 0


def test_recorded_vectors_of_the_sample_runs_are_among_the_ones_found_with_the_relations() -> None:
    # Every scenario of the sample (power-on states mid tool change, restarts, late first cycles) and a generated
    # search: each vector a step chain's decision recorded is among those the run from the sample's relations finds
    # (operands scenarios set after power-on break a relation, as in equiv). Catches: an unsound relation or start.
    from transpiler import api
    from transpiler.diagnostics import Diagnostics
    from transpiler.verify.guided import generate
    from transpiler.verify.mcdc import driven_operands, power_on_operands
    from transpiler.verify.scenario import load_scenario
    from transpiler.verify.simulate import build_machine, project_names, run_scenario
    sample = ROOT / "samples" / "basic_program"
    program = api.load_project(api.project_options(sample / "Main_PGM.src")).program
    names = project_names(program)
    compiled = compile_program(program, coverage=True)
    scenarios = [load_scenario(p, names) for p in sorted((sample / "scenarios").glob("*.yaml"))]
    scenarios += generate(program, names, 600, seed=6, seeds=scenarios, machine_parameters=sample / "MP_data.mp")
    relations = start_relations(program, driven_operands(scenarios, names) - power_on_operands(scenarios, names))
    assert any(r.names[0] == "MG_tc_active" for r in relations)
    recorded: dict = {}
    for scenario in scenarios:
        machine = build_machine(program, scenario, Diagnostics(), coverage=True, compiled=compiled)
        for key, found in run_scenario(program, scenario, names, machine=machine).machine.coverage.vectors.items():
            recorded.setdefault(key, set()).update(found)
    steps = frozenset({"Toolaut1.src", "Toolmag1.src"})
    assert _check_vectors(program, recorded, steps, Runner(program, relations)) > 20


def test_recorded_vectors_behind_overlapping_loops_are_among_the_ones_found(tmp_path: Path) -> None:
    # A joined subprogram with two loops, the second jumping back into the first from beyond it (a way back to a
    # head through code after its own jump back): every vector random memory and inputs record is among those
    # found. Catches: a loop head's state that misses a write on a way around through later code.
    text = ("CM Sub\nL M10\nAN I1\n= O1\nL M12\nA I2\n= O2\nL M10\nXO M12\n= O3\nEM\n"
            "LBL Sub\nL I1\n= M10\nL K0\n= B20\n"
            "LBL H1\nL B20\n+ K1\n= B20\nL M12\nXO I3\n= M12\nL B20\n< K2\nJPT H1\n"
            "L B20\n< K6\nJPF Done\n"
            "LBL H2\nL M12\n= M10\nL B20\n+ K1\n= B20\nL B20\n< K4\nJPT H1\nL B20\n< K6\nJPT H2\n"
            "LBL Done\nEM\n")
    program = _program(tmp_path, text)
    assert _check_recorded(program, _random_memory_runs(program, 12, 20, 8)) >= 2
