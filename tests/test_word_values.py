"""The values a word can hold at each compare (verify/word_values.py) and the boundary values claimed infeasible from
them: claimed where the program stores only constants and a dispatch has jumped away on the others, never where
anything else can change the word (a store of another width over its bytes, an indexed store that can reach it,
arithmetic, INC, a pull, a call that stores an unknown value, a scenario), and never for a value a run reached."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from transpiler import api
from transpiler.diagnostics import Diagnostics
from transpiler.exec.interp import Machine, compile_program
from transpiler.exec.interp.decisions import decision_table
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics
from transpiler.verify.guided import generate
from transpiler.verify.index_range import index_values
from transpiler.verify.mcdc import decision_coverage, driven_operands, power_on_operands
from transpiler.verify.scenario import load_scenario
from transpiler.verify.simulate import build_machine, project_names, run_scenario
from transpiler.verify.word_relations import word_bounds, word_relations
from transpiler.verify.word_values import word_values

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "basic_program"

# B10 is a step byte: 0 idle, 1 and 2 busy; each step is left by a constant store. The dispatch at the top jumps
# away on 0, then on 1: the compare with K1 never sees 0, the one with K2 sees only 2.
STEPS = """L     B10
<>    K0
JPT   Step1
L     I1
IFT
L     K1
=     B10
ENDI
JP    Done
LBL Step1
L     B10
<>    K1
JPT   Step2
L     K2
=     B10
JP    Done
LBL Step2
L     B10
==    K2
=     O1
L     K0
=     B10
LBL Done
{extra}EM
{routines}"""


def _program(folder: Path, text: str, **semantics):
    (folder / "main.src").write_text(text)
    result = compile_project(ProjectOptions(main=folder / "main.src"), make_semantics("itnc530", semantics))
    assert result.ok, [str(d) for d in result.diagnostics]
    return result.program


def _held(program, driven=frozenset(), power_on=frozenset()) -> dict[tuple[int, str, int], frozenset[int] | None]:
    """(source line, relation, constant) -> the values the analysis lets the compare's word hold (None: any)."""
    table = decision_table(program)
    values = word_values(program, table.compares, set(driven), set(power_on))
    out = {}
    for cmp in table.compares:
        found = values.at(cmp)
        out[(cmp.op.span.line, cmp.op.rel, cmp.constant)] = None if found is None else found.values
    return out


def _steps(folder: Path, extra: str = "", routines: str = "", **semantics):
    return _program(folder, STEPS.format(extra=extra, routines=routines), **semantics)


def test_a_step_byte_holds_only_its_constants_and_what_the_dispatch_leaves(tmp_path: Path) -> None:
    # Catches: a claim without the dispatch (0 at the compare with K1), a dispatch edge taken the wrong way round
    # (1 at the compare with K2), the power-on value 0 forgotten at the first compare.
    held = _held(_steps(tmp_path))
    assert held[(2, "<>", 0)] == {0, 1, 2}
    assert held[(12, "<>", 1)] == {1, 2}
    assert held[(19, "==", 2)] == {2}


def test_the_infeasible_boundary_values_have_their_reason(tmp_path: Path) -> None:
    program = _steps(tmp_path)
    machine = Machine(program, compiled=compile_program(program, coverage=True), coverage=True)
    for cycle, i1 in enumerate([0, 1, 0, 0, 0]):
        machine.run_cycle(cycle, [("I", 1, i1)])
    cov = decision_coverage(program, [machine.coverage])
    found = {item.what(): item for item in cov.boundaries}
    low = found["boundary B10 <> K0: B10 = c-1 (-1)"]
    assert low.status == "infeasible"
    assert low.reason.startswith("B10 holds only 0..2 here, not -1: the program writes only 0..2 to it (main.src:")
    assert "it starts at 0" in low.reason
    before = found["boundary B10 <> K1: B10 = c-1 (0)"]
    assert before.status == "infeasible" and "main.src:3:1" in before.reason, before.reason
    assert found["boundary B10 <> K1: B10 = c+1 (2)"].status == "reached"
    assert found["boundary B10 == K2: B10 = c-1 (1)"].status == "infeasible"
    assert found["boundary B10 == K2: B10 = c+1 (3)"].status == "infeasible"
    assert found["boundary B10 <> K0: B10 = c+1 (1)"].status == "reached"


