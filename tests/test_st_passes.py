"""Each pass of the ST back end on small hand-written IR, asserting on the pass's own output, so that a back-end
bug points at its pass: structure recovery, liveness, layout, names, expressions and the symbolic executor."""

from __future__ import annotations

import pytest

from transpiler.diagnostics import Span
from transpiler.frontend.resolve import routine_body
from transpiler.ir import Bracket, CallTarget, FileCode, Op, Operand, Program
from transpiler.language.semantics import make_semantics
from transpiler.backends.st import exprs as E
from transpiler.backends.st.arith import wrap32
from transpiler.backends.st.layout import Layout
from transpiler.backends.st.liveness import Liveness, use_def
from transpiler.backends.st.names import MAX_LEN, POU_KEY_PREFIX, NameTable, legalise
from transpiler.backends.st import printer
from transpiler.backends.st.routine import REG_TYPES, AccessorPool, Emitter, RoutineContext
from transpiler.backends.st.structure import NotStructured, RoutineInfo, Structurer, state_machine
from transpiler.backends.st.symbolic import Executor

SEM = make_semantics("itnc530")
FILE = "t.src"


# ---- hand-written IR

def op(code: str, operand: Operand | None = None, **kw) -> Op:
    return Op(code, code, Span(FILE, 1), operand, **kw)


def lbl(name: str) -> Op:
    return Op("LBL", "LBL", Span(FILE, 1), label=name)


def M(addr: int) -> Operand:
    return Operand("M", addr)


def program_of(ops: list[Op], routines: tuple[CallTarget, ...] = ()) -> Program:
    """One file; op spans get their position as line number (structure tags name the line)."""
    ops = tuple(o.__class__(**{**{f: getattr(o, f) for f in o.__slots__}, "span": Span(FILE, n + 1)})
                for n, o in enumerate(ops))
    labels = {o.label: n for n, o in enumerate(ops) if o.code == "LBL"}
    return Program(files=(FileCode(FILE, ops, labels, len(ops)),), symbols={}, semantics=SEM, routines=routines,
                   call_depth=1 if routines else 0, modules_used=(), source_files=(FILE,), defines={})


def routine_lines(program: Program, entry: CallTarget | None = None, fallback: bool = False) -> list[str]:
    """The lines the structurer (or the state machine) emits for one routine, comments left out."""
    names = NameTable()
    helpers: set[str] = set()
    layout = Layout(program, names, helpers.add)
    live = Liveness(program)
    entry = entry or CallTarget(0, 0, "<main>")
    key = entry.key
    file = program.files[entry.file]
    body = routine_body(program.files, entry)
    out = Emitter()
    temps: list[str] = []

    def temp(typ: str) -> str:
        temps.append(typ)
        return f"tmp{len(temps)}"

    def register(reg: str) -> str:
        typ, wanted, comment = REG_TYPES[reg]
        return layout.add_register(f"reg:{reg}", wanted, typ, comment)

    ctx = RoutineContext(layout, out, lambda i: live.at(key, i + 1) if i + 1 < len(file.ops) else frozenset(),
                         register, helpers.add, temp, lambda o: "KF", lambda: ("HH_STACK", "HH_SP"),
                         lambda n: f"MODULE{n}()", program.semantics, AccessorPool().pick)
    info = RoutineInfo(key, entry, file, body, entry.key == (0, 0), lambda t: f"i_{t.label}", {},
                       live.exit(key), lambda i: live.at(key, i))
    if fallback:
        state_machine(info, Executor(ctx))
    else:
        Structurer(info, Executor(ctx)).region(min(body), max(body) + 1)
    out.flush_comments()
    return [line for line in printer.lines(out.block) if not line.strip().startswith("(*")]


def structure_lines(program: Program, fallback: bool = False) -> list[str]:
    return routine_lines(program, fallback=fallback)


def W(addr: int, indexed: bool = False) -> Operand:
    return Operand("W", addr, indexed)


# ---- structure recovery (structure.py)

def test_forward_conditional_jump_becomes_if_around_the_skipped_block():
    # Catches: the JPF condition inverted (the block must run when LA is TRUE) or the block emitted outside the IF.
    lines = structure_lines(program_of([op("LD", M(1)), op("JPF", target=4), op("LD", M(2)), op("ST", M(3)),
                                        lbl("L1"), op("EM")]))
    assert [line.split(" (*")[0] for line in lines] == ["IF M1 THEN", "    M3 := M2;", "END_IF;"]


