"""Statement-level clean-up of a POU's statement tree, before the copy propagation of passes.py:

- a store of an accumulator register (HH_LA, HH_WA, ...) or of an error marker of arithmetic and module calls
  (the caller passes both as `registers`) that later stores of the same variable overwrite on every path before
  anything can read it is dropped;
- `IF c THEN x := TRUE; ELSE x := FALSE; END_IF;` becomes `x := c;` (and the swapped form `x := NOT c;`);
- an IF without statements in either branch leaves only its comments;
- consecutive IFs on the same condition become one where the first cannot change the condition (its body only
  assigns, to nothing the condition reads): a HEIDENHAIN S/R sequence on one logic result (`S a`, `R b`, `R c`)
  is one IF with three assignments.

Expressions only read variables (the functions they call are FUNCTIONs, which see no global), so dropping an
IF's condition or a store's value loses no effect. Registers are globals: a subprogram called in between, a
RETURN or EXIT, the end of the enclosing block (a loop's next pass, the caller, the next cycle) may read them, so
a store is dropped only when the overwrite follows in the same block with none of those in between.
"""

from __future__ import annotations

import dataclasses
from typing import Iterable

from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S

Block = tuple[S.Stmt, ...]


def simplify(block: Iterable[S.Stmt], registers: frozenset[str]) -> list[S.Stmt]:
    """`block` with the three simplifications applied; `registers` are the register variables (any case)."""
    registers = frozenset(r.upper() for r in registers)
    return list(_block(tuple(block), registers))


def _block(block: Block, registers: frozenset[str]) -> Block:
    """`block` simplified; `block` itself when nothing in it changes."""
    out: list[S.Stmt] = []
    kept = _without_dead_stores(block, registers)
    changed = kept is not block
    for stmt in kept:
        if type(stmt) not in _NESTING:     # (most statements: no block inside, no IF)
            out.append(stmt)
            continue
        inner_blocks = S.blocks(stmt)
        new = [_block(inner, registers) for inner in inner_blocks]
        if any(n is not inner for n, inner in zip(new, inner_blocks)):
            stmt = S.with_blocks(stmt, new)
            changed = True
        if isinstance(stmt, S.If):
            if not S.has_code(stmt.then) and not S.has_code(stmt.orelse):
                out.extend(stmt.then + stmt.orelse)
                changed = True
                continue
            simpler = _flag_from_condition(stmt)
            changed = changed or simpler is not stmt
            stmt = simpler
            if out and isinstance(stmt, S.If) and isinstance(out[-1], S.If) and _same_condition(out[-1], stmt):
                out[-1] = _joined(out[-1], stmt)
                changed = True
                continue
        out.append(stmt)
    return tuple(out) if changed else block


def _same_condition(first: S.If, second: S.If) -> bool:
    """Whether `second` may join `first`: the same condition, no ELSE, and a first body of assignments only,
    to none of the variables the condition reads (so the condition has the same value for the second)."""
    if first.orelse or second.orelse or first.cond.text != second.cond.text:
        return False
    if not all(isinstance(s, (S.Assign, S.Comment)) for s in first.then):
        return False
    written = {E.target_name(s.target) for s in first.then if isinstance(s, S.Assign)}
    return not written & {d.upper() for d in first.cond.deps} and not written & E.names_of(first.cond)


def _joined(first: S.If, second: S.If) -> S.If:
    """One IF with both bodies; the second's source note moves to its first statement if that has none."""
    then = second.then
    if second.note is not None and second.note != first.note:
        head = then[0]
        if not isinstance(head, (S.Assign, S.Call)) or head.note is not None:
            then = (S.Comment(second.note),) + then
        else:
            then = (dataclasses.replace(head, note=second.note),) + then[1:]
    return dataclasses.replace(first, then=first.then + then, inline=False)


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


def _reads(stmt: S.Stmt) -> set[str] | frozenset[str]:
    """Every variable a statement (nested ones included) may read: its expressions' deps and the names in its
    texts (an index in an assignment's target is read too)."""
    if type(stmt) is S.Assign:      # (most statements: no walk)
        return _assign_reads(stmt)
    found: set[str] = set()
    for s in S.walk((stmt,)):
        exprs: list[E.Expr] = []
        if isinstance(s, S.Assign):
            found |= _assign_reads(s)
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
            found |= e.deps | E.names_of(e)
    return found


def _assign_reads(stmt: S.Assign) -> frozenset[str]:
    found = stmt.value.deps | E.names_of(stmt.value)
    return found | E.names_in(stmt.target.split("[", 1)[1]) if "[" in stmt.target else found


def _leaves_or_calls(stmt: S.Stmt) -> bool:
    """The statement calls an FB (which may read a global) or leaves the block early."""
    kind = type(stmt)
    if kind is S.Assign:
        return False
    if kind is S.Call or kind is S.Return or kind is S.Exit:
        return True
    return any(isinstance(s, (S.Call, S.Return, S.Exit)) for s in S.walk((stmt,)))


def _register_store(stmt: S.Stmt, registers: frozenset[str]) -> str | None:
    if type(stmt) is not S.Assign or stmt.note is not None:
        return None
    name = E.unqualified(stmt.target).upper()
    return name if name in registers else None


def _overwritten(block: Block, reg: str, registers: frozenset[str], start: int = 0) -> bool:
    """Every path through `block[start:]` stores `reg` again before anything could read it: a store, or an IF/ELSE
    whose condition does not read it and whose two branches each overwrite it (a division's zero check sets its
    error marker on both)."""
    for k in range(start, len(block)):
        stmt = block[k]
        if (type(stmt) is S.If and stmt.orelse and reg not in stmt.cond.deps | E.names_of(stmt.cond)
                and _overwritten(stmt.then, reg, registers) and _overwritten(stmt.orelse, reg, registers)):
            return True
        if reg in _reads(stmt) or _leaves_or_calls(stmt):
            return False
        if _register_store(stmt, registers) == reg:
            return True
    return False


def _without_dead_stores(block: Block, registers: frozenset[str]) -> Block:
    # Only a later store can overwrite a register: a store with none after it (nested ones included) is kept
    # without looking at what the statements after it read (most stores of an error marker have none).
    dead = set()
    stored_later: set[str] = set()
    for i in range(len(block) - 1, -1, -1):
        stmt = block[i]
        if type(stmt) is S.Assign:
            # (_register_store, and the register this assignment stores whatever its note)
            name = E.unqualified(stmt.target).upper()
            if name in registers:
                if stmt.note is None and name in stored_later and _overwritten(block, name, registers, i + 1):
                    dead.add(i)
                stored_later.add(name)
        elif type(stmt) in _NESTING:
            stored_later |= _registers_stored(stmt, registers)
    return tuple(s for i, s in enumerate(block) if i not in dead) if dead else block


def _registers_stored(stmt: S.Stmt, registers: frozenset[str]) -> set[str]:
    """The registers the compound statement `stmt` assigns anywhere inside (notes or not): a superset of the stores
    _overwritten can find in it."""
    return {name for s in S.walk((stmt,)) if type(s) is S.Assign
            and (name := E.unqualified(s.target).upper()) in registers}


_NESTING = frozenset({S.If, S.Case, S.While, S.Repeat})