@pytest.mark.parametrize("extra, why", [
    ("L     K7\n=     W10\n", "a word store over the byte (W10 holds B10 and B11)"),
    ("L     K-1\n=     D8\n", "a double word store over the byte (D8 holds B8..B11)"),
    ("L     K7\n=     X\nL     K-1\n=     B3[X]\n", "a store through the index register that reaches B10"),
    ("L     B10\n+     K1\n=     B10\n", "an arithmetic store (a count)"),
    ("L     B10\nx     K3\n=     B10\n", "a product"),
    ("INC   B10\n", "INC"),
    ("PS    K3\nPL    B10\n", "a pull from the data stack"),
    ("L     W272\n=     B10\n", "a copy of a word the NC writes"),
    ("CM    Sub\n", "a call of a routine that stores an unknown value"),
])
def test_anything_else_that_changes_the_byte_leaves_it_any(tmp_path: Path, extra: str, why: str) -> None:
    # Catches: a write the analysis does not see (every one of these can give B10 any value).
    routines = "LBL Sub\nL     K1\n=     X\nL     B20[X]\n=     B10\nEM\n"
    held = _held(_steps(tmp_path, extra, routines))
    assert held[(2, "<>", 0)] is None, why
    assert held[(12, "<>", 1)] is None, why


def test_stores_that_cannot_reach_the_byte_leave_the_claim(tmp_path: Path) -> None:
    # B11 alone, an indexed store that reaches B3..B5 only, a call of a routine that stores constants into B10:
    # none can give B10 a value outside 0..3 (the routine's 3 joins the values). Catches: every store of memory
    # taken as a store of every word (no claim would ever be made).
    extra = "L     K-1\n=     B11\nL     K0\n=     X\nL     K-1\n=     B3[X]\nL     I3\nCMT   Sub\n"
    routines = "LBL Sub\nL     K3\n=     B10\nEM\n"
    held = _held(_steps(tmp_path, extra, routines))
    assert held[(2, "<>", 0)] == {0, 1, 2, 3}
    assert held[(12, "<>", 1)] == {1, 2, 3}


def test_a_call_in_the_middle_of_a_dispatch_adds_what_the_routine_stores(tmp_path: Path) -> None:
    # After `CM Sub` at the top of step 1 the byte can hold Sub's 5 as well as the 1 and 2 the dispatch left; a call
    # of a routine that does not store it keeps what was known. Catches: a call that keeps the state of a byte its
    # routine writes.
    program = _program(tmp_path, "L B10\n<> K0\nJPT One\nL K1\n= B10\nEM\nLBL One\nCM Sub\nCM Other\nL B10\n== K1\n"
                                 "= O1\nEM\nLBL Sub\nL I1\nIFT\nL K5\n= B10\nENDI\nEM\nLBL Other\nL K9\n= W20\nEM\n")
    assert _held(program)[(11, "==", 1)] == {1, 5}


def test_a_marker_assigned_from_a_compare_narrows_the_word_where_it_is_tested(tmp_path: Path) -> None:
    # B10 counts up only while it is below 3 (the marker M1 holds the compare): it holds 0..3. A write of M1 between
    # the compare and the test forgets what M1 says. Catches: a marker fact kept over a write of the marker.
    text = "L B10\n< K3\n= M1\n{between}L M1\nA I1\nIFT\nL B10\n+ K1\n= B10\nENDI\nL B10\n== K3\n= O1\nEM\n"
    held = _held(_program(tmp_path, text.format(between="")))
    assert held[(12, "==", 3)] == {0, 1, 2, 3}
    held = _held(_program(tmp_path, text.format(between="L I2\nS M1\n")))
    assert held[(14, "==", 3)] is None