def test_jump_over_an_else_block_becomes_if_else():
    # Catches: the trailing JP of the THEN block not recognised (two IFs or a fallback instead of ELSE), or the
    # branches swapped.
    lines = structure_lines(program_of([
        op("LD", M(1)), op("JPF", target=5), op("LD", M(2)), op("ST", M(3)), op("JP", target=8),
        lbl("ELSE"), op("LDN", M(4)), op("ST", M(3)), lbl("END"), op("EM")]))
    assert [line.split(" (*")[0] for line in lines] == [
        "IF M1 THEN", "    M3 := M2;", "ELSE", "    M3 := NOT M4;", "END_IF;"]


def test_conditional_back_jump_becomes_repeat_until_the_jump_is_not_taken():
    # Catches: a back jump turned into WHILE (the body must run at least once) or the UNTIL condition not negated.
    lines = structure_lines(program_of([lbl("TOP"), op("LD", M(1)), op("ST", M(2)), op("LD", M(3)),
                                        op("JPT", target=0), op("EM")]))
    assert [line.split(" (*")[0] for line in lines] == ["REPEAT", "    M2 := M1;", "UNTIL NOT M3", "END_REPEAT;"]


def test_unconditional_back_jump_with_exit_test_at_its_head_becomes_while():
    # Catches: the head's exit test not folded into the WHILE condition (WHILE TRUE with EXIT) or LA not refreshed
    # at the end of the body (it is read again by the loop test).
    lines = structure_lines(program_of([op("LD", M(1)), op("JPF", target=6), op("LD", M(2)), op("ST", M(3)),
                                        op("LD", M(1)), op("JP", target=1), op("EM")]))
    assert [line.split(" (*")[0] for line in lines] == [
        "HH_LA := M1;", "WHILE HH_LA DO", "    M3 := M2;", "    HH_LA := M1;", "END_WHILE;"]


def test_case_op_calls_one_routine_per_entry_in_table_order():
    # Catches: CASE entries numbered from 1 or out of table order (the selector value n must call entry n).
    routines = (CallTarget(0, 3, "FIRST"), CallTarget(0, 5, "SECOND"))
    program = program_of([op("WLD", W(0)), op("CASE", W(0), case_targets=routines), op("EM"),
                          lbl("FIRST"), op("EM"), lbl("SECOND"), op("EM")], routines)
    lines = structure_lines(program)
    start = next(n for n, line in enumerate(lines) if line.startswith("CASE "))
    assert lines[start].startswith("CASE W0 OF")
    assert lines[start + 1:start + 4] == ["    0: i_FIRST();", "    1: i_SECOND();", "END_CASE;"]


IRREDUCIBLE = [op("LD", M(1)), op("JPT", target=3), lbl("A"), op("LD", M(2)), op("ST", M(3)), op("LD", M(4)),
               op("JPT", target=2), op("EM")]


def test_jump_into_the_middle_of_a_loop_is_not_structured():
    # Catches: the structurer accepting a second loop entry and emitting a REPEAT that skips the jump's target.
    with pytest.raises(NotStructured):
        structure_lines(program_of(IRREDUCIBLE))


def test_state_machine_gives_each_basic_block_a_state_and_each_jump_its_target_state():
    # Catches: a jump sent to the wrong state (block numbering off by one) or a missing end state (-1 after EM).
    lines = [line.strip() for line in structure_lines(program_of(IRREDUCIBLE), fallback=True)]
    states = {}
    current = None
    for line in lines:
        if line[:-1].isdigit() and line.endswith(":") or line.split(":")[0].isdigit() and line.endswith("*)"):
            current = int(line.split(":")[0])
            states[current] = []
        elif line == "END_CASE;":
            break
        elif current is not None:
            states[current].append(line)
    assert sorted(states) == [0, 1, 2, 3]           # blocks start at op 0, 2 (LBL A), 3 (jump target), 7 (EM)
    assert "HH_STATE := 2;" in states[0] and "HH_STATE := 1;" in states[0]   # JPT into op 3, else fall to LBL A
    assert states[1] == ["HH_STATE := 2;"]           # the label block falls through into op 3
    assert "M3 := M2;" in states[2] and "HH_STATE := 1;" in states[2] and "HH_STATE := 3;" in states[2]
    assert states[3] == ["HH_STATE := -1;"]


