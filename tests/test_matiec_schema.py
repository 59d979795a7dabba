"""Mutant schemata on matiec (exec/compiled/schema_st.py, matiec_schema.py): one ST program holding every mutant
behind a global mutant number, built once, must judge every mutant as its own text built alone does.

Without iec2c (CI), the schema text is still checked: valid ST for blark and the built-in executor, and each mutant
number (0 the original) running what that mutant's own text runs, on the built-in executor."""

from __future__ import annotations

import importlib.util

import pytest

from tests.construct_judges import construct_judge, construct_parts, plain
from transpiler.backends.st.check import check_blark, find_iec2c
from transpiler.exec.compiled.schema_st import build_schema, checked_schema
from transpiler.exec.stexec import TextMutation
from transpiler.verify.cosim import builtin_side_factory
from transpiler.verify.mutate import judge_all, mutation_sites

def _mutations(st_text: str) -> list[TextMutation]:
    return [TextMutation(i + 1, m.changes) for i, m in enumerate(mutation_sites(st_text))]


# ---------------------------------------------------------------------------------------------- without matiec


@pytest.mark.parametrize("name", ["case_chain", "word_arith_flags"])
def test_the_schema_text_is_st_with_the_lines_of_the_original(name):
    # Catches: a switch that is not ST (a conditional expression, a misplaced END_IF), a declaration of the mutant
    # number that the executors reject, or an insertion that moves lines (a tool's line would name another line).
    _project, transpiled, *_ = construct_parts(name, random_cycles=0)
    text = transpiled.st_text
    # the writer's own text, unchecked (checked_schema would fall back to a schema without the lines the executor
    # rejects): only the mutant whose constant lies past DINT, which the checker rejects by design, is left out
    invalid = {i + 1 for i, m in enumerate(mutation_sites(text)) if "2147483649" in m.description}
    schema = build_schema(text, _mutations(text), leave_out=invalid)
    assert schema.switched and schema.text != text
    assert len(schema.text.splitlines()) == len(text.splitlines())
    assert f"{schema.names.mutant} : DINT" in schema.text
    if importlib.util.find_spec("blark") is not None:
        assert check_blark(schema.text, "schema.st") == []
    builtin_side_factory(schema.text)        # parses and type-checks like strict matiec, or raises


@pytest.mark.parametrize("name", ["case_chain", "word_arith_flags"])
def test_each_mutant_number_runs_what_its_own_text_runs(name):
    # The schema text on the built-in executor, its global set to each number in turn (0 the original), against
    # each mutant's own text: the same verdict and killer. Catches a switch that selects other code than the
    # mutation (a SEL with its arguments the wrong way round, a swapped CASE remapped wrongly, a number off by one).
    judge = construct_judge(name, lambda transpiled: builtin_side_factory)
    sites = mutation_sites(judge.st_text)
    schema = checked_schema(judge.st_text, _mutations(judge.st_text))
    built = builtin_side_factory(schema.text)

    def numbered(number: int):
        def make():
            side = built()
            side.set(schema.names.mutant, number)
            return side
        return make
    original = judge.run(sites[0], numbered(0), range(len(judge.scenarios)), 0.0)
    assert original.outcome == "survived" and original.runs == len(judge.scenarios)
    checked = 0
    for index, mutant in enumerate(sites):
        if index + 1 in schema.unswitched:
            continue
        assert plain(judge.run(mutant, numbered(index + 1), range(len(judge.scenarios)), 0.0)) == \
            plain(judge(mutant)), mutant
        checked += 1
    assert checked >= len(sites) * 3 // 4


def test_a_probing_run_marks_the_mutants_it_infects():
    # A negative number runs the original and sets the flag of each mutant whose mutated code computes another
    # value (or, for a call, runs): a constant no run reaches is never flagged, the mutants of a statement that
    # runs on every cycle are.
    judge = construct_judge("case_chain", lambda transpiled: builtin_side_factory)
    sites = mutation_sites(judge.st_text)
    schema = checked_schema(judge.st_text, _mutations(judge.st_text))
    side = builtin_side_factory(schema.text)()
    side.set(schema.names.mutant, -1)
    for _ in range(3):
        side.run_cycle()
    flagged = {k for k in range(1, schema.size + 1) if side.get(f"{schema.names.hits}[{k}]")}
    every_cycle = {i + 1 for i, m in enumerate(sites) if m.original.startswith("W6 :=")}
    assert every_cycle and every_cycle <= flagged
    assert flagged <= schema.switched and flagged != schema.switched


# ---------------------------------------------------------------------------------------------- with matiec


