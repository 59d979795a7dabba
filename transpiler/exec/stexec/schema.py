"""Mutant schemata: many single-place changes of one ST file (mutants) compiled once, each behind a switch on the
runtime's mutant number, so that running a mutant costs no parse and no compilation.

A mutation comes as text, the way mutation analysis defines it (TextMutation: the changed lines). Each is mapped
to the one place of the syntax tree its change lies in, and the changed text of that place is parsed on its own,
at its own line and column (so it parses, and reports positions, exactly as the whole mutated file would):
  * a statement (assignment or call): the code generator compiles the statement once per mutation and selects
    one by the mutant number;
  * an IF, ELSIF, WHILE or UNTIL condition or a CASE selector: one expression per mutation, selected likewise;
  * the first labels of two CASE branches exchanged (each the only label of its branch, neither value matched by
    any other label of the CASE): the selector's two values exchanged before the branches are chosen, which picks
    the same branch as the exchanged labels do.
A mutation that maps to none of these (a declaration's initial value, a FOR bound, two statements on one line)
or whose changed place the checker rejects is `unswitched`: the caller compiles its whole text instead.

Mutant number 0 runs the original program; PROBE runs it too and records, per mutation, whether it is infected:
whether the mutated expression would have computed another value than the original where the original computed
one (an assignment's value, a condition, a selector's value in one of the two exchanged labels), or, where that
cannot be told without running it (a call, a changed assignment target, an expression calling an `impure`
POU), whether its statement ran at all. A mutant never infected in a run runs exactly as the original there."""

from __future__ import annotations

import dataclasses
import re
from typing import Any, Callable, Iterable, Iterator, Optional

from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec.errors import StError
from transpiler.exec.stexec.parser import parse

PROBE = -1                     # the mutant number of a run that records infections instead of running a mutant

_LABEL = re.compile(r"^\s*(\d+)\s*:")


@dataclasses.dataclass(frozen=True)
class TextMutation:
    """One mutant: its number (1, 2, ...: the switch value that selects it) and the lines it changes
    (0-based line index -> the new text of that line)."""

    number: int
    changes: tuple[tuple[int, str], ...]


@dataclasses.dataclass(frozen=True)
class Variant:
    """One mutation at a place of the tree: `node` is the changed statement or expression, or for a CASE the two
    label values exchanged."""

    number: int
    node: object
    swap: Optional[tuple[int, int]] = None


@dataclasses.dataclass
class SchemaPlan:
    """What the code generator switches: id(original node) -> its variants; the mutations left to the caller."""

    variants: dict[int, list[Variant]]
    unswitched: set[int]
    impure: frozenset[str]


@dataclasses.dataclass(frozen=True)
class _Unit:
    node: object
    kind: str                  # "stmt" or "expr"
    line: int
    col: int
    end_line: int
    end_col: int


def _units(body: list[n.Stmt]) -> Iterator[_Unit]:
    """Every statement and condition of a body that a mutation can switch, nested bodies included."""
    for s in body:
        if isinstance(s, (n.Assign, n.CallStmt)):
            yield _unit(s, "stmt")
        elif isinstance(s, n.If):
            for cond, stmts in s.branches:
                yield _unit(cond, "expr")
                yield from _units(stmts)
            yield from _units(s.orelse or [])
        elif isinstance(s, n.Case):
            yield _unit(s.selector, "expr")
            for _labels, stmts in s.elems:
                yield from _units(stmts)
            yield from _units(s.orelse or [])
        elif isinstance(s, n.While):
            yield _unit(s.cond, "expr")
            yield from _units(s.body)
        elif isinstance(s, n.Repeat):
            yield from _units(s.body)
            yield _unit(s.cond, "expr")
        elif isinstance(s, n.For):
            yield _unit(s, "other")          # its bounds are not switched: a mutation there is compiled apart
            yield from _units(s.body)
        else:
            yield _unit(s, "other")


def _unit(node, kind: str) -> _Unit:
    span = node.span
    return _Unit(node, kind, span.line, span.col, span.end_line or span.line, span.end_col or span.col)


def _cases(body: list[n.Stmt]) -> Iterator[n.Case]:
    for s in body:
        if isinstance(s, n.Case):
            yield s
            for _labels, stmts in s.elems:
                yield from _cases(stmts)
            yield from _cases(s.orelse or [])
        elif isinstance(s, n.If):
            for _cond, stmts in s.branches:
                yield from _cases(stmts)
            yield from _cases(s.orelse or [])
        elif isinstance(s, (n.While, n.Repeat, n.For)):
            yield from _cases(s.body)