# ---- liveness (liveness.py)

def test_use_def_of_single_ops():
    # Catches: an op's register effect listed wrongly; e.g. '= X' reading X, a compare bracket not defining LA,
    # an indexed operand not reading X, AND not reading the LA it combines with.
    assert use_def(op("WST", Operand("X"))) == (frozenset({"WA"}), frozenset({"X"}))
    assert use_def(op("AND", M(1))) == (frozenset({"LA"}), frozenset({"LA"}))
    assert use_def(op("DECX")) == (frozenset({"X"}), frozenset({"X"}))
    assert use_def(op("PLX")) == (frozenset(), frozenset({"X"}))
    assert use_def(op("LD", Operand("M", 4, indexed=True))) == (frozenset({"X"}), frozenset({"LA"}))
    assert use_def(op("BCLOSE", bracket=Bracket("<", "WORD", False))) == (frozenset({"WA"}), frozenset({"LA"}))
    assert use_def(op("BOPEN", bracket=Bracket("A", "LOGIC", False))) == (frozenset({"LA"}), frozenset())
    assert use_def(op("SCAT", Operand("S", 0))) == (frozenset({"SA"}), frozenset({"SA"}))


def test_a_register_is_live_from_its_load_to_its_last_read_only():
    # Catches: liveness flowing forward instead of backward, or a definition not killing the older value.
    program = program_of([op("LD", M(1)), op("LD", M(2)), op("ST", M(3)), op("WLD", W(0)), op("WST", W(2)),
                          op("EM")])
    live = Liveness(program)
    at = [live.at((0, 0), i) for i in range(6)]
    assert "LA" not in at[0] and "LA" not in at[1]      # both loads define LA; the first value is never read
    assert "LA" in at[2]                                # '= M3' reads LA
    assert "WA" in at[4] and "WA" not in at[3]
    assert at[5] == live.exit((0, 0))


def test_a_register_read_by_a_called_routine_is_live_at_the_call():
    # Catches: calls treated as register-neutral (the word loaded before CALL is only read inside the callee).
    sub = CallTarget(0, 3, "SUB")
    program = program_of([op("WLD", W(0)), op("CALL", call=sub), op("EM"), lbl("SUB"), op("WST", W(2)), op("EM")],
                         (sub,))
    live = Liveness(program)
    assert "WA" in live.at((0, 0), 1)
    assert "WA" in live.at(sub.key, 3)


def test_registers_the_main_program_reads_first_are_live_at_its_end():
    # Catches: the persistence of registers from one PLC cycle to the next ignored (LA read before any load).
    live = Liveness(program_of([op("AND", M(1)), op("ST", M(2)), op("LD", M(3)), op("EM")]))
    assert "LA" in live.at((0, 0), 0) and "LA" in live.exit((0, 0))
    assert "LA" not in live.at((0, 0), 2)               # overwritten by LD M3 before the end: dead there


# ---- layout (layout.py)

def _layout(ops: list[Op]) -> Layout:
    return Layout(program_of(ops + [op("EM")]), NameTable())


def test_separate_words_get_named_variables_of_their_width():
    # Catches: a byte array forced where no access overlaps, or the wrong IEC type for a width.
    layout = _layout([op("WLD", W(0)), op("WST", W(2)), op("WLD", Operand("B", 4)), op("WST", Operand("D", 8))])
    assert layout.mem_array is None
    assert {n: layout.globals[n].type for n in ("W0", "W2", "B4", "D8")} == {
        "W0": "INT", "W2": "INT", "B4": "SINT", "D8": "DINT"}


def test_overlapping_byte_and_word_share_one_byte_array_and_others_keep_their_names():
    # Catches: overlap detection off by one (W0 covers bytes 0-1, so B1 overlaps; W2 does not) or the whole
    # memory moved to the array when only one group overlaps.
    layout = _layout([op("WLD", W(0)), op("WST", Operand("B", 1)), op("WST", W(2))])
    assert layout.mem_array is not None
    rows = {r.operand: r.iec for r in layout.rows}
    assert rows["W0"].startswith(layout.mem_array + "[") and rows["B1"] == f"{layout.mem_array}[1]"
    assert rows["W2"] == "W2" and layout.globals["W2"].type == "INT"


