"""The readability figure of emitted ST: how much of it is the program and how much is machinery (the emulated
data stack, temporaries, helper calls, VAR_EXTERNAL lists), so that a change that makes the output worse is seen
(`make bench`, report.md)."""

from __future__ import annotations

import dataclasses
import re

from transpiler.backends.st.names import TEMP_PREFIX
from transpiler.backends.st.writer import extract_pou_bodies

_COMMENT = re.compile(r"\(\*.*?\*\)")
# Each pattern starts with its name and only then looks behind it (so the regex engine skips from one occurrence of
# the name to the next instead of trying the look-behind at every character: fifteen times faster).
_TEMP = re.compile(TEMP_PREFIX + r"(?<![A-Za-z0-9_]" + TEMP_PREFIX + r")[0-9]+(?![A-Za-z0-9_])", re.I)
_HELPER = re.compile(r"HH_(?<![A-Za-z0-9_.]HH_)[A-Z0-9_]+\(")
_STACK = re.compile(r"HH_(?<!\wHH_)(SP|STACK)\b")


@dataclasses.dataclass(frozen=True)
class Readability:
    instructions: int           # source instructions (labels not counted)
    statements: int             # ST statement lines of the POUs translated from the program (no comments,
                                # declarations or blank lines; the HH_ library not counted)
    stack_lines: int            # statement lines that touch the emulated data stack
    temp_lines: int             # statement lines that read or write a temporary
    helper_calls: int           # calls of HH_ helper functions in those statements
    var_external_lines: int     # declaration lines inside VAR_EXTERNAL blocks (whole file)

    @property
    def per_instruction(self) -> float:
        return self.statements / self.instructions if self.instructions else 0.0

    def line(self) -> str:
        return (f"{self.statements} ST statement lines for {self.instructions} source instructions "
                f"({self.per_instruction:.2f} per instruction), {self.stack_lines} stack lines, "
                f"{self.temp_lines} temporary lines, {self.helper_calls} helper calls, "
                f"{self.var_external_lines} VAR_EXTERNAL lines")


def measure(st_text: str, instructions: int) -> Readability:
    statements = stack = temps = helpers = 0
    for name, body in extract_pou_bodies(st_text).items():
        if name.upper().startswith("HH_"):
            continue
        # A body at a time, not a line at a time (a hundred thousand lines in a large project): no pattern, the
        # comments included, reaches past a line's end, so the body's matches are its lines' matches.
        code = _COMMENT.sub("", body) if "(*" in body else body
        statements += sum(1 for line in code.split("\n") if line.strip())
        if TEMP_PREFIX in code.lower():
            temps += _lines_matching(_TEMP, code)
        if "HH_" in code:       # (both patterns start with it)
            stack += _lines_matching(_STACK, code)
            helpers += len(_HELPER.findall(code))
    externals = 0
    inside = False
    for line in st_text.split("\n"):
        if not inside and "VAR_EXTERNAL" not in line:
            continue                # (outside a block only its opening line matters)
        code = _code_of(line)       # a block may carry its title as a comment
        if code == "VAR_EXTERNAL":
            inside = True
        elif code == "END_VAR":
            inside = False
        elif inside and code:
            externals += 1
    return Readability(instructions, statements, stack, temps, helpers, externals)


def _lines_matching(pattern: re.Pattern, text: str) -> int:
    """How many lines of `text` hold a match of `pattern` (one that does not reach past a line's end)."""
    return len({text.rfind("\n", 0, match.start()) for match in pattern.finditer(text)})


def _code_of(line: str) -> str:
    """The line without its comments, stripped."""
    return (_COMMENT.sub("", line) if "(*" in line else line).strip()