def test_a_word_a_scenario_sets_is_any_unless_the_first_cycle_overwrites_it_unread(tmp_path: Path) -> None:
    # Set by a scenario at any cycle: any value. Set only at power-on: any value where the first cycle can read it
    # before a store; where the first-cycle marker's routine stores it first, its power-on value is never seen.
    # Catches: a scenario's operand taken as the program's own, a first-cycle store assumed without the marker.
    program = _steps(tmp_path)
    b10 = {("B", 10)}
    assert _held(program, driven=b10)[(2, "<>", 0)] is None
    assert _held(program, driven=b10, power_on=b10)[(2, "<>", 0)] is None
    init = "L     M4172\nCMT   Init\n"
    program = _program(tmp_path, init + STEPS.format(extra="", routines="LBL Init\nL K0\n= B10\nEM\n"))
    assert _held(program, driven=b10, power_on=b10)[(4, "<>", 0)] == {0, 1, 2}
    assert _held(program, driven=b10)[(4, "<>", 0)] is None
    # the init routine called on another marker: the first cycle may skip it and read the power-on value
    program = _program(tmp_path, "L     M100\nCMT   Init\n" + STEPS.format(extra="", routines="LBL Init\nL K0\n"
                                                                                          "= B10\nEM\n"))
    assert _held(program, driven=b10, power_on=b10)[(4, "<>", 0)] is None


def test_power_on_operands_are_those_set_only_before_cycle_0(tmp_path: Path) -> None:
    program = _steps(tmp_path)
    (tmp_path / "a.yaml").write_text("cycles: 3\ninitial: {B10: 4, W20: 1}\nevents:\n  - cycle: 1\n    set: {W20: 2}\n")
    (tmp_path / "b.yaml").write_text("cycles: 3\ninitial: {B12: 4}\nrandom: {seed: 1, inputs: [I1]}\n")
    names = project_names(program)
    scenarios = [load_scenario(tmp_path / name, names) for name in ("a.yaml", "b.yaml")]
    assert driven_operands(scenarios, names) == {("B", 10), ("W", 20), ("B", 12), ("I", 1)}
    assert power_on_operands(scenarios, names) == {("B", 10), ("B", 12)}


# ----------------------------------------------------------------------------------------------------- safety

def _bounds_inside(program, coverage_sets, driven=frozenset(), power_on=frozenset()) -> int:
    """Assert every boundary value a run reached lies inside what the analyses let the word hold there; returns
    how many reached values were checked against a claim."""
    table = decision_table(program)
    values = word_values(program, table.compares, set(driven), set(power_on))
    xs = index_values(program)
    relations = word_relations(program)
    ranges = word_bounds(program)
    checked = 0
    for cmp in table.compares:
        if cmp.constant is None:
            low, high = relations.get(cmp.key, (None, None))
            for cov in coverage_sets:
                for difference in cov.bounds.get(cmp.key, ()):
                    assert (low is None or difference >= low) and (high is None or difference <= high), \
                        (str(cmp.op.span), difference, (low, high))
                    checked += 1
            continue
        reached = set()
        for cov in coverage_sets:
            reached |= set(cov.bounds.get(cmp.key, ()))
        held = values.at(cmp)
        ops = program.files[cmp.file].ops
        word = ops[cmp.index].operand if cmp.constant_left else ops[cmp.index - 1].operand
        for difference in reached:
            value = cmp.constant + (-difference if cmp.constant_left else difference)
            if cmp.key in ranges and not cmp.constant_left:
                low, high = ranges[cmp.key]
                assert low <= value <= high, (str(cmp.op.span), value, (low, high))
                checked += 1
            if held is not None:
                assert value in held.values, (str(cmp.op.span), value, sorted(held.values))
                checked += 1
            if word is not None and word.kind == "X" and cmp.key in xs:
                x = xs[cmp.key]
                assert x.holds(value) or x.lo < 0, (str(cmp.op.span), value, x)
    return checked


CONSTRUCTS = sorted(p.name for p in (ROOT / "samples" / "constructs").iterdir() if (p / "main.src").exists())


@pytest.mark.parametrize("project", CONSTRUCTS)
def test_no_reached_boundary_value_is_outside_what_the_analysis_allows_on_a_construct(project: str) -> None:
    # The construct's own scenario and random inputs. Catches: any unsound claim (a store, overlap, call, jump or
    # first-cycle effect followed wrongly) on the constructs' compares.
    folder = ROOT / "samples" / "constructs" / project
    loaded = api.load_project(api.project_options(folder / "main.src"))
    program = loaded.program
    names = project_names(program)
    compiled = compile_program(program, coverage=True)
    scenarios = [load_scenario(folder / "scenario.yaml", names)] if (folder / "scenario.yaml").exists() else []
    scenarios += generate(program, names, 400, seed=2, seeds=scenarios)
    sets = _coverage_sets(program, scenarios, names, compiled)
    _bounds_inside(program, sets, driven_operands(scenarios, names), power_on_operands(scenarios, names))
    rng = random.Random(5)
    machine = Machine(program, compiled=compiled, coverage=True)
    for cycle in range(300):
        if machine.halted:
            break
        machine.run_cycle(cycle, [("I", rng.randrange(16), rng.randrange(2)) for _ in range(4)])
    _bounds_inside(program, [machine.coverage])


