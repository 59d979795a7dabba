"""Parsers: every mnemonic and operand form of spec 2.5/6, comments attached to statements, KFIELD tables, .def and MP lines."""

from __future__ import annotations

import itertools
from decimal import Decimal
from pathlib import Path

import pytest
from test_frontend_support import compile_files, errors, program_ops

from transpiler.frontend import ast
from transpiler.diagnostics import Diagnostics, Span
from transpiler.language.mnemonics import MNEMONICS, canonical
from transpiler.frontend.parse import DefParser, MpParser, SrcParser, parse_constant
from transpiler.frontend.preprocess import Line, split_comment

# An operand of each kind, as written, for building one valid line per mnemonic.
SAMPLE_OPERAND = {"M": "M12", "I": "I3", "O": "O4", "T": "T5", "C": "C6", "B": "B8", "W": "W10", "D": "D12",
                  "K": "K-7", "S": "S2", "SREF": "S#E12", "SIMM": 'S"a;b"', "KF": "KF Tab[X]", "X": "X"}


def _line(mnemonic: str, operand: str | None) -> str:
    return mnemonic if operand is None else f"{mnemonic}  {operand}"


def _every_mnemonic_line() -> list[tuple[str, str, str | None]]:
    """(mnemonic, written line, operand kind or None) for every mnemonic and every allowed operand kind."""
    rows = []
    for name, info in MNEMONICS.items():
        if info.form == "none":
            rows.append((name, name, None))
        elif info.form == "label":
            rows.append((name, _line(name, "Step_1"), "SYM"))
        elif info.form == "call":
            rows += [(name, _line(name, "Step_1"), "SYM"), (name, _line(name, "9032"), "NUM")]
        else:
            rows += [(name, _line(name, SAMPLE_OPERAND[k]), k) for k in sorted(info.kinds)]
    return rows


def _parse(code: str):
    status, result = SrcParser().parse_line(code)
    assert status == "ok", (code, status, result)
    return result


@pytest.mark.parametrize("mnemonic, text, kind", _every_mnemonic_line())
def test_every_mnemonic_parses(mnemonic, text, kind):
    tag, name, operand = _parse(text)
    assert (tag, name) == ("instr", mnemonic)
    assert (operand.kind if operand else None) == kind
    # mnemonics are case-insensitive (spec 2.3)
    assert _parse(text.replace(mnemonic, mnemonic.lower(), 1))[1] == mnemonic


# The oracle: the instruction tables of the language description (section 6), copied once into a data file; not the
# parser's own table (transpiler/language/mnemonics.py), so a mnemonic lost from or added to that table is caught.
DESCRIPTION_MNEMONICS = Path(__file__).resolve().parent / "data" / "instructions" / "mnemonics.txt"
FORM_OPERANDS = {   # operand form of the description -> (written operand, kind the parser must report)
    "bit": [("M12", "M"), ("I3", "I"), ("O4", "O"), ("T5", "T"), ("C6", "C")],
    "val": [("B8", "B"), ("W10", "W"), ("D12", "D"), ("K-7", "K")],
    "mem": [("B8", "B"), ("W10", "W"), ("D12", "D")],
    "K": [("K-7", "K")], "X": [("X", "X")], "KF": [("KF Tab[X]", "KF")], "S": [("S2", "S")],
    "string": [("S2", "S"), ("S#E12", "SREF"), ("S#D5", "SREF"), ('S"a;b"', "SIMM")],
    "label": [("Step_1", "SYM")], "module": [("9032", "NUM")], "-": [(None, None)],
}


def _description_table() -> dict[str, list[str]]:
    table = {}
    for line in DESCRIPTION_MNEMONICS.read_text(encoding="utf-8").splitlines():
        if line.strip() and not line.startswith("#"):
            words = line.split()
            forms = [w for w in words[1:] if not w[0].isdigit()]
            assert words[0] not in table, f"{words[0]} listed twice"
            assert forms and all(f in FORM_OPERANDS or f == "name" for f in forms), line
            table[words[0]] = forms
    return table


DESCRIPTION = _description_table()


def test_the_description_table_is_complete():
    # 17 bracket operators (6.9) plus ']' and 80 other mnemonics, LBL included: a short file is a broken copy
    assert len(DESCRIPTION) == 97
    assert sum(1 for m in DESCRIPTION if m.endswith("[")) == 17


