"""Tests of the built-in ST executor (transpiler.stexec): parsing, strict typing, IEC semantics, runtime API."""

from __future__ import annotations

import random
import time

import pytest

from transpiler.diagnostics import CompileFailed
from transpiler.exec.stexec import StError, StRuntimeError, load_st

CONFIG = """
CONFIGURATION Cfg
  {globals}
  RESOURCE Res ON PLC
    TASK Fast(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM inst WITH Fast : Main;
  END_RESOURCE
END_CONFIGURATION
"""


def source(body: str, decls: str = "", before: str = "", globals_: str = "", located: str = "") -> str:
    loc = f"VAR\n{located}\nEND_VAR" if located else ""
    glob = f"VAR_GLOBAL\n{globals_}\nEND_VAR" if globals_ else ""
    return (f"{before}\nPROGRAM Main\nVAR\n{decls}\nEND_VAR\n{loc}\n{body}\nEND_PROGRAM\n"
            + CONFIG.format(globals=glob))


def run(body: str, decls: str = "", cycles: int = 1, **kw):
    rt = load_st(source(body, decls, **kw), "t.st").instantiate()
    for _ in range(cycles):
        rt.run_cycle()
    return rt


def line_of(text: str, fragment: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), start=1) if fragment in line)


def errors(text: str) -> list:
    with pytest.raises(StError) as info:
        load_st(text, "bad.st")
    return info.value.diagnostics


def one_error(body: str, decls: str = "", **kw):
    diags = errors(source(body, decls, **kw))
    assert diags, "expected an error"
    return diags[0]


# ---------------------------------------------------------------------- integer widths and wrap-around

@pytest.mark.parametrize("ty,start,op,expected", [
    ("SINT", 127, "+ 1", -128), ("SINT", -128, "- 1", 127),
    ("INT", 32767, "+ 1", -32768), ("INT", -32768, "- 1", 32767),
    ("DINT", 2147483647, "+ 1", -2147483648), ("DINT", -2147483648, "- 1", 2147483647),
    ("LINT", 9223372036854775807, "+ 1", -9223372036854775808),
    ("USINT", 255, "+ 1", 0), ("UINT", 65535, "+ 1", 0),
    ("UDINT", 0, "- 1", 4294967295), ("ULINT", 0, "- 1", 18446744073709551615),
    ("INT", 300, "* 300", (300 * 300 + 32768) % 65536 - 32768),
    ("DINT", 65536, "* 65536", 0),
])
def test_integer_wrap_around(ty, start, op, expected):
    rt = run(f"x := x {op};", f"x : {ty} := {start};")
    assert rt.get("inst.x") == expected


def test_intermediate_results_wrap_to_the_operand_width():
    # (a + b) / 2 for INT: the sum wraps to -32768 before the division, as IEC integer arithmetic requires.
    rt = run("r := (a + b) / 2;", "a : INT := 32767; b : INT := 1; r : INT;")
    assert rt.get("inst.r") == -16384


def test_bit_strings_wrap_through_conversions():
    rt = run("w := UINT_TO_WORD(WORD_TO_UINT(w) + 1); b := NOT b; d := SHL(d, 4) OR DWORD#16#F;",
             "w : WORD := 16#FFFF; b : BYTE := 16#0F; d : DWORD := 16#F0000001;")
    assert rt.get("inst.w") == 0
    assert rt.get("inst.b") == 0xF0
    assert rt.get("inst.d") == 0x0000001F


# ---------------------------------------------------------------------- conversions (targets.md 1.3, measured on matiec)

@pytest.mark.parametrize("expr,ty,expected", [
    ("INT_TO_WORD(-1)", "WORD", 65535),
    ("WORD_TO_INT(16#FFFF)", "INT", -1),
    ("INT_TO_BYTE(300)", "BYTE", 44),
    ("DINT_TO_INT(70000)", "INT", 4464),
    ("WORD_TO_BOOL(16#0100)", "BOOL", True),
    ("WORD_TO_BOOL(0)", "BOOL", False),
    ("BOOL_TO_BYTE(TRUE)", "BYTE", 1),
    ("BOOL_TO_INT(FALSE)", "INT", 0),
    ("REAL_TO_INT(2.5)", "INT", 2),
    ("REAL_TO_INT(3.5)", "INT", 4),
    ("REAL_TO_INT(-2.7)", "INT", -3),
    ("REAL_TO_DINT(1.0E10)", "DINT", 1410065408),
    ("TIME_TO_DINT(T#1s)", "DINT", 1),
    ("TIME_TO_DINT(T#1500ms)", "DINT", 1),
    ("DINT_TO_TIME(250)", "TIME", 250000),
    ("SHL(WORD#16#FFFF, 16)", "WORD", 0),
    ("SHL(WORD#1, 15)", "WORD", 0x8000),
    ("SHR(WORD#16#8000, 15)", "WORD", 1),
    ("ROL(BYTE#16#81, 1)", "BYTE", 0x03),
    ("ROR(BYTE#16#81, 1)", "BYTE", 0xC0),
    ("INT_TO_STRING(-42)", "STRING", "-42"),
    ("REAL_TO_STRING(1.5)", "STRING", "1.5"),
    ("STRING_TO_INT('123')", "INT", 123),
    ("DINT_TO_UDINT(-1)", "UDINT", 4294967295),
    ("UDINT_TO_SINT(UDINT#16#FFFFFF80)", "SINT", -128),
    ("LINT_TO_DINT(LINT#4294967297)", "DINT", 1),
    ("BYTE_TO_WORD(16#FF)", "WORD", 255),
    ("DWORD_TO_WORD(16#12345678)", "WORD", 0x5678),
    ("INT_TO_REAL(-3)", "REAL", -3.0),
    ("WORD_BCD_TO_UINT(16#1234)", "UINT", 1234),
    ("UINT_TO_BCD_WORD(1234)", "WORD", 0x1234),
])
def test_conversions_match_matiec(expr, ty, expected):
    rt = run(f"r := {expr};", f"r : {ty};")
    assert rt.get("inst.r") == expected