def _coverage_sets(program, scenarios, names, compiled) -> list:
    """The reference machine's coverage of each scenario, run as `hh2iec simulate` runs it (up to its first fault)."""
    return [run_scenario(program, scenario, names,
                         machine=build_machine(program, scenario, Diagnostics(), coverage=True, compiled=compiled)
                         ).machine.coverage for scenario in scenarios]


def test_no_reached_boundary_value_is_outside_what_the_analysis_allows_on_the_sample() -> None:
    # Every scenario of the sample and a generated search, power-on values and all. Catches: an unsound claim on a
    # real program (the step chains of the tool changer are where the claims are).
    loaded = api.load_project(api.project_options(SAMPLE / "Main_PGM.src"))
    program = loaded.program
    names = project_names(program)
    compiled = compile_program(program, coverage=True)
    scenarios = [load_scenario(p, names) for p in sorted((SAMPLE / "scenarios").glob("*.yaml"))]
    scenarios += generate(program, names, 1500, seed=4, seeds=scenarios,
                          machine_parameters=SAMPLE / "MP_data.mp")
    sets = _coverage_sets(program, scenarios, names, compiled)
    checked = _bounds_inside(program, sets, driven_operands(scenarios, names), power_on_operands(scenarios, names))
    assert checked > 50


def test_a_word_masked_with_a_constant_holds_only_the_masks_bits(tmp_path: Path) -> None:
    # `A K15` after any word leaves 0..15 in WA, so `== K0` never sees -1; a mask with many bits, or a load from an
    # NC word without a mask, claims nothing. Catches: a claim on WA that ignores the load before the mask.
    program = _program(tmp_path, "L W1032\nA K15\n== K0\n= O1\nL W1032\nA K$7FFF\n== K0\n= O2\nL K3\n= W20\n"
                                 "L W1032\n+ K0\n== K0\n= O3\nEM\n")
    held = _held(program)
    assert held[(3, "==", 0)] == frozenset(range(16))
    assert held[(7, "==", 0)] is None and held[(13, "==", 0)] is None


def test_unsigned_compares_get_no_claim(tmp_path: Path) -> None:
    # With A-13 unsigned compares a byte's -1 is compared as 4294967295: the signed values followed here say
    # nothing about it. Catches: a claim made on the wrong reading of the word.
    held = _held(_steps(tmp_path, compare_signedness="unsigned"))
    assert set(held.values()) == {None}


def test_products_and_quotients_by_a_constant_are_followed(tmp_path: Path) -> None:
    # A doubling loop from 1 until 100 leaves only powers of two at its test (never 99, 100, 101); MOD and / of a
    # constant work the values out; a product by a word the analysis does not know leaves WA any. Catches: a
    # product taken as any value (no claim), or a product by an unknown word taken as known.
    text = ("L K1\n= W10\nREPEAT\nL W10\nx K2\n= W10\nL W10\n>= K100\nUNTILT\n"
            "L K7\n= W20\nL W20\nMOD K4\n== K3\n= O1\nL W20\n/ K-2\n== K-3\n= O2\n"
            "L W20\nx W30\n== K14\n= O3\nEM\n")
    program = _program(tmp_path, text)
    held = _held(program)
    assert held[(8, ">=", 100)] == {2, 4, 8, 16, 32, 64, 128}
    assert held[(14, "==", 3)] == {3}
    assert held[(18, "==", -3)] == {-3}
    assert held[(22, "==", 14)] is None
    # the whole coverage: the three values around 100 are infeasible with the stores named
    table = decision_table(program)
    items = {i.what(): i for i in decision_coverage(program, [], table=table).boundaries}
    item = items["boundary W10 >= K100: W10 = c (100)"]
    assert item.status == "infeasible" and "2, 4, 8, 16, 32, 64, 128" in item.reason, item.reason


