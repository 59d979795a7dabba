"""MC/DC and boundary values: the decisions found over the IR, the condition vectors the interpreter records, the
pairs that show a condition (unique-cause, masking for coupled conditions), boundaries at an operand's limit, and
the items explained as infeasible."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from transpiler.cli import main
from transpiler.exec.interp import Machine, compile_program
from transpiler.exec.interp.decisions import decision_table
from transpiler.exec.interp.faults import MachineHalted
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics
from transpiler.verify.implication import tied_vectors
from transpiler.verify.mcdc import decision_coverage, shown_masking, shown_unique
from transpiler.verify.implication import consumed_start_zero
from transpiler.verify.mcdc import _Implications, constant_bits
from transpiler.verify.nc_facts import NC_FACTS, applicable_facts

ROOT = Path(__file__).resolve().parents[1]


def _program(folder: Path, text: str, **semantics):
    (folder / "main.src").write_text(text)
    result = compile_project(ProjectOptions(main=folder / "main.src"), make_semantics("itnc530", semantics))
    assert result.ok
    return result.program


def _run(program, rows: list[dict[str, int]], exact: bool = False) -> Machine:
    """One cycle per row; a row names inputs I<n> and their values."""
    machine = Machine(program, compiled=compile_program(program, coverage=True, exact=exact), coverage=True)
    for cycle, row in enumerate(rows):
        machine.run_cycle(cycle, [("I", int(name[1:]), value) for name, value in row.items()])
    return machine


def _status(program, machines, driven=frozenset()):
    cov = decision_coverage(program, [m.coverage for m in machines], set(driven))
    return {(i.condition.text, i.decision.op.operand.display() if i.decision.op.operand else i.decision.op.mnemonic,
             i.number): i for i in cov.conditions}, cov


def test_complete_branch_coverage_is_not_complete_mcdc(tmp_path: Path) -> None:
    # I1 AND I2 decides a jump: (1, 1) and (0, 0) take it both ways, but no pair shows either condition alone.
    # Catches: MC/DC counted from branch outcomes, a pair accepted that differs in two conditions.
    program = _program(tmp_path, "L I1\nA I2\nJPF Skip\nL I3\n= O1\nLBL Skip\nEM\n")
    both_ways = _run(program, [{"I1": 1, "I2": 1}, {"I1": 0, "I2": 0}])
    assert both_ways.coverage.branches[(0, 2)] == {0, 1}
    items, cov = _status(program, [both_ways])
    assert items[("I1", "JPF", 0)].status == "missing" and items[("I2", "JPF", 1)].status == "missing"
    assert cov.summary()["mcdc"]["conditions_shown"] == 0
    # the two rows that complete it, in a second run: pairs are found across runs
    more = _run(program, [{"I1": 1, "I2": 0}, {"I1": 0, "I2": 1}, {"I1": 0, "I2": 0}])
    items, cov = _status(program, [both_ways, more])
    assert items[("I1", "JPF", 0)].status == "shown" and items[("I2", "JPF", 1)].status == "shown"
    jump = cov.summary()["mcdc"]
    assert jump["not_shown"] == [{"at": "main.src:4:1", "what": "condition I3 of I3 = O1"}]


def test_coupled_condition_needs_masking_mcdc(tmp_path: Path) -> None:
    # (I1 AND I2) OR (NOT I1 AND I3): I1 is read twice, so it can never change alone (no unique-cause pair); with
    # I2 = 1, I3 = 0 the second read is masked and I1 decides the outcome: a masking pair.
    program = _program(tmp_path, "L I1\nA I2\nO[\nLN I1\nA I3\n]\n= O1\nEM\n")
    decision = decision_table(program).decisions[0]
    assert [c.text for c in decision.conditions] == ["I1", "I2", "I1", "I3"]
    assert decision.coupled == (True, False, True, False)
    machine = _run(program, [{"I1": 1, "I2": 1, "I3": 0}, {"I1": 0, "I2": 1, "I3": 0}])
    vectors = machine.coverage.vectors[decision.key]
    assert not shown_unique(vectors, 4, 0)
    assert shown_masking(vectors, 4, 0, decision.function())
    items, _ = _status(program, [machine])
    first = items[("I1", "O1", 0)]
    assert first.status == "shown" and first.masking and "(masking MC/DC)" in first.what()
    # The pair (I2 = 0, I3 = 1) vs (I2 = 1, I3 = 0) at I1 = 1 differs in I2 and I3 with different outcomes? No:
    # I1 = 1 masks I3. A masking pair must not accept a second differing condition that is not masked.
    other = _run(program, [{"I1": 0, "I2": 0, "I3": 0}, {"I1": 1, "I2": 1, "I3": 1}])
    assert not shown_masking(other.coverage.vectors[decision.key], 4, 0, decision.function())


def test_bracket_and_xor_chains(tmp_path: Path) -> None:
    # Catches: a bracket's inner chain taken for a new chain, AN[ not negating, XO treated as OR.
    program = _program(tmp_path, "L I1\nAN[\nL I2\nO I3\n]\n= O1\nL I4\nXO I5\n= O2\nEM\n")
    table = decision_table(program)
    assert [d.text() for d in table.decisions] == ["I1 AND NOT (I2 OR I3) = O1", "I4 XOR I5 = O2"]
    rows = [{"I1": 1, "I2": 0, "I3": 0, "I4": 0, "I5": 0}, {"I1": 0, "I2": 0, "I3": 0, "I4": 1, "I5": 0},
            {"I1": 1, "I2": 1, "I3": 0, "I4": 0, "I5": 1}, {"I1": 1, "I2": 0, "I3": 1, "I4": 1, "I5": 1}]
    fast, exact = _run(program, rows), _run(program, rows, exact=True)
    assert fast.coverage.vectors == exact.coverage.vectors
    items, _ = _status(program, [fast])
    assert {key[0]: i.status for key, i in items.items()} == {c: "shown" for c in ("I1", "I2", "I3", "I4", "I5")}
    for d in table.decisions:
        n = len(d.conditions)
        assert all(d.function()(v & ((1 << n) - 1)) == v >> n for v in fast.coverage.vectors[d.key])
    # XO: without a row in which I5 changes alone, I5 is not shown
    items, _ = _status(program, [_run(program, rows[:2])])
    assert items[("I5", "O2", 1)].status == "missing"


def test_boundary_values_at_the_limit_of_a_byte(tmp_path: Path) -> None:
    # B10 == K127: c+1 = 128 is no value of a byte (infeasible), c-1 and c are reached; the compare of two words
    # counts its difference.
    program = _program(tmp_path, "L B10\n== K127\n= M1\nL W20\n< W22\n= M2\nEM\n")
    machine = Machine(program, compiled=compile_program(program, coverage=True, exact=False), coverage=True)
    for cycle, (b10, w20, w22) in enumerate([(126, 5, 6), (127, 6, 6), (0, 0, 9)]):
        machine.write("B", 10, b10)
        machine.write("W", 20, w20)
        machine.write("W", 22, w22)
        machine.run_cycle(cycle, [])
    cov = decision_coverage(program, [machine.coverage])
    found = {item.what(): (item.status, item.reason) for item in cov.boundaries}
    assert found["boundary B10 == K127: B10 = c-1 (126)"] == ("reached", "")
    assert found["boundary B10 == K127: B10 = c (127)"] == ("reached", "")
    status, reason = found["boundary B10 == K127: B10 = c+1 (128)"]
    assert status == "infeasible" and "-128..127" in reason
    assert found["boundary W20 < W22: W20 - W22 = -1"][0] == "reached"
    assert found["boundary W20 < W22: W20 - W22 = +0"][0] == "reached"
    assert found["boundary W20 < W22: W20 - W22 = +1"][0] == "missing"
    summary = cov.summary()["boundaries"]
    assert (summary["values"], summary["values_reached"], summary["values_infeasible"]) == (6, 4, 1)


def test_infeasible_conditions_have_their_reason(tmp_path: Path) -> None:
    # M5 is only ever reset (power-on 0): always 0, and it masks I2. M6 is only ever set: it is 0 before and 1
    # after, so it is NOT infeasible. M7 is never written, but a scenario sets it: not constant either.
    program = _program(tmp_path, "L I1\nR M5\nL M5\nA I2\n= O1\nL I3\nS M6\nL M6\nA I4\n= O2\n"
                                 "L M7\nA I5\n= O3\nEM\n")
    machine = _run(program, [{"I1": 1, "I2": 1, "I3": 0, "I4": 1}, {"I2": 0}])
    items, cov = _status(program, [machine], driven={("M", 7)})
    m5, i2 = items[("M5", "O1", 0)], items[("I2", "O1", 1)]
    assert m5.status == "infeasible" and m5.reason.startswith("M5 is always 0: the program writes only 0 to it")
    assert i2.status == "infeasible" and i2.reason == "masked by the constant M5 = 0"
    assert items[("M6", "O2", 0)].status == "missing"
    assert items[("M7", "O3", 0)].status == "missing"
    # without the scenario that sets it, M7 is never written: always 0
    items, _ = _status(program, [machine])
    assert items[("M7", "O3", 0)].status == "infeasible"
    assert "nothing in the program writes it" in items[("M7", "O3", 0)].reason
    summary = cov.summary()["mcdc"]
    assert summary["conditions_infeasible"] == 2 and len(summary["infeasible"]) == 2
    assert all(item["reason"] for item in summary["infeasible"])


def test_redundant_condition_is_infeasible_and_inputs_never_are(tmp_path: Path) -> None:
    # (I1 AND I2) OR I1 is I1: neither I2 nor the first read of I1 can ever decide the outcome (the second read
    # of I1 masks them); the second read can. Inputs themselves are never constant.
    program = _program(tmp_path, "L I1\nA I2\nO I1\n= O1\nEM\n")
    items, _ = _status(program, [_run(program, [{"I1": 0, "I2": 0}])])
    assert items[("I2", "O1", 1)].status == "infeasible"
    assert "never depends on it" in items[("I2", "O1", 1)].reason
    assert items[("I1", "O1", 0)].status == "infeasible" and "coupled" in items[("I1", "O1", 0)].reason
    assert items[("I1", "O1", 2)].status == "missing"
    items, _ = _status(program, [_run(program, [{"I1": 0, "I2": 0}, {"I1": 1}])])
    assert items[("I1", "O1", 2)].status == "shown"


@pytest.mark.parametrize("semantics", [{}, {"accumulator_model": "shared_bit7"}, {"chain_model": "dynamic"}],
                         ids=["default", "shared_bit7", "dynamic"])
@pytest.mark.parametrize("project", ["logic_chain", "brackets_logic", "chain_start", "compare", "edges", "stack",
                                     "ift_while_repeat", "jumps_loop", "calls_cmt_cmf"])
def test_recorded_outcome_is_the_function_of_the_recorded_conditions(project: str, semantics: dict) -> None:
    # The decision's formula (decisions.py) and the generated code agree on every vector recorded, in the fast and
    # the exact variant alike. Catches: a condition read at the wrong place, a negation lost, a bracket mis-modelled.
    result = compile_project(ProjectOptions(main=ROOT / "samples" / "constructs" / project / "main.src"),
                             make_semantics("itnc530", semantics))
    program = result.program
    table = decision_table(program)
    recorded = []
    for exact in (False, True):
        machine = Machine(program, compiled=compile_program(program, coverage=True, exact=exact), coverage=True)
        rng = random.Random(7)
        for cycle in range(200):
            machine.run_cycle(cycle, [("I", rng.randrange(16), rng.randrange(2)) for _ in range(3)])
        recorded.append(machine.coverage.vectors)
    assert recorded[0] == recorded[1] and recorded[0]
    for decision in table.decisions:
        n = len(decision.conditions)
        function = decision.function()
        for v in recorded[0].get(decision.key, ()):
            assert function(v & ((1 << n) - 1)) == v >> n, decision.text()


def test_equiv_prints_and_reports_mcdc_and_boundaries(tmp_path: Path, capsys) -> None:
    (tmp_path / "main.src").write_text("L I1\nA I2\n= O1\nL B4\n> K10\n= O2\nEM\n")
    (tmp_path / "s.yaml").write_text("cycles: 4\nevents:\n  - cycle: 1\n    set: {I1: 1, I2: 1}\n"
                                     "  - cycle: 2\n    set: {I2: 0, B4: 11}\n")
    report = tmp_path / "r.json"
    args = ["equiv", str(tmp_path / "main.src"), "--scenario", str(tmp_path / "s.yaml"), "--backend", "builtin",
            "--report", str(report)]
    assert main(args) == 0
    quiet = capsys.readouterr().out
    line = next(text for text in quiet.splitlines() if text.startswith("coverage: "))
    assert line.endswith("CASE entries 0/0, MC/DC 2/3 conditions, boundaries 1/3")
    assert "3 MC/DC conditions or boundary values no run covered, 0 infeasible (-v lists them)" in quiet
    assert main(args + ["-v"]) == 0
    loud = capsys.readouterr().out.splitlines()
    assert "  not covered: main.src:1:1: condition I1 of I1 AND I2 = O1" in loud
    assert "  not covered: main.src:5:1: boundary B4 > K10: B4 = c-1 (9)" in loud
    import json
    coverage = json.loads(report.read_text())["coverage"]
    assert coverage["branches"] == 0 and "never_taken" in coverage          # existing keys stay
    assert coverage["mcdc"]["conditions"] == 3 and coverage["mcdc"]["conditions_shown"] == 2
    assert coverage["boundaries"]["values_reached"] == 1


def test_marker_set_first_thing_in_every_cycle_is_constant(tmp_path: Path) -> None:
    # The "always one" idiom: M10 = I0 OR NOT I0 is assigned before anything reads it, in every cycle, so no read
    # sees its power-on 0; M11 = NOT M10 is always 0. A marker assigned after a read (M12) keeps its power-on value
    # for that read: not constant.
    program = _program(tmp_path, "L I0\nON I0\n= M10\nLN M10\n= M11\nL M12\nA I2\n= O3\nL I1\n= M12\n"
                                 "LBL Go\nL M10\nA I1\n= O1\nL M11\nO I1\n= O2\nEM\n")
    machine = _run(program, [{"I0": 0, "I1": 0}, {"I1": 1}])
    items, _ = _status(program, [machine], driven={("M", 10)})     # a scenario setting it changes nothing
    m10 = items[("M10", "O1", 0)]
    assert m10.status == "infeasible" and "first thing in every cycle" in m10.reason and "always 1" in m10.reason
    assert items[("I1", "O1", 1)].status == "shown"
    assert items[("M11", "O2", 0)].status == "infeasible" and "always 0" in items[("M11", "O2", 0)].reason
    assert items[("M12", "O3", 0)].status == "missing"
    tautology = [i for key, i in items.items() if key[1] == "M10"]
    assert {i.status for i in tautology} == {"infeasible"} and all("coupled" in i.reason for i in tautology)


def test_a_test_entered_by_a_jump_is_no_decision_of_the_chain_before_it(tmp_path: Path) -> None:
    # ENDW jumps back to the WHILET test with the LA of the loop's last chain: the test consumes two chains, and
    # recording it as a decision of the chain before WHILET paired that chain's values with another chain's outcome.
    program = _program(tmp_path, "L K0\n= X\nL X\n< K3\nWHILET\nINCX\nL X\n< K2\nA I2\n= O1\nENDW\nEM\n")
    table = decision_table(program)
    assert [d.op.mnemonic for d in table.decisions] == ["="]
    machine = _run(program, [{"I2": 0}, {"I2": 1}])
    decision = table.decisions[0]
    assert all(decision.function()(v & 3) == v >> 2 for v in machine.coverage.vectors[decision.key])


def test_an_indexed_marker_write_leaves_no_marker_constant(tmp_path: Path) -> None:
    # M5 is never named by a write, but `= M100[X]` may reach it: claiming it constant would be unsound.
    program = _program(tmp_path, "L I1\n= M100[X]\nL M5\nA I2\n= O1\nEM\n")
    items, _ = _status(program, [_run(program, [{"I2": 1}])])
    assert items[("M5", "O1", 0)].status == "missing" and items[("I2", "O1", 1)].status == "missing"


def test_generated_stimulus_completes_mcdc_of_a_chain_without_branches(tmp_path: Path, capsys) -> None:
    # No branch to take: only the MC/DC pairs (besides the output's two states) tell the search which inputs
    # matter. Catches: MC/DC pairs not counted as features of the search (then this seed shows 4 of the 6).
    (tmp_path / "main.src").write_text("L I1\nAN I2\nA I3\nAN I4\nA I5\nAN I6\n= O1\nEM\n")
    args = ["equiv", str(tmp_path / "main.src"), "--random-cycles", "400", "--seed", "1", "--backend", "builtin"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "MC/DC 6/6 conditions" in out, out


def test_an_indexed_write_reaches_only_the_markers_its_index_can_hold(tmp_path: Path) -> None:
    # A loop writes M100[X] with X = 0..3 only: M5 and M104 stay constant (never written), M103 does not (the loop
    # writes it). Catches: an indexed write taken as one of any marker (M5, M104 missing), or of its base alone
    # (M103 infeasible: unsound).
    loop = "L K0\n= X\nREPEAT\nL I1\n= M100[X]\nINCX\nL X\n>= K4\nUNTILT\n"
    reads = "L M5\nA I2\n= O1\nL M103\nA I2\n= O2\nL M104\nA I2\n= O3\nEM\n"
    program = _program(tmp_path, loop + reads)
    items, _ = _status(program, [_run(program, [{"I1": 0, "I2": 1}])])
    assert items[("M5", "O1", 0)].status == "infeasible"
    assert items[("M104", "O3", 0)].status == "infeasible"
    assert items[("M103", "O2", 0)].status == "missing"
    # the same loop after a call: X at the write is unknown, so the write may reach any marker
    unbounded = _program(tmp_path, "L K0\n= X\nREPEAT\nCM Sub\nL I1\n= M100[X]\nINCX\nL X\n>= K4\nUNTILT\n" + reads
                         + "LBL Sub\nEM\n")
    items, _ = _status(unbounded, [_run(unbounded, [{"I1": 0, "I2": 1}])])
    assert {items[(m, o, 0)].status for m, o in (("M5", "O1"), ("M103", "O2"), ("M104", "O3"))} == {"missing"}


def test_a_reset_on_every_path_before_the_chain_ties_its_conditions(tmp_path: Path) -> None:
    # `LN I1` `R M10` before `L M10` `A I1`: whenever I1 is 0 there, M10 has just been reset, so I1 can never
    # change the outcome on its own (the pair needs M10 = 1 with I1 = 0). M10 itself can (I1 = 1, M10 from I2).
    # Catches: an implication claimed without the reset, the reason not naming the line that fixes it.
    program = _program(tmp_path, "L I2\nS M10\nLN I1\nR M10\nL M10\nA I1\n= O1\nEM\n")
    machine = _run(program, [{"I1": 1, "I2": 1}, {"I1": 1, "I2": 0}, {"I1": 0}])
    items, cov = _status(program, [machine])
    i1 = items[("I1", "O1", 1)]
    assert i1.status == "infeasible", i1
    assert "main.src:4:1 R M10" in i1.reason and "before this chain on every path" in i1.reason
    assert items[("M10", "O1", 0)].status == "missing"
    assert cov.summary()["mcdc"]["conditions_infeasible"] == 1


def test_a_path_that_skips_the_reset_leaves_the_condition_reachable(tmp_path: Path) -> None:
    # The same reset, but I3 jumps over it: with I3 = 1, M10 keeps what I2 set and I1 decides O1 alone. The rule
    # must not fire, and the pair is really there: two cycles show it.
    program = _program(tmp_path, "L I2\nS M10\nL I3\nJPT Skip\nLN I1\nR M10\nLBL Skip\nL M10\nA I1\n= O1\nEM\n")
    items, _ = _status(program, [_run(program, [{"I1": 0, "I2": 0, "I3": 0}])])
    assert items[("I1", "O1", 1)].status == "missing"
    machine = _run(program, [{"I1": 1, "I2": 1, "I3": 1}, {"I1": 0, "I2": 0, "I3": 1}])
    items, _ = _status(program, [machine])
    assert items[("I1", "O1", 1)].status == "shown"


def test_a_marker_assigned_from_the_chain_ties_it_and_a_call_between_does_not(tmp_path: Path) -> None:
    # M10 = I1 AND I2 before the chain. In (M10 OR I3) AND I1 every condition can still decide alone (M10 via I2
    # with I1 = 1, I1 with M10 = 0 and I3 = 1): nothing claimed. In M10 AND NOT I1, M10 = 1 only with I1 = 1, so
    # the outcome is always 0: M10 is infeasible, naming the assignment. A call between the assignment and the
    # chain may write M10: nothing is claimed then.
    chain = "L M10\nO I3\nA I1\n= O1\n"
    program = _program(tmp_path, "L I1\nA I2\n= M10\n" + chain + "EM\n")
    items, _ = _status(program, [_run(program, [{"I1": 0}])])
    assert items[("M10", "O1", 0)].status == "missing" and items[("I1", "O1", 2)].status == "missing"
    assert items[("I3", "O1", 1)].status == "missing"
    tied = _program(tmp_path, "L I1\nA I2\n= M10\nL M10\nAN I1\n= O1\nEM\n")
    items, _ = _status(tied, [_run(tied, [{"I1": 0}])])
    assert items[("M10", "O1", 0)].status == "infeasible" and "main.src:3:1 = M10" in items[("M10", "O1", 0)].reason
    called = _program(tmp_path, "L I1\nA I2\n= M10\nCM Sub\nL M10\nAN I1\n= O1\nEM\nLBL Sub\nL I4\n= M10\nEM\n")
    items, _ = _status(called, [_run(called, [{"I1": 0}])])
    assert items[("M10", "O1", 0)].status == "missing"


@pytest.mark.parametrize("project", ["logic_chain", "brackets_logic", "chain_start", "compare", "edges", "stack",
                                     "ift_while_repeat", "jumps_loop", "calls_cmt_cmf"])
def test_every_recorded_vector_is_one_the_code_before_the_chain_allows(project: str) -> None:
    # The implication analysis over-approximates: each vector a run records must be among the ones it allows
    # (else an infeasible claim could be false). Catches: a write, jump, bracket or call followed wrongly.
    result = compile_project(ProjectOptions(main=ROOT / "samples" / "constructs" / project / "main.src"),
                             make_semantics("itnc530", {}))
    program = result.program
    table = decision_table(program)
    machine = Machine(program, compiled=compile_program(program, coverage=True), coverage=True)
    rng = random.Random(3)
    for cycle in range(300):
        machine.run_cycle(cycle, [("I", rng.randrange(16), rng.randrange(2)) for _ in range(4)])
    checked = 0
    for decision in table.decisions:
        tied = tied_vectors(program, decision, lambda kind, addr, file, index: None)
        if tied is None:
            continue
        checked += 1
        mask = (1 << len(decision.conditions)) - 1
        recorded = {v & mask for v in machine.coverage.vectors.get(decision.key, ())}
        assert recorded <= tied.vectors, decision.text()
    assert checked


def test_a_timer_start_read_before_its_only_write_in_the_cycle_is_always_0(tmp_path: Path) -> None:
    # The service clears a timer start after every cycle (A-34a): read before the program's own `= T0`, T0 is 0,
    # so it never decides O1. Read after the write in the same cycle it can; so can a start a scenario sets.
    # Catches: a start taken as constant although a write runs before the read, or although a scenario sets it.
    before = _program(tmp_path, "L I1\nAN T0\n= O1\nL I2\n= T0\nEM\n")
    items, _ = _status(before, [_run(before, [{"I1": 1, "I2": 1}, {"I1": 1}])])
    t0 = items[("T0", "O1", 1)]
    assert t0.status == "infeasible" and "the service clears after every cycle" in t0.reason, t0
    items, _ = _status(before, [_run(before, [{"I1": 1, "I2": 1}, {"I1": 1}])], driven={("T", 0)})
    assert items[("T0", "O1", 1)].status == "missing"
    after = _program(tmp_path, "L I2\n= T0\nL I1\nAN T0\n= O1\nEM\n")
    items, _ = _status(after, [_run(after, [{"I1": 1, "I2": 1}, {"I1": 1, "I2": 0}])])
    assert items[("T0", "O1", 1)].status == "shown"
    # the write in a subroutine called before the read runs first in the cycle too
    called = _program(tmp_path, "CM Start\nL I1\nAN T0\n= O1\nEM\nLBL Start\nL I2\n= T0\nEM\n")
    items, _ = _status(called, [_run(called, [{"I1": 1}])])
    assert items[("T0", "O1", 1)].status == "missing"


def _run_nc(program, rows: list[tuple[dict[str, int], list[dict]]]) -> Machine:
    """One cycle per row: inputs I<n> and the NC jobs queued in that cycle."""
    machine = Machine(program, compiled=compile_program(program, coverage=True), coverage=True)
    for cycle, (inputs, jobs) in enumerate(rows):
        machine.run_cycle(cycle, [("I", int(name[1:]), value) for name, value in inputs.items()], jobs)
    return machine


def _tool_calls(program, calls) -> list[Machine]:
    """One run per TOOL CALL (tool, pocket), acknowledged (I1) a few cycles after it starts, then TOOL DEFs."""
    runs = []
    for tool, pocket in calls:
        rows = [({"I1": 0}, [{"tool_call": {"tool": tool, "pocket": pocket}}]), ({"I1": 0}, []), ({"I1": 1}, []),
                ({"I1": 0}, [{"tool_def": {"tool": 3, "pocket": -1}}]), ({"I1": 0}, []), ({"I1": 1}, []),
                ({"I1": 0}, []), ({"I1": 0}, [])]
        runs.append(_run_nc(program, rows))
    return runs


_ACK_TOOL = "L M4073\nA I1\n= M4093\nL M4074\nA I1\n= M4094\n"


def test_the_nc_never_sets_two_tool_call_markers_together(tmp_path: Path) -> None:
    # M4522 AND NOT M4521: showing M4521 needs M4522 = 1 with M4521 = 1, which the NC never writes (exactly one of
    # M4521..M4523 with each TOOL CALL). Infeasible, naming the NC model; missing again where a scenario sets
    # M4521 (it could then be 1 with M4522), or where the program writes it itself.
    # Catches: the fact applied to an operand something else writes, a claim without saying it rests on the NC.
    program = _program(tmp_path, _ACK_TOOL + "L M4522\nAN M4521\n= O1\nEM\n")
    runs = _tool_calls(program, [(0, 5), (4, 5), (4, -1)])
    items, _ = _status(program, runs)
    t0 = items[("M4521", "O1", 1)]
    assert t0.status == "infeasible", t0
    assert "never 1 two at a time" in t0.reason and "(NC model)" in t0.reason and "M4073" not in t0.reason
    assert items[("M4522", "O1", 0)].status == "shown"
    items, _ = _status(program, runs, driven={("M", 4521)})
    assert items[("M4521", "O1", 1)].status == "missing"
    written = _program(tmp_path, _ACK_TOOL + "L I2\nS M4521\nL M4522\nAN M4521\n= O1\nEM\n")
    items, _ = _status(written, _tool_calls(written, [(4, 5)]))
    assert items[("M4521", "O1", 1)].status == "missing"


def test_while_the_tool_strobe_is_up_the_markers_describe_the_pocket(tmp_path: Path) -> None:
    # Behind `L M4073` `AN M4093` `EMF` the strobe is 1: M4523 AND NOT M4521 AND W262 == -1 then has M4523 = 1
    # whenever the other two are (M4521 = 0 and a pocket of -1 leave M4523 as the one marker), so M4523 never
    # decides alone; M4521 cannot either (M4523 = 1 with M4521 = 1 never). Without the strobe test before it, the
    # same chain can see M4523 = 0 with W262 = -1 (a TOOL DEF after the call): M4523 stays missing there, and
    # two cycles show it. Catches: the strobe fact applied to a chain not gated by the strobe.
    chain = "L M4523\nAN M4521\nA[\nL W262\n== K-1\n]\n= O1\n"
    gated = _program(tmp_path, _ACK_TOOL + "L M4073\nAN M4093\nEMF\n" + chain + "EM\n")
    runs = _tool_calls(gated, [(0, -1), (4, -1), (4, 0), (4, 5)])
    items, _ = _status(gated, runs)
    no_pocket, t0 = items[("M4523", "O1", 0)], items[("M4521", "O1", 1)]
    assert no_pocket.status == "infeasible" and "while the TOOL CALL strobe M4073 is 1" in no_pocket.reason, no_pocket
    assert t0.status == "infeasible" and "never 1 two at a time" in t0.reason, t0
    assert items[("W262 == K-1", "O1", 2)].status == "shown"
    # the same chain with nothing gating it: TOOL DEF -1 after a call with a pocket gives M4523 = 0, W262 = -1
    free = _program(tmp_path, _ACK_TOOL + chain + "EM\n")
    items, _ = _status(free, [])
    assert items[("M4523", "O1", 0)].status == "missing"
    items, _ = _status(free, _tool_calls(free, [(4, 5), (4, -1)]))
    assert items[("M4523", "O1", 0)].status == "shown"
    # the program writing the pocket word itself: no strobe fact
    written = _program(tmp_path, _ACK_TOOL + "L I3\nJPF Keep\nL K-1\n= W262\nLBL Keep\nL M4073\nAN M4093\nEMF\n"
                       + chain + "EM\n")
    items, _ = _status(written, _tool_calls(written, [(4, -1)]))
    assert items[("M4523", "O1", 0)].status == "missing"


def test_recorded_vectors_of_nc_driven_chains_are_allowed_by_the_nc_facts(tmp_path: Path) -> None:
    # Soundness of the facts as constraints: every vector random TOOL CALLs and TOOL DEFs make the chains record is
    # among the ones the analysis allows with the facts. Catches: a compare outcome worked out wrongly, a fact
    # that the model breaks.
    chains = ("L M4522\nAN M4521\n= O1\n", "L M4523\nAN M4521\nA[\nL W262\n== K-1\n]\n= O2\n",
              "L M4523\nAN M4521\nA[\nL W262\n== K0\n]\n= O3\n", "L M4521\nO[\nL W264\n<> K0\n]\nA M4073\n= O4\n",
              "L W262\n>= K1\nA M4522\n= O5\n")
    program = _program(tmp_path, _ACK_TOOL + "L M4073\nAN M4093\nEMF\n" + "".join(chains) + "EM\n")
    table = decision_table(program)
    assert len(applicable_facts(program, set())) == len(NC_FACTS)
    analysis = _Implications(program, constant_bits(program, table, set()), consumed_start_zero(program, set()),
                             applicable_facts(program, set()), table)
    machine = Machine(program, compiled=compile_program(program, coverage=True), coverage=True)
    rng = random.Random(5)
    for cycle in range(2000):
        jobs = []
        if rng.random() < 0.1:
            kind = rng.choice(("tool_call", "tool_def"))
            jobs = [{kind: {"tool": rng.choice((0, 2)), "pocket": rng.choice((-2, -1, 0, 1, 7))}}]
        machine.run_cycle(cycle, [("I", 1, rng.randrange(2))], jobs)
    checked = 0
    for decision in table.decisions:
        tied = tied_vectors(program, decision, lambda kind, addr, file, index: None, facts=analysis.facts_at)
        if tied is None:
            continue
        mask = (1 << len(decision.conditions)) - 1
        recorded = {v & mask for v in machine.coverage.vectors.get(decision.key, ())}
        assert recorded and recorded <= tied.vectors, decision.text()
        checked += 1
    assert checked >= len(chains)
    # after `= M4093` (which can write 1) the handshake facts of M4093 no longer hold; before it they do
    def acks(start: int) -> set:
        return {f.operands for f in analysis.facts_at(0, start) if ("M", 4093) in f.plc_owned}
    assert acks(0) == {(("M", 4073), ("M", 4093)), (("M", 4520), ("M", 4093))} and acks(3) == set()


def test_a_strobe_is_never_seen_with_its_acknowledgement_unless_the_program_set_it_before(tmp_path: Path) -> None:
    # The NC raises M4073 only while it reads M4093 as 0 and drops it once it reads 1: read before any write of
    # M4093 in the cycle, M4073 = 1 comes only with M4093 = 0, so M4093 never decides `M4073 AND NOT M4093`
    # alone. A reset of M4093 before the chain keeps that, and so does storing a chain that is always 0 (also as
    # the second store of one chain); a scenario setting M4093 too (the NC reads it in the same phase). `= M4093`
    # before the chain (which can write 1) does not: the pair shows up there.
    # Catches: the handshake fact taken at a point where the program may have set the acknowledgement.
    chain, ack = "L M4073\nAN M4093\n= O2\n", "L M4073\nA I1\n= M4093\n"
    calls = [({"I1": 0}, [{"tool_call": {"tool": 4, "pocket": 5}}]), ({"I1": 0}, []), ({"I1": 1}, []),
             ({"I1": 1}, []), ({"I1": 0}, [])]
    for before in ("", "L I2\nR M4093\n", "L M10\n= M11\n= M4093\n"):     # M10: never written, always 0
        program = _program(tmp_path, before + chain + ack + "EM\n")
        items, _ = _status(program, [_run_nc(program, calls)])
        item = items[("M4093", "O2", 1)]
        assert item.status == "infeasible" and "raises the strobe M4073 only while it reads" in item.reason, item
        items, _ = _status(program, [_run_nc(program, calls)], driven={("M", 4093)})
        assert items[("M4093", "O2", 1)].status == "infeasible"
    written = _program(tmp_path, ack + chain + "EM\n")
    items, _ = _status(written, [])
    assert items[("M4093", "O2", 1)].status == "missing"
    items, _ = _status(written, [_run_nc(written, calls)])
    assert items[("M4093", "O2", 1)].status == "shown"


def test_a_call_before_the_chain_is_followed_into_the_callee(tmp_path: Path) -> None:
    # Sub sets M10 = I1 AND I2 (through a forward jump and an early EMT); the chain after `CM Sub` is M10 AND NOT
    # I1: M10 = 1 only with I1 = 1, so the outcome is always 0 and M10 never decides alone. The reason names the
    # call. Catches: the region stopping at the call (missing), the callee's writes not followed.
    sub = "LBL Sub\nL I1\nA I2\n= M10\nL I3\nJPF Skip\nL I4\n= M11\nLBL Skip\nL I5\nEMT\nL I6\n= M12\nEM\n"
    program = _program(tmp_path, "L I7\n= M10\nCM Sub\nL M10\nAN I1\n= O1\nEM\n" + sub)
    items, _ = _status(program, [_run(program, [{"I1": 1, "I2": 1}, {"I1": 0}])])
    m10 = items[("M10", "O1", 0)]
    assert m10.status == "infeasible", m10
    assert "main.src:3:1 CM Sub" in m10.reason and "M10 = 1 only with I1 = 1" in m10.reason
    # nested one call deeper, and called only when I3 = 1 (CMT): on the path without the call, M10 keeps I7's
    # value and the pair is there (two cycles show it)
    nested = _program(tmp_path, "L I7\n= M10\nCM Outer\nL M10\nAN I1\n= O1\nEM\nLBL Outer\nCM Sub\nEM\n" + sub)
    items, _ = _status(nested, [])
    assert items[("M10", "O1", 0)].status == "infeasible"
    maybe = _program(tmp_path, "L I7\n= M10\nL I3\nCMT Sub\nL M10\nAN I1\n= O1\nEM\n" + sub)
    items, _ = _status(maybe, [])
    assert items[("M10", "O1", 0)].status == "missing"
    items, _ = _status(maybe, [_run(maybe, [{"I7": 1, "I1": 0, "I3": 0}, {"I7": 0, "I1": 0, "I3": 0}])])
    assert items[("M10", "O1", 0)].status == "shown"


@pytest.mark.parametrize("callee", ["LBL Sub\nLBL Again\nL I1\nA I2\n= M10\nL I3\nJPT Again\nEM\n",
                                    "LBL Sub\nL I1\nA I2\n= M10\nL I4\n= M20[X]\nEM\n",
                                    "LBL Sub\nL I1\nA I2\n= M10\nL K0\n= B0\nCASE B0\nCM Other\nENDC\nEM\n"
                                    "LBL Other\nL I4\n= M10\nEM\n"],
                         ids=["loop", "indexed_write", "case"])
def test_a_callee_that_cannot_be_run_so_ends_the_region(tmp_path: Path, callee: str) -> None:
    # A loop, an indexed marker write or a CASE in the callee: the region stops at the call, and nothing is
    # claimed (the indexed write or the CASE entry may leave M10 at anything). The loop's last pass sets M10 from
    # I1 AND I2 with I1 the same input the chain reads: the paths of the cycle (cycle_paths, the loop run again
    # from a state that forgets what it writes) show M10 = 1 only with I1 = 1; the region alone claims nothing.
    program = _program(tmp_path, "CM Sub\nL M10\nAN I1\n= O1\nEM\n" + callee)
    items, _ = _status(program, [])
    item = items[("M10", "O1", 0)]
    if "Again" in callee:
        assert item.status == "infeasible" and "on every path of the cycle to this chain" in item.reason, item
        assert "CM Sub" not in item.reason
    else:
        assert item.status == "missing"


def test_recorded_vectors_behind_calls_are_allowed(tmp_path: Path) -> None:
    # Soundness of following calls: every vector random inputs make the chains record is among the ones the
    # analysis allows. Catches: a return path lost (EMT, EMF, a jump past an EM), CMT/CMF taken the wrong way
    # round, LA or brackets carried wrongly into or out of a callee.
    text = ("L I1\nCMT A\nL M10\nA I2\n= O1\nL I3\nCMF B\nL M11\nXO M10\n= O2\nCM C\nL M12\nAN M10\nO M11\n= O3\n"
            "L I4\nCM D\n= M13\nL M13\nA I5\n= O4\nEM\n"
            "LBL A\nL I2\nAN I6\n= M10\nL I7\nEMT\nLN M10\n= M11\nEM\n"
            "LBL B\nL I6\nEMF\nL I2\nO I7\nS M11\nR M10\nEM\n"
            "LBL C\nL I8\nJPT Far\nL M10\n= M12\nEM\nLBL Far\nL M11\n= M12\nCM A\nEM\n"
            "LBL D\nA I9\nEM\n")
    program = _program(tmp_path, text)
    table = decision_table(program)
    machine = _run(program, [{f"I{i}": random.Random(cycle * 16 + i).randrange(2) for i in range(1, 10)}
                             for cycle in range(400)])
    checked = through = 0
    for decision in table.decisions:
        tied = tied_vectors(program, decision, lambda kind, addr, file, index: None)
        if tied is None:
            continue
        mask = (1 << len(decision.conditions)) - 1
        recorded = {v & mask for v in machine.coverage.vectors.get(decision.key, ())}
        assert recorded <= tied.vectors, decision.text()
        checked += 1
        through += any(program.main.ops[w].code in ("CALL", "CALLT", "CALLF") for w in tied.writes)
    assert checked >= 4 and through >= 3


# M2 toggles only while M1 is 1, and both are reset together: M2 = 1 only with M1 = 1 at every point of every cycle
# (between `R M1` and `R M2` it does not hold, but nothing can read there). The chain reads both before any write of
# the cycle, so only the relation across cycles ties them.
_TOGGLE = "L I1\nS M1\nLN I1\nR M1\nR M2\nL M1\nA I2\nJPF Keep\nLN M2\n= M2\nLBL Keep\n"


def test_a_relation_every_write_keeps_holds_across_cycles(tmp_path: Path) -> None:
    # `M2 AND M1` at the start of the cycle: showing M1 needs M2 = 1 with M1 = 0. Infeasible, naming the relation
    # and the writes it rests on; M2 itself stays to be shown (and a run shows it). Catches: the region alone
    # claimed to tie them (it cannot: no write before the chain), a relation not checked at the writes.
    program = _program(tmp_path, "L M2\nA M1\n= O1\n" + _TOGGLE + "EM\n")
    rows = [{"I1": 1, "I2": 1}, {"I1": 1, "I2": 0}, {"I1": 1, "I2": 1}, {"I1": 1}, {"I1": 0}, {"I1": 0}]
    items, _ = _status(program, [_run(program, rows)])
    m1 = items[("M1", "O1", 1)]
    assert m1.status == "infeasible", m1
    assert "M2 = 1 only with M1 = 1 at every point of every cycle" in m1.reason
    assert "(main.src:5:1 S M1, main.src:7:1 R M1, main.src:8:1 R M2, main.src:13:1 = M2)" in m1.reason
    assert items[("M2", "O1", 0)].status == "shown"


@pytest.mark.parametrize("breaking", ["L I3\n= M2\n", "L I3\nS M2\n", "L I3\nR M1\n"])
def test_a_write_that_breaks_the_relation_leaves_the_condition_missing(tmp_path: Path, breaking: str) -> None:
    # One more write that can give M2 = 1 with M1 = 0 (M2 set from an input, M1 reset alone): the relation does
    # not hold, nothing is claimed, and two cycles show M1 deciding alone.
    program = _program(tmp_path, "L M2\nA M1\n= O1\n" + _TOGGLE + breaking + "EM\n")
    items, _ = _status(program, [])
    assert items[("M1", "O1", 1)].status == "missing"
    rows = [{"I1": 1, "I3": 1}, {"I1": 1, "I3": 1}, {"I1": 1, "I2": 1, "I3": 1}, {"I1": 1, "I2": 0, "I3": 1},
            {"I1": 1, "I3": 0}, {"I1": 0, "I3": 1}, {"I1": 0, "I3": 0}]
    items, _ = _status(program, [_run(program, rows)])
    assert items[("M1", "O1", 1)].status == "shown"


def test_no_relation_over_an_operand_a_scenario_sets_or_an_indexed_write_reaches(tmp_path: Path) -> None:
    # A scenario setting M2 (or M1) can break the relation between cycles; an indexed write whose index is
    # unknown may write either. Catches: power-on values or writes outside the program not accounted for.
    program = _program(tmp_path, "L M2\nA M1\n= O1\n" + _TOGGLE + "EM\n")
    for driven in ({("M", 2)}, {("M", 1)}):
        items, _ = _status(program, [], driven=driven)
        assert items[("M1", "O1", 1)].status == "missing"
    indexed = _program(tmp_path, "L M2\nA M1\n= O1\n" + _TOGGLE + "L W4\n= X\nL I5\n= M0[X]\nEM\n")
    items, _ = _status(indexed, [])
    assert items[("M1", "O1", 1)].status == "missing"


def test_recorded_vectors_are_allowed_under_the_relations_proved(tmp_path: Path) -> None:
    # Soundness: with every relation the analysis proves assumed, each vector random inputs make the chains record
    # is still allowed. Catches: a relation proved that a run breaks.
    from transpiler.verify.implication import Invariant, inductive_invariants, program_entries
    text = ("L M2\nA M1\n= O1\nL M3\nAN M4\n= O2\nL M4\nO M5\nA M3\n= O3\n" + _TOGGLE +
            "L I3\nS M3\nS M4\nL I4\nR M4\nL M4\nA I5\nS M5\nLN M3\nR M3\nR M5\nEM\n")
    program = _program(tmp_path, text)
    table = decision_table(program)
    keys = [("M", n) for n in range(1, 6)]
    candidates = [Invariant((a, b), (x, y), (f"M{a[1]}", f"M{b[1]}")) for a in keys for b in keys if a < b
                  for x, y in ((1, 1), (1, 0), (0, 1))]
    proved = inductive_invariants(program, candidates, lambda kind, addr, file, index: None)
    assert any(p.operands == (("M", 1), ("M", 2)) and p.values == (0, 1) for p in proved)
    assert any(p.operands == (("M", 3), ("M", 5)) and p.values == (0, 1) for p in proved)   # M5 only with M3
    machine = _run(program, [{f"I{i}": random.Random(cycle * 8 + i).randrange(2) for i in range(1, 6)}
                             for cycle in range(500)])
    entries = program_entries(program)
    for decision in table.decisions:
        tied = tied_vectors(program, decision, lambda kind, addr, file, index: None, entries=entries,
                            invariants=proved)
        if tied is None:
            continue
        mask = (1 << len(decision.conditions)) - 1
        recorded = {v & mask for v in machine.coverage.vectors.get(decision.key, ())}
        assert recorded <= tied.vectors, decision.text()


@pytest.mark.parametrize("project", sorted(p.name for p in (ROOT / "samples" / "constructs").iterdir() if p.is_dir()))
def test_no_condition_a_run_shows_is_claimed_infeasible_without_runs(project: str) -> None:
    # Every reason (constants, the code before the chain with its calls, NC facts, relations across cycles) is
    # worked out with no run at all, then random inputs run: none of the conditions claimed infeasible may be shown.
    # Catches: an unsound claim of any rule on the construct projects.
    result = compile_project(ProjectOptions(main=ROOT / "samples" / "constructs" / project / "main.src"),
                             make_semantics("itnc530", {}))
    if not result.ok:
        pytest.skip("the project needs options this test does not give")
    program = result.program
    table = decision_table(program)
    claimed = {(i.decision.key, i.number) for i in decision_coverage(program, [], table=table).conditions
               if i.status == "infeasible"}
    machine = Machine(program, compiled=compile_program(program, coverage=True), coverage=True)
    rng = random.Random(11)
    try:
        for cycle in range(300):
            machine.run_cycle(cycle, [("I", rng.randrange(32), rng.randrange(2)) for _ in range(6)])
    except MachineHalted:           # a fault the inputs provoke: what ran until then counts
        pass
    shown = {(i.decision.key, i.number) for i in decision_coverage(program, [machine.coverage], table=table).conditions
             if i.status == "shown"}
    assert not claimed & shown


@pytest.mark.parametrize("semantics", [{}, {"load_extension": "zero"}])
def test_a_word_only_the_nc_writes_holds_only_what_an_nc_action_carries(tmp_path: Path, semantics: dict) -> None:
    # The mode word W272 and the pocket W262 hold what the scenario format lets an NC action carry (0..32767 and
    # -1..32767): a boundary below that is infeasible, named after the NC model; one inside it stays to be
    # reached, and a run of NC jobs at the edges reaches each value left. Catches: a claim of a value the NC can
    # write (the pocket -1), a claim read through the wrong extension (zero-extended, -1 is 65535).
    low = 65535 if semantics else -1
    program = _program(tmp_path, f"L W272\n== K0\n= O1\nL W262\n== K{low}\n= O2\nEM\n", **semantics)
    cov = decision_coverage(program, [])
    status = {(b.compare.left, b.offset): b for b in cov.boundaries}
    # (zero-extended, W272 = -1 is outside what the compare can read at all, and W262 = 65536 too)
    assert status[("W272", -1)].status == "infeasible"
    assert ("0..32767 to W272" in status[("W272", -1)].reason) == (not semantics)
    assert status[("W262", -1)].status == "infeasible" and "-1..32767 to W262" in status[("W262", -1)].reason
    assert {k for k, b in status.items() if b.status == "missing"} == {("W272", 0), ("W272", 1), ("W262", 0),
                                                                        *([] if semantics else [("W262", 1)])}
    machines = _tool_calls(program, [(7, -1), (7, 0)]) + [_run_nc(program, [({}, [{"mode": m}]) for m in (0, 1)])]
    reached = decision_coverage(program, [m.coverage for m in machines])
    assert all(b.status != "missing" for b in reached.boundaries)


@pytest.mark.parametrize("other", ["L I1\nIFT\nL K-5\n= W272\nENDI\n", "L K-5\n= B273\n",
                                   "L K3\n= X\nL K-5\n= B270[X]\n"])
def test_no_range_of_an_nc_word_where_something_else_writes_it(tmp_path: Path, other: str) -> None:
    # The program writes the mode word itself (by name, a byte of it, through the index register), or a scenario
    # sets it: no claim, and the value below 0 is one a run can give it. (The store by name is conditional: right
    # before the compare on every path it would fix the word there, a claim of its own, word_relations.word_bounds.)
    program = _program(tmp_path, f"{other}L W272\n== K0\n= O1\nEM\n")
    below = next(b for b in decision_coverage(program, []).boundaries if b.offset == -1)
    assert below.status == "missing"
    clean = _program(tmp_path, "L W272\n== K0\n= O1\nEM\n")
    assert next(b for b in decision_coverage(clean, [], {("W", 272)}).boundaries if b.offset == -1).status == "missing"


def test_constant_word_operations_fix_error_markers_compares_and_bit_tests(tmp_path: Path) -> None:
    # WA followed through constant loads and arithmetic: 65536 x 65536 overflows (M4200 = 1), 3 x -4 does not
    # (M4200 = 0), / K0 sets M4201, MOD K10 resets M4202; -5 >= -5, bit 2 of 4 and 5 < (2 + 4) are always 1. None
    # of these conditions can ever change its outcome. Catches: the rule missing, a marker taken as any value, a
    # compare of a constant WA left missing, the reason not naming the op the marker rests on.
    program = _program(tmp_path, "L K65536\nx K65536\n= D0\nL M4200\n= M10\nL K3\nx K-4\n= D4\nL M4200\n= M11\n"
                                 "L K100\n/ K0\n= D8\nL M4201\n= M12\nL K47\nMOD K10\n= D12\nL M4202\n= M13\n"
                                 "L K-5\n>= K-5\n= O1\nL K4\nBT K2\n= O2\nL K4\nBT K33\n= O3\n"
                                 "L K5\n<[\nL K2\n+ K4\n]\n= O4\nEM\n")
    machine = _run(program, [{}, {}])
    assert [machine.state.M[a] for a in (10, 11, 12, 13)] == [1, 0, 1, 0]
    items, cov = _status(program, [machine])
    assert cov.summary()["mcdc"]["conditions_infeasible"] == 8
    assert "M4200 is always 1 (set by main.src:2:1 x K65536 before this chain" in items[("M4200", "M10", 0)].reason
    assert "M4200 is always 0 (set by main.src:7:1 x K-4" in items[("M4200", "M11", 0)].reason
    assert "M4201 is always 1 (set by main.src:12:1 / K0" in items[("M4201", "M12", 0)].reason
    assert "M4202 is always 0" in items[("M4202", "M13", 0)].reason
    for text, out, value in (("K-5 >= K-5", "O1", 1), ("bit K2 of WA", "O2", 1), ("bit K33 of WA", "O3", 0)):
        assert f"{text} is always {value}" in items[(text, out, 0)].reason and "WA holds one value" in \
            items[(text, out, 0)].reason


@pytest.mark.parametrize("text", [
    "L W0\nx K65536\n= D0\nL M4200\n= M10\nEM\n",                  # WA not known: the product may not overflow
    "L K100\n/ W0\n= D8\nL M4200\nL M4201\n= M10\nEM\n",           # a divisor that is no constant
    "L K100\n/ K0\n= D8\nL I1\nJPT Skip\nL K7\n/ K7\n= D8\nLBL Skip\nL I2\nJPF Next\nL K100\n/ K2\nLBL Next\n"
    "L M4201\n= M10\nEM\n",                                        # paths that leave the marker 1 or 0
    "L K-5\nLBL Again\n>= K-5\n= M10\nL W0\nJPT Again\nEM\n",         # WA at a jump target: any value
])
def test_word_operations_not_all_constant_fix_nothing(tmp_path: Path, text: str) -> None:
    # Catches: WA or an error marker claimed known through a non-constant operand, a join or a jump back.
    program = _program(tmp_path, text)
    items, cov = _status(program, [])
    assert cov.summary()["mcdc"]["conditions_infeasible"] == 0, cov.summary()["mcdc"]


def test_the_shared_accumulator_model_follows_no_word(tmp_path: Path) -> None:
    # LA is bit 7 of WA there (A-05): a constant WA is not followed. Catches: the rule firing under that model.
    program = _program(tmp_path, "L K4\nBT K2\n= O2\nEM\n", accumulator_model="shared_bit7")
    _, cov = _status(program, [])
    assert cov.summary()["mcdc"]["conditions_infeasible"] == 0


@pytest.mark.parametrize("text, runs", [
    # WA computed from an NC word: 100 - M code takes -6 and -4 with M codes 106 and 104
    ("L K100\n- W260\n== K-5\n= O1\nEM\n", [[{"m_function": 104}], [{"m_function": 106}]]),
    # WA computed from X: 100 - X is 97 when X is 3, whatever range X holds
    ("L K0\n= X\nL I1\nIFT\nL K3\n= X\nENDI\nL K100\n- X\n== K97\n= O1\nEM\n", None),
])
def test_a_compare_of_a_computed_wa_is_no_compare_of_the_operand_before_it(tmp_path: Path, text: str, runs) -> None:
    # The op before the compare is arithmetic, not a load: neither the NC word's range nor the index register's
    # range says anything about WA. Catches: the operand before the compare taken for the compared word (W260's
    # 0..32767 claimed for 100 - W260, X's 0..3 for 100 - X).
    program = _program(tmp_path, text)
    assert all(b.status != "infeasible" for b in decision_coverage(program, []).boundaries)
    if runs is not None:
        machines = [_run_nc(program, [({}, []), ({}, jobs), ({}, []), ({}, [])]) for jobs in runs]
        machines += [_run_nc(program, [({}, [{"m_function": 105}]), ({}, [])])]
    else:
        machines = [_run(program, [{"I1": 0}]), _run(program, [{"I1": 1}, {"I1": 1}])]
    reached = decision_coverage(program, [m.coverage for m in machines])
    # (100 - X is 100 or 97 there: only 97 of the three values can occur, and it does)
    expected = {-1, 0, 1} if runs is not None else {0}
    assert {b.offset for b in reached.boundaries if b.status == "reached"} == expected


def test_a_string_compare_the_code_before_it_fixes_is_constant(tmp_path: Path) -> None:
    # "AB" + "CD" stored in S0 and loaded again: == "ABCD" is always 1, < "ABCE" always 1, > "ABCE" always 0; an error
    # text reference stored and compared likewise. The run agrees. Catches: the rule missing, a wrong order of the
    # appends, a store of another string operand taken for S0's.
    program = _program(tmp_path, 'L S"AB"\n+ S"CD"\n= S0\nL S"XY"\n= S1\nL S0\n== S"ABCD"\n= O1\nL S0\n< S"ABCE"\n'
                                 '= O2\nL S0\n> S"ABCE"\n= O3\nL S#E12\n= S3\nL S3\n== S"E0012"\n= O4\nEM\n')
    machine = _run(program, [{}, {}])
    assert [machine.state.bits("O")[a] for a in (1, 2, 3, 4)] == [1, 1, 0, 1]
    items, cov = _status(program, [machine])
    assert cov.summary()["mcdc"]["conditions_infeasible"] == 4
    reason = items[('SA == S"ABCD"', "O1", 0)].reason
    assert reason.startswith('SA == S"ABCD" is always 1: SA holds "ABCD"'), reason
    assert items[('SA > S"ABCE"', "O3", 0)].reason.startswith('SA > S"ABCE" is always 0')


@pytest.mark.parametrize("between", [
    "L I1\nJPF Skip\nL S\"ZZ\"\n= S0\nLBL Skip\n",       # a store on one path only: the compare is entered by a jump
    "CM Sub\n",                                          # a call (it may store S0)
    "L K0\n= X\nL S\"ZZ\"\n= S0[X]\n",                     # a store through the index register
])
def test_a_string_compare_is_not_fixed_where_something_else_can_reach_it(tmp_path: Path, between: str) -> None:
    # Catches: a string operand or the accumulator taken as known across a join, a call or an indexed store.
    program = _program(tmp_path, f'L S"AB"\n= S0\n{between}L S0\n== S"AB"\n= O1\nEM\nLBL Sub\nL S"ZZ"\n= S0\nEM\n')
    items, cov = _status(program, [])
    assert cov.summary()["mcdc"]["conditions_infeasible"] == 0, cov.summary()["mcdc"]
    machine = _run(program, [{"I1": 1}, {"I1": 0}])
    items, cov = _status(program, [machine])
    assert cov.summary()["mcdc"]["conditions_infeasible"] == 0


def _timed(program, mp: dict, rows: list[dict[str, int]]) -> Machine:
    machine = Machine(program, mp, compiled=compile_program(program, coverage=True), coverage=True)
    for cycle, row in enumerate(rows):
        machine.run_cycle(cycle, [("I", int(name[1:]), value) for name, value in row.items()])
    return machine


def test_the_running_bit_of_a_timer_with_preset_0_in_every_run_is_always_0(tmp_path: Path) -> None:
    # MP4110.3 = 0: T51 never runs however I1 starts T3, so its condition cannot be shown. A run with a preset of
    # 3 cycles shows it; a write of T51 by the program or a scenario, or no run at all, leaves it missing.
    # Catches: the claim made without looking at the runs' presets, or over a write of the bit.
    rows = [{"I1": 1}, {"I1": 0}, {}, {}, {"I1": 1}, {}]
    program = _program(tmp_path, "L I1\n= T3\nL T51\n= O4\nEM\n")
    idle = _timed(program, {"4110.3": 0}, rows)
    assert idle.coverage.idle_timers >= {51} and 51 not in _timed(program, {"4110.3": 0.06}, rows).coverage.idle_timers
    items, _ = _status(program, [idle])
    t51 = items[("T51", "O4", 0)]
    assert t51.status == "infeasible" and "MP4110.3" in t51.reason and "is 0 in every run" in t51.reason, t51
    items, _ = _status(program, [idle, _timed(program, {"4110.3": 0.06}, rows)])
    assert items[("T51", "O4", 0)].status == "shown"
    assert _status(program, [idle], driven={("T", 51)})[0][("T51", "O4", 0)].status == "missing"
    assert _status(program, [])[0][("T51", "O4", 0)].status == "missing"
    written = _program(tmp_path, "L I1\n= T3\nL I2\n= T51\nL T51\n= O4\nEM\n")
    items, _ = _status(written, [_timed(written, {"4110.3": 0}, rows)])
    assert items[("T51", "O4", 0)].status != "infeasible"