def test_trunc_rounds_toward_zero():
    rt = run("i := TRUNC(r); j := TRUNC(-r);", "r : REAL := 2.7; i : INT; j : DINT;")
    assert (rt.get("inst.i"), rt.get("inst.j")) == (2, -2)


def test_real_is_single_precision():
    rt = run("r := r + 1.0E-8; l := l + 1.0E-8;", "r : REAL := 1.0; l : LREAL := 1.0;")
    assert rt.get("inst.r") == 1.0          # 1e-8 is below REAL resolution at 1.0
    assert rt.get("inst.l") == 1.0 + 1e-8


# ---------------------------------------------------------------------- division

@pytest.mark.parametrize("a,b,q,m", [(-7, 2, -3, -1), (7, -2, -3, 1), (-7, -2, 3, -1), (7, 2, 3, 1)])
def test_division_truncates_toward_zero(a, b, q, m):
    rt = run("q := a / b; m := a MOD b;", f"a : DINT := {a}; b : DINT := {b}; q, m : DINT;")
    assert (rt.get("inst.q"), rt.get("inst.m")) == (q, m)


def test_division_overflow_wraps():
    rt = run("q := a / b;", "a : INT := -32768; b : INT := -1; q : INT;")
    assert rt.get("inst.q") == -32768


def test_integer_division_by_zero_is_a_runtime_error_with_line():
    text = source("x := 1;\nq := a / b;", "a : DINT := 5; b : DINT; q : DINT; x : INT;")
    rt = load_st(text, "t.st").instantiate()
    with pytest.raises(StRuntimeError) as info:
        rt.run_cycle()
    assert "division by zero" in info.value.message
    assert info.value.span is not None and info.value.span.line == line_of(text, "q := a / b")
    assert info.value.span.file == "t.st"


def test_div_function_by_zero_returns_zero_like_matiec():
    rt = run("q := DIV(a, b); m := MOD(a, b);", "a : DINT := 5; b : DINT; q, m : DINT;")
    assert (rt.get("inst.q"), rt.get("inst.m")) == (0, 0)


def test_real_division_by_zero_is_infinite():
    rt = run("r := 1.0 / z;", "r, z : REAL;")
    assert rt.get("inst.r") == float("inf")


# ---------------------------------------------------------------------- statements

CASE_BODY = """
CASE k OF
  1: r := 10;
  2, 3: r := 20;
  5..8, 10: r := 30;
  -4..-2: r := 40;
ELSE
  r := 99;
END_CASE;
"""


@pytest.mark.parametrize("sel,expected", [(1, 10), (2, 20), (3, 20), (4, 99), (5, 30), (8, 30), (9, 99),
                                          (10, 30), (-3, 40), (-2, 40), (-5, 99), (0, 99)])
def test_case_labels_ranges_lists_else(sel, expected):
    rt = run(CASE_BODY, f"k : INT := {sel}; r : INT;")
    assert rt.get("inst.r") == expected


@pytest.mark.parametrize("sel,expected", [(2, 1), (3, 1), (4, 3), (1, 1)])
def test_overlapping_case_labels_are_legal_and_the_first_branch_wins(sel, expected):
    # matiec accepts overlaps (a warning) and tests the branches in order, like an IF/ELSIF chain
    rt = run("CASE k OF 1..3: r := 1; 2: r := 2; 3, 4: r := 3; END_CASE;", f"k : INT := {sel}; r : INT;")
    assert rt.get("inst.r") == expected


def test_case_over_enum_and_no_match_without_else():
    before = "TYPE Mode : (Idle, Run, Stop); END_TYPE"
    body = "CASE m OF Idle: r := 1; Run, Stop: r := 2; END_CASE; CASE n OF 7: r := 100; END_CASE; m := Mode#Stop;"
    rt = run(body, "m : Mode := Run; n : INT := 3; r : INT := 5;", before=before)
    assert rt.get("inst.r") == 2
    assert rt.get("inst.m") == "Stop"


def test_while_repeat_exit():
    body = """
    i := 0; s := 0;
    WHILE i < 10 DO i := i + 1; IF i = 7 THEN EXIT; END_IF; s := s + i; END_WHILE;
    REPEAT k := k + 3; UNTIL k > 10 END_REPEAT;
    REPEAT n := n + 1; IF n >= 2 THEN EXIT; END_IF; UNTIL FALSE END_REPEAT;
    """
    rt = run(body, "i, s, k, n : DINT;")
    assert rt.get("inst.s") == sum(range(1, 7))
    assert rt.get("inst.i") == 7
    assert rt.get("inst.k") == 12          # REPEAT runs its body before the first test
    assert rt.get("inst.n") == 2


def test_for_loop_standard_semantics():
    body = """
    FOR i := 5 TO 5 DO a := a + 1; END_FOR;
    FOR i := 0 TO 1 BY 3 DO b := b + 1; END_FOR;
    FOR i := 0 TO 9 BY 3 DO c := c + 1; END_FOR;
    FOR i := 10 TO 0 BY -2 DO d := d + i; END_FOR;
    FOR j := 1 TO 0 DO e := e + 1; END_FOR;
    """
    rt = run(body, "i, j : INT; a, b, c, d, e : INT;")
    assert [rt.get(f"inst.{v}") for v in "abcde"] == [1, 1, 4, 30, 0]
    assert rt.get("inst.i") == -2


def test_nested_if_elsif_else_and_return():
    body = """
    IF x < 0 THEN r := -1;
    ELSIF x = 0 THEN r := 0;
    ELSIF x < 10 THEN r := 1; IF x = 5 THEN RETURN; END_IF;
    ELSE r := 2;
    END_IF;
    after := TRUE;
    """
    for x, r, after in [(-3, -1, True), (0, 0, True), (4, 1, True), (5, 1, False), (12, 2, True)]:
        rt = run(body, f"x : INT := {x}; r : INT; after : BOOL;")
        assert (rt.get("inst.r"), rt.get("inst.after")) == (r, after)


def test_infinite_loop_hits_the_watchdog():
    text = source("WHILE TRUE DO x := x + 1; END_WHILE;", "x : DINT;")
    rt = load_st(text, "t.st", loop_limit=1000).instantiate()
    with pytest.raises(StRuntimeError) as info:
        rt.run_cycle()
    assert "watchdog" in info.value.message
    assert rt.get("inst.x") == 1000


