"""The statements of a translated POU body as a tree: what the executor and the structurer build, what the clean-up
passes rewrite and what printer.py alone turns into ST text.

Values are `exprs.Expr` (their text, type and the variables they read); an assignment's target is lvalue text.
`note` is a comment printed after a statement or a block head: the source line a statement comes from
(`file:line`) or why it is there, so every statement stays traceable to the program it was translated from.
"""

from __future__ import annotations

import dataclasses
from typing import Iterator, Union

from transpiler.backends.st.exprs import Expr
from transpiler.records import quick_init, replaced


@quick_init
@dataclasses.dataclass(frozen=True)
class Comment:
    """A comment on a line of its own: a source comment, a label, an explanation."""

    text: str
    note: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class Assign:
    target: str                         # lvalue text: a variable, an array element or a member
    value: Expr
    note: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class Call:
    """A call statement of an FB instance (or a function whose result is not used) with named inputs."""

    callee: str
    args: tuple[tuple[str, Expr], ...] = ()
    note: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class Return:
    note: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class Exit:
    note: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class If:
    """IF/ELSE; `inline` asks for one line (a single short statement in `then`, no ELSE)."""

    cond: Expr
    then: tuple[Stmt, ...]
    orelse: tuple[Stmt, ...] = ()
    note: str | None = None
    inline: bool = False


@quick_init
@dataclasses.dataclass(frozen=True)
class CaseBranch:
    labels: tuple[int, ...]
    body: tuple[Stmt, ...]
    note: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class Case:
    selector: Expr
    branches: tuple[CaseBranch, ...]
    orelse: tuple[Stmt, ...] = ()
    note: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class While:
    cond: Expr
    body: tuple[Stmt, ...]
    note: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class Repeat:
    body: tuple[Stmt, ...]
    until: Expr
    note: str | None = None


Stmt = Union[Comment, Assign, Call, Return, Exit, If, Case, While, Repeat]
SIMPLE = (Assign, Call, Return, Exit)


def is_code(stmt: Stmt) -> bool:
    """Anything but a comment."""
    return not isinstance(stmt, Comment)


def has_code(block: tuple[Stmt, ...] | list[Stmt]) -> bool:
    """Anything but comments in `block` (is_code of each, without a call per statement)."""
    for s in block:
        if type(s) is not Comment:
            return True
    return False


def blocks(stmt: Stmt) -> tuple[tuple[Stmt, ...], ...]:
    """The statement lists nested directly in `stmt`."""
    kind = type(stmt)
    if kind is If:
        return (stmt.then, stmt.orelse)
    if kind is Case:
        return (*(branch.body for branch in stmt.branches), stmt.orelse)
    if kind is While or kind is Repeat:
        return (stmt.body,)
    return ()


def with_blocks(stmt: Stmt, new: list[tuple[Stmt, ...]]) -> Stmt:
    """`stmt` with its nested blocks replaced by `new`, given in the order of `blocks(stmt)`."""
    if isinstance(stmt, If):
        return replaced(stmt, then=new[0], orelse=new[1])
    if isinstance(stmt, Case):
        branches = tuple(replaced(b, body=body) for b, body in zip(stmt.branches, new))
        return replaced(stmt, branches=branches, orelse=new[-1])
    if isinstance(stmt, (While, Repeat)):
        return replaced(stmt, body=new[0])
    return stmt


def walk(block: tuple[Stmt, ...] | list[Stmt]) -> Iterator[Stmt]:
    """Every statement of `block`, nested ones included, in textual order."""
    for stmt in block:
        yield stmt
        if type(stmt) in _NESTING:
            for inner in blocks(stmt):
                yield from walk(inner)


_NESTING = frozenset({If, Case, While, Repeat})
