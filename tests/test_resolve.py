"""Resolver: symbols and auto-assignment, aliases, GLOBAL/EXTERN, the call graph, chain state and bracket facts (spec 4.2, 5.4, 6.9, 7)."""

from __future__ import annotations

import pytest
from test_frontend_support import Found, compile_files, errors, program_ops, warnings

from transpiler.ir import Bracket, CallTarget

# ------------------------------------------------------------------------------------------ auto-assignment


AUTO_PROJECT = {
    "main.src": "#define /g a.def\nL M0\n= M2\nL B0\n= B6\nL MG_a\n= MG_b\nL WG_a\n= DG_a\nL WG_b\n= BG_a\nEM\n",
    "a.def": "MG_fixed M 1\nMG_a M\nMG_b M\nWG_a W\nDG_a D\nWG_b W\nBG_a B\nWG_fixed W 4\nSG_a S\n",
}


def test_auto_assignment_skips_used_addresses_and_aligns(tmp_path):
    result = compile_files(tmp_path, AUTO_PROJECT)
    assert errors(result) == []
    symbols = result.program.symbols
    # M0 (src), M1 (def), M2 (src) are used: the auto markers take 3 and 4
    assert (symbols["MG_a"].addr, symbols["MG_b"].addr) == (3, 4)
    # bytes 0 (B0), 4-5 (W4), 6 (B6) are used: W -> 2, D -> 8 (multiple of 4), next W -> 12, B -> 1
    assert (symbols["WG_a"].addr, symbols["DG_a"].addr, symbols["WG_b"].addr, symbols["BG_a"].addr) == (2, 8, 12, 1)
    assert symbols["SG_a"].addr == 0
    assert all(symbols[n].auto for n in ("MG_a", "MG_b", "WG_a", "DG_a", "WG_b", "BG_a", "SG_a"))
    assert not symbols["MG_fixed"].auto and not symbols["WG_fixed"].auto
    assert [s.name for s in result.program.auto_assigned] == ["MG_a", "MG_b", "WG_a", "DG_a", "WG_b", "BG_a", "SG_a"]


def test_auto_assignment_is_deterministic(tmp_path):
    first = compile_files(tmp_path / "one", AUTO_PROJECT).program
    second = compile_files(tmp_path / "two", AUTO_PROJECT).program
    assert [(s.name, s.kind, s.addr) for s in first.auto_assigned] == [(s.name, s.kind, s.addr) for s in second.auto_assigned]


def test_auto_assignment_never_overlaps_and_avoids_interface_operands(tmp_path):
    names = [f"DG_{i}" for i in range(300)] + [f"WG_{i}" for i in range(300)] + [f"MG_{i}" for i in range(5000)]
    defs = "".join(f"{n} {n[0]}\n" for n in names)
    result = compile_files(tmp_path, {"main.src": "#define /g a.def\nEM\n", "a.def": defs})
    assert errors(result) == []
    syms = result.program.symbols
    taken: set[int] = set()
    for n in names[:600]:
        size = 4 if n.startswith("D") else 2
        span = set(range(syms[n].addr, syms[n].addr + size))
        assert syms[n].addr % size == 0 and not (span & taken)
        taken |= span
    markers = sorted(syms[n].addr for n in names[600:])
    assert len(set(markers)) == 5000 and 4172 not in markers and 4200 not in markers   # NC interface markers
    assert markers[0] == 0


def test_pool_exhaustion_is_an_error(tmp_path):
    defs = "".join(f"SG_{i} S\n" for i in range(101))
    result = compile_files(tmp_path, {"main.src": "#define /g a.def\nEM\n", "a.def": defs})
    assert errors(result) == [Found("E-DEF-POOL", "a.def", 101, 1)]


