"""The readability figure of emitted ST: how much of it is the program and how much is machinery (the emulated
data stack, temporaries, helper calls, VAR_EXTERNAL lists), so that a change that makes the output worse is seen
(`make bench`, report.md)."""

from __future__ import annotations

import dataclasses
import re

from transpiler.backends.iec_model import IecProject
from transpiler.backends.st.names import TEMP_PREFIX

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
    var_external_lines: int     # declaration lines inside VAR_EXTERNAL blocks (every POU)

    @property
    def per_instruction(self) -> float:
        return self.statements / self.instructions if self.instructions else 0.0

    def line(self) -> str:
        return (f"{self.statements} ST statement lines for {self.instructions} source instructions "
                f"({self.per_instruction:.2f} per instruction), {self.stack_lines} stack lines, "
                f"{self.temp_lines} temporary lines, {self.helper_calls} helper calls, "
                f"{self.var_external_lines} VAR_EXTERNAL lines")


def measure(project: IecProject, instructions: int) -> Readability:
    """The figure of the ST that render_st prints for `project`, read from the POUs it prints (their bodies are the
    printed ones less the indent: a large project's text need not be read back)."""
    statements = stack = temps = helpers = externals = 0
    for pou in project.pous:
        externals += sum(len(section.vars) for section in pou.sections if section.kind == "VAR_EXTERNAL")
        if pou.name.upper().startswith("HH_"):
            continue
        # A body at a time, not a line at a time: no pattern, the comments included, reaches past a line's end, so
        # the body's matches are its lines' matches.
        code = _COMMENT.sub("", pou.body) if "(*" in pou.body else pou.body
        statements += sum(1 for line in code.split("\n") if line.strip())
        if TEMP_PREFIX in code.lower():
            temps += _lines_matching(_TEMP, code)
        if "HH_" in code:       # (both patterns start with it)
            stack += _lines_matching(_STACK, code)
            helpers += len(_HELPER.findall(code))
    return Readability(instructions, statements, stack, temps, helpers, externals)


def _lines_matching(pattern: re.Pattern, text: str) -> int:
    """How many lines of `text` hold a match of `pattern` (one that does not reach past a line's end)."""
    return len({text.rfind("\n", 0, match.start()) for match in pattern.finditer(text)})
