"""Clean-up of a POU's statement tree before printing: a temporary written once and read once, by the very next
statement, is replaced by its value (copy propagation).

The symbolic executor already folds constants and simplifies boolean expressions while it builds them
(exprs.py). A temporary is propagated only where the next statement evaluates the read before anything it does
itself: an assignment's right side (or the index of its target), an IF or CASE condition, the inputs of an FB
call. So the value cannot have changed in between. Loop conditions are evaluated again on every pass and stay
named. An FB's output passed to the next call of that FB stays named too: the call reads the old value. So does a
temporary a bit of which is read with bit access (`tmp1.3`): `(a + b).3` would be no ST.
"""

from __future__ import annotations

import dataclasses
import re

from transpiler.backends.iec_model import Pou
from transpiler.backends.st import exprs as E
from transpiler.backends.st import printer
from transpiler.backends.st import stmt as S
from transpiler.backends.st.names import TEMP_PREFIX

_TEMP = re.compile(TEMP_PREFIX + r"[0-9]+")


def _word(name: str) -> re.Pattern[str]:
    """`name` as a variable in expression text (a member `fb.name` is another variable)."""
    return re.compile(r"(?<![A-Za-z0-9_.])" + re.escape(name) + r"(?![A-Za-z0-9_])", re.I)


def _bit_read(name: str) -> re.Pattern[str]:
    """`name` with a bit of it read (`tmp1.3`)."""
    return re.compile(r"(?<![A-Za-z0-9_.])" + re.escape(name) + r"\.", re.I)


def _atomic(text: str) -> bool:
    """No operator at the top level: the text can replace a name without parentheses."""
    depth = 0
    for ch in text:
        depth += ch in "(["
        depth -= ch in ")]"
        if depth == 0 and ch == " ":
            return False
    return True


def _texts(stmt: S.Stmt) -> list[str]:
    """The expression and lvalue texts a statement itself holds (not those of nested blocks), in printed order."""
    if isinstance(stmt, S.Assign):
        return [stmt.target, stmt.value.text]
    if isinstance(stmt, S.Call):
        return [stmt.callee] + [value.text for _, value in stmt.args]
    if isinstance(stmt, S.If):
        return [stmt.cond.text]
    if isinstance(stmt, S.Case):
        return [stmt.selector.text]
    if isinstance(stmt, S.While):
        return [stmt.cond.text]
    if isinstance(stmt, S.Repeat):
        return [stmt.until.text]
    return []


def _parts(stmt: S.Stmt) -> list[str | E.Expr]:
    """What `_texts` reads, with the expressions as expressions (their names known without reading the text)."""
    if isinstance(stmt, S.Assign):
        return [stmt.target, stmt.value]
    if isinstance(stmt, S.Call):
        return [stmt.callee] + [value for _, value in stmt.args]
    if isinstance(stmt, S.If):
        return [stmt.cond]
    if isinstance(stmt, S.Case):
        return [stmt.selector]
    if isinstance(stmt, S.While):
        return [stmt.cond]
    if isinstance(stmt, S.Repeat):
        return [stmt.until]
    return []


def _uses(block: list[S.Stmt] | tuple[S.Stmt, ...], word: re.Pattern[str], name: str) -> int:
    """How often `word` (built from the temporary `name`) occurs; an expression whose names lack it is not read."""
    upper = name.upper()
    count = 0
    for stmt in S.walk(block):
        for part in _parts(stmt):
            if isinstance(part, str):
                count += len(word.findall(part))
            elif upper in E.names_of(part):
                count += len(word.findall(part.text))
    return count