@pytest.mark.parametrize("semantics, value", [({}, 0), ({"mul_overflow_result": "unchanged"}, 65536)])
def test_an_overflowing_product_follows_the_assumption(tmp_path: Path, semantics: dict, value: int) -> None:
    # 65536 x 65536 overflows; the low bits (0) or WA unchanged (65536). Catches: one rule for both choices.
    held = _held(_program(tmp_path, "L K65536\nx K65536\n== K0\n= O1\nEM\n", **semantics))
    assert held[(3, "==", 0)] == {value}


def test_rply_gives_running_only_in_code_a_job_reaches(tmp_path: Path) -> None:
    # The main program's RPLY sees 0 or 2 (no job runs while it does); the job's own RPLY, and one in a routine the
    # job calls (also called from the main program), may see 1. Catches: 1 left out where a job can run the RPLY,
    # or RPLY's answer taken as any value.
    text = ("RPLY W12\n== K0\n= O1\nL I1\nCMT Ask\nL M4172\nJPF Done\nSUBM Job\n= W12\nLBL Done\nEM\n"
            "LBL Job\nRPLY W12\n== K1\n= O2\nCM Ask\nEM\n"
            "LBL Ask\nRPLY W12\n== K2\n= O3\nEM\n")
    program = _program(tmp_path, text)
    held = _held(program)
    assert held[(2, "==", 0)] == {0, 2}
    assert held[(14, "==", 1)] == {0, 1, 2}
    assert held[(20, "==", 2)] == {0, 1, 2}
    table = decision_table(program)
    items = {i.what(): i for i in decision_coverage(program, [], table=table).boundaries}
    item = items["boundary WA == K0: WA = c+1 (1)"]
    assert item.status == "infeasible" and "only inside the job it asks about" in item.reason, item.reason
    assert items["boundary WA == K1: WA = c (1)"].status == "missing"


COUNTING = "L K0\n= W6\nL W6\n< W30\nWHILET\n{body}L W6\n{step}= W6\nL W6\n< W30\nENDW\nEM\n{routines}"


def _compare_at(program, line: int):
    """The compare of the decision table at source line `line`."""
    return next(c for c in decision_table(program).compares if c.op.span.line == line)


def _boundary(program, coverage: list, what: str):
    """The boundary item `what` (as BoundaryItem.what() prints it) of the decision coverage over `coverage`."""
    return {i.what(): i for i in decision_coverage(program, coverage).boundaries}[what]


def _reached_and_claimed(program, machine, line: int, reached: set[int], what: str, reason: str) -> None:
    """Asserts that the runs of `machine` reached exactly `reached` at the compare on `line`, and that the boundary
    item `what` they left is infeasible with a reason starting with `reason`."""
    assert machine.coverage.bounds[_compare_at(program, line).key] == reached
    item = _boundary(program, [machine.coverage], what)
    assert item.status == "infeasible" and item.reason.startswith(reason), item


def _relation(program, line: int) -> tuple:
    return word_relations(program).get(_compare_at(program, line).key, (None, None))


def test_a_counting_loop_never_passes_its_limit_at_its_test(tmp_path: Path) -> None:
    # The body runs with W6 < W30 and adds 1: at the test at its end W6 - W30 <= 0, so +1 is infeasible; runs with
    # limits -1..40 reach -1 and 0 only. Catches: the fact lost over the step (no claim), or the step not counted.
    program = _program(tmp_path, COUNTING.format(body="", step="+ K1\n", routines=""))
    assert _relation(program, 10) == (None, 0)
    assert _relation(program, 4) == (None, None)
    machine = Machine(program, compiled=compile_program(program, coverage=True), coverage=True)
    for cycle, limit in enumerate(range(-1, 40)):
        machine.state.write("W", 30, limit)
        machine.run_cycle(cycle, [])
    _bounds_inside(program, [machine.coverage])
    _reached_and_claimed(program, machine, 10, {-1, 0}, "boundary W6 < W30: W6 - W30 = +1",
                         "W6 - W30 is at most 0 here, never +1")


@pytest.mark.parametrize("body, step, routines, why", [
    ("", "+ K2\n", "", "a step of 2 can pass the limit by one"),
    ("L W6\n= W30\n", "+ K1\n", "", "the limit written in the body"),
    ("CM Sub\n", "+ K1\n", "LBL Sub\nL K9\n= W30\nEM\n", "a call in the body"),
    ("L K-1\n= B7\n", "+ K1\n", "", "a store of a byte of W6"),
    ("L K0\n= X\nL K5\n= W6[X]\n", "+ K1\n", "", "a store through the index register"),
    ("", "- K1\n", "", "a step down"),
])
def test_no_difference_is_claimed_where_the_loop_may_break_it(tmp_path: Path, body: str, step: str, routines: str,
                                                               why: str) -> None:
    # Catches: a fact kept over a write that changes one of the words, or a step that may pass the limit.
    program = _program(tmp_path, COUNTING.format(body=body, step=step, routines=routines))
    assert _relation(program, 10 + body.count("\n"))[1] is None, why


