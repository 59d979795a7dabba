"""Statement-level clean-up (simplify.py) on small hand-built trees: dead register stores, an IF that sets a
flag to its condition, an IF without statements."""

from __future__ import annotations

from transpiler.backends.st import exprs as E
from transpiler.backends.st import printer
from transpiler.backends.st import stmt as S
from transpiler.backends.st.simplify import simplify

REGS = frozenset({"HH_WA", "HH_LA"})


def _d(name: str) -> E.Expr:
    return E.var(name, "DINT")


def _b(name: str) -> E.Expr:
    return E.var(name, "BOOL")


def _text(block: list[S.Stmt]) -> str:
    return printer.body_text(simplify(block, REGS))


def test_register_store_overwritten_before_any_read_is_dropped():
    block = [S.Assign("HH_WA", _d("a")), S.Assign("W1", _d("b")), S.Assign("HH_WA", _d("c"))]
    assert _text(block) == "W1 := b;\nHH_WA := c;"


def test_register_store_read_in_between_or_by_the_overwrite_stays():
    # Catches: a read in an assignment's value, in a target's index or in the overwrite itself missed.
    for reader in (S.Assign("W1", _d("HH_WA")), S.Assign("MEM[HH_WA]", _d("b")),
                   S.If(E.binop(">", _d("HH_WA"), E.int_const(0), "BOOL", E.PREC_CMP), (S.Assign("x", _b("y")),))):
        block = [S.Assign("HH_WA", _d("a")), reader, S.Assign("HH_WA", _d("c"))]
        assert simplify(block, REGS) == block
    block = [S.Assign("HH_WA", _d("a")), S.Assign("HH_WA", E.binop("+", _d("HH_WA"), E.int_const(1), "DINT", E.PREC_ADD))]
    assert simplify(block, REGS) == block


def test_register_store_stays_across_a_call_a_return_or_the_end_of_its_block():
    # A subprogram, the caller or the next loop pass may read the global register.
    for between in (S.Call("i_SUB"), S.If(_b("c"), (S.Return(),)), S.If(_b("c"), (S.Exit(),))):
        block = [S.Assign("HH_WA", _d("a")), between, S.Assign("HH_WA", _d("c"))]
        assert simplify(block, REGS) == block
    loop = [S.While(_b("c"), (S.Assign("W1", _d("HH_WA")), S.Assign("HH_WA", _d("a"))))]
    assert simplify(loop, REGS) == loop


def test_only_registers_count():
    block = [S.Assign("W1", _d("a")), S.Assign("W1", _d("b"))]
    assert simplify(block, REGS) == block


def test_if_setting_a_flag_to_its_condition_becomes_an_assignment():
    cond = E.b_and(_b("a"), _b("b"))
    block = [S.If(cond, (S.Assign("M1", E.bool_const(True)),), (S.Assign("M1", E.bool_const(False)),), note="f.src:3")]
    assert _text(block) == "M1 := a AND b; (* f.src:3 *)"
    swapped = [S.If(cond, (S.Assign("M1", E.bool_const(False)),), (S.Assign("M1", E.bool_const(True)),))]
    assert _text(swapped) == "M1 := NOT (a AND b);"


def test_if_setting_two_targets_or_values_stays():
    other = [S.If(_b("a"), (S.Assign("M1", E.bool_const(True)),), (S.Assign("M2", E.bool_const(False)),))]
    assert simplify(other, REGS) == other
    same = [S.If(_b("a"), (S.Assign("M1", E.bool_const(True)),), (S.Assign("M1", E.bool_const(True)),))]
    assert simplify(same, REGS) == same


def test_if_without_statements_leaves_its_comments():
    block = [S.If(_b("a"), (S.Comment("nothing here"),)), S.Assign("x", _b("y"))]
    assert _text(block) == "(* nothing here *)\nx := y;"


def test_dead_store_inside_a_branch_is_dropped():
    block = [S.If(_b("a"), (S.Assign("HH_LA", _b("b")), S.Assign("HH_LA", _b("c")))), S.Assign("x", _b("y"))]
    assert _text(block) == "IF a THEN\n    HH_LA := c;\nEND_IF;\nx := y;"


def test_consecutive_ifs_on_one_condition_become_one():
    cond = E.b_or(_b("m3"), _b("key"))
    block = [S.If(cond, (S.Assign("cw", E.bool_const(True)),)), S.If(cond, (S.Assign("ccw", E.bool_const(False)),)),
             S.If(cond, (S.Assign("orient", E.bool_const(False)),), note="Spindle.src:66")]
    assert _text(block) == ("IF m3 OR key THEN\n    cw := TRUE;\n    ccw := FALSE;\n"
                            "    orient := FALSE; (* Spindle.src:66 *)\nEND_IF;")


def test_ifs_stay_apart_where_the_first_changes_the_condition_or_calls():
    # Catches: a join that ignores a write to the condition's variable (the second IF would see the new value),
    # an FB call in the first body (it may write any global), an ELSE, or different conditions.
    cond = E.b_or(_b("m3"), _b("key"))
    for first in (S.If(cond, (S.Assign("key", E.bool_const(False)),)),
                  S.If(cond, (S.Call("Sub_1"),)),
                  S.If(cond, (S.Assign("cw", E.bool_const(True)),), (S.Assign("ccw", E.bool_const(True)),)),
                  S.If(_b("m4"), (S.Assign("cw", E.bool_const(True)),))):
        block = [first, S.If(cond, (S.Assign("ccw", E.bool_const(False)),))]
        assert simplify(block, REGS) == block


def test_store_overwritten_in_both_branches_of_a_later_if_is_dropped():
    # A division by a run-time divisor sets its error marker on both paths of the zero check: the store before it
    # is dead. Catches: one branch that does not overwrite, or reads first, or a condition that reads the store.
    def check(cond: E.Expr, then: tuple, orelse: tuple) -> list[S.Stmt]:
        block = [S.Assign("HH_LA", E.bool_const(False)), S.If(cond, then, orelse)]
        return simplify(block, REGS)

    nonzero = E.binop("<>", _d("d"), E.int_const(0), "BOOL", E.PREC_EQ)
    both = check(nonzero, (S.Assign("HH_WA", _d("q")), S.Assign("HH_LA", E.bool_const(False))),
                 (S.Assign("HH_LA", E.bool_const(True)),))
    assert [type(s) for s in both] == [S.If]
    for then, orelse, cond in (
            ((S.Assign("HH_WA", _d("q")),), (S.Assign("HH_LA", E.bool_const(True)),), nonzero),
            ((S.Assign("W1", _b("HH_LA")), S.Assign("HH_LA", _b("x"))), (S.Assign("HH_LA", _b("y")),), nonzero),
            ((S.Assign("HH_LA", _b("x")),), (S.Assign("HH_LA", _b("y")),), _b("HH_LA"))):
        assert len(check(cond, then, orelse)) == 2, (then, orelse, cond)
