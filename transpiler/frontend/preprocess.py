"""Preprocessor: DEFINE values, #if/#ifdef/#else/#endif, INCLUDE; yields active lines mapped to their original file and line."""

from __future__ import annotations

import dataclasses
import difflib
import re
from pathlib import Path
from typing import Callable, Mapping, NamedTuple, Union

from lark import LarkError, Transformer

from transpiler.diagnostics import Diagnostics, Span, new_span
from transpiler.frontend.grammars import lalr_parser

DefineValue = Union[int, str]

_PP_LINE = re.compile(r"^\s*(#if|#ifdef|#ifndef|#else|#endif|DEFINE)(?![A-Za-z0-9_])", re.IGNORECASE)
_MAY_HOLD_DASH = re.compile("[\u2013\x96\xe2]")     # what _normalise_dashes looks for (its first characters)
_DIRECTIVE_STARTS = frozenset("#dD")       # the first characters _PP_LINE can match after blanks
_INCLUDE_LINE = re.compile(r'^\s*(?:INCLUDE|#include)\s+"?([^";\s]+)"?\s*$', re.IGNORECASE)


class Line(NamedTuple):
    """One active line of code with the original position of its first character.

    A typed named tuple rather than a frozen dataclass: one is made per source line, and a tuple is built
    several times faster (tests/bench_frontend.py)."""

    code: str          # text before the comment
    comment: str | None
    span: Span         # line and column of the line start in the original file


# Line(code, comment, span) without the named tuple's Python-level __new__ (one Line is made per source line)
_new_line = tuple.__new__


@dataclasses.dataclass(frozen=True)
class InactiveRegion:
    file: str
    first_line: int
    last_line: int
    condition: str


@dataclasses.dataclass
class Defines:
    """The DEFINE table of one run; `-D` overrides are fixed and win over every DEFINE line.

    With `case_insensitive` (A-61, the default) a name matches a DEFINE of any spelling; a use spelled otherwise
    than the definition is an E-PP-CASE warning naming both. `used` collects (lower-case) every name a file
    defines or tests, so that a `-D` for a name no file uses can be reported. `no_config` is set when the project
    has no configuration file: an #if on an undefined name is then E-CFG-MISSING (once), not a warning per line."""

    values: dict[str, DefineValue]
    spans: dict[str, Span]
    fixed: frozenset[str] = frozenset()
    case_insensitive: bool = True
    no_config: bool = False
    used: dict[str, str] = dataclasses.field(default_factory=dict)    # lower-case name -> first spelling
    missing_config_reported: bool = False

    def key(self, name: str, span: Span, diags: Diagnostics) -> str | None:
        """The table's key for `name` (None when undefined); a differing spelling is reported."""
        self.used.setdefault(name.lower(), name)
        if name in self.values:
            return name
        if not self.case_insensitive:
            return None
        lower = name.lower()
        found = next((k for k in self.values if k.lower() == lower), None)
        if found is not None:
            diags.report("E-PP-CASE", span, f"{name} is spelled {found} where it is defined ({self.spans[found]}); "
                         "DEFINE names compare ignoring case (A-61)")
        return found

    def define(self, name: str, value: DefineValue, span: Span, diags: Diagnostics) -> None:
        existing = self.key(name, span, diags)
        if existing is not None and existing in self.fixed:
            return
        if existing is not None:
            diags.report("E-DEF-REDEFINE", span, f"DEFINE {name} redefined (was {self.values[existing]!r} at "
                         f"{self.spans[existing]})")
            del self.values[existing], self.spans[existing]
        self.values[name] = value
        self.spans[name] = span


def split_comment(text: str) -> tuple[str, str | None]:
    """Split a line into code and `;` comment; a ';' inside a string literal belongs to the string."""
    cut = text.find(";")
    if cut < 0:
        return text, None
    if '"' not in text[:cut]:          # the common case: no string before the first ';'
        return text[:cut], text[cut + 1:]
    in_string = False
    for i, ch in enumerate(text):
        if ch == '"':
            in_string = not in_string
        elif ch == ";" and not in_string:
            return text[:i], text[i + 1:]
    return text, None


