"""Screen masks (*.msk, *.a): find the project's mask files and read them into ir.Mask (mask_refs resolves them).

A mask is a sequence of `;`-terminated statements (docs/masks.md):

    /* comment */
    CHARSIZE=AUTO;                                   setting KEY=VALUE
    "DIAG TOOL CHANGE\\n";                            static text, \\n starts a new line
    " %4D %4D\\n", $WG_a$/c, $WG_b$/c;                formatted line: one reference per field
    ERRQUE=10/c/l/s;                                 ten lines of the PLC error queue

Statements may span lines, so the reader is a small tokenizer over the whole text rather than a line grammar.
Every problem is reported (file:line:col) and the reader goes on after the next `;`.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path
from types import MappingProxyType
from typing import Iterator

from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend.sources import ProjectFolders, SourceText, read_source
from transpiler.ir import Mask, MaskField, MaskRef, MaskStatement

MASK_SUFFIXES = (".msk", ".a")
MASK_FOLDERS = ("mask", "masks")          # sub-folders of the main program's folder searched as well
MAX_WIDTH = 255                           # a field wider than a screen line is a typing error
MAX_DECIMALS = 9
MAX_QUEUE_LINES = 99
CONVERSIONS = "dDsF"
_FIELD = re.compile(r"%([-+0 #]*)([0-9]{0,4})(?:\.([0-9]{0,4}))?(.?)", re.DOTALL)   # (longer numbers: no field)
_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_NUMBER = re.compile(r"[0-9]+")
_MODIFIER = re.compile(r"/([A-Za-z]+)(?:=([0-9]{1,9}))?")
_SYMBOL = re.compile(r"[A-Za-z_][A-Za-z0-9_.]*")
_ESCAPES = MappingProxyType({"n": "\n", "t": "\t", "\\": "\\", '"': '"'})


def mask_files(main: Path) -> list[Path]:
    """Every mask file (*.msk, *.a, any case) beside the main program and in its `mask`/`masks` sub-folder."""
    folders = [main.parent]
    try:
        folders += sorted(p for p in main.parent.iterdir() if p.is_dir() and p.name.lower() in MASK_FOLDERS)
    except OSError:
        return []
    found: list[Path] = []
    for folder in folders:
        try:
            found += sorted(p for p in folder.iterdir() if p.suffix.lower() in MASK_SUFFIXES and p.is_file())
        except OSError:
            continue
    return found


def read_masks(main: Path, folders: ProjectFolders, diags: Diagnostics, encoding: str | None = None) -> tuple[Mask, ...]:
    """The project's mask files, parsed (references not yet resolved); unreadable files are reported and skipped."""
    masks = []
    for path in mask_files(main):
        text = read_source(path, folders, Span(folders.display(path), 1, 1), diags, encoding)
        if text is not None:
            masks.append(parse_mask(text, diags))
    return tuple(masks)


# ---------------------------------------------------------------------------------------------
# tokens


@dataclasses.dataclass(frozen=True)
class _Token:
    kind: str           # STRING REF WORD NUMBER MOD ; , = + - EOF
    value: str
    span: Span
    bad: bool = False   # a string whose faults were reported: its statement is read, then dropped