def plan(tree: n.SourceFile, text: str, mutations: Iterable[TextMutation], impure: Iterable[str] = ()) -> SchemaPlan:
    """Map each mutation to its place in `tree` (the parse of `text`) and parse its changed text there."""
    lines = text.splitlines()
    bodies = [el.body for el in tree.elements if isinstance(el, n.Pou)]
    by_line: dict[int, list[_Unit]] = {}
    for body in bodies:
        for unit in _units(body):
            for line in range(unit.line, unit.end_line + 1):
                by_line.setdefault(line, []).append(unit)
    labels: dict[int, tuple[n.Case, int]] = {}
    for body in bodies:
        for case in _cases(body):
            for arm, (arm_labels, _stmts) in enumerate(case.elems):
                if arm_labels:
                    labels.setdefault(arm_labels[0].span.line, (case, arm))
    out = SchemaPlan({}, set(), frozenset(name.lower() for name in impure))
    for mutation in mutations:
        variant = (_swap(mutation, lines, labels) if len(mutation.changes) == 2
                   else _changed_place(mutation, lines, by_line, tree.filename))
        if variant is None:
            out.unswitched.add(mutation.number)
        else:
            node, found = variant
            out.variants.setdefault(id(node), []).append(found)
    return out


def _changed_place(mutation: TextMutation, lines: list[str], by_line: dict[int, list[_Unit]],
                   filename: str) -> Optional[tuple[object, Variant]]:
    if len(mutation.changes) != 1:
        return None
    index, new = mutation.changes[0]
    line = index + 1
    units = by_line.get(line, [])
    if len(units) != 1 or units[0].kind == "other":
        return None
    unit = units[0]
    if any(u is not unit for at in (unit.line, unit.end_line) for u in by_line.get(at, [])):
        return None                          # another statement shares a line with it
    old = lines[index]
    start, end = unit.col - 1, unit.end_col - 1
    delta = len(new) - len(old)
    if line == unit.line and new[:start] != old[:start]:
        return None
    if line == unit.end_line and old[end:] != new[end + delta:]:
        return None
    changed = list(lines[unit.line - 1:unit.end_line])
    changed[line - unit.line] = new
    changed[-1] = changed[-1][:end + (delta if line == unit.end_line else 0)]
    changed[0] = " " * start + changed[0][start:]
    region = "\n".join(changed)
    if unit.line < 2:
        return None
    head = "\n" * (unit.line - 2)
    try:
        if unit.kind == "stmt":
            parsed = parse(f"{head}PROGRAM p__\n{region}\nEND_PROGRAM\n", filename)
            body = parsed.elements[0].body
            if len(body) != 1:
                return None
            return unit.node, Variant(mutation.number, body[0])
        parsed = parse(f"{head}PROGRAM p__ x__ :=\n{region}; END_PROGRAM\n", filename)
        body = parsed.elements[0].body
        if len(body) != 1:
            return None
        return unit.node, Variant(mutation.number, body[0].value)
    except StError:
        return None


def _swap(mutation: TextMutation, lines: list[str], labels: dict[int, tuple[n.Case, int]]
          ) -> Optional[tuple[object, Variant]]:
    (i1, new1), (i2, new2) = mutation.changes
    first, second = labels.get(i1 + 1), labels.get(i2 + 1)
    if first is None or second is None or first[0] is not second[0]:
        return None
    case = first[0]
    values = []
    for (line_index, new), (_case, arm) in ((mutation.changes[0], first), (mutation.changes[1], second)):
        arm_labels = case.elems[arm][0]
        label = arm_labels[0]
        if len(arm_labels) != 1 or label.enum is not None or label.lo != label.hi:
            return None
        old_m, new_m = _LABEL.match(lines[line_index]), _LABEL.match(new)
        if old_m is None or new_m is None or int(old_m.group(1)) != label.lo:
            return None
        old = lines[line_index]
        if new[new_m.end(1):] != old[old_m.end(1):] or new[:new_m.start(1)] != old[:old_m.start(1)]:
            return None
        values.append((label.lo, int(new_m.group(1))))
    (a, a_new), (b, b_new) = values
    if a_new != b or b_new != a or a == b:
        return None
    matching = sum(1 for arm_labels, _ in case.elems for lab in arm_labels
                   if lab.enum is None and lab.lo is not None and (lab.lo <= a <= lab.hi or lab.lo <= b <= lab.hi))
    if matching != 2:
        return None                          # another label matches one of the values: the exchange is not a remap
    return case, Variant(mutation.number, case, (a, b))


def probe_helpers(infected: set[int]) -> dict[str, Callable]:
    """The functions a PROBE run's switches call: _PX(value, ((number, variant), ...)) records the variants that
    compute another value (or fail) and gives the original value; _PR(numbers, value) records them as reached."""
    add = infected.add

    def px(value: Any, variants: tuple) -> Any:
        for number, variant in variants:
            try:
                if variant() != value:
                    add(number)
            except Exception:  # noqa: BLE001 - a variant that fails where the original does not is infected
                add(number)
        return value

    def pr(numbers: tuple, value: Any) -> Any:
        infected.update(numbers)
        return value
    return {"_PX": px, "_PR": pr}