def _description_lines():
    for mnemonic, forms in DESCRIPTION.items():
        for form in forms:
            if form != "name":
                for operand, kind in FORM_OPERANDS[form]:
                    yield pytest.param(mnemonic, _line(mnemonic, operand), kind, id=f"{mnemonic} {operand or ''}".strip())


@pytest.mark.parametrize("mnemonic, text, kind", list(_description_lines()))
def test_the_parser_accepts_every_mnemonic_of_the_description(mnemonic, text, kind):
    tag, name, operand = _parse(text)
    assert (tag, name) == ("instr", mnemonic)
    assert (operand.kind if operand else None) == kind


def test_the_parser_knows_exactly_the_mnemonics_of_the_description():
    described = {m for m, forms in DESCRIPTION.items() if forms != ["name"]}
    assert sorted(set(MNEMONICS) - described) == [], "the parser accepts mnemonics the description does not have"
    assert sorted(described - set(MNEMONICS)) == [], "the parser lacks mnemonics of the description"
    # LBL is a label definition of its own (6.12), not an instruction
    assert _parse("LBL Step_1") == ("label", "Step_1")
    # words that are not mnemonics of the description are refused
    for text in ("LX K1", "AX[", "NOT", "JMP Step_1", "CALL Step_1", "ENDIF", "MUL K2", "LA", "=X W2"):
        assert SrcParser().parse_line(text)[0] != "ok", text


@pytest.mark.parametrize("text, mnemonic", [
    ("A [", "A["), ("a[", "A["), ("XON  [", "XON["), ("x[", "x["), ("X[", "x["), ("MOD [", "MOD["), ("<> [", "<>["),
    ("- [", "-["), ("==[", "==["), ("]", "]"), ("x K3", "x"), ("X K3", "x"), ("L- W2", "L-"), ("=n O1", "=N"),
    ("b= M8", "B="), ("endc", "ENDC"), ("whilet", "WHILET"),
])
def test_symbolic_and_bracket_spellings(text, mnemonic):
    assert _parse(text)[1] == mnemonic


@pytest.mark.parametrize("written, kind, value, indexed, text", [
    ("M12", "M", 12, False, "M12"), ("i 212", "I", 212, False, "I212"), ("O4095", "O", 4095, False, "O4095"),
    ("T 0", "T", 0, False, "T0"), ("C143", "C", 143, False, "C143"), ("B0", "B", 0, False, "B0"),
    ("W 262", "W", 262, False, "W262"), ("d12", "D", 12, False, "D12"), ("M12[X]", "M", 12, True, "M12[X]"),
    ("W4 [ x ]", "W", 4, True, "W4[X]"), ("K123", "K", 123, False, "K123"), ("K+25", "K", 25, False, "K+25"),
    ("K-4000", "K", -4000, False, "K-4000"), ("K$1F0", "K", 0x1F0, False, "K$1F0"), ("k 5", "K", 5, False, "K5"),
    ("K%1010", "K", 10, False, "K%1010"), ("K$FFFFFFFF", "K", -1, False, "K$FFFFFFFF"),
    ("K-2147483648", "K", -2 ** 31, False, "K-2147483648"), ("S3", "S", 3, False, "S3"),
    ("S3[X]", "S", 3, True, "S3[X]"), ("S#E12", "SREF", "E12", False, "S#E12"), ("s#d4095", "SREF", "D4095", False, "s#d4095"),
    ('S"a;b"', "SIMM", "a;b", False, 'S"a;b"'), ('S""', "SIMM", "", False, 'S""'), ("X", "X", 0, False, "X"),
    ("KF Speeds[X]", "KF", "Speeds", True, "KF Speeds[X]"), ("MG_step_done", "SYM", "MG_step_done", False, "MG_step_done"),
    ("_x1", "SYM", "_x1", False, "_x1"), ("MG_table[X]", "SYM", "MG_table", True, "MG_table[X]"),
    ("M12X", "SYM", "M12X", False, "M12X"), ("KFx", "SYM", "KFx", False, "KFx"),
])
def test_operand_forms(written, kind, value, indexed, text):
    _, _, operand = _parse(f"L {written}")
    assert operand == ast.OperandSyntax(kind, value, indexed, text)


