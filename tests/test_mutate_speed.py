"""How `mutate` saves work without changing a verdict (verify/mutate.py prepare and Judging): the reference run of
each scenario recorded once (verify/recording.py), all mutants compiled once as a mutant schema
(exec/stexec/schema.py), and each mutant run only under the runs that infect it."""

from __future__ import annotations


import pytest

from tests.construct_judges import construct_judge, plain
from transpiler.exec.stexec import PROBE, TextMutation, load_st
from transpiler.verify.cosim import BuiltinSchema, builtin_side_factory, cosimulate
from transpiler.verify.mutate import NEVER_INFECTED, SURVIVED, judge_all, mutation_sites, prepare

def _judge(name: str, random_cycles: int = 300):
    return construct_judge(name, lambda t: builtin_side_factory, lambda t: BuiltinSchema, random_cycles)


@pytest.mark.parametrize("name, jobs", [("case_chain", 1), ("word_arith_flags", 2)])
def test_every_mutant_gets_the_verdict_of_its_own_text_run_in_lockstep(name, jobs):
    # Catches: a schema switch that runs other code than the mutated text compiles to (precedence, typing, a
    # swapped CASE label), a recording that replays other values than the reference computes, or a run left out
    # that would have killed the mutant. The reference: each mutant's text compiled on its own and run under
    # every scenario beside the reference interpreter, as mutate judged before.
    judge = _judge(name)
    sites = mutation_sites(judge.st_text)
    before = [plain(judge(m)) for m in sites]
    verdicts = list(judge_all(judge, sites, jobs))
    after = {v.mutant: plain(v) for v in verdicts}
    assert [after[m] for m in sites] == before
    assert {outcome for outcome, _ in before} >= {"killed"}
    # the runs a verdict names are the ones it went through: the killer (what the mutation report's killedBy says)
    # is the last of them, also where runs that do not infect the mutant were left out
    for v in verdicts:
        if v.outcome == "killed":
            assert v.by.startswith(judge.scenarios[v.scenarios_run[-1]].name + ": ")


def test_a_construct_with_swapped_case_labels_and_rejected_mutants_is_covered():
    # the verdict comparison above is only worth something if the constructs have mutants of every path:
    # switched CASE labels, switched statements and conditions, and mutants left to their own text
    judge = _judge("word_arith_flags")
    judging = prepare(judge, mutation_sites(judge.st_text))
    assert judging.sides is not None and judging.infected is not None and judging.sides.unswitched
    text = _judge("case_chain", random_cycles=0).st_text
    sites = mutation_sites(text)
    schema = BuiltinSchema(text, [TextMutation(i + 1, m.changes) for i, m in enumerate(sites)])
    swaps = [i + 1 for i, m in enumerate(sites) if m.operator == "swap_case"]
    assert swaps and not set(swaps) & schema.unswitched


ST = """PROGRAM Main
VAR
    n : INT;
    x : INT;
    y : BOOL;
END_VAR
    n := 0;
    IF n > 100 THEN
        x := 5;
    END_IF;
    y := n = 0 OR x = 3;
END_PROGRAM
CONFIGURATION C
    RESOURCE R ON PLC
        TASK T(INTERVAL := T#20ms, PRIORITY := 0);
        PROGRAM P WITH T : Main;
    END_RESOURCE
END_CONFIGURATION
"""


def test_probing_finds_the_mutants_a_run_infects_and_only_those():
    sites = mutation_sites(ST)
    schema = load_st(ST, mutations=[TextMutation(i + 1, m.changes) for i, m in enumerate(sites)])
    assert not schema.unswitched
    rt = schema.instantiate(mutant=PROBE)
    for _ in range(3):
        rt.run_cycle()
    infected = {(sites[k - 1].line, sites[k - 1].description) for k in rt.infected}
    # `x := 5` never runs and `n > 100` is false for 101, 99 and `>=` alike: none of their mutants is infected
    assert not {(line, d) for line, d in infected if line in (8, 9)}
    assert (11, "OR -> AND at column 16") in infected          # TRUE OR FALSE against TRUE AND FALSE
    assert (11, "3 -> 4 at column 24") not in infected          # x = 3 and x = 4 are both false
    assert (7, "assignment loses its effect") not in infected   # n := 0 stores the 0 already there
    # the probing run is the original: a mutant's run differs from it, the original's does not
    plain = load_st(ST).instantiate()
    for _ in range(3):
        plain.run_cycle()
    assert rt.get("P.y") == plain.get("P.y") is True
    killer = next(i + 1 for i, m in enumerate(sites) if m.line == 11 and m.description.startswith("OR -> AND"))
    mutant = schema.instantiate(mutant=killer)
    mutant.run_cycle()
    assert mutant.get("P.y") is False


def test_a_mutant_no_run_infects_survives_without_a_run():
    judge = _judge("timers")
    sites = mutation_sites(judge.st_text)
    judging = prepare(judge, sites)
    never = [i for i, m in enumerate(sites) if not any(i + 1 in run for run in judging.infected)]
    assert never, "the timers construct has statements no scenario changes"
    for index in never:
        verdict = judging(index)
        assert verdict.outcome == SURVIVED and verdict.runs == 0 and verdict.by == NEVER_INFECTED
        assert judge(sites[index]).outcome == SURVIVED          # its own text, every scenario: the same


def test_a_recorded_reference_replays_what_the_lockstep_run_compares():
    judge = _judge("indexed", random_cycles=400)
    judging = prepare(judge, [])
    sites = mutation_sites(judge.st_text)
    killed_late = [m for m in sites if m.operator == "constant"][:4]
    for index, scenario in list(enumerate(judge.scenarios))[-2:]:
        for text in [judge.st_text] + [m.apply(judge.st_text) for m in killed_late]:
            try:
                factory = builtin_side_factory(text)
            except Exception:  # noqa: BLE001 - an invalid mutant has no run to compare
                continue
            lockstep = cosimulate(judge.program, factory, judge.iomap, scenario, judge.names,
                                  compiled=judge.compiled, base_mp=judge.base_mp)
            replayed = cosimulate(judge.program, factory, judge.iomap, scenario, judge.names,
                                  compiled=judge.compiled, base_mp=judge.base_mp,
                                  recording=judging.judge.recordings[index])
            assert (replayed.cycles_run, replayed.divergence, replayed.error, replayed.error_side,
                    replayed.missing, replayed.compared_indexed, replayed.swept, replayed.expectation_failures) == (
                lockstep.cycles_run, lockstep.divergence, lockstep.error, lockstep.error_side, lockstep.missing,
                lockstep.compared_indexed, lockstep.swept, lockstep.expectation_failures)
