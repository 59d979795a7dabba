"""Parsers (lark, LALR): preprocessed lines of .src, .def and MP files into typed syntax trees with spans and comments."""

from __future__ import annotations

import dataclasses
import re
from decimal import Decimal
from typing import Iterable, Iterator

from lark import LarkError, Token, Transformer
from lark.exceptions import UnexpectedInput, VisitError

from transpiler.frontend import ast
from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend.grammars import lalr_parser
from transpiler.language.mnemonics import MNEMONICS, canonical
from transpiler.frontend.preprocess import Line, split_comment

INT32_MIN, INT32_MAX = -(2 ** 31), 2 ** 31 - 1
UINT32_MAX = 2 ** 32 - 1


def parse_constant(text: str, documented: bool = False) -> int | None:
    """A constant literal (without K) to its int32 value; None when it does not fit in 32 bits (A-56).

    `documented` (literal_range = documented) accepts only the manuals' range -2147483647 ... 2147483647 and
    hexadecimal/binary literals up to $7FFFFFFF.
    """
    text = text.replace(" ", "").replace("\t", "")
    if text.startswith(("$", "%")):
        value = int(text[1:], 16 if text[0] == "$" else 2)
        if documented and value > INT32_MAX:
            return None
        return _pattern(value)
    value = decimal_int(text)
    if (INT32_MIN + (1 if documented else 0)) <= value <= INT32_MAX:
        return value
    return None


_TOO_LONG = 10 ** 15


def decimal_int(text: str) -> int:
    """A decimal number of any length; one with more than 15 significant digits is taken as +-10**15, far out of
    every range (CPython refuses int() of more than 4300 digits, which would make a range error a syntax error)."""
    digits = text.lstrip("+-").lstrip("0")
    if len(digits) > 15:
        return -_TOO_LONG if text.startswith("-") else _TOO_LONG
    return int(text)


def _pattern(value: int) -> int | None:
    if value > UINT32_MAX:
        return None
    return value - 2 ** 32 if value > INT32_MAX else value


class _ConstRange(Exception):
    pass


class _SrcTransformer(Transformer):
    """Turns one parsed line into a position-free tuple (cached by line text)."""

    def __init__(self, documented_literals: bool = False) -> None:
        super().__init__()
        self.documented = documented_literals

    def label(self, items):
        return ("label", str(items[1]))

    def kfield(self, items):
        return ("kfield", str(items[1]))

    def endk(self, items):
        return ("endk",)

    def kentry(self, items):
        return ("kentry", _const_value(items[0], self.documented))

    def uses(self, items):
        return ("uses", str(items[1]))

    def global_(self, items):
        return ("global", str(items[1]))

    def extern(self, items):
        return ("extern", str(items[1]))

    def define_file(self, items):
        return ("define_file", str(items[2]), items[1] is not None)

    def instr(self, items):
        return ("instr", canonical(str(items[0])), items[1])

    def operand(self, items):
        base, index = items
        if index is None:
            return base
        return base._replace(indexed=True, text=base.text + "[X]")

    def bit_op(self, items):
        return _addr_operand(items[0])

    def word_op(self, items):
        return _addr_operand(items[0])

    def const_op(self, items):
        # written text normalised like the other operands: upper-case letter, no blank after it ("k 5" -> "K5")
        return ast.OperandSyntax("K", _const_value(items[0], self.documented), False, "K" + str(items[0])[1:].strip())

    def str_op(self, items):
        return ast.OperandSyntax("S", decimal_int(str(items[0])[1:]), False, str(items[0]))

    def strref_op(self, items):
        text = str(items[0])
        return ast.OperandSyntax("SREF", text[2].upper() + text[3:], False, text)

    def strimm_op(self, items):
        text = str(items[0])
        return ast.OperandSyntax("SIMM", text[2:-1], False, text)

    def kf_op(self, items):
        return ast.OperandSyntax("KF", str(items[1]), False, f"KF {items[1]}")

    def x_op(self, items):
        return ast.OperandSyntax("X", 0, False, "X")

    def num_op(self, items):
        return ast.OperandSyntax("NUM", decimal_int(str(items[0])), False, str(items[0]))

    def sym_op(self, items):
        return ast.OperandSyntax("SYM", str(items[0]), False, str(items[0]))

    def start(self, items):
        return items[0]


