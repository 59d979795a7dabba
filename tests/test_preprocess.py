"""Preprocessor (spec 3): DEFINE values, conditional compilation, -D/--cfg, #define scopes, INCLUDE, regions and line map."""

from __future__ import annotations

import pytest
from test_frontend_support import Found, compile_files, errors, program_ops, warnings

from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend.preprocess import (PPParser, Preprocessor, initial_defines, parse_define_value, read_config,
                                   split_comment)
from transpiler.frontend.sources import split_lines


def _run(text: str, defines: dict | None = None, fixed: dict | None = None) -> tuple[list, Diagnostics, Preprocessor]:
    diags = Diagnostics()
    table = initial_defines(fixed or {})
    for name, value in (defines or {}).items():
        table.define(name, value, Span("<test>", 1), diags)
    pre = Preprocessor(table, diags, PPParser())
    return pre.run("f.src", tuple(text.split("\n"))), diags, pre


def _active(text: str, **kw) -> list[str]:
    lines, _, _ = _run(text, **kw)
    return [line.code.strip() for line in lines if line.code.strip()]


def _defines_after(text: str) -> dict:
    diags = Diagnostics()
    table = initial_defines({})
    read_config("OEM.cfg", tuple(text.split("\n")), table, diags, PPParser())
    return table.values


# --------------------------------------------------------------------------------------------------- DEFINE


def test_define_value_forms():
    values = _defines_after('DEFINE S = "belt"\nDEFINE I = 42\nDEFINE N = -7\nDEFINE B = %0101\nDEFINE H = $1F\n'
                            "DEFINE R = &I\nDEFINE Q=&S\ndefine lower = 1\n")
    assert values == {"S": "belt", "I": 42, "N": -7, "B": 5, "H": 31, "R": 42, "Q": "belt", "lower": 1}


def test_define_of_an_undefined_reference_is_its_name_with_a_warning():
    diags = Diagnostics()
    table = initial_defines({})
    read_config("OEM.cfg", ("DEFINE A = &active",), table, diags, PPParser())
    assert table.values == {"A": "active"}
    assert [(d.code, d.severity.value, d.span.line) for d in diags.items] == [("E-PP-UNDEF-REF", "warning", 1)]


def test_redefinition_warns_and_the_later_value_wins():
    diags = Diagnostics()
    table = initial_defines({})
    read_config("OEM.cfg", ("DEFINE A = 1", "DEFINE A = 2"), table, diags, PPParser())
    assert table.values["A"] == 2
    assert [(d.code, d.span.line) for d in diags.warnings] == [("E-DEF-REDEFINE", 2)]


def test_command_line_defines_win_over_every_define_line():
    diags = Diagnostics()
    table = initial_defines({"A": 7})
    read_config("OEM.cfg", ("DEFINE A = 1", "DEFINE B = &A"), table, diags, PPParser())
    assert table.values == {"A": 7, "B": 7}
    assert diags.items == []


@pytest.mark.parametrize("text, value", [("5", 5), ("-5", -5), ("%101", 5), ("$1f", 31), ('"x y"', "x y"),
                                         ("word", "word"), (" 12 ", 12)])
def test_command_line_values(text, value):
    assert parse_define_value(text) == value


def test_malformed_define_value_is_an_error_and_free_text_a_warning():
    diags = Diagnostics()
    read_config("OEM.cfg", ("DEFINE A = 1.5", "free text line", "* star comment", "; comment", ""),
                initial_defines({}), diags, PPParser())
    assert [(d.code, d.severity.value, d.span.line) for d in diags.items] == [
        ("E-CFG-SYNTAX", "error", 1), ("E-CFG-IGNORED", "warning", 2)]


# --------------------------------------------------------------------------------------- conditional code


@pytest.mark.parametrize("condition, taken", [
    ('A = "belt"', True), ('A = "Belt"', False), ('A <> "gear"', True), ('A <> "belt"', False),
    ("N = 5", True), ("N = %101", True), ("N = $5", True), ("N <> 5", False), ("N = 6", False),
    ('N = "5"', True),                   # one side a string: compared as strings
    ("M = 1", True), ("M = &ONE", True), ("A = &STR", True), ("A = &UNDEFINED_NAME", False),
    ("A=\"belt\"", True),
])
def test_if_comparisons(condition, taken):
    defines = {"A": "belt", "N": 5, "M": 1, "ONE": 1, "STR": "belt"}
    assert _active(f"#if {condition}\nL I1\n#else\nL I2\n#endif", defines=defines) == (["L I1"] if taken else ["L I2"])


