"""Issue 20, parts 3-4 in the front end: what real Basic-Program files contain, and strict, right diagnostics."""

from __future__ import annotations

from test_frontend_support import Found, compile_files, errors, warnings


def test_long_literal_is_a_range_error_not_a_syntax_error(tmp_path):
    result = compile_files(tmp_path, {"main.src": "L K" + "9" * 5000 + "\n= M1\nEM\n"})
    assert errors(result) == [Found("E-LIT-RANGE", "main.src", 1, 1)]
    message = result.diagnostics.errors[0].message
    assert len(message) < 120 and "..." in message


def test_endc_without_case_is_a_nesting_error(tmp_path):
    result = compile_files(tmp_path, {"main.src": "L I1\n= O1\nENDC\nEM\n"})
    assert errors(result) == [Found("E-STRUCT-NEST", "main.src", 3, 1)]


def test_extern_without_global_anywhere_is_unresolved_even_uncalled(tmp_path):
    result = compile_files(tmp_path, {"main.src": "EXTERN Fn\nL I1\n= O1\nEM\n"})
    assert errors(result) == [Found("E-SYM-UNRESOLVED", "main.src", 1, 1)]


def test_extern_hint_asks_for_the_missing_global_only(tmp_path):
    files = {"main.src": "USES mod.src\nEXTERN Fn\nCM Fn\nEM\n", "mod.src": "LBL Fn\nEM\n"}
    message = compile_files(tmp_path, files).diagnostics.errors[0].message
    assert "add GLOBAL Fn there" in message and "EXTERN Fn here" not in message


def test_missing_extern_hint_does_not_ask_for_a_global_that_is_there(tmp_path):
    files = {"main.src": "USES mod.src\nCM Fn\nEM\n", "mod.src": "GLOBAL Fn\nLBL Fn\nEM\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [Found("E-SYM-UNRESOLVED", "main.src", 2, 1)]
    message = result.diagnostics.errors[0].message
    assert "add EXTERN Fn here" in message and "add GLOBAL" not in message


def test_duplicate_symbol_is_reported_at_the_second_definition_also_for_an_alias(tmp_path):
    files = {"main.src": "#define /g d.def\nL I_x\n= O1\nEM\n", "d.def": "I_b I 7\nI_x I &I_b\nI_x I 6\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [Found("E-SYM-DUP", "d.def", 3, 1)]
    assert "d.def:2:1" in result.diagnostics.errors[0].message


def test_def_note_after_kind_or_address_is_a_comment(tmp_path):
    files = {"main.src": "#define /g Glb_IO.def\nL I_HR410_key_spindle_M5\nA I_y\n= O1\nEM\n",
             "Glb_IO.def": "I_HR410_key_spindle_M5 M *I174\nI_y I 5   * was I6 on the HR 410\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [] and warnings(result) == []
    sym = result.program.symbols["I_y"]
    assert (sym.kind, sym.addr) == ("I", 5) and "was I6 on the HR 410" in sym.comment