def _addr_operand(token: Token) -> ast.OperandSyntax:
    text = str(token)
    kind = text[0].upper()
    return ast.OperandSyntax(kind, decimal_int(text[1:].strip()), False, kind + text[1:].strip())


def _const_value(token: Token, documented: bool = False) -> int:
    text = str(token)[1:].strip()
    value = parse_constant(text, documented)
    if value is None:
        raise _ConstRange(text if len(text) <= 40 else text[:37] + "...")
    return value


def _code_lines(lines: Iterable[Line], pending: list[str]) -> Iterator[tuple[str, Span, tuple[str, ...]]]:
    """(stripped code, span, comments) of every line with code; the comments of comment-only lines go to the next
    line with code, and those after the last one are left in `pending` (a file's trailing comments)."""
    for code, comment, span in lines:
        code = code.strip()
        if not code:
            if comment is not None:
                pending.append(comment.strip())
            continue
        own = (comment.strip(),) if comment is not None else ()
        if pending:
            own = tuple(pending) + own
            pending.clear()
        yield code, span, own


@dataclasses.dataclass
class _PendingKField:
    name: str
    span: Span
    comments: tuple[str, ...]
    values: list[int]


# Lines that differ only in their last name (`L  MG_a` / `L  MG_b`) parse alike: such a line is parsed once
# with a placeholder name and the real name is put into the result, so that large projects with many distinct
# symbols do not pay a lark parse per line. Names that could lex as another terminal (M12, K5, S3, X, KF) are
# never replaced; tests/test_parse.py checks that both paths give the same result.
_LAST_NAME = re.compile(r"(?<=[ \t])([A-Za-z_][A-Za-z0-9_]*)((?:[ \t]*\[[ \t]*[Xx][ \t]*\])?)$")
_OPERAND_LIKE = re.compile(r"(?i)(?:[MIOTCBWDS][0-9]+|K[0-9]+|X|KF)")
_PLACEHOLDER = "Hh2iecPlaceholderName"


def _with_name(result: tuple, name: str) -> tuple:
    """The parse result of a template line with the placeholder replaced by the real name (flat results only)."""
    out = []
    for item in result:
        if isinstance(item, str):
            item = item.replace(_PLACEHOLDER, name)
        elif isinstance(item, ast.OperandSyntax):
            item = _operand_with_name(item, name)
        out.append(item)
    return tuple(out)


def _operand_with_name(operand: ast.OperandSyntax, name: str) -> ast.OperandSyntax:
    value = operand.value.replace(_PLACEHOLDER, name) if isinstance(operand.value, str) else operand.value
    return ast.OperandSyntax(operand.kind, value, operand.indexed, operand.text.replace(_PLACEHOLDER, name))


class _CachedLineParser:
    """A lark line parser whose results are cached by line text and, through the placeholder template, by shape.

    Subclasses say where a line's one replaceable name is (`_name_slot`) and how to put the real name into the
    template's result (`_renamed`)."""

    def __init__(self, grammar: str, transformer: Transformer) -> None:
        self._lark = lalr_parser(grammar)
        self._transformer = transformer
        self._cache: dict[str, tuple] = {}

    def parse_line(self, code: str) -> tuple:
        """('ok', tuple) | ('range', literal) | ('syntax', column) for one line without its comment."""
        key = code.strip()
        cached = self._cache.get(key)
        if cached is not None:
            return cached
        slot = self._name_slot(key) if _PLACEHOLDER not in key else None
        if slot is not None:
            template, name = slot
            shape = self._cache.get(template)
            if shape is None:
                shape = self._cache[template] = self.parse_uncached(template)
            renamed = self._renamed(shape, name)
            if renamed is not None:
                self._cache[key] = renamed
                return renamed
        cached = self._cache[key] = self.parse_uncached(key)
        return cached

    def parse_uncached(self, key: str) -> tuple:
        """The lark parse of one stripped line, without any cache."""
        try:
            return ("ok", self._transformer.transform(self._lark.parse(key)))
        except VisitError as exc:
            # A transformer callback raised (lark wraps it): the only expected case is a constant outside 32 bits,
            # which is E-LIT-RANGE, not E-SYNTAX.
            if isinstance(exc.orig_exc, _ConstRange):
                return ("range", str(exc.orig_exc))
            return ("syntax", 1)
        except UnexpectedInput as exc:
            return ("syntax", getattr(exc, "column", 1))
        except (LarkError, RecursionError):
            return ("syntax", 1)

    def _name_slot(self, key: str) -> tuple[str, str] | None:
        """(template line, real name) when the line's result does not depend on that name, else None."""
        raise NotImplementedError

    def _renamed(self, shape: tuple, name: str) -> tuple | None:
        """The template's result with the real name, or None when the line must be parsed as it is."""
        raise NotImplementedError