def test_indexed_word_access_puts_memory_in_the_array():
    # Catches: an indexed access planned as a named variable (the index can reach any byte).
    layout = _layout([op("WLD", W(10, indexed=True)), op("WST", W(20))])
    assert layout.mem_array is not None and "indexed access" in layout.globals[layout.mem_array].comment
    assert {r.operand: r.iec for r in layout.rows}["W20"] == f"{layout.mem_array}[20]"


def test_inputs_and_outputs_are_located_in_the_process_image():
    # Catches: a wrong %IX/%QX byte.bit address or group for I/O bits.
    layout = _layout([op("LD", Operand("I", 13)), op("ST", Operand("O", 9)), op("ST", M(5))])
    assert (layout.globals["I13"].address, layout.globals["I13"].group) == ("%IX1.5", "io_in")
    assert (layout.globals["O9"].address, layout.globals["O9"].group) == ("%QX1.1", "io_out")
    assert layout.globals["M5"].address is None


def test_division_declares_its_error_marker():
    # Catches: the DIV error marker not declared (the translation writes it).
    layout = _layout([op("WLD", W(0)), op("DIV", W(2)), op("WST", W(4))])
    marker = SEM.profile.interface.div_err
    assert f"M{marker}" in {r.operand for r in layout.rows}


def test_word_in_the_byte_array_is_written_byte_by_byte_in_profile_byte_order():
    # Catches: bytes written in the wrong order for the profile's endianness.
    layout = _layout([op("WLD", W(0)), op("WST", Operand("B", 1))])
    writes = layout.write_value(W(0), None, E.var("V", "DINT"))
    arr = layout.mem_array
    order = [f"{arr}[0]", f"{arr}[1]"] if SEM.little_endian else [f"{arr}[1]", f"{arr}[0]"]
    assert [lv for lv, _ in writes] == order
    assert [rv.text for _, rv in writes] == ["HH_BYTEOF(V, 0)", "HH_BYTEOF(V, 1)"]


# ---- names (names.py)

def test_keywords_and_standard_names_are_renamed_and_recorded():
    # Catches: an IEC keyword or standard function name used as a variable (matiec rejects it).
    names = NameTable()
    assert names.name("M1", "AND") == "AND_2"
    assert names.name("M2", "ton") == "ton_2"
    assert [(r.original, r.iec, r.reason) for r in names.renames] == [
        ("AND", "AND_2", "IEC keyword or standard name"), ("ton", "ton_2", "IEC keyword or standard name")]


def test_a_pou_avoids_the_variable_names_of_the_iec_libraries_a_variable_may_take_them():
    # Catches: a subprogram Init or Cycle becoming an FB of that name (matiec's standard library and OpenPLC's own
    # libraries declare variables so named, and no longer parse once a POU has taken it as a type name).
    names = NameTable()
    assert names.name(f"{POU_KEY_PREFIX}0:4", "Init") == "Init_2"
    assert names.name(f"{POU_KEY_PREFIX}0:9", "cycle") == "cycle_2"
    assert names.name("M5", "Init") == "Init"               # a marker may
    assert names.name(f"{POU_KEY_PREFIX}0:12", "Spindle") == "Spindle"
    assert [r.iec for r in names.renames] == ["Init_2", "cycle_2"]
    assert "libraries" in names.renames[0].reason


def test_illegal_characters_and_shapes_are_legalised():
    # Catches: characters outside [A-Za-z0-9_], double or trailing underscores, a leading digit, overlong names.
    assert legalise("Tool-Change.ok") == ("Tool_Change_ok", "illegal character")
    assert legalise("A__B") == ("A_B", "double underscore")
    assert legalise("Ready_") == ("Ready", "trailing underscore")
    assert legalise("1st") == ("H_1st", "must start with a letter")
    long, reason = legalise("X" * 100)
    assert len(long) == MAX_LEN and "longer than" in reason


def test_names_differing_only_in_case_are_made_distinct_and_each_key_keeps_its_name():
    # Catches: IEC's case-insensitivity ignored (Motor and MOTOR would be one variable) or unstable naming.
    names = NameTable()
    first, second = names.name("a", "Motor"), names.name("b", "MOTOR")
    assert first == "Motor" and second == "MOTOR_2"
    assert names.name("b", "anything") == "MOTOR_2" and len(names.renames) == 1