def test_a_copy_after_an_indexed_store_does_not_equal_the_word_loaded_before_it(tmp_path: Path) -> None:
    # `L W6` `= D0[X]` `= W8`: the double word through X (bytes 4..7 here) rewrites W6's bytes with WA's upper half,
    # so W8 (WA, 1) is W6 (0) + 1. Catches: WA still taken as W6's value after a store that may change W6.
    program = _program(tmp_path, "L K1\n= W6\nL K4\n= X\nL W6\n= D0[X]\n= W8\nL W8\n== W6\n= O1\nEM\n")
    assert _relation(program, 9) == (None, None)
    machine = Machine(program, compiled=compile_program(program, coverage=True), coverage=True)
    machine.run_cycle(0, [])
    cmp = _compare_at(program, 9)
    assert machine.coverage.bounds[cmp.key] == {1}
    _bounds_inside(program, [machine.coverage])


# W6 counts the set markers among M100..M107: set to 0 with X, INC'd at most once per pass of the loop over X; after
# the loop W6 is 0..8 (W6 - X <= 0 and X = 8 there), so its compare with K0 never sees -1.
COUNT_BESIDE_X = """{before}L     K0
=     X
=     W6
LBL Scan
L     M100[X]
IFT
INC   W6
{body}ENDI
INCX
L     X
<     K8
JPT   Scan
L     W6
>     K0
=     O1
EM
{routines}"""


def _bound_at(program, line: int) -> tuple[int, int] | None:
    return word_bounds(program).get(_compare_at(program, line).key)


def test_a_count_kept_beside_x_stays_within_the_loop_s_passes(tmp_path: Path) -> None:
    # Catches: the fact W6 - X lost over INC or INCX (no claim), the INC counted as possibly wrapping, the bound of
    # X at the loop's exit not used, or a claim a run contradicts (random markers, all set, none set).
    program = _program(tmp_path, COUNT_BESIDE_X.format(before="", body="", routines=""))
    assert _bound_at(program, 14) == (0, 8)
    machine = Machine(program, compiled=compile_program(program, coverage=True), coverage=True)
    rng = random.Random(3)
    for cycle in range(40):
        for bit in range(8):
            machine.state.write("M", 100 + bit, 1 if cycle == 1 else 0 if cycle == 2 else rng.randrange(2))
        machine.run_cycle(cycle, [])
    assert _bounds_inside(program, [machine.coverage]) > 0
    # c and c+1 reached, c-1 not
    _reached_and_claimed(program, machine, 14, {0, 1}, "boundary W6 > K0: W6 = c-1 (-1)",
                         "W6 holds only 0..8 here, not -1")


@pytest.mark.parametrize("before, body, routines, why", [
    ("", "INC   W6\n", "", "two INCs in one pass: the count can pass X"),
    ("", "L     W20\n=     W6\n", "", "another write of the count"),
    ("", "CM    Sub\n", "LBL Sub\nL     K-5\n=     W6\nEM\n", "a call in the loop"),
    ("", "L     W20\n=     X\n", "", "X written in the loop"),
    ("", "PLX\n", "", "X pulled in the loop"),
    ("", "L     K-9\n=     W4[X]\n", "", "a store through the index register that can reach the count"),
    ("", "L     K-1\n=     B7\n", "", "a store of a byte of the count"),
    ("L     I1\nJPT   Scan\n", "", "", "the loop entered from elsewhere"),
])
def test_no_count_bound_is_claimed_where_the_loop_may_break_it(tmp_path: Path, before: str, body: str,
                                                             routines: str, why: str) -> None:
    # Catches: a fact kept over a write of the count or of X, a call, an indexed store, or a way into the loop that
    # skips the stores that set the count and X together.
    program = _program(tmp_path, COUNT_BESIDE_X.format(before=before, body=body, routines=routines))
    line = 14 + before.count("\n") + body.count("\n")
    assert _bound_at(program, line) is None, why


