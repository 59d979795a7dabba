"""The names an ST expression holds are built with it from its parts (exprs.Expr.names), so that the clean-up
passes and the VAR_EXTERNAL declarations look them up instead of scanning printed text: these tests hold the
built names to what a scan of the text (exprs.names_in) finds, on the constructors and on every expression of
translated projects, on each target."""

from __future__ import annotations

from pathlib import Path

import pytest

from transpiler import api
from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.st.backend import StBackend
from transpiler.backends.st.dialect import TARGETS
from transpiler.diagnostics import Diagnostics

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "basic_program" / "Main_PGM.src"


def _scanned(e: E.Expr) -> frozenset[str]:
    return frozenset(E.names_in(e.text))


@pytest.mark.parametrize("make", [
    lambda: E.var("ML_ax", "BOOL"),
    lambda: E.var("ML_ax.inpos", "BOOL"),
    lambda: E.var("GVL_Markers.ML_ax.inpos", "BOOL", "ML_AX.INPOS"),
    lambda: E.var("HH_STACK[HH_SP]", "INT", "HH_STACK"),
    lambda: E.int_const(-5, "INT"),
    lambda: E.int_const(-5),
    lambda: E.int_const(7, "SINT"),
    lambda: E.bool_const(True),
    lambda: E.call("HH_MKINT", [E.var("B0", "SINT"), E.var("GVL_Words.B1", "SINT", "B1")], "INT"),
    lambda: E.binop("MOD", E.var("W0", "INT"), E.int_const(3), "DINT", E.PREC_MUL),
    lambda: E.binop("+", E.to_dint(E.var("W0", "INT")), E.int_const(-3), "DINT", E.PREC_ADD),
    lambda: E.b_not(E.b_and(E.var("M1", "BOOL"), E.var("M2", "BOOL"))),
    lambda: E.b_not(E.b_not(E.b_or(E.var("M1", "BOOL"), E.var("fb.Q", "BOOL")))),
    lambda: E.to_dint(E.var("M1", "BOOL")),
    lambda: E.bit_of(E.to_dint(E.var("W4", "INT")), 3, access=True),
    lambda: E.bit_of(E.var("D8", "DINT"), 40, access=False),
    lambda: E.unwiden(E.to_dint(E.var("W4", "INT"))),
])
def test_built_names_are_the_names_in_the_text(make):
    e = make()
    assert E.names_of(e) == _scanned(e), e.text


def test_an_expression_made_from_text_alone_reads_its_text_once():
    e = E.Expr("HH_BIT(GVL_Words.W4, 3) AND ML_ax.inpos", "BOOL")
    assert e.names is None and e.parts is None
    assert E.names_of(e) == {"HH_BIT", "W4", "AND", "ML_AX", "ML_AX.INPOS"}
    assert e.names == E.names_of(e)


def test_names_come_from_the_parts_not_the_text():
    """A joined expression's names are its words' and operands' (the text is not read): an operand whose names
    were already known decides them."""
    a = E.var("M1", "BOOL")
    object.__setattr__(a, "names", frozenset({"SEEN_FROM_THE_TREE"}))
    assert E.names_of(E.b_and(a, E.var("M2", "BOOL"))) == {"SEEN_FROM_THE_TREE", "AND", "M2"}


def _expressions(statements) -> list[E.Expr]:
    found = []
    for s in S.walk(statements):
        if isinstance(s, S.Assign):
            found.append(s.value)
        elif isinstance(s, S.Call):
            found += [value for _, value in s.args]
        elif isinstance(s, (S.If, S.While)):
            found.append(s.cond)
        elif isinstance(s, S.Case):
            found.append(s.selector)
        elif isinstance(s, S.Repeat):
            found.append(s.until)
    return found


@pytest.mark.parametrize("target", sorted(TARGETS))
@pytest.mark.parametrize("main", [SAMPLE] + sorted((ROOT / "samples" / "constructs").glob("*/main.src"))[:6],
                         ids=lambda p: p.parent.name)
def test_every_expression_of_a_translation_knows_its_names(main, target):
    project = api.load_project(api.project_options(main))
    result = StBackend(project.program, Diagnostics(), {}, dialect=TARGETS[target]).build()
    built = 0
    for pou in result.project.pous:
        for e in _expressions(pou.statements):
            built += e.parts is not None or e.var is not None
            assert E.names_of(e) == _scanned(e), f"{pou.name}: {e.text}"
    assert built > 0