def test_one_local_definition_file_of_two_modules_is_one_operand(tmp_path):
    files = {"main.src": "USES a.src\nUSES b.src\nEXTERN A\nEXTERN B\nCM A\nCM B\nEM\n",
             "a.src": "#define l.def\nGLOBAL A\nLBL A\nL M_x\n= O1\nEM\n",
             "b.src": "#define l.def\nGLOBAL B\nLBL B\nL M_x\n= O2\nEM\n", "l.def": "M_x M\nI_q I 3\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [] and warnings(result) == []
    addresses = {op.operand.addr for f in (1, 2) for op in program_ops(result, f) if op.code == "LD"}
    assert addresses == {0} and len(result.program.auto_assigned) == 1


# ------------------------------------------------------------------------------------ aliases and /c


def test_aliases_share_the_operand_of_their_target(tmp_path):
    files = {"main.src": "#define /g a.def\nUSES m.src\nEXTERN F\nL I_unused\n= O_lamp\nCM F\nEM\n",
             "m.src": "#define l.def\nGLOBAL F\nLBL F\nL I_local\n= O2\nEM\n",
             "a.def": "MG_marker_one M 100\n/c I_unused M &MG_marker_one\nO_lamp O 3\nMG_auto M\n/c MG_auto2 M &MG_auto\n",
             "l.def": "/c I_local M &MG_marker_one\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [] and warnings(result) == []
    syms = result.program.symbols
    assert (syms["I_unused"].kind, syms["I_unused"].addr, syms["I_unused"].alias_of) == ("M", 100, "MG_marker_one")
    assert syms["MG_auto2"].addr == syms["MG_auto"].addr
    assert program_ops(result, 1)[1].operand.addr == 100


def test_c_prefix_marks_an_intended_second_use(tmp_path):
    files = {"main.src": "#define /g a.def\nEM\n", "a.def": "I_a I 5\n/c I_b I 5\nI_c I 5\nW_a W 10\nB_a B 10\n"}
    result = compile_files(tmp_path, files)
    assert warnings(result) == [Found("E-DEF-DUP-ADDR", "a.def", 3, 1)]     # W10/B10 differ in kind: no warning


def test_identical_redefinition_is_not_a_duplicate(tmp_path):
    files = {"main.src": "#define /g a.def\n#define /g b.def\nL I_a\n= O1\nEM\n", "a.def": "I_a I 5\n", "b.def": "I_a I 5\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [] and warnings(result) == []


def test_symbols_may_be_indexed_and_keep_their_spelling(tmp_path):
    files = {"main.src": "#define /g a.def\nL K2\n= X\nL MG_tab[X]\n= O1\nL WG_tab [X]\n= W0\nEM\n",
             "a.def": "MG_tab M 10\nWG_tab W 20\n"}
    ops = program_ops(compile_files(tmp_path, files))
    assert [(op.operand.kind, op.operand.addr, op.operand.indexed, op.operand.symbol) for op in ops if op.code in ("LD", "WLD")][1:] == [
        ("M", 10, True, "MG_tab"), ("W", 20, True, "WG_tab")]
    assert ops[2].operand.display() == "MG_tab[X]"


def test_symbol_case(tmp_path):
    files = {"main.src": "#define /g a.def\nL mg_Ready\n= O1\nCM sub\nEM\nLBL Sub\nEM\n", "a.def": "MG_ready M 5\n"}
    assert [e.code for e in errors(compile_files(tmp_path, files))] == ["E-SYM-UNDEF", "E-SYM-UNRESOLVED"]
    result = compile_files(tmp_path, files, semantics={"symbol_case": "insensitive"})
    assert errors(result) == []
    assert program_ops(result)[0].operand.addr == 5 and program_ops(result)[2].call.label == "Sub"


# ----------------------------------------------------------------------------- labels, GLOBAL/EXTERN, calls


CALL_PROJECT = {
    "main.src": "USES a.src\nEXTERN A_entry\nL I1\nCMT A_entry\nCM Local\nCM 9032\nEM\nLBL Local\nEM\n",
    "a.src": "USES b.src\nEXTERN B_entry\nGLOBAL A_entry\nLBL A_entry\nCM B_entry\nEM\n",
    "b.src": "GLOBAL B_entry\nLBL Other\nEM\nLBL B_entry\nCASE B0\nCM Other\nCM Other\nENDC\nEM\n",
}


def test_global_extern_calls_resolve_to_the_label_op(tmp_path):
    result = compile_files(tmp_path, CALL_PROJECT)
    assert errors(result) == []
    main, a, b = result.program.files
    call = main.ops[1]
    assert (call.code, call.call) == ("CALLT", CallTarget(1, a.labels["A_entry"], "A_entry"))
    assert a.ops[a.labels["A_entry"]].label == "A_entry"
    assert main.ops[2].call == CallTarget(0, main.labels["Local"], "Local")
    assert main.ops[3].call == CallTarget(module=9032)
    assert b.ops[b.labels["B_entry"] + 1].case_targets == (CallTarget(2, 0, "Other"), CallTarget(2, 0, "Other"))
    assert result.program.modules_used == (9032,)


def test_call_graph_routines_and_depth(tmp_path):
    program = compile_files(tmp_path, CALL_PROJECT).program
    assert [(r.file, r.label) for r in program.routines] == [(0, "Local"), (1, "A_entry"), (2, "Other"), (2, "B_entry")]
    assert program.call_depth == 3        # main -> A_entry -> B_entry -> Other (through the CASE table)


def test_subm_targets_are_roots_of_the_call_graph(tmp_path):
    result = compile_files(tmp_path, {"main.src": "SUBM Job\nEM\nLBL Job\nCM Step\nEM\nLBL Step\nEM\n"})
    assert errors(result) == []
    assert [r.label for r in result.program.routines] == ["Job", "Step"]


def test_kfield_after_jp_and_uses_cycle(tmp_path):
    files = {"main.src": "USES m.src\nEXTERN F\nCM F\nJP End\nKFIELD T\nK1\nENDK\nLBL End\nEM\n",
             "m.src": "USES main.src\nGLOBAL F\nLBL F\nEM\n"}
    assert errors(compile_files(tmp_path, files)) == []


# -------------------------------------------------------------------------------------- chain state (5.4)


def _shape(tmp_path, program: str, **semantics) -> list[tuple[str, bool]]:
    result = compile_files(tmp_path, {"main.src": program}, semantics=semantics)
    assert errors(result) == [], [d.render() for d in result.diagnostics.items]
    return [(op.code, op.chain_open) for op in program_ops(result)]


CHAIN_SHAPES = {
    # gate after an assignment acts as L / LN (TV-03, TV-04, TV-05, TV-06 shapes)
    "gates-after-assignment": (
        "L I4\n= O4\nA I5\n= O5\nO I6\n= O6\nXO I7\n= O7\nAN I5\n= O5\nON I6\n= O6\nXON I7\n= O7\nEM\n",
        [("LD", False), ("ST", True), ("LD", False), ("ST", True), ("LD", False), ("ST", True), ("LD", False),
         ("ST", True), ("LDN", False), ("ST", True), ("LDN", False), ("ST", True), ("LDN", False), ("ST", True),
         ("EM", False)]),
    # a call closes the chain (TV-84 shape); the first gate after it loads
    "call-closes": ("L I1\nCM Sub\nAN I2\n= O1\nEM\nLBL Sub\nEM\n",
                    [("LD", False), ("CALL", True), ("LDN", False), ("ST", True), ("EM", False), ("LBL", False),
                     ("EM", False)]),
    # a conditional jump closes, and so does the label (TV-39 shape)
    "jump-and-label-close": ("L I1\nJPF Next\nO I2\n= O1\nLBL Next\nA I3\n= M1\nEM\n",
                             [("LD", False), ("JPF", True), ("LD", False), ("ST", True), ("LBL", False), ("LD", False),
                              ("ST", True), ("EM", False)]),
    # a comparison opens the chain: a following A gates (TV-29 shape)
    "compare-opens": ("L W0\n<> K7\nA I1\n= O1\nEM\n", [("WLD", False), ("CMP", False), ("AND", True), ("ST", True),
                                                         ("EM", False)]),
    # word instructions are neutral (TV-69 shape): the logic chain stays open across them
    "word-neutral": ("L I1\nL W0\n+ K1\n= W0\nA I2\n= O1\nEM\n",
                     [("LD", False), ("WLD", True), ("ADD", True), ("WST", True), ("LD", False), ("ST", True),
                      ("EM", False)]),
    # word gates never turn into loads (TV-70 shape, A-51)
    "word-gate-after-store": ("L K$F0\n= W0\nA K$3C\nO W2\n= W2\nEM\n",
                              [("WLD", False), ("WST", False), ("WAND", False), ("WOR", False), ("WST", False),
                               ("EM", False)]),
    # BT and PLL open, L restarts, structured keywords close
    "bt-pll-struct": ("L W0\nBT K3\nIFT\nA I1\n= O1\nENDI\nPLL\nA I2\n= O2\nEM\n",
                      [("WLD", False), ("BT", False), ("JPF", True), ("LD", False), ("ST", True), ("NOP", False),
                       ("PLL", False), ("AND", True), ("ST", True), ("EM", False)]),
    # string compare opens
    "string-compare": ('L S"ab"\n== S1\nA I1\n= O1\nEM\n', [("SLD", False), ("SCMP", False), ("AND", True),
                                                            ("ST", True), ("EM", False)]),
}


@pytest.mark.parametrize("name", sorted(CHAIN_SHAPES))
def test_static_chain_state(tmp_path, name):
    program, expected = CHAIN_SHAPES[name]
    assert _shape(tmp_path, program) == expected


def test_logic_bracket_at_chain_start_is_a_load(tmp_path):
    """TV-14 shape: a logic bracket right after an assignment loads (A-04); inside, a new chain starts."""
    result = compile_files(tmp_path, {"main.src": "L I1\n= O1\nA[\nL I2\nO I3\n]\n= O2\nL I1\nA[\nA I2\n]\n= O3\nEM\n"})
    ops = program_ops(result)
    assert [(op.code, op.chain_open) for op in ops] == [
        ("LD", False), ("ST", True), ("BOPEN", False), ("LD", False), ("OR", True), ("BCLOSE", True), ("ST", True),
        ("LD", False), ("BOPEN", True), ("LD", False), ("BCLOSE", True), ("ST", True), ("EM", False)]
    assert ops[2].bracket == Bracket("A", "LOGIC", True) and ops[5].bracket == Bracket("A", "LOGIC", True)
    assert ops[8].bracket == Bracket("A", "LOGIC", False) and ops[10].bracket == Bracket("A", "LOGIC", False)


def test_bracket_at_chain_start_can_gate(tmp_path):
    result = compile_files(tmp_path, {"main.src": "L I1\n= O1\nA[\nL I2\n]\n= O2\nEM\n"},
                           semantics={"bracket_at_chain_start": "gate"})
    assert program_ops(result)[2].bracket == Bracket("A", "LOGIC", False)


@pytest.mark.parametrize("before, op, mode", [
    ("L W0", "A", "WORD"), ("L W0", "+", "WORD"), ("L W0", "==", "WORD"), ("L I1", "O", "LOGIC"),
    ("LBL Here", "A", "LOGIC"), ("LBL Here", "+", "WORD"), ("LBL Here", "<", "WORD"), ("PSW", "AN", "WORD"),
    ("PLW", "XO", "WORD"), ("PSL", "A", "LOGIC"), ("PLL", "ON", "LOGIC"), ("NOTL", "A", "LOGIC"), ("INCW", "x", "WORD"),
    ("TWOC", "MOD", "WORD"), ("L X", "/", "WORD"), ("BT K1", "XON", "LOGIC"), ("L W0\n== K1", "A", "LOGIC"),
    ("L I1\n= W0", "-", "WORD"), ("L I1\n= O1", "A", "LOGIC"), ("PS K1", "A", "LOGIC"), ("CM Here", "+", "WORD"),
])
def test_bracket_mode_follows_the_previous_accumulator(tmp_path, before, op, mode):
    inner = "L I2" if mode == "LOGIC" else "L K2"
    program = f"L I0\n{before}\n{op}[\n{inner}\n]\nEM\nLBL Here\nEM\n"
    if "LBL Here" in before:
        program = f"L I0\nJP Here\n{before}\n{op}[\n{inner}\n]\nEM\n"
    result = compile_files(tmp_path, {"main.src": program})
    assert errors(result) == [], [d.render() for d in result.diagnostics.items]
    opening = next(o for o in program_ops(result) if o.code == "BOPEN")
    closing = next(o for o in program_ops(result) if o.code == "BCLOSE")
    assert opening.bracket.mode == mode and opening.bracket.op == op
    assert closing.bracket == opening.bracket
    assert opening.rel == closing.rel == (op if op in ("==", "<", ">", "<=", ">=", "<>") else "")


def test_nested_brackets_share_the_mode_and_the_inner_one_starts_a_chain(tmp_path):
    result = compile_files(tmp_path, {"main.src": "L I1\nA[\nA[\nL I2\n]\n]\n= O1\nL W0\n+[\n-[\nL K1\n]\n]\n= W2\nEM\n"})
    brackets = [(op.code, op.bracket) for op in program_ops(result) if op.bracket]
    assert brackets == [("BOPEN", Bracket("A", "LOGIC", False)), ("BOPEN", Bracket("A", "LOGIC", True)),
                        ("BCLOSE", Bracket("A", "LOGIC", True)), ("BCLOSE", Bracket("A", "LOGIC", False)),
                        ("BOPEN", Bracket("+", "WORD", False)), ("BOPEN", Bracket("-", "WORD", False)),
                        ("BCLOSE", Bracket("-", "WORD", False)), ("BCLOSE", Bracket("+", "WORD", False))]


def test_word_bracket_keeps_the_logic_chain_open(tmp_path):
    shape = _shape(tmp_path, "L I1\nL W0\n+[\nL K1\n]\nA I2\n= O1\nEM\n")
    assert shape == [("LD", False), ("WLD", True), ("BOPEN", True), ("WLD", True), ("BCLOSE", True), ("AND", True),
                     ("ST", True), ("EM", False)]


def test_dynamic_chain_model_never_turns_gates_into_loads(tmp_path):
    assert [c for c, _ in _shape(tmp_path, "L I1\n= O1\nA I2\n= O2\nEM\n", chain_model="dynamic")] == [
        "LD", "ST", "AND", "ST", "EM"]


def test_word_gate_at_chain_start_can_load(tmp_path):
    assert [c for c, _ in _shape(tmp_path, "L K1\n= W0\nA K3\n= W2\nEM\n", word_gate_at_chain_start="load")] == [
        "WLD", "WST", "WLD", "WST", "EM"]


def test_brackets_may_span_control_flow_when_allowed(tmp_path):
    files = {"main.src": "L I1\nA[\nJPF Skip\nL I2\nLBL Skip\n]\n= O1\nEM\n"}
    assert [e.code for e in errors(compile_files(tmp_path, files))] == ["E-BRACKET-SPAN", "E-BRACKET-SPAN"]
    assert errors(compile_files(tmp_path, files, semantics={"bracket_span": "allowed"})) == []


def test_structured_statements_lower_to_jumps(tmp_path):
    result = compile_files(tmp_path, {"main.src": "L I1\nIFT\nL I2\n= O1\nELSE\nL I3\n= O2\nENDI\nWHILEF\nL I4\nENDW\n"
                                                  "REPEAT\nL I5\nUNTILT\nEM\n"})
    ops = program_ops(result)
    assert [(op.code, op.target) for op in ops] == [
        ("LD", None), ("JPF", 5), ("LD", None), ("ST", None), ("JP", 7), ("LD", None), ("ST", None), ("NOP", None),
        ("JPT", 11), ("LD", None), ("JP", 8), ("NOP", None), ("LD", None), ("JPF", 11), ("EM", None)]


def test_jumps_resolve_inside_their_file(tmp_path):
    ops = program_ops(compile_files(tmp_path, {"main.src": "LBL Top\nL I1\nJPT Top\nJP End\nLBL End\nEM\n"}))
    assert [(op.code, op.target) for op in ops] == [("LBL", None), ("LD", None), ("JPT", 0), ("JP", 4), ("LBL", None),
                                                    ("EM", None)]