def test_undefined_name_compares_as_empty_string_with_a_warning():
    lines, diags, _ = _run('#if NOPE = ""\nL I1\n#endif\n#if NOPE = 0\nL I2\n#endif')
    assert [line.code for line in lines] == ["L I1"]
    assert [(d.code, d.span.line) for d in diags.warnings] == [("E-PP-UNDEF", 1), ("E-PP-UNDEF", 4)]


def test_ifdef_and_ifndef():
    text = "#ifdef A\nL I1\n#else\nL I2\n#endif\n#ifndef A\nL I3\n#endif\n#IFDEF B\nL I4\n#ENDIF"
    assert _active(text, defines={"A": 0}) == ["L I1"]
    assert _active(text, defines={"B": ""}) == ["L I2", "L I3", "L I4"]


def test_nesting_and_no_evaluation_inside_inactive_code():
    text = ("#if A = 1\n  #if B = 1\n  L I1\n  #else\n  L I2\n  #endif\n#else\n  #if UNDEFINED = 1\n  L I3\n"
            "  #endif\n  L I4\n#endif\nL I5")
    assert _active(text, defines={"A": 1, "B": 1}) == ["L I1", "L I5"]
    assert _active(text, defines={"A": 1, "B": 0}) == ["L I2", "L I5"]
    lines, diags, _ = _run(text, defines={"A": 1, "B": 1})
    assert diags.items == []            # the #if UNDEFINED in the inactive branch is not evaluated
    assert _active(text, defines={"A": 0}) == ["L I4", "L I5"]


def test_endif_may_carry_a_comment_and_directives_are_case_insensitive():
    assert _active("#IF A = 1 ; why\nL I1\n#Else ; other\nL I2\n#ENDIF ; done\nL I3", defines={"A": 1}) == ["L I1", "L I3"]


def test_defines_inside_inactive_code_are_ignored():
    lines, diags, pre = _run("#if A = 2\nDEFINE B = 1\n#endif\n#ifdef B\nL I1\n#endif", defines={"A": 1})
    assert lines == [] and "B" not in pre.defines.values


def test_very_deep_nesting_is_allowed():
    depth = 10_000
    text = "#if A = 1\n" * depth + "L I1\n" + "#endif\n" * depth + "L I2"
    lines, diags, _ = _run(text, defines={"A": 1})
    assert [line.code for line in lines] == ["L I1", "L I2"] and diags.items == []
    lines, diags, _ = _run("#if A = 1\n" * depth + "L I1", defines={"A": 1})
    assert len(diags.errors) == depth and {d.code for d in diags.errors} == {"E-PP-NEST"}


def test_unbalanced_directives():
    _, diags, _ = _run("#endif\n#else\n#if A = 1\n#else\n#else\n#endif\n#if A = 1")
    assert [(d.code, d.span.line) for d in diags.errors] == [
        ("E-PP-NEST", 1), ("E-PP-NEST", 2), ("E-PP-NEST", 5), ("E-PP-NEST", 7)]


def test_malformed_endif_still_closes_its_block():
    lines, diags, _ = _run("#if A = 1\nL I1\n#else junk\nL I2\n#endif junk\nL I3", defines={"A": 1})
    assert [line.code for line in lines] == ["L I1", "L I3"]
    assert [(d.code, d.span.line) for d in diags.errors] == [("E-PP-SYNTAX", 3), ("E-PP-SYNTAX", 5)]


def test_inactive_regions_are_recorded():
    _, _, pre = _run("L I0\n#if A = 2\nL I1\nL I2\n#else\nL I3\n#endif\n#if A = 1\nL I4\n#else\nL I5\n#endif\n"
                     "#if A = 3\n#if A = 1\nL I6\n#endif\n#endif", defines={"A": 1})
    assert [(r.file, r.first_line, r.last_line, r.condition) for r in pre.inactive] == [
        ("f.src", 3, 4, "#if A = 2"), ("f.src", 11, 11, "#if A = 1"), ("f.src", 14, 16, "#if A = 3")]


def test_spans_point_at_the_original_line_and_column():
    lines, _, _ = _run("#if A = 1\nL I1\n#else\nL I2\n#endif\n\t  L I3 ; note", defines={"A": 1})
    assert [(line.code.strip(), line.span.line, line.span.col, line.comment) for line in lines] == [
        ("L I1", 2, 1, None), ("L I3", 6, 4, " note")]