def test_array_index_out_of_range_is_a_runtime_error():
    rt = load_st(source("a[i] := 1;", "a : ARRAY[1..3] OF INT; i : INT := 4;"), "t.st").instantiate()
    with pytest.raises(StRuntimeError) as info:
        rt.run_cycle()
    assert "outside 1..3" in info.value.message


def test_arrays_structs_and_multi_dimensional():
    before = """TYPE
      TPt : STRUCT x : INT; y : INT := 7; END_STRUCT;
      TMat : ARRAY[0..2, 1..3] OF DINT;
      TPts : ARRAY[-1..1] OF TPt;
    END_TYPE"""
    body = """
    FOR i := 0 TO 2 DO FOR j := 1 TO 3 DO m[i, j] := i * 10 + j; END_FOR; END_FOR;
    pts[-1].x := 5; pts[1] := pts[-1]; pts[-1].x := 6;
    m2 := m; m[0, 1] := -1;
    """
    rt = run(body, "i, j : DINT; m, m2 : TMat; pts : TPts;", before=before)
    assert rt.get("inst.m[2,3]") == 23
    assert rt.get("inst.m2[0,1]") == 1 and rt.get("inst.m[0,1]") == -1   # array assignment copies
    assert rt.get("inst.pts[1]") == {"x": 5, "y": 7}                      # struct assignment copies
    assert rt.get("inst.pts[-1].x") == 6


def test_array_initialisers_with_repetition():
    before = "TYPE TA : ARRAY[0..5] OF INT := [1, 2(7), 3]; END_TYPE"
    rt = run("x := a[2] + b[1];", "a : TA; b : ARRAY[0..3] OF INT := [4(5)]; x : INT;", before=before)
    assert rt.get("inst.a") == [1, 7, 7, 3, 0, 0]
    assert rt.get("inst.x") == 12


# ---------------------------------------------------------------------- POUs

def test_function_block_with_var_external_reads_and_writes_globals():
    before = """
    FUNCTION_BLOCK Acc
      VAR_INPUT stp : DINT; END_VAR
      VAR_OUTPUT seen : DINT; END_VAR
      VAR_EXTERNAL G_SUM : DINT; G_LIMIT : DINT; END_VAR
      VAR_EXTERNAL CONSTANT G_K : DINT; END_VAR
      seen := G_SUM;
      IF G_SUM < G_LIMIT THEN G_SUM := G_SUM + stp * G_K; END_IF;
    END_FUNCTION_BLOCK
    """
    rt = load_st(source("a(stp := 3, seen => s);", "a : Acc; s : DINT;", before=before,
                        globals_="G_SUM : DINT; G_LIMIT : DINT := 20;")
                 .replace("VAR_GLOBAL", "VAR_GLOBAL CONSTANT G_K : DINT := 2; END_VAR VAR_GLOBAL"), "t.st").instantiate()
    for _ in range(3):
        rt.run_cycle()
    assert rt.get("G_SUM") == 18 and rt.get("inst.s") == 12
    rt.set("G_LIMIT", 100)
    rt.run_cycle()
    assert rt.get("G_SUM") == 24 and rt.get("inst.a.seen") == 18
    with pytest.raises(ValueError):
        rt.set("G_K", 3)


def test_function_with_var_in_out_and_outputs():
    before = """
    FUNCTION Bump : INT
      VAR_INPUT inc : INT; END_VAR
      VAR_IN_OUT acc : INT; END_VAR
      VAR_OUTPUT old : INT; END_VAR
      old := acc;
      acc := acc + inc;
      Bump := acc * 2;
    END_FUNCTION
    FUNCTION Fill : BOOL
      VAR_INPUT v : INT; END_VAR
      VAR_IN_OUT arr : TA; END_VAR
      VAR i : INT; END_VAR
      FOR i := 0 TO 3 DO arr[i] := v; END_FOR;
      Fill := TRUE;
    END_FUNCTION
    """
    before = "TYPE TA : ARRAY[0..3] OF INT; END_TYPE\n" + before
    body = "r := Bump(inc := 5, acc := n, old => o); ok := Fill(9, a); r2 := Bump(1, n);"
    rt = run(body, "n : INT := 10; r, r2, o : INT; a : TA; ok : BOOL;", before=before)
    assert rt.get("inst.o") == 10
    assert rt.get("inst.r") == 30
    assert rt.get("inst.n") == 16 and rt.get("inst.r2") == 32
    assert rt.get("inst.a") == [9, 9, 9, 9] and rt.get("inst.ok") is True


def test_function_missing_input_gets_default_and_result_defaults():
    before = """
    FUNCTION F : DINT
      VAR_INPUT a : DINT; b : DINT := 100; END_VAR
      IF a > 0 THEN F := a + b; END_IF;
    END_FUNCTION
    """
    rt = run("x := F(1); y := F(-1);", "x, y : DINT;", before=before)
    assert (rt.get("inst.x"), rt.get("inst.y")) == (101, 0)


def test_fb_instance_keeps_state_and_inputs_between_calls():
    before = """
    FUNCTION_BLOCK Counter
      VAR_INPUT inc : INT := 1; END_VAR
      VAR_OUTPUT n : INT; END_VAR
      n := n + inc;
    END_FUNCTION_BLOCK
    """
    rt = run("c(); c(inc := 5); c(); x := c.n;", "c : Counter; x : INT;", cycles=2, before=before)
    assert rt.get("inst.x") == 26          # 1 + 5 + 5, then 5 + 5 + 5: an input keeps its last value
    assert rt.get("inst.c.inc") == 5