def test_a_count_stepped_down_or_not_set_first_gets_no_bound(tmp_path: Path) -> None:
    # DEC can wrap below once the lower bound is lost; without `= W6` the count starts from what the last cycle (or
    # a scenario) left. Catches: a lower bound kept over DEC, a fact from the constant store of X alone.
    down = _program(tmp_path, COUNT_BESIDE_X.format(before="", body="", routines="").replace("INC   W6", "DEC   W6"))
    assert _bound_at(down, 14) is None
    unset = _program(tmp_path, COUNT_BESIDE_X.format(before="", body="", routines="").replace("=     W6\n", "", 1))
    assert _bound_at(unset, 13) is None


# W8 is the first set marker's number or -1: it becomes X (>= 0) in the pass whose INC raises the count W6, and it is
# read only under M50 = (W6 > 0): there it is never -1.
FIRST_BESIDE_COUNT = """L     K0
=     X
=     W6
L     K-1
=     W8
LBL Scan
L     M100[X]
IFT
INC   W6
L     W8
<     K0
IFT
{set_first}ENDI
ENDI
INCX
L     X
<     K8
JPT   Scan
L     W6
>     K0
=     M50
{between}L     M50
IFT
L     W8
==    K0
=     O1
ENDI
EM
"""


def test_a_word_set_with_a_count_is_known_where_the_count_is_not_zero(tmp_path: Path) -> None:
    # Catches: the implication "W6 >= 1 => W8 >= 0" not formed where the two ways of the IFT join, lost over the
    # indexed bit reads and writes, not applied where the marker assigned from W6 > 0 is read, or a claim a run
    # contradicts (random markers, none set).
    text = FIRST_BESIDE_COUNT.format(set_first="L     X\n=     W8\n", between="")
    program = _program(tmp_path, text)
    assert _bound_at(program, 27) == (0, 7)
    machine = Machine(program, compiled=compile_program(program, coverage=True), coverage=True)
    rng = random.Random(4)
    for cycle in range(40):
        for bit in range(8):
            machine.state.write("M", 100 + bit, 0 if cycle % 3 == 0 else rng.randrange(2))
        machine.run_cycle(cycle, [])
    assert _bounds_inside(program, [machine.coverage]) > 0
    item = _boundary(program, [machine.coverage], "boundary W8 == K0: W8 = c-1 (-1)")
    assert item.status == "infeasible" and item.reason.startswith("W8 holds only 0..7 here, not -1"), item


@pytest.mark.parametrize("set_first, between, why", [
    ("L     I2\nIFT\nL     X\n=     W8\nENDI\n", "", "the word not set in every counting pass"),
    ("L     X\n=     W8\n", "L     I1\n=     M50\n", "the marker written again"),
    ("L     X\n=     W8\n", "L     K-1\n=     W8\n", "the word written after the marker"),
    ("L     X\n=     W8\n", "L     K0\n=     W6\n", "the count written after the marker"),
    ("L     X\n=     W8\n", "L     K1\n=     M48[X]\n", "a marker written through X"),
])
def test_no_bound_is_implied_where_the_count_and_the_word_may_part(tmp_path: Path, set_first: str, between: str,
                                                                   why: str) -> None:
    # Catches: an implication formed where one way of the join neither sets the word nor denies the count, kept over
    # a write of either, or a marker fact kept over a write of the marker or of its compare's word.
    program = _program(tmp_path, FIRST_BESIDE_COUNT.format(set_first=set_first, between=between))
    line = 27 + set_first.count("\n") - 2 + between.count("\n")
    bound = _bound_at(program, line)
    assert bound is None or bound[0] <= -1, (why, bound)


TABLE_READ = "PS    K0\nPS    W20\nPS    K1\nCM    9093\n{pulls}L     W40\n==    K0\n=     O1\nEM\n"