@pytest.mark.skipif(find_iec2c() is None, reason="iec2c not found ($MATIEC_HOME/iec2c or PATH): set MATIEC_HOME")
def test_matiec_schema_gives_every_mutant_the_verdict_of_its_own_build(tmp_path, monkeypatch):
    # Every mutant of one construct, built on its own (as without schemata) and in one schema: the same killed and
    # survived lists and the same killers. Catches what the built-in run above cannot: ST that matiec compiles
    # differently in the schema (SEL's typing, a flag array or external matiec declares otherwise), a mutant number
    # the harness does not set, or a probing run that misses a run that would kill.
    from transpiler.exec.compiled.matiec_schema import MatiecSchema
    from transpiler.exec.compiled.matiec_side import matiec_side_factory
    monkeypatch.setenv("HH2IEC_CACHE", str(tmp_path))
    iec2c = find_iec2c()
    # The construct's scenario with a few generated cycles: stimulus that kills some mutants and leaves others, so
    # that both lists are compared (the full generated budget kills all of them).
    judge = construct_judge("case_chain", lambda t: (lambda text: matiec_side_factory(text, t.result.project, iec2c)),
                   lambda t: (lambda text, mutations: MatiecSchema(text, mutations, t.result.project, iec2c)),
                   random_cycles=40)
    sites = mutation_sites(judge.st_text)
    schema = judge.schema_factory(judge.st_text, _mutations(judge.st_text))
    assert not schema.unswitched
    verdicts = list(judge_all(judge, sites, 1))
    before = [plain(judge(m)) for m in sites]
    assert [plain(v) for v in verdicts] == before
    assert {outcome for outcome, _ in before} >= {"killed", "survived"}
    for v in verdicts:
        if v.outcome == "killed":
            assert v.by.startswith(judge.scenarios[v.scenarios_run[-1]].name + ": ")


def test_a_mutant_that_is_no_valid_st_is_left_to_its_own_build():
    # word_arith_flags has a constant mutated past DINT's range: the checker rejects its line in the schema, and
    # only that mutant (not the whole schema) is left out, to be built alone (and found invalid) as before.
    _project, transpiled, *_ = construct_parts("word_arith_flags", random_cycles=0)
    sites = mutation_sites(transpiled.st_text)
    schema = checked_schema(transpiled.st_text, _mutations(transpiled.st_text))
    out_of_range = {i + 1 for i, m in enumerate(sites) if "2147483649" in m.description}
    assert out_of_range and out_of_range <= schema.unswitched
    assert len(schema.unswitched) <= 3


def test_the_lines_matiec_rejects_are_read_from_its_message():
    from transpiler.exec.compiled.matiec_schema import rejected_lines
    message = ("iec2c failed: /tmp/x/project.st:105-5..105-22: error: Incompatible data types for ':=' operation.\n"
               "/tmp/x/project.st:110-9..111-4: error: Data type mismatch\n2 error(s) found. Bailing out!")
    assert rejected_lines(message) == {105, 110, 111}


GUARDED = """PROGRAM Main
VAR
    i : INT;
    a : ARRAY [0..3] OF INT;
    y : BOOL;
END_VAR
    i := i + 1;
    IF i > 3 THEN
        y := FALSE;
    ELSIF a[i] = 0 THEN
        y := TRUE;
    END_IF;
END_PROGRAM
CONFIGURATION C
    RESOURCE R ON PLC
        TASK T(INTERVAL := T#20ms, PRIORITY := 0);
        PROGRAM P WITH T : Main;
    END_RESOURCE
END_CONFIGURATION
"""


def test_an_elsif_condition_is_probed_only_where_its_if_computes_it():
    # `a[i]` is read only while i <= 3: a probe that compared the ELSIF's mutants on entering the IF without the
    # first condition would index out of range (the built-in executor raises; compiled C reads stray memory).
    sites = mutation_sites(GUARDED)
    schema = checked_schema(GUARDED, _mutations(GUARDED))
    elsif = {i + 1 for i, m in enumerate(sites) if m.line == 10}
    assert elsif and elsif <= schema.switched
    from transpiler.exec.stexec import load_st
    rt = load_st(schema.text).instantiate()
    rt.set(schema.names.mutant, -1)
    for _ in range(6):
        rt.run_cycle()                     # i runs past 3: raises if a[i] is computed there
    assert rt.get("P.i") == 6
    flagged = {k for k in elsif if rt.get(f"{schema.names.hits}[{k}]")}
    constant = {i + 1 for i, m in enumerate(sites) if m.line == 10 and m.description.startswith("0 -> 1")}
    assert constant and constant <= flagged     # a[1] = 0 and a[1] = 1 differ on the first cycle