def test_no_name_takes_the_form_of_a_temporary():
    # Catches: a symbol called like a POU temporary (tmp1) that a temporary declared later would shadow.
    names = NameTable()
    assert names.name("M1", "TMP1") == "TMP1_2"
    assert names.renames[0].reason == "the form of the translator's temporaries"
    assert names.name("M2", "tmp_flag") == "tmp_flag"


def test_reserved_names_are_never_handed_out_again():
    # Catches: a program symbol taking the name of a library POU reserved before it.
    names = NameTable()
    names.reserve("HH_ADD", "lib:HH_ADD")
    assert names.name("W0", "hh_add") == "hh_add_2"


# ---- expressions (exprs.py)

A, B, C = (E.var(n, "BOOL") for n in "ABC")
X, Y, Z = (E.var(n, "DINT") for n in "XYZ")


def test_boolean_precedence_parenthesises_only_where_needed():
    # Catches: OR inside AND printed without parentheses (changes the meaning) or needless parentheses.
    assert E.b_and(E.b_or(A, B), C).text == "(A OR B) AND C"
    assert E.b_or(A, E.b_and(B, C)).text == "A OR B AND C"
    assert E.b_xor(E.b_or(A, B), C).text == "(A OR B) XOR C"
    assert E.b_not(E.b_and(A, B)).text == "NOT (A AND B)"


def test_binary_operators_are_left_associative():
    # Catches: the right operand of an equal-precedence operator left unparenthesised (X - (Y - Z) != X - Y - Z).
    assert E.binop("-", X, E.binop("-", Y, Z, "DINT", E.PREC_ADD), "DINT", E.PREC_ADD).text == "X - (Y - Z)"
    assert E.binop("-", E.binop("-", X, Y, "DINT", E.PREC_ADD), Z, "DINT", E.PREC_ADD).text == "X - Y - Z"
    assert E.binop("*", E.binop("+", X, Y, "DINT", E.PREC_ADD), Z, "DINT", E.PREC_MUL).text == "(X + Y) * Z"


def test_double_negation_cancels_and_keeps_the_inner_precedence():
    # Catches: NOT NOT left in, or the stripped expression losing the parentheses it needs in a larger one.
    inner = E.b_or(A, B)
    twice = E.b_not(E.b_not(inner))
    assert twice.text == "A OR B"
    assert E.b_and(twice, C).text == "(A OR B) AND C"
    assert E.b_not(E.bool_const(True)).text == "FALSE"


def test_ranges_follow_the_type_and_widening():
    # Catches: a range-less expression assumed narrower than its type (overflow checks would be dropped), or a
    # widening that forgets the narrow range.
    assert (E.Expr("f()", "DINT").lo, E.Expr("f()", "DINT").hi) == E.INT32
    wide = E.to_dint(E.var("W0", "INT"))
    assert (wide.text, wide.lo, wide.hi) == ("INT_TO_DINT(W0)", -32768, 32767)
    narrow = E.unwiden(wide)
    assert (narrow.text, narrow.typ) == ("W0", "INT")
    assert E.unwiden(E.Expr("INT_TO_DINT(A) + INT_TO_DINT(B)", "DINT")) is None


def test_negative_constants_carry_their_type_and_precedence():
    # Catches: a negative literal printed without its type prefix for narrow types, or bound tighter than unary.
    assert E.int_const(-5, "INT").text == "INT#-5"
    assert E.int_const(-5).prec == E.PREC_UNARY and E.int_const(5).prec == E.PREC_ATOM


def test_wrap32_is_twos_complement():
    # Catches: constant folding that saturates or leaves values outside DINT.
    assert wrap32(2 ** 31) == -2 ** 31 and wrap32(-2 ** 31 - 1) == 2 ** 31 - 1 and wrap32(5) == 5


# ---- symbolic execution (symbolic.py and its parts)