class SrcParser(_CachedLineParser):
    """Parses the active lines of a .src file; identical line texts are parsed once per run.

    lenient_brackets (A-02b) accepts a blank between a bracket mnemonic and '['; documented_literals is
    literal_range = documented (A-56).
    """

    def __init__(self, lenient_brackets: bool = True, documented_literals: bool = False) -> None:
        super().__init__("src.lark", _SrcTransformer(documented_literals))
        self.lenient_brackets = lenient_brackets
        # Line text -> (mnemonic, operand) of an instruction line that parsed and passed _instruction's checks
        # without a diagnostic: the same text gives the same instruction, so it is checked once per run.
        self._accepted: dict[str, tuple[str, ast.OperandSyntax]] = {}
        # Template line -> (mnemonic, operand with the placeholder name) of an accepted instruction line whose
        # instruction is its template's with the name put in: every line of that shape parses alike and passes the
        # same checks, so a line with a new name costs neither a parse nor the checks (most lines of a project).
        self._accepted_shapes: dict[str, tuple[str, ast.OperandSyntax]] = {}

    def _name_slot(self, key: str) -> tuple[str, str] | None:
        last = _LAST_NAME.search(key)
        if last is None:
            return None
        name = last.group(1)
        if _OPERAND_LIKE.fullmatch(name):
            return None
        start = last.start(1)
        return key[:start] + _PLACEHOLDER + key[start + len(name):], name

    def _renamed(self, shape: tuple, name: str) -> tuple | None:
        return ("ok", _with_name(shape[1], name)) if shape[0] == "ok" else None

    def _accepted_by_shape(self, code: str) -> tuple[str, ast.OperandSyntax] | None:
        """(mnemonic, operand) of an instruction line of an accepted shape (see `_accepted_shapes`), else None."""
        slot = self._name_slot(code) if _PLACEHOLDER not in code else None
        shape = self._accepted_shapes.get(slot[0]) if slot is not None else None
        if shape is None:
            return None
        known = self._accepted[code] = (shape[0], _operand_with_name(shape[1], slot[1]))
        return known

    def _remember_shape(self, code: str, mnemonic: str, operand: ast.OperandSyntax | None) -> None:
        """After the line `code` was accepted as (mnemonic, operand): its shape is accepted when that is exactly its
        template's instruction with the name put in (not when _instruction rewrote the operand otherwise)."""
        slot = self._name_slot(code) if _PLACEHOLDER not in code and operand is not None else None
        template = self._cache.get(slot[0]) if slot is not None else None
        if template is None or template[0] != "ok" or template[1][0] != "instr":
            return
        _, template_mnemonic, template_operand = template[1]
        if template_mnemonic == mnemonic and template_operand is not None \
                and _operand_with_name(template_operand, slot[1]) == operand:
            self._accepted_shapes[slot[0]] = (mnemonic, template_operand)

    def parse_file(self, display: str, lines: Iterable[Line], line_count: int, diags: Diagnostics) -> ast.SourceFile:
        statements: list[ast.Statement] = []
        trailing_comments: list[str] = []
        kfield: _PendingKField | None = None
        broken_labels: list[str] = []
        accepted, new_instr = self._accepted, ast.new_instr
        for code, span, comments in _code_lines(lines, trailing_comments):
            if kfield is None:
                known = accepted.get(code) or self._accepted_by_shape(code)
                if known is not None:       # an instruction line (or its shape) met before, accepted without a diagnostic
                    statements.append(new_instr(known[0], known[1], span, comments))
                    continue
            status, result = self.parse_line(code)
            if status == "range":
                diags.report("E-LIT-RANGE", span, f"literal {result} does not fit in 32 bits")
                continue
            if status == "syntax":
                self._report_syntax(code, span, result, diags)
                broken_labels.extend(_LABEL_LINE.findall(code)[:1])
                continue
            tag = result[0]
            if kfield is not None:
                if tag == "kentry":
                    kfield.values.append(result[1])
                    continue
                if tag == "endk":
                    statements.append(ast.KField(kfield.name, tuple(kfield.values), kfield.span, kfield.comments))
                    kfield = None
                    continue
                diags.report("E-SYNTAX", span, "only K constants may stand between KFIELD and ENDK")
                continue
            if tag == "kfield":
                kfield = _PendingKField(result[1], span, comments, [])
            elif tag == "endk":
                diags.report("E-SYNTAX", span, "ENDK without KFIELD")
            elif tag == "kentry":
                diags.report("E-SYNTAX", span, "a constant line outside a KFIELD table")
            elif tag == "label":
                statements.append(ast.Label(result[1], span, comments))
            elif tag == "uses":
                statements.append(ast.Uses(result[1], span, comments))
            elif tag == "global":
                statements.append(ast.Global(result[1], span, comments))
            elif tag == "extern":
                statements.append(ast.Extern(result[1], span, comments))
            elif tag == "define_file":
                statements.append(ast.DefineFile(result[1], result[2], span, comments))
            else:
                blank = not self.lenient_brackets and result[1].endswith("[") and _BLANK_BEFORE_BRACKET.match(code)
                if blank:
                    # reported, but the bracket is kept so that its ']' does not cascade into E-BRACKET-BALANCE
                    diags.report("E-SYNTAX", span, f"blank between {result[1][:-1]} and '[' (lenient_brackets is off, A-02b)")
                instr = self._instruction(result[1], result[2], span, comments, diags, code)
                if instr is not None:
                    statements.append(instr)
                    if not blank:
                        accepted[code] = (instr.mnemonic, instr.operand)
                        self._remember_shape(code, instr.mnemonic, instr.operand)
        if kfield is not None:
            diags.report("E-SYNTAX", kfield.span, f"KFIELD {kfield.name} has no ENDK")
        return ast.SourceFile(display, tuple(statements), tuple(trailing_comments), line_count, tuple(broken_labels))

    def _instruction(self, mnemonic: str, operand: ast.OperandSyntax | None, span: Span,
                     comments: tuple[str, ...], diags: Diagnostics, code: str) -> ast.Instr | None:
        info = MNEMONICS.get(mnemonic)
        if info is None:
            diags.report("E-SYNTAX", span, f"unknown mnemonic '{mnemonic}'")
            return None
        if info.form == "none" and operand is not None:
            diags.report("E-SYNTAX", span, f"{mnemonic} takes no operand")
            return None
        if info.form != "none" and operand is None:
            what = {"label": "a label", "call": "a label or module number"}.get(info.form, "an operand")
            diags.report("E-SYNTAX", span, f"{mnemonic} needs {what}")
            return None
        if info.form == "label" or info.form == "call" and operand.kind != "NUM":
            # A jump or call target is a label name, whatever terminal it lexed as (`LBL S12` defines a
            # label that `CM S12` must reach): take it exactly as written.
            parts = code.split(None, 1)
            written = parts[1].strip() if len(parts) == 2 else operand.text
            if operand.indexed or not _LABEL_NAME.fullmatch(written):
                what = "a label name" if info.form == "label" else "a label name or a module number"
                diags.report("E-SYNTAX", span, f"{mnemonic} needs {what}, not '{operand.text}'")
                return None
            operand = ast.OperandSyntax("SYM", written, False, written)
        if info.form == "operand" and operand.kind == "NUM":
            diags.report("E-SYNTAX", span, f"'{operand.text}' is not an operand (a constant is written K{operand.text})")
            return None
        return ast.Instr(mnemonic, operand, span, comments)

    @staticmethod
    def _report_syntax(code: str, span: Span, column: int, diags: Diagnostics) -> None:
        first = re.match(r"\S+", code)
        word = first.group(0) if first else code
        col = span.col + max(0, (column or 1) - 1)
        # Spec 3.7: a first word that is no mnemonic, directive or label keyword is E-UNSUPPORTED (a macro call,
        # or a typo such as EMM) naming the word; otherwise the line is malformed (E-SYNTAX at the column).
        if first and canonical(word) not in MNEMONICS and not _DIRECTIVE_WORD.fullmatch(word) \
                and not _CONSTANT_LINE.match(code):
            diags.report("E-UNSUPPORTED", span, f"'{word[:40]}' is neither a mnemonic, a directive nor a label definition")
            return
        diags.report("E-SYNTAX", Span(span.file, span.line, col), f"cannot parse '{code[:80]}'")