@pytest.mark.parametrize("text, value", [("123", 123), ("+25", 25), ("-4000", -4000), ("$1F0", 0x1F0), ("%1010", 10),
                                         ("$FFFFFFFF", -1), ("$80000000", -2 ** 31), ("2147483647", 2 ** 31 - 1),
                                         ("-2147483648", -2 ** 31), ("2147483648", None), ("$100000000", None),
                                         ("%1" + "0" * 32, None), ("-2147483649", None)])
def test_constants_are_32_bit(text, value):
    assert parse_constant(text) == value


@pytest.mark.parametrize("text, expected", [
    ("LBL Step_1", ("label", "Step_1")), ("lbl x", ("label", "x")), ("KFIELD Speeds", ("kfield", "Speeds")),
    ("ENDK", ("endk",)), ("K$7D0", ("kentry", 2000)), ("USES Spindle.src", ("uses", "Spindle.src")),
    ("uses sub/Mod.SRC", ("uses", "sub/Mod.SRC")), ("GLOBAL Entry", ("global", "Entry")),
    ("EXTERN Entry", ("extern", "Entry")), ("#define /g Machine_IO.def", ("define_file", "Machine_IO.def", True)),
    ("#DEFINE Local.def", ("define_file", "Local.def", False)),
])
def test_directives_labels_and_tables(text, expected):
    assert _parse(text) == expected


@pytest.mark.parametrize("text", ["L I1 I2", "USES a b", "LBL", "LBL 1x", "L K1.5", "L M-1", "KFIELD",
                                  "S\"x\"", "GLOBAL", "L S#X1", "\x00\x01", "L S\"open"])
def test_malformed_lines_are_reported_not_raised(text):
    status, _ = SrcParser().parse_line(text)
    assert status in ("syntax", "range")


def test_out_of_range_literal_is_a_range_error_not_a_syntax_error():
    assert SrcParser().parse_line("L K4294967296") == ("range", "4294967296")
    assert SrcParser().parse_line("K$1FFFFFFFF") == ("range", "$1FFFFFFFF")


# Names that would lex as another terminal are never parsed through the placeholder template.
NAME_CORPUS = ["MG_a", "x1", "X", "x", "KF", "kf", "M12", "m12", "K5", "k5", "S3", "I0", "W10", "D4", "B1", "T9", "C2",
               "Hh2iecPlaceholderName", "LBL", "EM", "ENDK", "USES", "KFIELD", "Mx", "K", "S", "_", "A_1", "CASE"]
SHAPES = ["L {}", "L {}[X]", "= {} ", "JP {}", "CM {}", "CMT  {}", "LBL {}", "KFIELD {}", "GLOBAL {}", "EXTERN {}",
          "USES {}", "L KF {}[X]", "L KF {}", "SUBM {}", "A {} [X]", "EM {}", "{}", "L {} {}", "#define /g {}", "x {}"]


def test_template_cache_gives_the_same_result_as_a_direct_parse():
    parser = SrcParser()
    for shape, name in itertools.product(SHAPES, NAME_CORPUS):
        line = shape.format(name, name)
        cached = parser.parse_line(line)
        assert cached == parser.parse_uncached(line.strip()), line
        assert parser.parse_line(line) == cached         # and again from the line cache


def test_lines_of_an_accepted_shape_give_what_each_line_gives_alone():
    """A file's lines of one shape (`L MG_a`, `L x1`, ...) after the first are taken from the accepted shape: the
    statements and diagnostics are those of parsing and checking each line on its own."""
    for shape in SHAPES:
        if shape.startswith("KFIELD"):        # (opens a table: the lines after it do not stand alone)
            continue
        texts = [shape.format(name, name) for name in NAME_CORPUS] * 2
        lines = [Line(text, None, Span("f.src", i + 1)) for i, text in enumerate(texts)]
        diags = Diagnostics()
        together = SrcParser().parse_file("f.src", lines, len(lines), diags).statements
        alone, alone_diags = [], Diagnostics()
        for line in lines:
            alone.extend(SrcParser().parse_file("f.src", [line], len(lines), alone_diags).statements)
        assert together == tuple(alone), shape
        assert [d.render() for d in diags.items] == [d.render() for d in alone_diags.items], shape


