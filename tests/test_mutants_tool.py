"""The pure parts of `make mutants` (tests/mutants.py): where it mutates, how it samples, which values it aims at."""

from __future__ import annotations

import pytest

import tests.mutants as mutants
from tests.mutants import ERROR, INVALID, KILLED, OPERATORS, SURVIVED, Harness, Mutant, Verdict, boundary_values, \
    choose, mutation_sites, report
from transpiler.diagnostics import CompileFailed, Diagnostic, Severity, Span
from transpiler.verify.cosim import CosimResult, Divergence
from transpiler.frontend.load import ProjectOptions
from transpiler.frontend.pipeline import compile_project
from transpiler.language.semantics import make_semantics

ST = """\
FUNCTION HH_HELPER : BOOL
VAR_INPUT
    A : BOOL;
END_VAR
    HH_HELPER := A AND TRUE;
END_FUNCTION

FUNCTION_BLOCK Step_chain
VAR_EXTERNAL
    M1 : BOOL; (* AND 7 in a comment *)
    W2 : INT;
END_VAR
    M1 := M1 AND NOT W2 >= 7; (* 3 OR 4 *)
    CASE W2 OF
        1: W2 := 2;
        2: W2 := 1;
    END_CASE;
END_FUNCTION_BLOCK
"""


def _changed_lines(original: str, mutated: str) -> list[int]:
    a, b = original.splitlines(), mutated.splitlines()
    if len(a) != len(b):
        return [-1]
    return [i for i, (x, y) in enumerate(zip(a, b)) if x != y]


def test_every_operator_finds_its_sites_in_translated_bodies_only():
    sites = mutation_sites(ST)
    assert {m.operator for m in sites} == set(OPERATORS)
    assert all(m.pou == "Step_chain" for m in sites)                  # the HH_ library is left alone
    descriptions = {(m.operator, m.description) for m in sites}
    assert ("and_or", "AND -> OR") in descriptions
    assert ("negation", "NOT dropped") in descriptions
    assert ("comparison", "'>=' -> '>'") in descriptions
    assert ("constant", "7 -> 8") in descriptions and ("constant", "7 -> 6") in descriptions
    assert ("swap_case", "CASE branches 1 and 2 swapped") in descriptions
    # Lines with a CASE label are left to the swap (a bumped label would only duplicate or drop a branch).
    assert not any(m.operator == "constant" and m.line in (15, 16) for m in sites)
    for m in sites:
        assert "(* AND 7 in a comment *)" in m.text
        assert "(* 3 OR 4 *)" in m.text or m.operator == "drop_statement"


def test_a_mutant_changes_one_place_except_a_case_swap_or_a_dropped_statement():
    for m in mutation_sites(ST):
        changed = _changed_lines(ST, m.text)
        if m.operator == "swap_case":
            assert len(changed) == 2
        elif m.operator == "drop_statement":
            assert len(m.text.splitlines()) == len(ST.splitlines()) - 1
        else:
            assert changed == [m.line - 1], m


def test_choose_spreads_the_sample_over_the_operators_and_oversampling_returns_every_site():
    sites = mutation_sites(ST)
    picked = choose(sites, 6, seed=3)
    assert len(picked) == 6 and len({m.operator for m in picked}) == len(OPERATORS)
    # More than there are: every site once, the shares of small operators passed on to the larger ones.
    assert sorted(choose(sites, len(sites) + 10, seed=3), key=id) == sorted(sites, key=id)


def test_boundary_values_hold_each_constant_of_the_program_and_its_neighbours(tmp_path):
    (tmp_path / "main.src").write_text("L     W10\n>=    K24\n=     M1\nL     K-5\n=     W12\nEM\n")
    program = compile_project(ProjectOptions(main=tmp_path / "main.src"), make_semantics("itnc530", {})).program
    values = boundary_values(program)
    assert {23, 24, 25, -6, -5, -4} <= set(values)
    assert 0 in values and 32767 in values and values == tuple(sorted(values))


# ---- judging: only a divergence kills a mutant

MUTANT = Mutant("and_or", 3, "Step_chain", "AND -> OR", ST)


class _Scenario:
    def __init__(self, name: str):
        self.name = name
        self.cycles = 10


def _harness(monkeypatch, outcomes, factory_error: Exception | None = None) -> Harness:
    """A Harness without the sample: `outcomes` gives, per scenario, a CosimResult or an exception to raise."""
    harness = object.__new__(Harness)
    harness.program = harness.iomap = harness.names = harness.compiled = None
    harness.scenarios = [_Scenario(f"s{n}") for n in range(len(outcomes))]

    def side_factory(text):
        if factory_error is not None:
            raise factory_error
        return lambda: None

    def cosimulate(program, factory, iomap, scenario, names, compiled=None):
        outcome = outcomes[int(scenario.name[1:])]
        if isinstance(outcome, Exception):
            raise outcome
        return outcome

    harness.side_factory = side_factory
    monkeypatch.setattr(mutants, "cosimulate", cosimulate)
    return harness