def test_located_variables_by_address():
    text = """
    PROGRAM Main
      VAR
        in1 AT %IX0.0 : BOOL;
        out1 AT %QX0.1 : BOOL;
        mw AT %MW10 : INT := 5;
        qd AT %QD4 : DWORD;
      END_VAR
      VAR_EXTERNAL lamp : BOOL; END_VAR
      out1 := in1;
      mw := mw + 1;
      qd := SHL(DWORD#1, INT_TO_DINT(mw) MOD 32);
      lamp := NOT in1;
    END_PROGRAM
    CONFIGURATION Cfg
      VAR_GLOBAL lamp AT %QX1.0 : BOOL; END_VAR
      RESOURCE Res ON PLC
        TASK T(INTERVAL := T#20ms, PRIORITY := 1);
        PROGRAM inst WITH T : Main;
      END_RESOURCE
    END_CONFIGURATION
    """
    rt = load_st(text, "loc.st").instantiate()
    rt.set("%IX0.0", True)
    rt.run_cycle()
    assert rt.get("%QX0.1") is True and rt.get("inst.out1") is True
    assert rt.get("%MW10") == 6 and rt.get("%QD4") == 64
    assert rt.get("%QX1.0") is False and rt.get("lamp") is False
    rt.set("inst.in1", False)
    rt.run_cycle()
    assert rt.get("%QX0.1") is False and rt.get("%QX1.0") is True
    names = rt.names()
    assert {"%IX0.0", "%QX0.1", "%MW10", "%QD4", "%QX1.0", "inst.mw", "lamp"} <= set(names)
    assert rt.cycle_time_ms == 20


MIXED_BEFORE = """
TYPE
  MyInt : INT := 5;
  Lvl : INT (0..10);
  Mode : (Idle, Run, Stop) := Run;
  TPt : STRUCT x : INT := 1; y : MyInt; END_STRUCT;
END_TYPE
VAR_GLOBAL RETAIN gv : DINT := 10; END_VAR
FUNCTION Sq : DINT
  VAR_INPUT a : DINT; END_VAR
  VAR_OUTPUT neg : BOOL; END_VAR
  VAR_TEMP t : DINT; END_VAR
  t := a * a; Sq := t; neg := a < 0;
END_FUNCTION
FUNCTION Twice : DINT VAR_INPUT a : DINT; END_VAR Twice := Sq(a) * 2; END_FUNCTION
FUNCTION_BLOCK Inc
  VAR_IN_OUT v : DINT; END_VAR
  VAR_TEMP k : DINT := 3; END_VAR
  v := v + k; k := 100;
END_FUNCTION_BLOCK
"""

MIXED_BODY = """
IF x > 100 THEN r := 1;
ELSIF Sq(a := x, neg => n) > 50 THEN r := 2;
ELSE r := 3; END_IF;
i := 0;
WHILE Sq(a := i, neg => n) < 30 DO i := i + 1; IF i = 2 THEN CONTINUE; END_IF; cnt := cnt + 1; END_WHILE;
FOR j := 1 TO 10 DO IF j MOD 2 = 0 THEN CONTINUE; END_IF; odd := odd + j; END_FOR;
%QX3.0 := TRUE; w := %MW7;
inc1(v := gv); inc1(v := gv);
gfb(v := loc);
tw := Twice(3);
t1(IN := TRUE, NOT Q => nq);
m := Stop; lv := 7;
"""


def test_calls_with_outputs_in_conditions_temps_in_outs_and_defaults():
    decls = ("x : DINT := 9; r : INT; n : BOOL; i, cnt, j, odd, loc, tw : DINT; w : WORD; inc1 : Inc;"
             "t1 : TON := (PT := T#20ms); nq : BOOL; m : Mode; lv : Lvl; mi : MyInt; p : TPt;"
             "\nEND_VAR\nVAR_EXTERNAL gv : DINT; gfb : Inc;")
    rt = load_st(source(MIXED_BODY, decls, before=MIXED_BEFORE, globals_="gfb : Inc;"), "mix.st").instantiate()
    assert rt.get("inst.m") == "Run" and rt.get("inst.mi") == 5 and rt.get("inst.p") == {"x": 1, "y": 5}
    rt.set("%MW7", 0x1234)
    rt.run_cycle()
    assert (rt.get("inst.r"), rt.get("inst.n")) == (2, False)          # the ELSIF called Sq(9) = 81
    assert (rt.get("inst.i"), rt.get("inst.cnt")) == (6, 5)            # Sq(6) = 36 ends the WHILE
    assert rt.get("inst.odd") == 1 + 3 + 5 + 7 + 9
    assert rt.get("%QX3.0") is True and rt.get("inst.w") == 0x1234
    assert rt.get("gv") == 16 and rt.get("inst.loc") == 3                # VAR_TEMP k is 3 again on each call
    assert rt.get("inst.tw") == 18 and rt.get("inst.nq") is True
    assert rt.get("inst.t1.PT") == 20 and rt.get("inst.m") == "Stop"
    rt.set("inst.m", "idle")
    assert rt.get("inst.m") == "Idle"
    with pytest.raises(ValueError):
        rt.set("inst.lv", 11)


def test_located_size_mismatch_is_rejected():
    d = errors(source("x := TRUE;", located="x AT %MW0 : BOOL;"))[0]
    assert "bit size" in d.message


# ---------------------------------------------------------------------- timers, counters, edges

def test_ton_against_the_simulated_clock():
    body = "t(IN := start, PT := T#50ms); q := t.Q; et := t.ET;"
    rt = load_st(source(body, "t : TON; start : BOOL; q : BOOL; et : TIME;"), "t.st").instantiate()
    assert rt.cycle_time_ms == 10
    rt.run_cycle()                          # t = 0 ms
    rt.set("inst.start", True)
    history = []
    for _ in range(8):                      # cycles at 10, 20, ... 80 ms; started at 10 ms
        rt.run_cycle()
        history.append((rt.get("inst.q"), rt.get("inst.et")))
    assert [q for q, _ in history] == [False, False, False, False, False, True, True, True]
    assert [et for _, et in history][:6] == [0, 10, 20, 30, 40, 50]
    rt.set("inst.start", False)
    rt.run_cycle()
    assert (rt.get("inst.q"), rt.get("inst.et")) == (False, 0)