@pytest.mark.parametrize("text, code, comment", [
    ('L S"a;b" ; c', 'L S"a;b" ', " c"), ("L I1;;;X9.7a", "L I1", ";;X9.7a"), ("; only", "", " only"),
    ("L I1", "L I1", None), ('L S"unterminated;x', 'L S"unterminated;x', None),
])
def test_split_comment(text, code, comment):
    assert split_comment(text) == (code, comment)


def test_star_lines_are_comments_unless_switched_off(tmp_path):
    files = {"main.src": "* a star comment\nL I1\n= O1\nEM\n"}
    assert errors(compile_files(tmp_path, files)) == []
    assert errors(compile_files(tmp_path, files, semantics={"star_comments": False})) != []


def test_en_dash_in_every_encoding_means_minus(tmp_path):
    for dash in (b"\x96", "\u2013".encode("utf-8")):
        result = compile_files(tmp_path, {"main.src": b"L" + dash + b" W2\n= W4\nL W2\n" + dash + b"[\nL K1\n]\n= W6\nEM\n"})
        assert errors(result) == []
        assert [op.code for op in program_ops(result)][:6] == ["WNEG", "WST", "WLD", "BOPEN", "WLD", "BCLOSE"]


def test_line_endings_and_latin1_bytes(tmp_path):
    result = compile_files(tmp_path, {"main.src": b"L I1 ;\xe4\xf6\xfc\r\n= O1\rL I2\n= O2\r\nEM\r\n"})
    assert errors(result) == []
    ops = program_ops(result)
    assert [(op.code, op.span.line) for op in ops] == [("LD", 1), ("ST", 2), ("LD", 3), ("ST", 4), ("EM", 5)]
    assert ops[0].comments == ("\xe4\xf6\xfc",)


def test_lines_end_at_cr_lf_cr_or_lf_only():
    # a form feed, NEL or Unicode line separator inside a line (a comment may hold one) does not end it
    text = "L I1\r\n= O1\rA I2 ;\x0c\x85\u2028x\n\r\nEM"
    assert split_lines(text) == ["L I1", "= O1", "A I2 ;\x0c\x85\u2028x", "", "EM"]
    assert split_lines("") == [""] and split_lines("EM\n") == ["EM", ""]


# ---------------------------------------------------------------------------------- whole projects


def _assigned(result) -> list[str]:
    return [op.operand.display() for op in program_ops(result) if op.code == "ST"]


SELECT = {"main.src": '#if CFG = "a"\nL I1\n= O1\n#else\nL I2\n= O2\n#endif\nEM\n'}


def test_default_cfg_is_found_case_insensitively(tmp_path):
    result = compile_files(tmp_path, {**SELECT, "oem.CFG": 'DEFINE CFG = "a"\n'})
    assert _assigned(result) == ["O1"] and result.program.defines["CFG"] == "a"
    assert "oem.CFG" in result.program.source_files


def test_cfg_option_and_no_default(tmp_path):
    files = {**SELECT, "OEM.cfg": 'DEFINE CFG = "a"\n', "other/variant.cfg": 'DEFINE CFG = "b"\n'}
    assert _assigned(compile_files(tmp_path, files)) == ["O1"]
    assert _assigned(compile_files(tmp_path, files, cfg=tmp_path / "other" / "variant.cfg")) == ["O2"]
    result = compile_files(tmp_path, files, use_default_cfg=False)
    assert _assigned(result) == ["O2"]
    assert [w.code for w in warnings(result)] == ["E-PP-UNDEF"]


def test_command_line_define_wins_over_cfg_and_source(tmp_path):
    files = {"main.src": 'DEFINE CFG = "a"\n' + SELECT["main.src"], "OEM.cfg": 'DEFINE CFG = "a"\n'}
    assert _assigned(compile_files(tmp_path, files)) == ["O1"]
    assert _assigned(compile_files(tmp_path, files, defines={"CFG": "b"})) == ["O2"]


def test_conditional_code_in_def_files_and_case_tables(tmp_path):
    files = {"main.src": "#define /g a.def\nCASE B0\nCM A\n#if X = 1\nCM B\n#endif\nCM C\nENDC\nL I_door\n= O1\nEM\n"
                         "LBL A\nEM\nLBL B\nEM\nLBL C\nEM\n",
             "a.def": "#if X = 1\nI_door I 10\n#else\nI_door I 20\n#endif\n"}
    for x, door, entries in ((1, 10, ["A", "B", "C"]), (0, 20, ["A", "C"])):
        result = compile_files(tmp_path, files, defines={"X": x})
        assert errors(result) == []
        case = next(op for op in program_ops(result) if op.code == "CASE")
        assert [t.label for t in case.case_targets] == entries
        load = next(op for op in program_ops(result) if op.code == "LD")
        assert (load.operand.kind, load.operand.addr, load.operand.symbol) == ("I", door, "I_door")