class _Substitution:
    """The first occurrence of a temporary, in printed order, replaced by its value (each use is one call)."""

    def __init__(self, word: re.Pattern[str], value: E.Expr):
        self.word = word
        self.value = value
        self.text = value.text if _atomic(value.text) else f"({value.text})"
        self.done = False

    def in_text(self, text: str) -> str:
        if self.done or not self.word.search(text):
            return text
        self.done = True
        return self.word.sub(lambda _: self.text, text, count=1)

    def in_expr(self, expr: E.Expr) -> E.Expr:
        if self.done or not self.word.search(expr.text):
            return expr
        self.done = True
        if self.word.fullmatch(expr.text):
            return self.value if self.text == self.value.text else E.Expr(
                self.text, self.value.typ, self.value.deps, self.value.lo, self.value.hi)
        name = self.word.search(expr.text).group(0).upper()
        return dataclasses.replace(expr, text=self.word.sub(lambda _: self.text, expr.text, count=1),
                                   deps=(expr.deps - {name}) | self.value.deps, var=None, const=None,
                                   bool_const=None, parts=None, names=None)

    def in_statement(self, stmt: S.Stmt) -> S.Stmt:
        if isinstance(stmt, S.Assign):
            target = self.in_text(stmt.target)
            return dataclasses.replace(stmt, target=target, value=self.in_expr(stmt.value))
        if isinstance(stmt, S.Call):
            return dataclasses.replace(stmt, args=tuple((name, self.in_expr(value)) for name, value in stmt.args))
        if isinstance(stmt, S.If):
            cond = self.in_expr(stmt.cond)
            then = tuple(self.in_statement(s) for s in stmt.then) if stmt.inline else stmt.then
            return dataclasses.replace(stmt, cond=cond, then=then)
        if isinstance(stmt, S.Case):
            return dataclasses.replace(stmt, selector=self.in_expr(stmt.selector))
        return stmt


def _reads_first(stmt: S.Stmt, word: re.Pattern[str], value: E.Expr) -> bool:
    """`stmt` reads the temporary before it does anything else (see the module docstring)."""
    if isinstance(stmt, S.Assign):
        if word.search(stmt.target):
            return "(" in stmt.target     # read in a call inside the target's index; else the target is written
        return bool(word.search(stmt.value.text))
    if isinstance(stmt, S.Call):
        if E.base_name(stmt.callee) == E.base_name(value.text):
            return False
        return any(word.search(v.text) for _, v in stmt.args)
    if isinstance(stmt, S.If) and stmt.inline:
        return any(word.search(text) for text in [stmt.cond.text] + [t for s in stmt.then for t in _texts(s)])
    if isinstance(stmt, (S.If, S.Case)):
        return bool(word.search(_texts(stmt)[0]))
    return False


def _propagate_one(root: list[S.Stmt]) -> tuple[list[S.Stmt], str] | None:
    """The tree with the first temporary (in printed order) that qualifies propagated, and its name; None when
    no temporary does."""
    return _propagate_in(root, root)


def _propagate_in(root: list[S.Stmt], block: tuple[S.Stmt, ...] | list[S.Stmt]) -> tuple[list[S.Stmt], str] | None:
    """_propagate_one within `block`, a block of `root`. (A function of its own, not a closure: a closure that calls
    itself is a reference cycle, which kept each POU's statements alive until the process exited.)"""
    for i, stmt in enumerate(block):
        if type(stmt) is S.Assign:
            if stmt.note is not None or not stmt.target.startswith(TEMP_PREFIX) or not _TEMP.fullmatch(stmt.target):
                continue        # (most statements: an assignment of no temporary, nothing nested)
            word = _word(stmt.target)
            j = next((k for k in range(i + 1, len(block)) if S.is_code(block[k])), None)
            if j is not None and _uses(root, word, stmt.target) == 2 \
                    and not _uses(root, _bit_read(stmt.target), stmt.target) \
                    and _reads_first(block[j], word, stmt.value):
                new = list(block)
                new[j] = _Substitution(word, stmt.value).in_statement(block[j])
                del new[i]
                return new, stmt.target
        nested_blocks = S.blocks(stmt)
        if not nested_blocks:
            continue
        inner = list(nested_blocks)
        for k, nested in enumerate(inner):
            found = _propagate_in(root, nested)
            if found is not None:
                inner[k] = tuple(found[0])
                return [*block[:i], S.with_blocks(stmt, inner), *block[i + 1:]], found[1]
    return None


def propagate_temporaries(pou: Pou) -> Pou:
    """`pou` with every temporary that is read once, by the next statement, replaced by its value."""
    statements = list(pou.statements)
    removed: set[str] = set()
    while (found := _propagate_one(statements)) is not None:
        statements, name = found
        removed.add(name.upper())
    if not removed:
        return pou
    sections = tuple(dataclasses.replace(s, vars=tuple(v for v in s.vars if v.name.upper() not in removed))
                     if s.kind == "VAR" else s for s in pou.sections)
    sections = tuple(s for s in sections if s.vars or s.kind != "VAR")
    if not sections and pou.kind == "FUNCTION_BLOCK":
        return pou          # matiec rejects a FUNCTION_BLOCK without any declaration
    return printer.with_statements(dataclasses.replace(pou, sections=sections), statements)