def test_tof_tp_edges_counters_bistables():
    body = """
    tof1(IN := x, PT := T#30ms, Q => qof);
    tp1(IN := x, PT := T#20ms, Q => qp);
    r1(CLK := x, Q => rise); f1(CLK := x, Q => fall);
    cu(CU := x, R := FALSE, PV := 2, Q => cq, CV => cv);
    sr1(S1 := x, R := rst, Q1 => srq); rs1(S := x, R1 := rst, Q1 => rsq);
    """
    decls = ("tof1 : TOF; tp1 : TP; r1 : R_TRIG; f1 : F_TRIG; cu : CTU; sr1 : SR; rs1 : RS; x, rst : BOOL;"
             "qof, qp, rise, fall, cq, srq, rsq : BOOL; cv : INT;")
    rt = load_st(source(body, decls), "t.st").instantiate()
    trace = []
    pattern = [1, 1, 0, 0, 0, 0, 1, 0, 1, 1]
    for i, x in enumerate(pattern):
        rt.set("inst.x", bool(x))
        rt.set("inst.rst", i == 8)
        rt.run_cycle()
        trace.append(tuple(int(rt.get(f"inst.{v}")) for v in ("qof", "qp", "rise", "fall", "cq", "cv", "srq", "rsq")))
    qof = [t[0] for t in trace]
    assert qof == [1, 1, 1, 1, 1, 0, 1, 1, 1, 1]             # off-delay 30 ms after the falling edge at 20 ms
    assert [t[1] for t in trace] == [1, 1, 0, 0, 0, 0, 1, 1, 0, 0]   # 20 ms pulses from 0 and 60 ms, IN ignored
    assert [t[2] for t in trace] == [1, 0, 0, 0, 0, 0, 1, 0, 1, 0]
    assert [t[3] for t in trace] == [0, 0, 1, 0, 0, 0, 0, 1, 0, 0]
    assert [t[5] for t in trace] == [1, 1, 1, 1, 1, 1, 2, 2, 2, 2]   # CTU counts rising edges up to PV
    assert trace[6][4] == 1 and trace[5][4] == 0
    assert [t[6] for t in trace][7:] == [1, 1, 1]                   # SR: set dominates reset
    assert [t[7] for t in trace][7:] == [1, 0, 1]                   # RS: reset dominates set


def test_tasks_with_different_intervals():
    text = """
    PROGRAM P1 VAR_EXTERNAL a : DINT; END_VAR a := a + 1; END_PROGRAM
    PROGRAM P2 VAR_EXTERNAL a, b : DINT; END_VAR b := b * 10 + a; END_PROGRAM
    CONFIGURATION C
      VAR_GLOBAL a, b : DINT; END_VAR
      RESOURCE R ON PLC
        TASK fast(INTERVAL := T#10ms, PRIORITY := 0);
        TASK slow(INTERVAL := T#30ms, PRIORITY := 1);
        PROGRAM p2i WITH slow : P2;
        PROGRAM p1i WITH fast : P1;
      END_RESOURCE
    END_CONFIGURATION
    """
    rt = load_st(text).instantiate()
    assert rt.cycle_time_ms == 10
    for _ in range(4):
        rt.run_cycle()
    # slow runs at 0 ms and 30 ms, before fast (program order of the resource)
    assert rt.get("a") == 4 and rt.get("b") == 0 * 10 + 3


# ---------------------------------------------------------------------- strings

@pytest.mark.parametrize("expr,expected", [
    ("CONCAT('ab', 'cd', 'e')", "abcde"),
    ("LEFT('abcdef', 2)", "ab"),
    ("RIGHT('abcdef', 2)", "ef"),
    ("MID('abcdef', 2, 3)", "cd"),
    ("INSERT('abef', 'cd', 2)", "abcdef"),
    ("DELETE('abcdef', 2, 3)", "abef"),
    ("REPLACE('abcdef', 'XYZ', 2, 3)", "abXYZef"),
    ("LEFT('abc', 10)", "abc"),
    ("'it$'s $$5'", "it's $5"),
    ("'a$0Ab'", "a\nb"),
])
def test_string_functions(expr, expected):
    rt = run(f"s := {expr};", "s : STRING;")
    assert rt.get("inst.s") == expected


def test_string_len_find_and_comparisons():
    rt = run("n := LEN(s); f := FIND(s, 'cd'); g := FIND(s, 'zz'); less := s < 'abd'; same := s = 'abcdef';",
             "s : STRING := 'abcdef'; n, f, g : INT; less, same : BOOL;")
    assert [rt.get(f"inst.{v}") for v in ("n", "f", "g", "less", "same")] == [6, 3, 0, True, True]


def test_concat_caps_at_126_characters():
    rt = run("s := CONCAT(s, s);", "s : STRING := '" + "x" * 100 + "';")
    assert len(rt.get("inst.s")) == 126


# ---------------------------------------------------------------------- literals and names

def test_literal_forms_and_case_insensitivity():
    body = """
    A := 16#FF + 2#1010 + 8#17 + 1_000;
    b := dint#-5; W := WORD#16#FF_FF; t := T#1h2m3s4ms + TIME#1.5s; f := BOOL#1;
    R := 1.5E3;
    """
    rt = run(body, "a : DINT; B : DINT; w : WORD; T : TIME; f : BOOL; r : LREAL;")
    assert rt.get("INST.A") == 255 + 10 + 15 + 1000
    assert rt.get("inst.b") == -5 and rt.get("inst.w") == 0xFFFF and rt.get("inst.f") is True
    assert rt.get("inst.t") == 3723004 + 1500
    assert rt.get("inst.r") == 1500.0


def test_long_and_chains_compile():
    terms = " AND ".join(f"(x > {i})" for i in range(400))
    rt = run(f"b := {terms};", "x : INT := 1000; b : BOOL;")
    assert rt.get("inst.b") is True


# ---------------------------------------------------------------------- type errors and parse errors