class _Tokenizer:
    def __init__(self, text: SourceText, diags: Diagnostics):
        self.file = text.display
        self.lines = text.lines
        self.diags = diags

    def tokens(self) -> Iterator[_Token]:
        line_no, col = 0, 0
        in_comment: Span | None = None
        for line_no, line in enumerate(self.lines, 1):
            col = 0
            while col < len(line):
                if in_comment is not None:
                    end = line.find("*/", col)
                    if end < 0:
                        col = len(line)
                        continue
                    col, in_comment = end + 2, None
                    continue
                ch = line[col]
                at = Span(self.file, line_no, col + 1)
                if ch in " \t\f\v\x00\ufeff":
                    col += 1
                elif line.startswith("/*", col):
                    in_comment, col = at, col + 2
                elif ch == '"':
                    token, col = self._string(line, col, at)
                    if token is not None:
                        yield token
                elif ch == "$":
                    end = line.find("$", col + 1)
                    name = line[col + 1:end] if end > 0 else ""
                    if end < 0 or not _SYMBOL.fullmatch(name):
                        self.diags.report("E-MASK-SYNTAX", at, "a reference is a symbol name between dollar signs, "
                                          "like $WG_tc_status$")
                        col = end + 1 if end > 0 else len(line)
                        continue
                    yield _Token("REF", name, at)
                    col = end + 1
                elif ch == "/":
                    m = _MODIFIER.match(line, col)
                    if m is None:
                        self.diags.report("E-MASK-SYNTAX", at, "'/' starts a modifier (/c, /n=3) or a comment (/* */)")
                        col += 1
                        continue
                    yield _Token("MOD", m.group(1).lower() + (f"={m.group(2)}" if m.group(2) is not None else ""), at)
                    col = m.end()
                elif ch.isascii() and (ch.isalpha() or ch == "_"):
                    m = _WORD.match(line, col)
                    yield _Token("WORD", m.group(0), at)
                    col = m.end()
                elif ch in "0123456789":
                    m = _NUMBER.match(line, col)
                    yield _Token("NUMBER", m.group(0), at)
                    col = m.end()
                elif ch in ";,=+-":
                    yield _Token(ch, ch, at)
                    col += 1
                else:
                    self.diags.report("E-MASK-SYNTAX", at, f"unexpected character {ch!r}")
                    col += 1
        if in_comment is not None:
            self.diags.report("E-MASK-SYNTAX", in_comment, "comment '/*' is not closed with '*/'")
        yield _Token("EOF", "", Span(self.file, max(line_no, 1), col + 1))

    def _string(self, line: str, col: int, at: Span) -> tuple[_Token | None, int]:
        """A string literal on one line; escapes \\n \\t \\\\ \\" (a `%` stays for the format reader)."""
        out = []
        bad = False
        i = col + 1
        while i < len(line):
            ch = line[i]
            if ch == '"':
                return _Token("STRING", "".join(out), at, bad), i + 1
            if ch == "\\":
                nxt = line[i + 1] if i + 1 < len(line) else ""
                if nxt not in _ESCAPES:
                    self.diags.report("E-MASK-SYNTAX", Span(self.file, at.line, i + 1),
                                      f"unknown escape '\\{nxt}' (\\n, \\t, \\\\ and \\\" are known)")
                    bad = True
                    i += 2
                    continue
                out.append(_ESCAPES[nxt])
                i += 2
                continue
            out.append(ch)
            i += 1
        self.diags.report("E-MASK-SYNTAX", at, "string is not closed on its line")
        return None, len(line)


# ---------------------------------------------------------------------------------------------
# statements


class _Parser:
    def __init__(self, text: SourceText, diags: Diagnostics):
        self.diags = diags
        self.tokens = list(_Tokenizer(text, diags).tokens())
        self.pos = 0

    def peek(self) -> _Token:
        return self.tokens[self.pos]

    def take(self) -> _Token:
        token = self.tokens[self.pos]
        if token.kind != "EOF":
            self.pos += 1
        return token

    def fail(self, token: _Token, message: str) -> None:
        """Report and skip to just after the next `;`."""
        self.diags.report("E-MASK-SYNTAX", token.span, message)
        while self.peek().kind not in (";", "EOF"):
            self.take()
        self.take()

    def statements(self) -> list[MaskStatement]:
        out: list[MaskStatement] = []
        while self.peek().kind != "EOF":
            token = self.take()
            if token.kind == "STRING":
                stmt = self._text(token)
            elif token.kind == "WORD":
                stmt = self._setting(token)
            else:
                self.fail(token, f"a statement starts with a string or a KEY=VALUE setting, not {_what(token)}")
                continue
            if stmt is not None:
                out.append(stmt)
        return out

    def _end(self, after: str) -> bool:
        token = self.peek()
        if token.kind == ";":
            self.take()
            return True
        self.fail(token, f"expected ';' after {after}, found {_what(token)}")
        return False

    def _text(self, string: _Token) -> MaskStatement | None:
        if self.peek().kind == ";":
            self.take()
            pieces = None if string.bad else _format_pieces(string, [], self.diags, static=True)
            return None if pieces is None else MaskStatement("text", string.span, pieces)
        if self.peek().kind != ",":
            self.fail(self.peek(), f"expected ';' or ',' after the string, found {_what(self.peek())}")
            return None
        refs: list[MaskRef] = []
        while self.peek().kind == ",":
            self.take()
            ref = self._reference()
            if ref is None:
                return None
            refs.append(ref)
        if not self._end("the references"):
            return None
        pieces = None if string.bad else _format_pieces(string, refs, self.diags, static=False)
        return None if pieces is None else MaskStatement("line", string.span, pieces)

    def _reference(self) -> MaskRef | None:
        token = self.take()
        if token.kind == "REF":
            text, symbol = f"${token.value}$", token.value
        elif token.kind == "WORD":
            text, symbol = token.value, None
        else:
            self.fail(token, f"expected a reference ($SYMBOL$ or an operand such as S1), found {_what(token)}")
            return None
        modifiers = self._modifiers(("c",), allow_decimals=True)
        return None if modifiers is None else MaskRef(text, symbol, modifiers, token.span)

    def _modifiers(self, known: tuple[str, ...], allow_decimals: bool) -> tuple[str, ...] | None:
        found: list[str] = []
        while self.peek().kind == "MOD":
            token = self.take()
            name = token.value
            if allow_decimals and name.startswith("n="):
                if int(name[2:]) > MAX_DECIMALS:
                    self.fail(token, f"/{name}: at most {MAX_DECIMALS} decimal places")
                    return None
            elif name not in known:
                allowed = ", ".join(f"/{k}" for k in known) + (", /n=k" if allow_decimals else "")
                self.fail(token, f"unknown modifier /{name} (known here: {allowed})")
                return None
            found.append(name)
        return tuple(found)

    def _setting(self, key: _Token) -> MaskStatement | None:
        if self.peek().kind != "=":
            self.fail(self.peek(), f"expected '=' after {key.value} (a setting is KEY=VALUE;)")
            return None
        self.take()
        if key.value.upper() == "ERRQUE":
            count = self.take()
            if count.kind != "NUMBER" or len(count.value) > 3 or not 1 <= int(count.value) <= MAX_QUEUE_LINES:
                self.fail(count, f"ERRQUE= takes the number of lines, 1 ... {MAX_QUEUE_LINES}")
                return None
            modifiers = self._modifiers(("c", "l", "s"), allow_decimals=False)
            if modifiers is None or not self._end("the error queue"):
                return None
            return MaskStatement("errque", key.span, lines=int(count.value), modifiers=modifiers)
        value = []
        while self.peek().kind in ("WORD", "NUMBER", "+", "-"):
            value.append(self.take().value)
        if not value:
            self.fail(self.peek(), f"{key.value}= needs a value, found {_what(self.peek())}")
            return None
        if not self._end(f"{key.value}={''.join(value)}"):
            return None
        return MaskStatement("setting", key.span, key=key.value.upper(), value="".join(value))


