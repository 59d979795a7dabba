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


# ---------------------------------------------------------------------------------------------
# DEFINE names, configuration, -D (A-61, E-CFG-MISSING, E-DEF-UNUSED)

PANEL = {"main.src": '#define /g Glb_IO.def\nL I_key\n= O1\nEM\n',
         "OEM.cfg": 'DEFINE CFG_machine_operating_panel_TE535Q_MB520 = "active"\n',
         "Glb_IO.def": '#if CFG_Machine_operating_panel_TE535Q_MB520 = "active"\nI_key I 10\n#else\nI_key I 20\n'
                       '#endif\n'}


def test_define_names_compare_ignoring_case_with_a_warning(tmp_path):
    result = compile_files(tmp_path, PANEL)
    assert errors(result) == []
    assert warnings(result) == [Found("E-PP-CASE", "Glb_IO.def", 1, 1)]
    assert result.program.symbols["I_key"].addr == 10            # the TE 535Q branch, as PLCdesign compiles it
    message = result.diagnostics.warnings[0].message
    assert "CFG_machine_operating_panel_TE535Q_MB520" in message and "CFG_Machine_" in message


def test_define_case_sensitive_is_the_switchable_alternative(tmp_path):
    result = compile_files(tmp_path, PANEL, semantics={"define_case": "sensitive"})
    assert result.program.symbols["I_key"].addr == 20
    assert [w.code for w in result.diagnostics.warnings] == ["E-PP-UNDEF"]


def test_if_on_defines_without_any_configuration_is_one_error(tmp_path):
    files = {"main.src": '#if CFG_A = 1\nL I1\n= O1\n#endif\n#if CFG_B = "x"\nL I2\n= O2\n#endif\nEM\n'}
    result = compile_files(tmp_path, files)
    assert errors(result) == [Found("E-CFG-MISSING", "main.src", 1, 1)]
    assert warnings(result) == []
    # given with -D (or an OEM.cfg) the same project is fine
    assert compile_files(tmp_path, files, defines={"CFG_A": 1, "CFG_B": "x"}).ok


def test_unused_command_line_define_names_the_nearest_names(tmp_path):
    result = compile_files(tmp_path, PANEL, defines={"CFG_machine_operating_panel_TE535Q_MB52": "active"})
    unused = [d for d in result.diagnostics.warnings if d.code == "E-DEF-UNUSED"]
    assert len(unused) == 1 and "CFG_machine_operating_panel_TE535Q_MB520" in unused[0].message
    used = compile_files(tmp_path, PANEL, defines={"CFG_MACHINE_operating_panel_TE535Q_MB520": "x"})
    assert not [d for d in used.diagnostics.warnings if d.code == "E-DEF-UNUSED"]


def test_werror_turns_warnings_into_a_failure(tmp_path):
    assert compile_files(tmp_path, PANEL).ok
    result = compile_files(tmp_path, PANEL, werror=True)
    assert not result.ok and [d.code for d in result.diagnostics.errors] == ["E-WERROR"]


# ---------------------------------------------------------------------------------------------
# encodings

def _comment_of(result, name):
    return result.program.symbols[name].comment


def test_utf8_with_and_without_bom_and_cp1252_comments_read_right(tmp_path):
    text = "I_tür I 5 ; Türkontakt – geschlossen (Ø 5 mm)\n"
    main = "#define /g io.def\nL I_tür\n= O1\nEM\n".replace("I_tür", "I_tuer")
    text = text.replace("I_tür", "I_tuer")
    for data in (text.encode("utf-8"), b"\xef\xbb\xbf" + text.encode("utf-8"), text.encode("cp1252")):
        result = compile_files(tmp_path, {"main.src": main, "io.def": data})
        assert result.ok, [d.render() for d in result.diagnostics.items]
        assert _comment_of(result, "I_tuer") == "Türkontakt – geschlossen (Ø 5 mm)"


def test_forced_encoding_is_used_and_a_byte_it_forbids_is_an_error(tmp_path):
    main = "#define /g io.def\nL I_x\n= O1\nEM\n"
    data = "I_x I 5 ; Tür\n".encode("cp1252")
    assert _comment_of(compile_files(tmp_path, {"main.src": main, "io.def": data}, encoding="latin_1"), "I_x") == "Tür"
    result = compile_files(tmp_path, {"main.src": main, "io.def": data}, encoding="utf-8")
    assert errors(result)[0] == Found("E-ENCODING", "io.def", 1, 12)


# ---------------------------------------------------------------------------------------------
# which file is the main program

def test_module_given_as_main_is_one_clear_error(tmp_path):
    files = {"Main.src": "#define /g io.def\nUSES Mod.src\nEXTERN Fn\nCM Fn\nEM\n", "io.def": "I_a I 1\nO_b O 1\n",
             "Mod.src": "GLOBAL Fn\nLBL Fn\nL I_a\n= O_b\nL I_a\nA I_a\n= O_b\nEM\n"}
    result = compile_files(tmp_path, files, main="Mod.src")
    assert errors(result) == [Found("E-MAIN-MODULE", "Mod.src", 1, 1)]
    assert compile_files(tmp_path, files, main="Main.src").ok


def test_folder_as_main_picks_the_main_program_or_lists_candidates(tmp_path):
    import pytest
    from transpiler import api
    from test_frontend_support import write_project
    write_project(tmp_path, {"Main.src": "USES Mod.src\nEXTERN Fn\nCM Fn\nEM\n", "Mod.src": "GLOBAL Fn\nLBL Fn\nEM\n",
                             "Lib.src": "L I1\n= O1\nEM\n"})
    (tmp_path / "Lib.src").unlink()
    assert api.project_options(tmp_path).main.name == "Main.src"
    (tmp_path / "Other.src").write_text("L I1\n= O1\nEM\n")
    with pytest.raises(api.HH2IECError) as info:
        api.project_options(tmp_path)
    assert "Main.src, Other.src" in info.value.diagnostics[-1].message


# ---------------------------------------------------------------------------------------------
# NUMBERMP4111: from the configuration or the command line

TIMER = {"main.src": "L I1\nJPF DONE\nPS K96\nCM 9006\nLBL DONE\nL T96\n= O1\nEM\n"}


def test_numbermp4111_from_the_configuration_reaches_the_program(tmp_path):
    assert compile_files(tmp_path, TIMER).program.semantics["number_mp4111"] == 0
    result = compile_files(tmp_path, {**TIMER, "OEM.cfg": "DEFINE NUMBERMP4111 = 4\n"})
    assert result.ok and result.program.semantics["number_mp4111"] == 4
    override = compile_files(tmp_path, {**TIMER, "OEM.cfg": "DEFINE NUMBERMP4111 = 4\n"},
                             semantics={"number_mp4111": 2})
    assert override.program.semantics["number_mp4111"] == 2
    bad = compile_files(tmp_path, {**TIMER, "OEM.cfg": "DEFINE NUMBERMP4111 = 2000\n"})
    assert errors(bad) == [Found("E-CFG-SYNTAX", "OEM.cfg", 1, 1)]