@pytest.mark.parametrize("body,decls,fragment", [
    ("x := y;", "x : INT; y : DINT;", "DINT where INT"),
    ("x := x + y;", "x : INT; y : DINT;", "mismatch for '+'"),
    ("b := 300;", "b : BYTE;", "does not fit BYTE"),
    ("w := w + 1;", "w : WORD;", "bit string"),
    ("x := x AND 1;", "x : INT;", "'AND'"),
    ("r := 2;", "r : REAL;", "REAL"),
    ("b := x;", "b : BOOL; x : INT;", "INT where BOOL"),
    ("IF x THEN x := 1; END_IF;", "x : INT;", "must be BOOL"),
    ("CASE w OF 1: x := 1; END_CASE;", "w : WORD; x : INT;", "CASE"),
    ("x := undefined_var;", "x : INT;", "undeclared"),
    ("w := SHL(w, b);", "w : WORD; b : BYTE;", "shift count"),
    ("s := s + 'a';", "s : STRING;", "not a number"),
    ("LEN(s);", "s : STRING;", "as a statement"),
    ("x := 1.5;", "x : INT;", "literal"),
])
def test_type_errors_are_reported_with_line(body, decls, fragment):
    d = one_error(body, decls)
    assert d.code == "E-ST-PARSE"
    assert fragment in d.message
    assert d.span.file == "bad.st" and d.span.line == line_of(source(body, decls), body)
    assert "Traceback" not in d.render()


def test_several_errors_are_all_reported():
    text = source("x := y;\nz := 1;\nx := TRUE;", "x : INT; y : DINT;")
    diags = errors(text)
    assert [d.span.line for d in diags] == [line_of(text, f) for f in ("x := y", "z := 1", "x := TRUE")]


def test_declaration_errors():
    d = errors(source("x := 1;", "x : INT;", before="FUNCTION_BLOCK F VAR_EXTERNAL nope : INT; END_VAR nope := 1; "
                                                         "END_FUNCTION_BLOCK"))[0]
    assert "does not match any global" in d.message
    d = errors(source("y := 1;", "y : INT;", globals_="K : INT := 3;").replace(
        "VAR_GLOBAL", "VAR_GLOBAL CONSTANT").replace("END_VAR\n\ny := 1;", "END_VAR\nVAR_EXTERNAL K : INT; END_VAR\ny := 1;"))
    assert any("CONSTANT" in x.message for x in d)
    diags = errors("FUNCTION F : INT VAR_EXTERNAL g : INT; END_VAR F := 1; END_FUNCTION")
    assert any("external variable(s) declaration in function" in x.message for x in diags)
    d = errors(source("x := F(1);", "x : INT;") + "\nFUNCTION F : INT VAR_INPUT a : INT; END_VAR F := a; END_FUNCTION")[0]
    assert "before its declaration" in d.message
    # keywords cannot name anything (matiec: "invalid located variable declaration."); IL operators can
    diags = errors(source("step := 1; by := 2;", "step : INT; by : INT; ld : INT;"))
    assert [x.message for x in diags if "reserved word" in x.message] == [
        "'step' is a reserved word of IEC 61131-3 and cannot be a variable name",
        "'by' is a reserved word of IEC 61131-3 and cannot be a variable name"]


def test_assignment_to_constant_and_fb_output_is_rejected():
    before = "FUNCTION_BLOCK Fb VAR_OUTPUT q : INT; END_VAR q := 1; END_FUNCTION_BLOCK"
    d = one_error("k := 2;", "x : INT;\nEND_VAR\nVAR CONSTANT k : INT := 1;")
    assert "CONSTANT" in d.message
    d = one_error("f.q := 2;", "f : Fb;", before=before)
    assert "output" in d.message


def test_parse_error_has_line_and_column():
    text = "PROGRAM Main\nVAR x : INT; END_VAR\n  x := 1\n  x := 2;\nEND_PROGRAM\n"
    diags = errors(text)
    assert len(diags) == 1
    d = diags[0]
    assert (d.span.line, d.span.col) == (4, 3)
    assert d.code == "E-ST-PARSE" and "unexpected 'x'" in d.message
    assert d.render().startswith("bad.st:4:3: error[E-ST-PARSE]")
    assert isinstance(StError([d]), CompileFailed)


@pytest.mark.parametrize("text,fragment", [
    ("PROGRAM P VAR x : INT; END_VAR x := 1; // c\nEND_PROGRAM", "(* ... *)"),
    ("PROGRAM P VAR x : INT; END_VAR {pragma} x := 1; END_PROGRAM", "pragmas"),
    ("PROGRAM P VAR x : INT; END_VAR x := 1; (* open", "unterminated comment"),
    ("PROGRAM P VAR x : INT; END_VAR IF TRUE THEN END_IF; END_PROGRAM", "syntax error"),
])
def test_parse_errors_are_diagnostics(text, fragment):
    d = errors(text)[0]
    assert fragment in d.message


def test_missing_configuration_is_reported_on_instantiate():
    project = load_st("PROGRAM P VAR x : INT; END_VAR x := 1; END_PROGRAM")
    with pytest.raises(StError):
        project.instantiate()


# ---------------------------------------------------------------------- externals and the runtime API

def test_external_overrides_function_and_function_block():
    before = """
    FUNCTION Scale : DINT
      VAR_INPUT v : DINT; k : DINT; END_VAR
      VAR_OUTPUT big : BOOL; END_VAR
      Scale := v * k; big := FALSE;
    END_FUNCTION
    FUNCTION_BLOCK Sensor
      VAR_INPUT req : BOOL; END_VAR
      VAR_OUTPUT value : INT; END_VAR
      value := 0;
    END_FUNCTION_BLOCK
    """
    body = "r := Scale(v := 5, k := 7, big => b); s(req := TRUE, value => sv);"
    text = source(body, "r : DINT; b : BOOL; s : Sensor; sv : INT;", before=before)
    plain = load_st(text).instantiate()
    plain.run_cycle()
    assert (plain.get("inst.r"), plain.get("inst.b"), plain.get("inst.sv")) == (35, False, 0)
    calls = []

    def scale(v, k):
        calls.append((v, k))
        return v + k, {"big": True}

    def sensor(state):
        assert state["req"] is True
        state["value"] = 70000             # wrapped to INT by the runtime

    rt = load_st(text).instantiate({"SCALE": scale, "sensor": sensor})
    rt.run_cycle()
    assert calls == [(5, 7)]
    assert (rt.get("inst.r"), rt.get("inst.b"), rt.get("inst.sv")) == (12, True, 70000 - 65536)


