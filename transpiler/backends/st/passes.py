"""Clean-up of a POU body before printing: a temporary written once and read once, in the very next statement,
is replaced by its value (copy propagation). The symbolic executor already folds constants and simplifies boolean
expressions while it builds them (exprs.py); this pass works on the emitted statements, one per line, and only
where the next statement evaluates the read before anything it does itself (an assignment's right side, an IF or
CASE condition, the inputs of an FB call), so the value cannot have changed in between.
"""

from __future__ import annotations

import dataclasses
import re

from transpiler.backends.iec_model import Pou
from transpiler.backends.st.names import TEMP_PREFIX

_DEF = re.compile(r"^(\s*)(" + TEMP_PREFIX + r"[0-9]+) := (.*);$")
_LOOP_HEADS = ("WHILE ", "UNTIL ", "ELSIF ", "REPEAT", "FOR ", "END_", "ELSE", "RETURN", "EXIT")
_COMMENT = re.compile(r"\(\*.*?\*\)")


def _code(line: str) -> str:
    return _COMMENT.sub("", line)


def _atomic(text: str) -> bool:
    """No operator at the top level: the text can replace a name without parentheses."""
    depth = 0
    for ch in text:
        depth += ch in "(["
        depth -= ch in ")]"
        if depth == 0 and ch == " ":
            return False
    return True


def _uses(lines: list[str], name: str) -> int:
    word = re.compile(r"(?<![A-Za-z0-9_.])" + name + r"(?![A-Za-z0-9_])", re.I)
    return sum(len(word.findall(_code(line))) for line in lines)


def propagate_temporaries(pou: Pou) -> Pou:
    """`pou` with every temporary that is read once, by the next statement, replaced by its value."""
    lines = pou.body.split("\n")
    removed: set[str] = set()
    changed = True
    while changed:
        changed = False
        for i, line in enumerate(lines):
            m = _DEF.match(line)
            if m is None or _uses(lines, m.group(2)) != 2:
                continue
            indent, name, value = m.groups()
            j = i + 1
            while j < len(lines) and lines[j].strip().startswith("(*"):
                j += 1
            if j >= len(lines):
                continue
            nxt = lines[j]
            stripped = nxt.strip()
            if not nxt.startswith(indent) or nxt[len(indent):len(indent) + 1] == " " or stripped.startswith(_LOOP_HEADS):
                continue
            word = re.compile(r"(?<![A-Za-z0-9_.])" + name + r"(?![A-Za-z0-9_])", re.I)
            code = _code(nxt)
            target = code.split(":=", 1)[0] if " := " in code and not stripped.startswith("IF ") else ""
            if not word.search(code) or word.search(target) and "(" not in target:
                continue        # the temporary is written there, not read
            if stripped.split("(", 1)[0].upper() == value.split(".", 1)[0].upper():
                continue        # an FB's output passed to its own next call stays named: it reads the old value
            text = value if _atomic(value) else f"({value})"
            lines[j] = word.sub(lambda _: text, nxt, count=1)
            del lines[i]
            removed.add(name.upper())
            changed = True
            break
    if not removed:
        return pou
    sections = tuple(dataclasses.replace(s, vars=tuple(v for v in s.vars if v.name.upper() not in removed))
                     if s.kind == "VAR" else s for s in pou.sections)
    sections = tuple(s for s in sections if s.vars or s.kind != "VAR")
    if not sections and pou.kind == "FUNCTION_BLOCK":
        return pou          # matiec rejects a FUNCTION_BLOCK without any declaration
    return dataclasses.replace(pou, body="\n".join(lines), sections=sections)