class _PPTransformer(Transformer):
    def v_string(self, items):
        return ("str", str(items[0])[1:-1])

    def v_int(self, items):
        return ("int", int(str(items[0])))

    def v_bin(self, items):
        return ("int", int(str(items[0])[1:], 2))

    def v_hex(self, items):
        return ("int", int(str(items[0])[1:], 16))

    def v_ref(self, items):
        return ("ref", str(items[0]))

    def define(self, items):
        return ("define", str(items[1]), items[2])

    def if_cmp(self, items):
        return ("if", str(items[1]), str(items[2]), items[3])

    def if_def(self, items):
        return ("ifdef" if str(items[0]).lower() == "#ifdef" else "ifndef", str(items[1]))

    def else_(self, items):
        return ("else",)

    def endif(self, items):
        return ("endif",)

    def start(self, items):
        return items[0]


class PPParser:
    """Parses one preprocessor or DEFINE line with the lark grammar `pp.lark`."""

    def __init__(self) -> None:
        self._lark = lalr_parser("pp.lark")
        self._transformer = _PPTransformer()
        self._cache: dict[str, tuple | None] = {}     # directives repeat a lot (#endif, #else, the same #if)

    def parse(self, code: str) -> tuple | None:
        key = code.strip()
        if key in self._cache:
            return self._cache[key]
        try:
            result = self._transformer.transform(self._lark.parse(key))
        except (LarkError, RecursionError):
            result = None
        self._cache[key] = result
        return result


def resolve_value(raw: tuple, defines: Defines, span: Span, diags: Diagnostics) -> DefineValue:
    kind, value = raw
    if kind != "ref":
        return value
    key = defines.key(value, span, diags)
    if key is not None:
        return defines.values[key]
    diags.report("E-PP-UNDEF-REF", span, f"&{value} names no DEFINE; it is taken as the string \"{value}\"")
    return value


def values_equal(left: DefineValue, right: DefineValue) -> bool:
    if isinstance(left, int) and isinstance(right, int):
        return left == right
    return str(left) == str(right)


def parse_define_value(text: str) -> DefineValue:
    """A `-D NAME=VALUE` value: integer, %binary, $hex, "string" or a bare word taken as a string."""
    text = text.strip()
    if re.fullmatch(r"[+-]?[0-9]+", text):
        return int(text)
    if re.fullmatch(r"%[01]+", text):
        return int(text[1:], 2)
    if re.fullmatch(r"\$[0-9A-Fa-f]+", text):
        return int(text[1:], 16)
    if len(text) >= 2 and text[0] == text[-1] == '"':
        return text[1:-1]
    return text


@dataclasses.dataclass
class _Frame:
    active_before: bool
    taking: bool
    seen_else: bool
    span: Span
    condition: str
    region_start: int | None


