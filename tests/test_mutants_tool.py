"""The pure parts of `make mutants` (tests/mutants.py): where it mutates, how it samples, which values it aims at."""

from __future__ import annotations

from tests.mutants import OPERATORS, boundary_values, choose, mutation_sites
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