def test_addition_in_range_is_plain_st_and_may_overflow_goes_through_the_wrapping_helper():
    # Catches: range analysis wrong in either direction: HH_ADD needed for D+D (may overflow DINT), plain '+' for
    # two words (cannot), and constant folding of K+K.
    small = routine_lines(program_of([op("WLD", W(0)), op("ADD", W(2)), op("WST", Operand("D", 8))]
                                     + [op("EM")]))
    assert small == ["D8 := INT_TO_DINT(W0) + INT_TO_DINT(W2);"]
    big = routine_lines(program_of([op("WLD", Operand("D", 0)), op("ADD", Operand("D", 4)), op("WST", Operand("D", 8)),
                                    op("EM")]))
    assert big == ["D8 := HH_ADD(D0, D4);"]
    const = routine_lines(program_of([op("WLD", Operand("K", 2 ** 31 - 1)), op("ADD", Operand("K", 1)),
                                      op("WST", Operand("D", 8)), op("EM")]))
    assert const == ["D8 := -2147483648;"]


def test_a_value_in_flight_is_saved_before_its_source_is_overwritten():
    # Catches: LA kept symbolic as 'M1' after M1 is reassigned, so the later store would read the new M1.
    lines = routine_lines(program_of([op("LD", M(1)), op("LDN", M(2)), op("ST", M(1)), op("EM")]))
    assert lines == ["M1 := NOT M2;"]
    lines = routine_lines(program_of([op("LD", M(1)), op("PSL"), op("LD", M(2)), op("ST", M(1)), op("PLL"),
                                      op("ST", M(3)), op("EM")]))
    save = next(n for n, line in enumerate(lines) if line.endswith(":= M1;"))
    assert save < lines.index("M1 := M2;")
    assert lines[-1] == f"M3 := {lines[save].split(' :=')[0]};"


def test_bits_of_a_constant_word_are_written_as_true_and_false():
    # Catches: B= of a constant word left as HH_BIT(0, k) calls (an unfolded constant), or the bit order reversed.
    lines = routine_lines(program_of([op("WLD", Operand("K", 5)), op("STBITS", M(10), nbits=4), op("EM")]))
    assert lines == ["M10 := TRUE;", "M11 := FALSE;", "M12 := TRUE;", "M13 := FALSE;"]
    lines = routine_lines(program_of([op("WLD", W(0)), op("STBITS", M(10), nbits=2), op("EM")]))
    assert lines == ["tmp1 := INT_TO_DINT(W0);", "M10 := HH_BIT(tmp1, 0);", "M11 := HH_BIT(tmp1, 1);"]


# ---- indexed bit reads: the accessor's output Q is the value, no temporary (operands.py)

def Mx(addr: int) -> Operand:
    return Operand("M", addr, True)


def test_two_indexed_reads_in_one_expression_take_two_instances_and_no_temporary():
    # Catches: a temporary per read ('tmp1 := HH_M_index.Q;'), or both reads through one instance (the second
    # call overwrites the Q the first value is).
    lines = routine_lines(program_of([op("LD", Mx(1100)), op("OR", Mx(4800)), op("ST", Mx(4800)), op("EM")]))
    assert lines == ["HH_M_index(IDX := 1100 + HH_X, WRITE := FALSE);",
                     "HH_M_index_2(IDX := 4800 + HH_X, WRITE := FALSE);",
                     # the write goes through the instance that holds M4800[X] (its value is stale after it)
                     "HH_M_index_2(IDX := 4800 + HH_X, WRITE := TRUE, VALUE := HH_M_index.Q OR HH_M_index_2.Q);"]


def test_an_indexed_read_in_flight_keeps_the_old_value_across_a_write_to_the_same_operand():
    # Catches: the write through the instance the value in flight reads, so that 'M3 :=' gets the new value.
    lines = routine_lines(program_of([op("LD", Mx(10)), op("STN", Mx(10)), op("ST", M(3)), op("EM")]))
    assert lines == ["HH_M_index(IDX := 10 + HH_X, WRITE := FALSE);",
                     "HH_M_index_2(IDX := 10 + HH_X, WRITE := TRUE, VALUE := NOT HH_M_index.Q);",
                     "M3 := HH_M_index.Q;"]
    # On the data stack too: the pushed value still reads the instance when it is pulled.
    lines = routine_lines(program_of([op("LD", Mx(10)), op("PSL"), op("LD", M(1)), op("ST", Mx(10)), op("PLL"),
                                      op("ST", M(3)), op("EM")]))
    assert lines == ["HH_M_index(IDX := 10 + HH_X, WRITE := FALSE);", "HH_LA := M1;",
                     "HH_M_index_2(IDX := 10 + HH_X, WRITE := TRUE, VALUE := HH_LA);", "M3 := HH_M_index.Q;"]