def _what(token: _Token) -> str:
    return {"EOF": "the end of the file", "STRING": "a string", "REF": f"${token.value}$",
            "MOD": f"/{token.value}"}.get(token.kind, f"'{token.value}'")


def _format_pieces(string: _Token, refs: list[MaskRef], diags: Diagnostics, static: bool
                   ) -> tuple[str | MaskField, ...] | None:
    """The string split into literal text and fields, each field with its reference (in order)."""
    text = string.value
    pieces: list[str | MaskField] = []
    literal: list[str] = []
    fields = 0
    i = 0
    ok = True
    while i < len(text):
        ch = text[i]
        if ch != "%":
            literal.append(ch)
            i += 1
            continue
        m = _FIELD.match(text, i)
        flags, width, precision, conversion = m.group(1), m.group(2), m.group(3), m.group(4)
        i = m.end()
        if conversion == "%" and not (flags or width or precision is not None):
            literal.append("%")
            continue
        if conversion not in CONVERSIONS or not conversion:
            diags.report("E-MASK-FORMAT", string.span, f"field '{m.group(0)}': the formats are %d, %D, %s, %F "
                         "(with flags, width and precision, e.g. %+5.0F) and %% for a percent sign")
            ok = False
            continue
        if (width and int(width) > MAX_WIDTH) or (precision and int(precision) > MAX_DECIMALS):
            diags.report("E-MASK-FORMAT", string.span, f"field '{m.group(0)}': at most {MAX_WIDTH} characters "
                         f"wide and {MAX_DECIMALS} decimals")
            ok = False
            continue
        fields += 1
        if fields <= len(refs):
            if literal:
                pieces.append("".join(literal))
                literal = []
            pieces.append(MaskField(m.group(0), flags, int(width) if width else None,
                                    int(precision) if precision else (0 if precision is not None else None),
                                    conversion, refs[fields - 1]))
    if literal:
        pieces.append("".join(literal))
    if fields != len(refs) and ok:
        if static:
            diags.report("E-MASK-FORMAT", string.span, f"the text has {fields} field(s) but no references: "
                         "write them after a comma (\"%4D\\n\", $NAME$/c;) or write %% for a percent sign")
        else:
            diags.report("E-MASK-FORMAT", string.span, f"{fields} field(s) in the format but {len(refs)} "
                         "reference(s) after it")
        return None
    return tuple(pieces) if ok else None


def parse_mask(text: SourceText, diags: Diagnostics) -> Mask:
    """The mask of one file (references unresolved)."""
    return Mask(text.path.name, text.display, tuple(_Parser(text, diags).statements()))