class Preprocessor:
    """Evaluates conditional compilation for one file at a time; `include` reads INCLUDE targets."""

    def __init__(self, defines: Defines, diags: Diagnostics, pp: PPParser):
        self.defines = defines
        self.diags = diags
        self.pp = pp
        self.inactive: list[InactiveRegion] = []

    def run(self, display: str, lines: tuple[str, ...], include: Callable[[str, Span], tuple[str, tuple[str, ...]] | None] | None = None,
            star_comments: bool = True, _chain: tuple[str, ...] = ()) -> list[Line]:
        out: list[Line] = []
        stack: list[_Frame] = []
        active = True
        chain = _chain + (display,)        # the files being included, for cycle detection
        pp_line, append = _PP_LINE.match, out.append
        for lineno, raw in enumerate(lines, 1):
            # (the dashes looked for are not ASCII, and a directive starts with '#' or 'D': most lines skip both scans)
            text = _normalise_dashes(raw) if not raw.isascii() and _MAY_HOLD_DASH.search(raw) else raw
            stripped = text.lstrip()
            first = stripped[:1]
            if first in _DIRECTIVE_STARTS:
                directive = pp_line(text)
                if directive:
                    handled, active = self._directive(display, lineno, text, directive.group(1).lower(), stack,
                                                      active)
                    if handled:
                        continue
            if not active or not first:
                continue
            # The common line: code and an optional comment, no '*' comment, no INCLUDE, no string before a ';'
            # (_code_line handles every other line, and this one in the same way).
            if first != "*" and first not in "Ii#" and '"' not in text:
                cut = text.find(";")
                span = new_span(display, lineno, len(text) - len(stripped) + 1)
                append(_new_line(Line, (text, None, span) if cut < 0 else (text[:cut], text[cut + 1:], span)))
                continue
            self._code_line(display, lineno, text, out, include, star_comments, chain)
        for frame in stack:
            self.diags.report("E-PP-NEST", frame.span, f"'{frame.condition}' has no matching #endif")
            self._close_region(display, frame, len(lines))
        return out

    def _directive(self, display: str, lineno: int, text: str, keyword: str, stack: list[_Frame],
                   active: bool) -> tuple[bool, bool]:
        """One DEFINE or #if/#ifdef/#ifndef/#else/#endif line: (whether it was handled, whether code is active after it)."""
        stripped = text.lstrip()
        span = Span(display, lineno, len(text) - len(stripped) + 1)
        code, _ = split_comment(text)
        parsed = self.pp.parse(code)
        if parsed is None:
            if active or keyword != "define":       # (a DEFINE in inactive code is not looked at)
                code_name = "E-CFG-SYNTAX" if keyword == "define" else "E-PP-SYNTAX"
                self.diags.report(code_name, span, f"malformed {keyword} line: {code.strip()[:80]}")
            if keyword in ("#if", "#ifdef", "#ifndef"):
                stack.append(_Frame(active, False, False, span, code.strip(), None))
                return True, False
            if keyword not in ("#else", "#endif"):
                return True, active
            # "#endif junk": still closes its block, so that the #if above does not cascade into E-PP-NEST
            parsed = (keyword[1:],)
        kind = parsed[0]
        if kind == "define":
            if active:
                self.defines.define(parsed[1], resolve_value(parsed[2], self.defines, span, self.diags), span, self.diags)
            return True, active
        if kind in ("if", "ifdef", "ifndef"):
            # #if blocks nest to any depth; the stack is a list, so depth costs no recursion.
            taking = self._condition(parsed, span) if active else False
            frame = _Frame(active, taking, False, span, code.strip(), None)
            stack.append(frame)
            if active and not taking:
                frame.region_start = lineno + 1
            return True, active and taking
        if kind == "else":
            return True, self._else(display, lineno, span, stack, active)
        if kind == "endif":
            if not stack:
                self.diags.report("E-PP-NEST", span, "#endif without a matching #if")
                return True, active
            frame = stack.pop()
            self._close_region(display, frame, lineno - 1)
            return True, frame.active_before
        return False, active

    def _else(self, display: str, lineno: int, span: Span, stack: list[_Frame], active: bool) -> bool:
        """An #else line: whether code is active after it."""
        if not stack or stack[-1].seen_else:
            self.diags.report("E-PP-NEST", span, "#else without a matching #if")
            return active
        frame = stack[-1]
        frame.seen_else = True
        if frame.active_before:
            if frame.taking:
                frame.region_start = lineno + 1
            else:
                self._close_region(display, frame, lineno - 1)
        return frame.active_before and not frame.taking

    def _code_line(self, display: str, lineno: int, text: str, out: list[Line],
                   include: Callable[[str, Span], tuple[str, tuple[str, ...]] | None] | None, star_comments: bool,
                   chain: tuple[str, ...]) -> None:
        """An active line that is not a directive: a `*` comment, an INCLUDE (expanded in place) or code."""
        stripped = text.lstrip()
        if not stripped:
            return                         # blank: nothing to parse and no comment to attach
        span = Span(display, lineno, len(text) - len(stripped) + 1)
        if star_comments and stripped.startswith("*"):
            out.append(Line("", stripped[1:], span))
            return
        code, comment = split_comment(text)
        inc = _INCLUDE_LINE.match(code) if include else None
        if inc:
            if len(chain) > 32:
                self.diags.report("E-FILE-INCLUDE-CYCLE", span, "INCLUDE nested more than 32 files deep")
                return
            got = include(inc.group(1), span)
            if got is not None:
                inc_display, inc_lines = got
                if inc_display in chain:
                    # a cycle would otherwise be expanded again and again (exponentially with two INCLUDEs)
                    self.diags.report("E-FILE-INCLUDE-CYCLE", span, f"{inc_display} includes itself "
                                     f"({' -> '.join(chain[chain.index(inc_display):] + (inc_display,))})")
                    return
                out.extend(self.run(inc_display, inc_lines, include, star_comments, chain))
            return
        out.append(Line(code, comment, span))

    def _close_region(self, display: str, frame: _Frame, last: int) -> None:
        """Record the frame's open inactive region (if any) as ending at line `last`."""
        if frame.region_start is not None and last >= frame.region_start:
            self.inactive.append(InactiveRegion(display, frame.region_start, last, frame.condition))
        frame.region_start = None

    def _condition(self, parsed: tuple, span: Span) -> bool:
        if parsed[0] in ("ifdef", "ifndef"):
            defined = self.defines.key(parsed[1], span, self.diags) is not None
            return defined if parsed[0] == "ifdef" else not defined
        _, name, op, raw = parsed
        key = self.defines.key(name, span, self.diags)
        if key is not None:
            left: DefineValue = self.defines.values[key]
        elif self.defines.no_config:
            # One root error instead of a warning per #if and silently dropped code.
            if not self.defines.missing_config_reported:
                self.defines.missing_config_reported = True
                self.diags.report("E-CFG-MISSING", span, f"#if tests {name}, but no DEFINE sets it and the project "
                                  "has no configuration: put OEM.cfg beside the main program, name one with --cfg, "
                                  "or give the values with -D NAME=VALUE")
            left = ""
        else:
            self.diags.report("E-PP-UNDEF", span, f"{name} is not defined; it compares as the empty string")
            left = ""
        right = resolve_value(raw, self.defines, span, self.diags)
        equal = values_equal(left, right)
        return equal if op == "=" else not equal