def _result(divergence: bool = False, error: str | None = None) -> CosimResult:
    return CosimResult("s", "builtin", 5, Divergence(4, "M1", "Flag", 0, 1) if divergence else None, 3, error=error)


def test_a_divergence_kills_the_mutant(monkeypatch):
    # Catches: a diverging scenario not reported as a kill, or the verdict not naming the scenario and cycle.
    verdict = _harness(monkeypatch, [_result(), _result(divergence=True)]).judge(MUTANT)
    assert (verdict.outcome, verdict.detected) == (KILLED, True)
    assert verdict.by == "s1: Flag at cycle 4"


def test_a_mutant_the_executor_rejects_is_invalid_with_its_message_not_killed(monkeypatch):
    # Catches the old behaviour: ST that no longer compiles counted as detected.
    fault = CompileFailed([Diagnostic("E-ST-PARSE", Severity.ERROR, Span("project.st", 14), "unexpected OR")])
    verdict = _harness(monkeypatch, [_result(divergence=True)], factory_error=fault).judge(MUTANT)
    assert (verdict.outcome, verdict.detected) == (INVALID, False)
    assert "unexpected OR" in verdict.by
    verdict = _harness(monkeypatch, [_result()], factory_error=RuntimeError("no such POU")).judge(MUTANT)
    assert verdict.outcome == INVALID and "RuntimeError: no such POU" in verdict.by


def test_runtime_faults_of_the_translated_side_are_errors_not_kills(monkeypatch):
    # Catches the old behaviour: a co-simulation result with an error (executor fault, handshake timeout, loop
    # watchdog) but no divergence counted as detected.
    verdict = _harness(monkeypatch, [_result(error="translated program failed in cycle 2: Trap: loop watchdog"),
                                     _result()]).judge(MUTANT)
    assert (verdict.outcome, verdict.detected) == (ERROR, False)
    assert verdict.by == "s0: translated program failed in cycle 2: Trap: loop watchdog"


def test_an_exception_raised_by_the_cosimulation_is_an_error_and_the_next_scenarios_still_run(monkeypatch):
    # Catches: a crash of the harness propagating (aborting the whole run) or counted as a kill; and a later
    # divergence being missed because judging stopped at the first exception.
    verdict = _harness(monkeypatch, [ValueError("bad accessor"), _result()]).judge(MUTANT)
    assert (verdict.outcome, verdict.by) == (ERROR, "s0: ValueError: bad accessor")
    verdict = _harness(monkeypatch, [ValueError("bad accessor"), _result(error="fault"),
                                     _result(divergence=True)]).judge(MUTANT)
    assert (verdict.outcome, verdict.by) == (KILLED, "s2: Flag at cycle 4")


def test_a_mutant_without_divergence_or_exception_survives(monkeypatch):
    # Catches: a clean run counted as anything but a survivor.
    verdict = _harness(monkeypatch, [_result(), _result()]).judge(MUTANT)
    assert (verdict.outcome, verdict.detected, verdict.by) == (SURVIVED, False, "")


def test_the_summary_counts_each_category_separately_and_only_kills_count(capsys):
    # Catches: errors or invalid mutants counted as killed in the rate, or not listed with their messages.
    verdicts = [Verdict(MUTANT, KILLED, "s0: Flag at cycle 4", 0.1)] * 8 + [
        Verdict(MUTANT, ERROR, "s1: Trap: loop watchdog", 0.1), Verdict(MUTANT, SURVIVED, "", 0.1),
        Verdict(MUTANT, INVALID, "rejected: unexpected OR", 0.1)]
    assert report(verdicts, 1.0) == 1                  # 8 of 10 valid = 80 % < 90 %, though 10 of 11 "did something"
    out = capsys.readouterr().out
    assert "killed 8 of 10 valid mutants = 80.0 %" in out and "errors 1 (not killed)" in out
    assert "invalid 1 (excluded)" in out
    and_or = next(line for line in out.splitlines() if line.startswith("and_or"))
    assert and_or.split() == ["and_or", "11", "8", "1", "1", "1"]
    assert "Trap: loop watchdog" in out and "rejected: unexpected OR" in out
    assert report([Verdict(MUTANT, KILLED, "s0", 0.1)] * 9 + [Verdict(MUTANT, INVALID, "x", 0.1)] * 5, 1.0) == 0


@pytest.mark.parametrize("outcome", [ERROR, INVALID, SURVIVED])
def test_only_killed_is_detected(outcome):
    # Catches: the `detected` view (used by callers that only ask yes/no) treating errors as detections.
    assert Verdict(MUTANT, outcome, "", 0.0).detected is False