def test_a_dead_indexed_value_frees_its_instance_and_a_write_may_read_its_own_instance():
    # The IF condition is read before the branch: the branch reuses its instance. INC writes NOT of the value it
    # read through the same instance (the inputs are evaluated before the call).
    lines = routine_lines(program_of([op("LD", Mx(10)), op("JPF", target=5), op("LD", Mx(20)), op("AND", Mx(21)),
                                      op("ST", Mx(22)), lbl("b"), op("INC", Mx(30)), op("EM")]))
    assert lines == ["HH_M_index(IDX := 10 + HH_X, WRITE := FALSE);",
                     "IF HH_M_index.Q THEN (* t.src:2 *)",
                     "    HH_M_index(IDX := 20 + HH_X, WRITE := FALSE);",
                     "    HH_M_index_2(IDX := 21 + HH_X, WRITE := FALSE);",
                     "    HH_M_index(IDX := 22 + HH_X, WRITE := TRUE, VALUE := HH_M_index.Q AND HH_M_index_2.Q);",
                     "END_IF;",
                     "HH_M_index(IDX := 30 + HH_X, WRITE := FALSE);",
                     "HH_M_index(IDX := 30 + HH_X, WRITE := TRUE, VALUE := NOT HH_M_index.Q);"]


def test_indexed_reads_in_a_loop_and_across_its_exit():
    # Catches: a value of one iteration read after the instance was called again; the last read leaves the loop
    # in the register variable (it is live after the loop), read once more there.
    lines = routine_lines(program_of([op("WLD", Operand("K", 0)), op("WST", Operand("X", 0)), lbl("a"),
                                      op("LD", Mx(10)), op("SET", Mx(20)), op("INCX"), op("LD", Mx(30)),
                                      op("JPT", target=2), op("ST", M(1)), op("EM")]))
    assert lines == ["HH_X := 0;",
                     "REPEAT (* t.src:3 *)",
                     "    HH_M_index(IDX := 10 + HH_X, WRITE := FALSE);",
                     "    HH_M_index_2(IDX := 20 + HH_X, WRITE := FALSE);",
                     "    HH_M_index_2(IDX := 20 + HH_X, WRITE := TRUE, VALUE := HH_M_index.Q OR HH_M_index_2.Q);",
                     "    HH_M_index(IDX := 30 + HH_ADD(HH_X, 1), WRITE := FALSE);",
                     "    HH_LA := HH_M_index.Q;",
                     "    HH_X := HH_ADD(HH_X, 1);",
                     "UNTIL NOT HH_LA",
                     "END_REPEAT;",
                     "M1 := HH_LA;"]


def test_bits_read_together_by_one_op_each_keep_their_instance():
    # Catches: LDBITS holding its bits outside the symbolic state while one instance is called for each.
    lines = routine_lines(program_of([op("LDBITS", Mx(10), nbits=3), op("WST", W(0)), op("EM")]))
    assert lines == ["HH_M_index(IDX := 10 + HH_X, WRITE := FALSE);",
                     "HH_M_index_2(IDX := 11 + HH_X, WRITE := FALSE);",
                     "HH_M_index_3(IDX := 12 + HH_X, WRITE := FALSE);",
                     "W0 := DINT_TO_INT(HH_PACK3(HH_M_index.Q, HH_M_index_2.Q, HH_M_index_3.Q));"]


def test_indexed_set_reads_la_after_it_was_saved():
    # Catches: S M4800[X] writing 'HH_LA XOR M5 OR ...' after 'HH_LA := HH_LA XOR M5' (M5 applied twice).
    lines = routine_lines(program_of([op("XOR", M(5)), op("SET", Mx(4800)), op("ST", M(6)), op("EM")]))
    assert lines[:3] == ["HH_M_index(IDX := 4800 + HH_X, WRITE := FALSE);", "HH_LA := HH_LA XOR M5;",
                         "HH_M_index(IDX := 4800 + HH_X, WRITE := TRUE, VALUE := HH_LA OR HH_M_index.Q);"]