_LABEL_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_LABEL_LINE = re.compile(r"(?i)^\s*(?:LBL|KFIELD)\s+([A-Za-z_][A-Za-z0-9_]*)")      # the name a bad LBL line meant
_DIRECTIVE_WORD = re.compile(r"(?i)LBL|KFIELD|ENDK|USES|GLOBAL|EXTERN|#define|INCLUDE|#include")
_CONSTANT_LINE = re.compile(r"(?i)K[\s+\-$%0-9]")
_BLANK_BEFORE_BRACKET = re.compile(r"\S+[ \t]+\[")


class _DefTransformer(Transformer):
    def __init__(self, documented_literals: bool = False) -> None:
        super().__init__()
        self.documented = documented_literals

    def type_marker(self, items):
        return ("type", " ".join(str(i) for i in items))

    def define_file(self, items):
        return ("define_file", str(items[2]), items[1] is not None)

    def symbol_def(self, items):
        cflag, name, target = items
        return ("symbol", cflag is not None, str(name)) + target

    def t_fixed(self, items):
        text = str(items[0])
        return (text[0].upper(), decimal_int(text[1:].strip()), None, None)

    def t_const(self, items):
        return ("K", None, _const_value(items[0], self.documented), None)

    def t_auto(self, items):
        return (str(items[0]).upper(), None, None, None)

    def t_alias(self, items):
        return (str(items[0]).upper(), None, None, str(items[1]))

    def start(self, items):
        return items[0]


