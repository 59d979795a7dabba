"""The one place that knows ST statement syntax: prints a statement tree (stmt.py) as the text of a POU body.

Keywords, `:=`, `;`, comments and indentation (four spaces a level) are decided here; expressions arrive as text
already (exprs.py prints them). The body is unindented: the writers indent it inside its POU.
"""

from __future__ import annotations

from typing import Iterable

from transpiler.backends.iec_model import Pou, st_comment
from transpiler.records import replaced
from transpiler.backends.st.stmt import (SIMPLE, Assign, Call, Case, CaseBranch, Comment, Exit, If, Repeat, Return,
                                        Stmt, While)

INDENT = "    "


def body_text(block: Iterable[Stmt]) -> str:
    """The ST text of a POU body."""
    return "\n".join(lines(block))


def with_statements(pou: Pou, block: Iterable[Stmt]) -> Pou:
    """`pou` with `block` as its statement tree and the body printed from it."""
    statements = tuple(block)
    return replaced(pou, statements=statements, body=body_text(statements))


def lines(block: Iterable[Stmt], depth: int = 0) -> list[str]:
    out: list[str] = []
    for stmt in block:
        _statement(stmt, depth, out)
    return out


def one_line(stmt: Stmt) -> bool:
    """The statement prints as a single line."""
    return type(stmt) in _ONE_LINE or type(stmt) is If and stmt.inline


_ONE_LINE = frozenset({Comment, *SIMPLE})


def _note(note: str | None) -> str:
    return "" if note is None else " " + st_comment(note)


def _simple(stmt: Stmt) -> str:
    if type(stmt) is Assign:        # (most statements)
        if stmt.note is None:
            return f"{stmt.target} := {stmt.value.text};"
        return f"{stmt.target} := {stmt.value.text};{_note(stmt.note)}"
    if isinstance(stmt, Call):
        args = ", ".join(f"{name} := {value.text}" for name, value in stmt.args)
        return f"{stmt.callee}({args});{_note(stmt.note)}"
    if isinstance(stmt, Return):
        return f"RETURN;{_note(stmt.note)}"
    if isinstance(stmt, Exit):
        return f"EXIT;{_note(stmt.note)}"
    if isinstance(stmt, Comment):
        return st_comment(stmt.text) + _note(stmt.note)
    if isinstance(stmt, If) and stmt.inline and len(stmt.then) == 1 and not stmt.orelse:
        return f"IF {stmt.cond.text} THEN {_simple(stmt.then[0])} END_IF;{_note(stmt.note)}"
    raise ValueError(f"not a one-line statement: {stmt!r}")


def _statement(stmt: Stmt, depth: int, out: list[str]) -> None:
    pad = INDENT * depth
    if one_line(stmt):
        out.append(pad + _simple(stmt))
    elif isinstance(stmt, If):
        out.append(f"{pad}IF {stmt.cond.text} THEN{_note(stmt.note)}")
        out += lines(stmt.then, depth + 1)
        if stmt.orelse:
            out.append(f"{pad}ELSE")
            out += lines(stmt.orelse, depth + 1)
        out.append(f"{pad}END_IF;")
    elif isinstance(stmt, Case):
        out.append(f"{pad}CASE {stmt.selector.text} OF{_note(stmt.note)}")
        for branch in stmt.branches:
            _branch(branch, depth + 1, out)
        if stmt.orelse:
            out.append(f"{pad}ELSE")
            out += lines(stmt.orelse, depth + 1)
        out.append(f"{pad}END_CASE;")
    elif isinstance(stmt, While):
        out.append(f"{pad}WHILE {stmt.cond.text} DO{_note(stmt.note)}")
        out += lines(stmt.body, depth + 1)
        out.append(f"{pad}END_WHILE;")
    elif isinstance(stmt, Repeat):
        out.append(f"{pad}REPEAT{_note(stmt.note)}")
        out += lines(stmt.body, depth + 1)
        out.append(f"{pad}UNTIL {stmt.until.text}")
        out.append(f"{pad}END_REPEAT;")
    else:
        raise ValueError(f"unknown statement {stmt!r}")


def _branch(branch: CaseBranch, depth: int, out: list[str]) -> None:
    """A branch of one simple statement shares the label's line; others start below it."""
    labels = ", ".join(str(label) for label in branch.labels)
    if branch.note is None and len(branch.body) == 1 and isinstance(branch.body[0], SIMPLE):
        out.append(f"{INDENT * depth}{labels}: {_simple(branch.body[0])}")
        return
    out.append(f"{INDENT * depth}{labels}:{_note(branch.note)}")
    out += lines(branch.body, depth + 1)