def test_global_and_local_definition_files(tmp_path):
    files = {"main.src": "#define /g glob.def\nUSES m.src\nEXTERN F\nL I_glob\n= O1\nCM F\nEM\n",
             "m.src": "#define loc.def\nGLOBAL F\nLBL F\nL I_glob\nA I_loc\n= O2\nEM\n",
             "glob.def": "I_glob I 1\n", "loc.def": "I_loc I 2\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == []
    files["main.src"] = files["main.src"].replace("= O1", "A I_loc\n= O1")
    assert errors(compile_files(tmp_path, files)) == [Found("E-SYM-UNDEF", "main.src", 5, 1)]
    # a local symbol shadows a global one in its own file only
    files.update({"main.src": "#define /g glob.def\nUSES m.src\nEXTERN F\nL I_glob\n= O1\nCM F\nEM\n",
                  "loc.def": "I_loc I 2\nI_glob I 3\n"})
    result = compile_files(tmp_path, files)
    assert [op.operand.addr for op in program_ops(result, 0) if op.code == "LD"] == [1]
    assert [op.operand.addr for op in program_ops(result, 1) if op.code == "LD"] == [3]


def test_system_def_is_read_first(tmp_path):
    files = {"main.src": "#define /g b.def\n#define /g SYSTEM.DEF\nL MG_x\n= O1\nEM\n",
             "b.def": "MG_y M &MG_x\n", "SYSTEM.DEF": "MG_x M 5\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == []
    assert result.program.source_files.index("SYSTEM.DEF") < result.program.source_files.index("b.def")


def test_include_is_textual_and_keeps_its_own_line_numbers(tmp_path):
    files = {"main.src": 'L I1\nINCLUDE "part.inc"\n#include sub/Other.INC\n= O1\nL I_bad\nEM\n',
             "part.inc": "; included\nA I2\nA I_missing_a\n", "sub/other.inc": "O I3\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [Found("E-SYM-UNDEF", "main.src", 5, 1), Found("E-SYM-UNDEF", "part.inc", 3, 1)]
    files["part.inc"] = "; included\nA I2\n"
    files["main.src"] = files["main.src"].replace("L I_bad\n", "")
    ops = program_ops(compile_files(tmp_path, files))
    assert [(op.code, op.span.file, op.span.line) for op in ops] == [
        ("LD", "main.src", 1), ("AND", "part.inc", 2), ("OR", "sub/other.inc", 1), ("ST", "main.src", 4),
        ("EM", "main.src", 5)]


def test_diagnostic_after_an_if_block_points_at_the_original_line(tmp_path):
    files = {"main.src": "DEFINE A = 1\n#if A = 2\nL I1\nL I1\n#else\nL I2\n#endif\n\nL I_bad\n= O1\nEM\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [Found("E-SYM-UNDEF", "main.src", 9, 1)]
    assert [(r.file, r.first_line, r.last_line) for r in result.program.inactive_regions] == [("main.src", 3, 4)]


def test_inactive_regions_of_every_file_reach_the_program(tmp_path):
    files = {"main.src": "#define /g a.def\nUSES m.src\n#if X = 1\nUSES never.src\n#endif\nEM\n",
             "m.src": "#if X = 1\nL I1\n#endif\nEM\n", "a.def": "#if X = 1\nI_a I 1\n#endif\n", "OEM.cfg": ""}
    result = compile_files(tmp_path, files)
    assert errors(result) == []
    assert sorted((r.file, r.first_line, r.last_line) for r in result.program.inactive_regions) == [
        ("a.def", 2, 2), ("m.src", 2, 2), ("main.src", 4, 4)]


def test_uses_cycles_are_allowed_and_each_file_is_read_once(tmp_path):
    files = {"main.src": "USES a.src\nEXTERN A\nCM A\nEM\n",
             "a.src": "USES b.src\nEXTERN B\nGLOBAL A\nLBL A\nCM B\nEM\n",
             "b.src": "USES A.SRC\nUSES main.src\nGLOBAL B\nLBL B\nEM\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == []
    assert [f.path for f in result.program.files] == ["main.src", "a.src", "b.src"]