# The name a malformed definition line was meant to define (its first word after an optional /c).
_DEF_NAME = re.compile(r"^\s*(?:/c\s+)?([A-Za-z_][A-Za-z0-9_]*)", re.IGNORECASE)


# A definition line whose first word is the symbol name: lines that differ only in that name parse alike.
_DEF_LEADING_NAME = re.compile(r"^((?:/[cC][ \t]+)?)([A-Za-z_][A-Za-z0-9_]*)(?=[ \t])")
# ... and a fixed address or a constant given as a plain decimal number at the line's end (`M 4172`, `K 100`):
# lines that also differ only in that number parse alike (the template has 0 there; up to 9 digits, so that the
# number is the address or constant itself, well inside 32 bits).
_DEF_NUMBER = re.compile(r"(?<![0-9])([0-9]{1,9})$")
_DEF_KIND_BEFORE_NUMBER = re.compile(r"[MIOTCBWDSKmiotcbwdsk][ \t]*$")


class DefParser(_CachedLineParser):
    """Parses the active lines of a .def file; line results are cached like SrcParser's (by text and by shape)."""

    def __init__(self, documented_literals: bool = False) -> None:
        super().__init__("def.lark", _DefTransformer(documented_literals))

    def _name_slot(self, key: str) -> tuple[str, str] | None:
        lead = _DEF_LEADING_NAME.match(key)
        if lead is None:
            return None
        return lead.group(1) + _PLACEHOLDER + key[lead.end():], lead.group(2)

    def _renamed(self, shape: tuple, name: str) -> tuple | None:
        if shape[0] != "ok" or shape[1][0] != "symbol":
            return None
        return ("ok", shape[1][:2] + (name,) + shape[1][3:])

    def parse_line(self, code: str) -> tuple:
        """As _CachedLineParser.parse_line; a symbol line with a decimal address or constant at its end is parsed
        through the template with 0 there (a project's .def lines nearly all differ in name and address)."""
        key = code.strip()
        cached = self._cache.get(key)
        if cached is not None:
            return cached
        number = _DEF_NUMBER.search(key)
        if number is None or _DEF_KIND_BEFORE_NUMBER.search(key, 0, number.start()) is None \
                or number.group(1) == "0":
            return super().parse_line(key)
        shape = super().parse_line(key[:number.start()] + "0")
        result = shape[1] if shape[0] == "ok" else None
        value = int(number.group(1))
        if result is not None and result[0] == "symbol" and result[3] != "K" and result[4] == 0:
            cached = ("ok", result[:4] + (value,) + result[5:])
        elif result is not None and result[0] == "symbol" and result[3] == "K" and result[5] == 0:
            cached = ("ok", result[:5] + (value,) + result[6:])
        else:
            return super().parse_line(key)
        self._cache[key] = cached
        return cached

    def parse_file(self, display: str, lines: Iterable[Line], line_count: int, diags: Diagnostics) -> ast.DefFile:
        symbols: list[ast.SymbolDef] = []
        includes: list[ast.DefineFile] = []
        section: str | None = None
        broken: list[str] = []
        for code, span, comments in _code_lines(lines, []):
            cut = code.find("*")
            if cut > 0 and not code.startswith("#"):
                # `I_HR410_key_spindle_M5 M *I174` - a note after the kind or address, kept as a comment
                code, comments = code[:cut].rstrip(), comments + (code[cut + 1:].strip(),)
            parsed = self.parse_line(code)
            if parsed[0] != "ok":
                if parsed[0] == "range":
                    diags.report("E-LIT-RANGE", span, f"literal {parsed[1]} does not fit in 32 bits")
                else:
                    diags.report("E-SYNTAX", span, f"cannot parse definition '{code[:80]}'")
                broken.extend(_DEF_NAME.findall(code)[:1])
                continue
            result = parsed[1]
            if result[0] == "type":
                section = result[1]
                if result[1].lower().startswith("#typedef"):
                    diags.report("E-UNSUPPORTED", span, "structured symbols (#TYPEDEF) are not supported for this profile")
                continue
            if result[0] == "define_file":
                includes.append(ast.DefineFile(result[1], result[2], span, comments))
                continue
            _, cflag, name, kind, address, constant, alias = result
            if kind == "K" and constant is None:
                diags.report("E-SYNTAX", span, f"constant {name} needs a value (K 5, K $FF)")
                broken.append(name)
                continue
            symbols.append(ast.SymbolDef(name, kind, address, constant, alias, cflag, span, comments, section))
        return ast.DefFile(display, tuple(symbols), tuple(includes), line_count, tuple(broken))


@dataclasses.dataclass(frozen=True)
class MachineParameter:
    number: int
    index: int
    value: Decimal
    span: Span


class MpParser:
    """Parses machine-parameter files: `MP4110.0 : 0.125 ;comment`."""

    def __init__(self) -> None:
        self._lark = lalr_parser("mp.lark")

    def parse_lines(self, display: str, lines: tuple[str, ...], diags: Diagnostics) -> list[MachineParameter]:
        out: list[MachineParameter] = []
        for index, raw in enumerate(lines):
            code, _ = split_comment(raw)
            code = code.strip()
            if not code or code.startswith("*"):
                continue
            span = Span(display, index + 1, len(raw) - len(raw.lstrip()) + 1)
            try:
                tree = self._lark.parse(code)
            except (LarkError, RecursionError):
                diags.report("E-MP-VALUE", span, f"cannot parse machine parameter line '{code[:80]}'")
                continue
            tokens = [str(t) for t in tree.children if t is not None]
            number = int(tokens[1])
            idx = int(tokens[2]) if len(tokens) == 4 else 0
            out.append(MachineParameter(number, idx, Decimal(tokens[-1]), span))
        return out