def test_external_function_results_are_completed_and_checked():
    before = """
    FUNCTION Stepper : INT
      VAR_INPUT k : INT; END_VAR
      VAR_IN_OUT acc : INT; END_VAR
      VAR_OUTPUT flag : BOOL; END_VAR
      Stepper := k; acc := acc + k; flag := TRUE;
    END_FUNCTION
    """
    body = "r := Stepper(k := 2, acc := n, flag => f);"
    text = source(body, "r : INT; n : INT := 5; f : BOOL := TRUE;", before=before)
    # a bare result: wrapped to INT; the missing in-out stays unchanged, the missing output gets its default
    rt = load_st(text, "t.st").instantiate({"stepper": lambda k, acc: 70000})
    rt.run_cycle()
    assert (rt.get("inst.r"), rt.get("inst.n"), rt.get("inst.f")) == (70000 - 65536, 5, False)
    # an output value that does not fit its type is a runtime error at the call
    rt = load_st(text, "t.st").instantiate({"stepper": lambda k, acc: (1, {"FLAG": 7})})
    with pytest.raises(StRuntimeError) as info:
        rt.run_cycle()
    assert "Stepper.flag: BOOL needs True/False, got 7" in info.value.message
    assert info.value.span is not None and info.value.span.line == line_of(text, body)


def test_set_wraps_and_validates():
    rt = run("x := x;", "x : INT; b : BOOL; w : WORD; s : STRING; a : ARRAY[0..1] OF INT;")
    rt.set("inst.x", 40000)
    assert rt.get("inst.x") == 40000 - 65536
    rt.set("inst.w", -1)
    assert rt.get("inst.w") == 0xFFFF
    rt.set("inst.b", 1)
    assert rt.get("inst.b") is True
    for path, value in (("inst.b", 2), ("inst.x", 1.5), ("inst.s", "x" * 127), ("inst.a", [1, 2])):
        with pytest.raises(ValueError):
            rt.set(path, value)
    with pytest.raises(KeyError):
        rt.get("inst.nope")
    with pytest.raises(KeyError):
        rt.get("inst.a[2]")


def test_runtimes_are_independent():
    project = load_st(source("x := x + 1;", "x : INT;"))
    a, b = project.instantiate(), project.instantiate()
    a.run_cycle()
    a.run_cycle()
    b.run_cycle()
    assert (a.get("inst.x"), b.get("inst.x")) == (2, 1)


# ---------------------------------------------------------------------- a large generated program

def _wrap32(v: int) -> int:
    return (v + 2 ** 31) % 2 ** 32 - 2 ** 31


def _wrap16(v: int) -> int:
    return (v + 2 ** 15) % 2 ** 16 - 2 ** 15


def _tdiv(a: int, b: int) -> int:
    q = abs(a) // abs(b)
    return q if (a < 0) == (b < 0) else -q


def generate_program(n_statements: int, seed: int):
    """A random straight-line/branching program in ST plus an independent Python model of one cycle."""
    rnd = random.Random(seed)
    st: list[str] = []
    model: list = []
    for _ in range(n_statements):
        a, b, c = rnd.randrange(16), rnd.randrange(16), rnd.randrange(16)
        k = rnd.randrange(-50, 50)
        kind = rnd.randrange(8)
        if kind == 0:
            st.append(f"v{a} := v{b} + {k};")
            model.append(lambda s, a=a, b=b, k=k: s["v"].__setitem__(a, _wrap32(s["v"][b] + k)))
        elif kind == 1:
            st.append(f"v{a} := v{b} * v{c} - v{a};")
            model.append(lambda s, a=a, b=b, c=c: s["v"].__setitem__(a, _wrap32(s["v"][b] * s["v"][c] - s["v"][a])))
        elif kind == 2:
            d = rnd.choice([3, 7, -5, 11])
            st.append(f"v{a} := v{b} / {d} + v{c} MOD {abs(d)};")
            model.append(lambda s, a=a, b=b, c=c, d=d: s["v"].__setitem__(
                a, _wrap32(_tdiv(s["v"][b], d) + (abs(s["v"][c]) % abs(d)) * (1 if s["v"][c] >= 0 else -1))))
        elif kind == 3:
            st.append(f"w{a % 8} := DINT_TO_INT(v{b}) + w{c % 8};")
            model.append(lambda s, a=a, b=b, c=c: s["w"].__setitem__(a % 8, _wrap16(_wrap16(s["v"][b]) + s["w"][c % 8])))
        elif kind == 4:
            st.append(f"f{a % 4} := (v{b} > v{c}) XOR f{c % 4};")
            model.append(lambda s, a=a, b=b, c=c: s["f"].__setitem__(a % 4, (s["v"][b] > s["v"][c]) != s["f"][c % 4]))
        elif kind == 5:
            st.append(f"IF f{a % 4} THEN v{b} := v{b} + 1; ELSE v{c} := v{c} - INT_TO_DINT(w{a % 8}); END_IF;")

            def m(s, a=a, b=b, c=c):
                if s["f"][a % 4]:
                    s["v"][b] = _wrap32(s["v"][b] + 1)
                else:
                    s["v"][c] = _wrap32(s["v"][c] - s["w"][a % 8])
            model.append(m)
        elif kind == 6:
            st.append(f"arr[{a}] := arr[{b}] + v{c}; v{a} := arr[{c}];")

            def m(s, a=a, b=b, c=c):
                s["arr"][a] = _wrap32(s["arr"][b] + s["v"][c])
                s["v"][a] = s["arr"][c]
            model.append(m)
        else:
            st.append(f"CASE v{a} MOD 4 OF 0: v{b} := v{b} + 2; 1, 2: v{b} := v{b} - 3; ELSE v{c} := {k}; END_CASE;")

            def m(s, a=a, b=b, c=c, k=k):
                r = abs(s["v"][a]) % 4 * (1 if s["v"][a] >= 0 else -1)
                if r == 0:
                    s["v"][b] = _wrap32(s["v"][b] + 2)
                elif r in (1, 2):
                    s["v"][b] = _wrap32(s["v"][b] - 3)
                else:
                    s["v"][c] = k
            model.append(m)
    decls = ("\n".join(f"v{i} : DINT := {i * 1000 + 7};" for i in range(16))
             + "\n" + "\n".join(f"w{i} : INT;" for i in range(8)) + "\nf0, f1, f2, f3 : BOOL;\narr : ARRAY[0..15] OF DINT;")
    text = source("\n".join(st), decls)
    state = {"v": [i * 1000 + 7 for i in range(16)], "w": [0] * 8, "f": [False] * 4, "arr": [0] * 16}
    return text, model, state