def _normalise_dashes(text: str) -> str:
    # The manuals print "L–" with an en dash; files may carry it as UTF-8 (read as Latin-1),
    # as the cp1252 byte 0x96, or as U+2013. All of them mean '-'.
    # Only the code is changed: a comment keeps its dashes (it is copied into the ST, the XML and the report).
    if "\u2013" in text or "\xe2\x80\x93" in text or "\x96" in text:
        if text.lstrip().startswith("*"):
            return text
        code, comment = split_comment(text)
        code = code.replace("\xe2\x80\x93", "-").replace("\u2013", "-").replace("\x96", "-")
        return code if comment is None else code + ";" + comment
    return text


def read_config(display: str, lines: tuple[str, ...], defines: Defines, diags: Diagnostics, pp: PPParser) -> None:
    """A .cfg file: DEFINE lines under conditional compilation; free text is a warning."""
    pre = Preprocessor(defines, diags, pp)
    for line in pre.run(display, lines):
        if line.code.strip():
            diags.report("E-CFG-IGNORED", line.span, f"line ignored: {line.code.strip()[:80]}")


def initial_defines(overrides: Mapping[str, DefineValue], case_insensitive: bool = True,
                    no_config: bool = False) -> Defines:
    """The table before any file is read: the `-D` values, fixed."""
    return Defines(dict(overrides), {name: Span("<command line>", 1, 1) for name in overrides}, frozenset(overrides),
                   case_insensitive, no_config)


def unused_overrides(defines: Defines, diags: Diagnostics) -> None:
    """A `-D NAME=...` for a name no file defines or tests: E-DEF-UNUSED with the nearest names used."""
    for name in sorted(defines.fixed):
        if name.lower() in defines.used:
            continue
        near = difflib.get_close_matches(name.lower(), sorted(defines.used), n=3, cutoff=0.6)
        hint = f"; nearest names used: {', '.join(defines.used[n] for n in near)}" if near else ""
        diags.report("E-DEF-UNUSED", Span("<command line>", 1, 1), f"-D {name}: no file defines or tests this name"
                     f"{hint}")


def find_default_cfg(main: Path) -> Path | None:
    """`OEM.cfg` beside the main file, matched case-insensitively."""
    try:
        for p in sorted(main.parent.iterdir()):
            if p.name.lower() == "oem.cfg" and p.is_file():
                return p
    except OSError:
        return None
    return None