def test_comments_are_attached_to_the_statement_they_annotate():
    lines = ["; header of the file", "", "; before the label", "LBL Start   ; on the label",
             "L  I1", "; before the store", ";;;X9.7a", "=  O1 ; same line", "KFIELD T ; the table",
             "K1 ; first", "ENDK", "; trailing"]
    parsed = SrcParser().parse_file("f.src", [Line(*split_comment(t), Span("f.src", i + 1)) for i, t in enumerate(lines)],
                                    len(lines), Diagnostics())
    label, load, store, table = parsed.statements
    assert label.comments == ("header of the file", "before the label", "on the label")
    assert load.comments == ()
    assert store.comments == ("before the store", ";;X9.7a", "same line")
    assert isinstance(table, ast.KField) and table.comments == ("the table",)
    assert parsed.trailing_comments == ("trailing",)


def test_kfield_tables(tmp_path):
    program = "L K1\n= X\nL KF Speeds[X]\n= D20\nEM\nKFIELD Speeds   ; rpm\nK+500\nk 1000\nK$7D0\nK%11\nENDK\n"
    result = compile_files(tmp_path, {"main.src": program})
    assert errors(result) == []
    load = program_ops(result)[2]
    assert (load.operand.kind, load.operand.kfield, load.operand.text) == ("KF", (500, 1000, 2000, 3), "Speeds")
    table = program_ops(result)[5]
    assert (table.code, table.label, table.span.line, table.comments) == ("KFIELD", "Speeds", 6, ("rpm",))


def test_kfield_body_accepts_only_constants(tmp_path):
    result = compile_files(tmp_path, {"main.src": "EM\nKFIELD T\nK1\nL I1\nK2\nENDK\n"})
    assert [(e.code, e.line) for e in errors(result)] == [("E-SYNTAX", 4)]


def test_spans_carry_the_column_of_the_first_character(tmp_path):
    result = compile_files(tmp_path, {"main.src": "L I1\n    = O1\n\t\tEM\n"})
    assert [(op.span.line, op.span.col) for op in program_ops(result)] == [(1, 1), (2, 5), (3, 3)]


def test_en_dash_spellings_of_l_minus():
    """The manuals print `L–`; U+2013, its UTF-8 bytes read as Latin-1 and the cp1252 byte all mean '-'."""
    from transpiler.frontend.preprocess import PPParser, Preprocessor, initial_defines
    lines = ("L\u2013 W2", "L\xe2\x80\x93 W4", "L\x96 W6", "\u2013[")
    out = Preprocessor(initial_defines({}), Diagnostics(), PPParser()).run("f.src", lines)
    assert [_parse(line.code)[1] for line in out] == ["L-", "L-", "L-", "-["]


def test_definition_template_cache_gives_the_same_result_as_a_direct_parse():
    parser = DefParser()
    shapes = ["{} M", "{} M 12", "{} W4", "{} K $FF", "{} K 99999999999", "/c {} M &Other", "{} I &{}", "{} Q 5",
              "{} K", "#define /g {}", "{}", "{} S 4 x",
              # a number at the line's end goes through the template with 0 there
              "{} M 4172", "{} K 100", "{} k100", "{} W\t123456789", "{} D 1234567890", "{} K 0012", "{} K -12",
              "{} K +12", "{} T 07", "/c {} B 9", "{} I &{}7", "{} M &x 5", "{} 12", "{} X 12", "{} M 12 3",
              "{} K 2147483648", "{} K 99999999999999999999", "{} M  0", "{} S4 5"]
    for shape, name in itertools.product(shapes, NAME_CORPUS):
        line = shape.format(name, name)
        assert parser.parse_line(line) == parser.parse_uncached(line), line
        assert parser.parse_line(line) == parser.parse_uncached(line), line     # and again from the line cache


def test_canonical_spelling():
    assert [canonical(t) for t in ("a [", "X", "x", "X[", "l-", "mod[", "= n")] == ["A[", "x", "x", "x[", "L-", "MOD[", "=N"]


# ---------------------------------------------------------------------------------------------- .def files