def test_generated_2000_statement_program_matches_an_independent_model():
    text, model, state = generate_program(2000, seed=7)
    rt = load_st(text, "gen.st").instantiate()
    for _ in range(5):
        rt.run_cycle()
        for step in model:
            step(state)
        assert [rt.get(f"inst.v{i}") for i in range(16)] == state["v"]
        assert [rt.get(f"inst.w{i}") for i in range(8)] == state["w"]
        assert [rt.get(f"inst.f{i}") for i in range(4)] == state["f"]
        assert rt.get("inst.arr") == state["arr"]


# IEC precedence levels used to print random expressions with as few parentheses as the grammar allows
_PREC = {"OR": 1, "XOR": 2, "AND": 3, "=": 4, "<>": 4, "<": 5, ">=": 5, "+": 6, "-": 6, "*": 7, "/": 7, "MOD": 7}


def _random_int_expr(rnd: random.Random, depth: int, env: dict):
    """(ST text, precedence, value) of a random DINT expression; value computed with IEC rules in plain Python."""
    if depth == 0 or rnd.random() < 0.2:
        if rnd.random() < 0.5:
            name = rnd.choice(sorted(env))
            return name, 10, env[name]
        k = rnd.randrange(0, 100000)
        return str(k), 10, k
    op = rnd.choice(["+", "-", "*", "/", "MOD", "neg"])
    if op == "neg":
        text, prec, value = _random_int_expr(rnd, depth - 1, env)
        return f"-{text if prec >= 9 else '(' + text + ')'}", 8, _wrap32(-value)
    lt, lp, lv = _random_int_expr(rnd, depth - 1, env)
    rt_, rp, rv = _random_int_expr(rnd, depth - 1, env)
    if op in ("/", "MOD"):
        rt_, rp, rv = f"({rt_}) MOD 7 + 8", 6, (abs(rv) % 7) * (1 if rv >= 0 else -1) + 8
    p = _PREC[op]
    text = f"{lt if lp >= p else '(' + lt + ')'} {op} {rt_ if rp > p else '(' + rt_ + ')'}"
    if op == "+":
        value = lv + rv
    elif op == "-":
        value = lv - rv
    elif op == "*":
        value = lv * rv
    elif op == "/":
        value = _tdiv(lv, rv)
    else:
        value = (abs(lv) % abs(rv)) * (1 if lv >= 0 else -1)
    return text, p, _wrap32(value)


def _random_bool_expr(rnd: random.Random, depth: int, env: dict):
    if depth == 0 or rnd.random() < 0.25:
        a, _, av = _random_int_expr(rnd, 2, env)
        b, _, bv = _random_int_expr(rnd, 2, env)
        if not any(name in a + b for name in env):
            # a comparison of two literal-only expressions has no context type to compute in; avoid it
            a = rnd.choice(sorted(env))
            av = env[a]
        op = rnd.choice(["<", ">=", "=", "<>"])
        value = {"<": av < bv, ">=": av >= bv, "=": av == bv, "<>": av != bv}[op]
        return f"({a}) {op} ({b})", _PREC[op], value
    op = rnd.choice(["AND", "OR", "XOR", "NOT", "="])
    if op == "NOT":
        text, prec, value = _random_bool_expr(rnd, depth - 1, env)
        return f"NOT {text if prec >= 8 else '(' + text + ')'}", 8, not value
    lt, lp, lv = _random_bool_expr(rnd, depth - 1, env)
    rt_, rp, rv = _random_bool_expr(rnd, depth - 1, env)
    p = _PREC[op]
    text = f"{lt if lp >= p else '(' + lt + ')'} {op} {rt_ if rp > p else '(' + rt_ + ')'}"
    value = {"AND": lv and rv, "OR": lv or rv, "XOR": lv != rv, "=": lv == rv}[op]
    return text, p, value


def test_random_expressions_respect_precedence_and_wrap_around():
    rnd = random.Random(11)
    env = {f"a{i}": rnd.randrange(-2 ** 31, 2 ** 31) for i in range(4)}
    env.update({f"s{i}": rnd.randrange(-300, 300) for i in range(4)})
    ints, bools = [], []
    for _ in range(150):
        ints.append(_random_int_expr(rnd, 4, env))
        bools.append(_random_bool_expr(rnd, 3, env))
    decls = "\n".join(f"{k} : DINT := {v};" for k, v in env.items())
    decls += "\n" + "\n".join(f"r{i} : DINT; b{i} : BOOL;" for i in range(len(ints)))
    body = "\n".join(f"r{i} := {t};\nb{i} := {bt};" for i, ((t, _, _), (bt, _, _)) in enumerate(zip(ints, bools)))
    rt = run(body, decls)
    assert [rt.get(f"inst.r{i}") for i in range(len(ints))] == [v for _, _, v in ints]
    assert [rt.get(f"inst.b{i}") for i in range(len(bools))] == [v for _, _, v in bools]


def test_report_statement_rate(capsys):
    """Prints the execution rate (informative only; no timing assertion)."""
    text, model, _state = generate_program(2000, seed=3)
    t0 = time.perf_counter()
    rt = load_st(text, "gen.st").instantiate()
    t1 = time.perf_counter()
    cycles = 100
    for _ in range(cycles):
        rt.run_cycle()
    t2 = time.perf_counter()
    with capsys.disabled():
        print(f"\n[stexec] load {t1 - t0:.2f} s; {cycles} cycles of a {len(model)}-statement program in "
              f"{t2 - t1:.2f} s: {len(model) * cycles / (t2 - t1) / 1e6:.2f} M ST statements/s")
    assert rt.cycle == cycles
