"""Statement-level clean-up of a POU's statement tree, before the copy propagation of passes.py:

- a store of an accumulator register (HH_LA, HH_WA, ...) that a later store of the same register overwrites
  before anything can read it is dropped;
- `IF c THEN x := TRUE; ELSE x := FALSE; END_IF;` becomes `x := c;` (and the swapped form `x := NOT c;`);
- an IF without statements in either branch leaves only its comments.

Expressions only read variables (the functions they call are FUNCTIONs, which see no global), so dropping an
IF's condition or a store's value loses no effect. Registers are globals: a subprogram called in between, a
RETURN or EXIT, the end of the enclosing block (a loop's next pass, the caller, the next cycle) may read them, so
a store is dropped only when the overwrite follows in the same block with none of those in between.
"""

from __future__ import annotations

import dataclasses
import re
from typing import Iterable

from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S

Block = tuple[S.Stmt, ...]


def simplify(block: Iterable[S.Stmt], registers: frozenset[str]) -> list[S.Stmt]:
    """`block` with the three simplifications applied; `registers` are the register variables (any case)."""
    registers = frozenset(r.upper() for r in registers)
    return list(_block(tuple(block), registers))


def _block(block: Block, registers: frozenset[str]) -> Block:
    out: list[S.Stmt] = []
    for stmt in _without_dead_stores(block, registers):
        stmt = S.with_blocks(stmt, [_block(inner, registers) for inner in S.blocks(stmt)])
        if isinstance(stmt, S.If):
            if not S.has_code(stmt.then) and not S.has_code(stmt.orelse):
                out.extend(stmt.then + stmt.orelse)
                continue
            stmt = _flag_from_condition(stmt)
        out.append(stmt)
    return tuple(out)


def _flag_from_condition(stmt: S.If) -> S.Stmt:
    """`IF c THEN x := TRUE; ELSE x := FALSE; END_IF;` as `x := c;` (both branches a single store of one target)."""
    if len(stmt.then) != 1 or len(stmt.orelse) != 1 or stmt.inline:
        return stmt
    then, orelse = stmt.then[0], stmt.orelse[0]
    if not (isinstance(then, S.Assign) and isinstance(orelse, S.Assign) and then.target == orelse.target
            and then.note is None and orelse.note is None):
        return stmt
    if {then.value.bool_const, orelse.value.bool_const} != {True, False}:
        return stmt
    value = stmt.cond if then.value.bool_const else E.b_not(stmt.cond)
    return S.Assign(then.target, value, stmt.note)


def _names(text: str) -> set[str]:
    return {m.group(0).upper() for m in re.finditer(r"(?<![A-Za-z0-9_.])[A-Za-z_][A-Za-z0-9_]*", text)}


def _reads(stmt: S.Stmt) -> set[str]:
    """Every variable a statement (nested ones included) may read: its expressions' deps and the names in its
    texts (an index in an assignment's target is read too)."""
    found: set[str] = set()
    for s in S.walk((stmt,)):
        exprs: list[E.Expr] = []
        if isinstance(s, S.Assign):
            exprs = [s.value]
            found |= _names(s.target.split("[", 1)[1]) if "[" in s.target else set()
        elif isinstance(s, S.Call):
            exprs = [value for _, value in s.args]
        elif isinstance(s, S.If):
            exprs = [s.cond]
        elif isinstance(s, S.Case):
            exprs = [s.selector]
        elif isinstance(s, S.While):
            exprs = [s.cond]
        elif isinstance(s, S.Repeat):
            exprs = [s.until]
        for e in exprs:
            found |= set(e.deps) | _names(e.text)
    return found


def _leaves_or_calls(stmt: S.Stmt) -> bool:
    """The statement calls an FB (which may read a global) or leaves the block early."""
    return any(isinstance(s, (S.Call, S.Return, S.Exit)) for s in S.walk((stmt,)))


def _register_store(stmt: S.Stmt, registers: frozenset[str]) -> str | None:
    if isinstance(stmt, S.Assign) and stmt.target.upper() in registers and stmt.note is None:
        return stmt.target.upper()
    return None


def _without_dead_stores(block: Block, registers: frozenset[str]) -> Block:
    dead: set[int] = set()
    for i, stmt in enumerate(block):
        reg = _register_store(stmt, registers)
        if reg is None:
            continue
        for later in block[i + 1:]:
            if reg in _reads(later) or _leaves_or_calls(later):
                break
            if _register_store(later, registers) == reg:
                dead.add(i)
                break
    return tuple(s for i, s in enumerate(block) if i not in dead)
