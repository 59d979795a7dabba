"""Clean-up of the emitted ST: constant comparisons folded, boolean constants simplified (exprs.py), temporaries
read once by the next statement propagated (passes.py), and the readability figure that watches all of it."""

from __future__ import annotations

from pathlib import Path

from transpiler import api
from transpiler.backends.iec_model import Configuration, IecProject, IecVar, Pou, VarSection
from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.st.passes import propagate_temporaries
from transpiler.backends.st.printer import with_statements
from transpiler.backends.st.readability import measure

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "samples" / "basic_program" / "Main_PGM.src"


def test_comparison_of_two_literals_is_folded():
    assert E.binop("<=", E.int_const(1), E.int_const(24), "BOOL", E.PREC_CMP).bool_const is True
    assert E.binop("=", E.int_const(3), E.int_const(4), "BOOL", E.PREC_EQ).text == "FALSE"
    x = E.var("x", "DINT")
    assert E.binop("<=", x, E.int_const(24), "BOOL", E.PREC_CMP).text == "x <= 24"


def test_boolean_constants_drop_out():
    a = E.var("a", "BOOL")
    assert E.b_and(E.bool_const(True), a).text == "a"
    assert E.b_and(a, E.bool_const(False)).text == "FALSE"
    assert E.b_or(E.bool_const(False), a).text == "a"
    assert E.b_or(a, E.bool_const(True)).text == "TRUE"


def _fb(statements: list[S.Stmt], temps: list[str]) -> Pou:
    local = tuple(IecVar(t, "BOOL") for t in temps) + (IecVar("keep", "BOOL"),)
    return with_statements(Pou("F", "FUNCTION_BLOCK", (VarSection("VAR", local),), ""), statements)


def _b(name: str) -> E.Expr:
    return E.var(name, "BOOL")


def test_temporary_read_once_by_the_next_statement_is_propagated():
    pou = propagate_temporaries(_fb([S.Assign("tmp1", E.b_and(_b("a"), _b("b"))),
                                     S.If(_b("tmp1"), (S.Assign("x", E.bool_const(True)),)),
                                     S.Assign("y", E.b_not(_b("tmp2")))], ["tmp1", "tmp2"]))
    assert pou.body.startswith("IF (a AND b) THEN") and "tmp1" not in pou.body
    assert pou.statements[0].cond.deps == {"A", "B"}
    assert [v.name for v in pou.sections[0].vars] == ["tmp2", "keep"]


def test_temporary_read_in_a_loop_condition_or_later_stays():
    statements = [S.Assign("tmp1", _b("a")), S.While(_b("tmp1"), (S.Assign("a", E.bool_const(False)),)),
                  S.Assign("tmp2", _b("b")), S.Assign("b", E.bool_const(False)), S.Assign("c", _b("tmp2"))]
    pou = _fb(statements, ["tmp1", "tmp2"])
    assert propagate_temporaries(pou) == pou


def test_temporary_read_twice_stays():
    pou = _fb([S.Assign("tmp1", _b("a")), S.Assign("x", E.b_and(_b("tmp1"), _b("tmp1")))], ["tmp1"])
    assert propagate_temporaries(pou) == pou


def test_temporary_propagates_inside_a_nested_block_past_comments():
    # Catches: only the top-level block searched, or a comment taken for the statement that reads the value.
    inner = (S.Assign("tmp1", E.b_not(_b("a"))), S.Comment("source comment"), S.Assign("x", _b("tmp1")))
    pou = propagate_temporaries(_fb([S.If(_b("c"), inner, (S.Return(),))], ["tmp1"]))
    assert pou.body == "IF c THEN\n    (* source comment *)\n    x := (NOT a);\nELSE\n    RETURN;\nEND_IF;"


def test_fb_output_passed_to_its_own_next_call_stays_named():
    # The call reads its input before it changes its output: the temporary holds the old output.
    statements = [S.Assign("tmp1", E.var("acc.Q", "BOOL")), S.Call("acc", (("IDX", E.int_const(3)), ("VALUE", _b("tmp1"))))]
    pou = _fb(statements, ["tmp1"])
    assert propagate_temporaries(pou) == pou


def test_temporary_whose_bit_is_read_stays():
    # Catches: a word's temporary replaced by its expression where its bit is read (`(a + b).3` is no ST).
    word = E.binop("+", E.var("a", "DINT"), E.var("b", "DINT"), "DINT", E.PREC_ADD)
    pou = _fb([S.Assign("tmp1", word), S.Assign("x", E.bit_of(E.var("tmp1", "DINT"), 3, access=True))], ["tmp1"])
    assert propagate_temporaries(pou) == pou


def test_temporary_written_by_the_next_statement_stays():
    # Catches: an occurrence as the next statement's target taken for a read (the value would be lost).
    pou = _fb([S.Assign("tmp1", _b("a")), S.Assign("tmp1", _b("b"))], ["tmp1"])
    assert propagate_temporaries(pou) == pou


def test_sample_has_no_unfolded_constant_comparison_and_no_stack_lines():
    project = api.load_project(api.project_options(SAMPLE))
    out = api.transpile(project, formats=("st",))
    assert "1 <= 24" not in out.st_text
    figure = measure(out.result.project, project.program.instruction_count())
    assert figure.stack_lines == 0 and figure.statements > 0
    assert figure.per_instruction <= 1.2
    assert "### Readability" in out.files["report.md"].decode()


def _readability_project(externals_title: str | None = None) -> IecProject:
    externals = VarSection("VAR_EXTERNAL", (IecVar("HH_SP", "INT"), IecVar("A", "BOOL")), comment=externals_title)
    body = "(* comment *)\nHH_SP := HH_SP - 1;\ntmp1 := HH_BIT(A, 3);\n\nA := tmp1;"
    user = Pou("F", "FUNCTION_BLOCK", (externals,), body)
    helper = Pou("HH_BIT", "FUNCTION", (), "HH_BIT := tmp1 AND HH_SP(1);", return_type="BOOL")    # (not counted)
    return IecProject("P", (), (helper, user), Configuration("C", "R", (), (), ()))


def test_readability_counts_what_it_says():
    figure = measure(_readability_project(), 4)
    assert (figure.statements, figure.stack_lines, figure.temp_lines, figure.helper_calls, figure.var_external_lines) \
        == (3, 1, 2, 1, 2)
    assert figure.per_instruction == 0.75
    # a titled block (matiec's lists are grouped by area) counts the same
    assert measure(_readability_project("Markers"), 4).var_external_lines == 2