def _def(text: str) -> tuple[ast.DefFile, Diagnostics]:
    diags = Diagnostics()
    lines = [Line(*split_comment(t), Span("a.def", i + 1)) for i, t in enumerate(text.split("\n"))]
    return DefParser().parse_file("a.def", [line for line in lines if not line.code.lstrip().startswith("*")],
                                  len(lines), diags), diags


def test_definition_forms():
    parsed, diags = _def("#type Markers\nI_door_closed I 17 ; door\nO_lamp O4\nNP_W262_pocket W262\nKL_retries K 3\n"
                         "KG_mask K $00FF\nKG_bits K%0101\nKG_neg K -5\nMG_step_done M\n/c I_air_ok M &MG_always_one\n"
                         "#TYPE Strings\nSG_text S\nSG_fixed S 4\n/C I_guard_2 I11")
    assert diags.items == []
    rows = [(s.name, s.kind, s.address, s.constant, s.alias, s.cflag, s.section, s.comments) for s in parsed.symbols]
    assert rows == [
        ("I_door_closed", "I", 17, None, None, False, "#type Markers", ("door",)),
        ("O_lamp", "O", 4, None, None, False, "#type Markers", ()),
        ("NP_W262_pocket", "W", 262, None, None, False, "#type Markers", ()),
        ("KL_retries", "K", None, 3, None, False, "#type Markers", ()),
        ("KG_mask", "K", None, 255, None, False, "#type Markers", ()),
        ("KG_bits", "K", None, 5, None, False, "#type Markers", ()),
        ("KG_neg", "K", None, -5, None, False, "#type Markers", ()),
        ("MG_step_done", "M", None, None, None, False, "#type Markers", ()),
        ("I_air_ok", "M", None, None, "MG_always_one", True, "#type Markers", ()),
        ("SG_text", "S", None, None, None, False, "#TYPE Strings", ()),
        ("SG_fixed", "S", 4, None, None, False, "#TYPE Strings", ()),
        ("I_guard_2", "I", 11, None, None, True, "#TYPE Strings", ()),
    ]


def test_definition_errors_name_the_broken_symbol():
    parsed, diags = _def("MG_ok M 1\nMG_bad Q 1\nKG_big K 99999999999\nKG_none K\n/c MG_x M &\n")
    assert [s.name for s in parsed.symbols] == ["MG_ok"]
    assert [(d.code, d.span.line) for d in diags.errors] == [("E-SYNTAX", 2), ("E-LIT-RANGE", 3), ("E-SYNTAX", 4),
                                                             ("E-SYNTAX", 5)]
    assert parsed.broken == ("MG_bad", "KG_big", "KG_none", "MG_x")


def test_io_config_form(tmp_path):
    files = {"main.src": "#define /g GLB_IO_CONFIG.DEF\nL I_x\n= O_y\nL CONF_TIME_STAMP\n= D0\nEM\n",
             "GLB_IO_CONFIG.DEF": "*####################\n* generated by IOconfig\n*####################\n"
                                  "CONF_TIME_STAMP K 1234567\nI_x I 212 ;;;X9.7a\nO_y O 12 ;;;X10.3\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == []
    assert result.program.symbols["I_x"].comment == ";;X9.7a"
    assert result.program.symbols["CONF_TIME_STAMP"].addr == 1234567


# ----------------------------------------------------------------------------------------------- MP files


def test_machine_parameter_lines():
    diags = Diagnostics()
    lines = ("MP4110.0 : 0.125 ;clamp delay", "mp 4110.12:0.35", "MP4120 : -3", "  MP 4111.5 : 7  ", "* star",
             "; comment", "MP4110 : x", "MP : 1", "4110.0 : 1")
    params = MpParser().parse_lines("m.mp", lines, diags)
    assert [(p.number, p.index, p.value, p.span.line) for p in params] == [
        (4110, 0, Decimal("0.125"), 1), (4110, 12, Decimal("0.35"), 2), (4120, 0, Decimal("-3"), 3),
        (4111, 5, Decimal("7"), 4)]
    assert [(d.code, d.span.line) for d in diags.errors] == [("E-MP-VALUE", 7), ("E-MP-VALUE", 8), ("E-MP-VALUE", 9)]