def test_a_pulled_error_result_holds_only_the_module_s_codes(tmp_path: Path) -> None:
    # 9093's second result is its error code (0..5, error_values): a word pulled from it is never -1. Catches: the
    # value result taken for the error result (pull order), a claim where a scenario replaces the module's results,
    # where something runs between the call and the pull, and for a module whose result carries a value too.
    program = _program(tmp_path, TABLE_READ.format(pulls="PL    D32\nPL    W40\n"))
    assert _held(program)[(8, "==", 0)] == frozenset(range(6))
    assert _held(program, driven={("module", 9093)})[(8, "==", 0)] is None
    cov = decision_coverage(program, [])
    low = {item.what(): item for item in cov.boundaries}["boundary W40 == K0: W40 = c-1 (-1)"]
    assert low.status == "infeasible" and "(the error result of module 9093)" in low.reason, low.reason
    swapped = _program(tmp_path, TABLE_READ.format(pulls="PL    W40\nPL    D32\n"))
    assert _held(swapped)[(8, "==", 0)] is None
    between = _program(tmp_path, TABLE_READ.format(pulls="PL    D32\nL     K3\nPL    W40\n"))
    assert _held(between)[(9, "==", 0)] is None
    timer = _program(tmp_path, "PS    K0\nCM    9192\nPL    W40\nL     W40\n==    K0\n=     O1\nEM\n")
    assert _held(timer)[(5, "==", 0)] is None


def test_module_results_of_a_scenario_count_as_driven(tmp_path: Path) -> None:
    program = _program(tmp_path, TABLE_READ.format(pulls="PL    D32\nPL    W40\n"))
    (tmp_path / "s.yaml").write_text("name: s\ncycles: 1\nmodule_results:\n  9093: [7, -1]\n")
    scenario = load_scenario(tmp_path / "s.yaml", project_names(program))
    assert ("module", 9093) in driven_operands([scenario], project_names(program))


JOB_TABLE_READ = """{main}EM

LBL Read
PS    K0
PS    W20
PS    K1
CM    9093
PL    D32
PL    W40
L     W40
==    K0
=     O1
EM
"""


def _line_of_compare(program) -> int:
    """The source line of the program's only `==    K0`."""
    lines = program.files[0].ops
    found = {op.span.line for op in lines if op.code == "CMP" and op.rel == "=="}
    assert len(found) == 1, found
    return found.pop()


def test_a_submit_module_called_only_in_a_job_never_gives_its_wrong_context_code(tmp_path: Path) -> None:
    # 9093 is submit-only: code 1 is its result in the cyclic program. Called only from a submitted job, W40 holds
    # 0, 2..5. Catches: the claim where the routine is called cyclically too, or only cyclically (1 is all it can
    # give there), or where the A-46q context rule is off.
    job = _program(tmp_path, JOB_TABLE_READ.format(main="SUBM  Read\n"))
    assert _held(job)[(_line_of_compare(job), "==", 0)] == frozenset({0, 2, 3, 4, 5})
    cov = decision_coverage(job, [])
    c1 = {item.what(): item for item in cov.boundaries}["boundary W40 == K0: W40 = c+1 (1)"]
    assert c1.status == "infeasible" and "called only in a submitted job" in c1.reason, c1.reason
    both = _program(tmp_path, JOB_TABLE_READ.format(main="SUBM  Read\nCM    Read\n"))
    assert _held(both)[(_line_of_compare(both), "==", 0)] == frozenset(range(6))
    cyclic = _program(tmp_path, JOB_TABLE_READ.format(main="CM    Read\n"))
    assert _held(cyclic)[(_line_of_compare(cyclic), "==", 0)] == frozenset(range(6))
    ignored = _program(tmp_path, JOB_TABLE_READ.format(main="SUBM  Read\n"), module_context="ignore")
    assert _held(ignored)[(_line_of_compare(ignored), "==", 0)] == frozenset(range(6))


def test_a_job_s_callee_and_a_fall_through_run_in_the_job_context(tmp_path: Path) -> None:
    # The job calls a routine that falls into the reading label: both run in the job only. The same call reached
    # from the cyclic program through a CASE table is in both contexts.
    text = "{main}EM\n\nLBL Job\nCM    Pre\nEM\n\nLBL Pre\nL     K0\n" + JOB_TABLE_READ.split("EM\n", 1)[1]
    job = _program(tmp_path, text.format(main="SUBM  Job\n"))
    assert _held(job)[(_line_of_compare(job), "==", 0)] == frozenset({0, 2, 3, 4, 5})
    case = _program(tmp_path, text.format(main="SUBM  Job\nL     K0\nCASE  B0\nCM    Pre\nENDC\n"))
    assert _held(case)[(_line_of_compare(case), "==", 0)] == frozenset(range(6))

