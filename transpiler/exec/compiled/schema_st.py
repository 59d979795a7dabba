"""Mutant schemata as ST text, for an executor that compiles the text itself (matiec): one program in which every
mutation is a selection on a global mutant number, so that all mutants cost one build.

The mutations are mapped to their places exactly as the built-in executor's schemata map them
(stexec/schema.py plan): a statement, a condition or CASE selector, or two exchanged CASE labels. Each place
becomes plain IEC 61131-3 that matiec compiles:
  * a statement:  `IF HH_MUTANT = 7 THEN <mutated> ELSIF ... ELSE <original> END_IF;`
  * a condition or selector:  `SEL(HH_MUTANT <> 7, <mutated>, SEL(..., <original>))` (ST has no conditional
    expression; SEL computes every argument, harmless for the pure expressions conditions are: one calling a
    stateful POU is not switched);
  * exchanged labels: the selector's two values exchanged, `SEL(s = a, SEL(s = b, s, a), b)`, which picks the
    branch the exchanged labels pick (plan only accepts labels no other label of the CASE matches).
The global number is 0 for the original. A negative number runs the original and records, in the global array
HH_HIT, each mutant the run infects: for a statement that stores a value, or a condition or selector, whether the
mutated expression gives another value at the place (the condition of an ELSIF is compared on entering its IF,
where the conditions before it are false: what the IF then computes); for any other change (a call, a loop
condition), whether its statement ran.

Every insertion is made on the line of the text it belongs to, so the schema has the original's line numbers
(a tool's message about line N is about the original's line N; the first line gets the array type).
A mutation that cannot be expressed is `unswitched`: the caller builds its own text."""

from __future__ import annotations

import dataclasses
import re
from typing import Iterable, Iterator, Optional, Sequence

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec.errors import StError
from transpiler.exec.stexec.gen_schema import calls_impure
from transpiler.exec.stexec.parser import parse
from transpiler.exec.stexec.schema import TextMutation, Variant, plan

_HEADER = re.compile(r"^\s*(PROGRAM|FUNCTION_BLOCK|CONFIGURATION)\s+\w+", re.IGNORECASE)


@dataclasses.dataclass(frozen=True)
class SchemaNames:
    """The names the schema adds: the mutant number (DINT), the infection flags and their array type."""

    mutant: str
    hits: str
    hits_type: str


@dataclasses.dataclass(frozen=True)
class StSchema:
    """The schema text; `switched` the mutation numbers it holds, `unswitched` the others; `size` the length of
    the flag array (indexed by mutation number, 1..size)."""

    text: str
    switched: frozenset[int]
    unswitched: frozenset[int]
    size: int
    names: SchemaNames


@dataclasses.dataclass
class _Place:
    """A switchable place: the statement or expression, what kind of place it is, the statement to put a probe
    before (for an expression) and its POU."""

    node: object
    kind: str                  # "stmt", "cond" (value probed), "loop" (reached only), "case" (label swaps)
    owner: object
    pou: n.Pou


def _names(text: str) -> SchemaNames:
    """Names not used by the text (the emitted library's HH_ prefix, with a number if ever taken)."""
    used = {w.upper() for w in re.findall(r"\w+", text)}
    suffix = ""
    k = 0
    while {f"HH_MUTANT{suffix}", f"HH_HIT{suffix}", f"HH_HITS{suffix}"} & used:
        k += 1
        suffix = f"_{k}"
    return SchemaNames(f"HH_MUTANT{suffix}", f"HH_HIT{suffix}", f"HH_HITS{suffix}")


def _places(pou: n.Pou) -> Iterator[_Place]:
    def walk(body: list) -> Iterator[_Place]:
        for s in body:
            if isinstance(s, (n.Assign, n.CallStmt)):
                yield _Place(s, "stmt", s, pou)
            elif isinstance(s, n.If):
                for cond, stmts in s.branches:
                    yield _Place(cond, "cond", s, pou)
                    yield from walk(stmts)
                yield from walk(s.orelse or [])
            elif isinstance(s, n.Case):
                yield _Place(s.selector, "cond", s, pou)
                yield _Place(s, "case", s, pou)
                for _labels, stmts in s.elems:
                    yield from walk(stmts)
                yield from walk(s.orelse or [])
            elif isinstance(s, (n.While, n.Repeat)):
                yield _Place(s.cond, "loop", s, pou)
                yield from walk(s.body)
            elif isinstance(s, n.For):
                yield from walk(s.body)
    yield from walk(pou.body)


def _slice(lines: Sequence[str], span: Span) -> str:
    """The text a span covers, on one line (ST is free-form; a comment or string never spans a joined line)."""
    end_line = span.end_line or span.line
    if end_line == span.line:
        return lines[span.line - 1][span.col - 1:span.end_col - 1]
    parts = [lines[span.line - 1][span.col - 1:]] + list(lines[span.line:end_line - 1]) + \
        [lines[end_line - 1][:span.end_col - 1]]
    return " ".join(part.strip() for part in parts)


class _Edits:
    """Insertions into the original text at (line, column); at one position, ends of earlier text come before
    starts of later text."""

    def __init__(self) -> None:
        self.items: list[tuple[int, int, int, int, str]] = []

    def before(self, span: Span, text: str) -> None:
        self.items.append((span.line, span.col, 1, len(self.items), text))

    def after(self, span: Span, text: str) -> None:
        self.items.append((span.end_line or span.line, span.end_col, 0, -len(self.items), text))

    def at(self, line: int, col: int, text: str) -> None:
        self.items.append((line, col, 1, len(self.items), text))

    def apply(self, text: str) -> str:
        lines = text.split("\n")
        by_line: dict[int, list] = {}
        for item in self.items:
            by_line.setdefault(item[0], []).append(item)
        for line, items in by_line.items():
            old = lines[line - 1]
            out, last = [], 0
            for _line, col, _order, _seq, insert in sorted(items, key=lambda i: (i[1], i[2], i[3])):
                out.append(old[last:col - 1])
                out.append(insert)
                last = col - 1
            out.append(old[last:])
            lines[line - 1] = "".join(out)
        return "\n".join(lines)


def build_schema(st_text: str, mutations: Iterable[TextMutation], filename: str = "project.st",
                 leave_out: Iterable[int] = (), impure: Iterable[str] = ()) -> StSchema:
    """The schema text of `mutations` over `st_text` (leaving out the numbers in `leave_out`); `impure` names the
    POUs a condition must not call twice. Raises StError when `st_text` does not parse."""
    mutations = list(mutations)
    numbers = {m.number for m in mutations}
    tree = parse(st_text, filename)
    found = plan(tree, st_text, mutations, impure)
    writer = _Writer(st_text, mutations, found.impure)
    skipped = set(found.unswitched) | (set(leave_out) & numbers)
    headers: dict[int, int] = {}           # id(POU) -> the column after its name, where its externals go
    for el in tree.elements:
        if isinstance(el, n.Pou) and el.kind != "function":     # a FUNCTION cannot have a VAR_EXTERNAL
            m = _HEADER.match(writer.lines[el.span.line - 1])
            if m is not None:
                headers[id(el)] = m.end() + 1
    configuration = next((el for el in tree.elements if isinstance(el, n.Configuration)), None)
    header = _HEADER.match(writer.lines[configuration.span.line - 1]) if configuration is not None else None
    if header is None:
        return StSchema(st_text, frozenset(), frozenset(numbers), 1, writer.names)
    for el in tree.elements:
        if not isinstance(el, n.Pou):
            continue
        used = False
        for place in _places(el):
            variants = [v for v in found.variants.get(id(place.node), []) if v.number not in skipped
                        and (place.kind != "case" or v.swap is not None)]
            if not variants:
                continue
            if id(el) not in headers or not writer.switch(place, variants):
                skipped.update(v.number for v in variants)
                continue
            used = True
        if used:
            writer.edits.at(el.span.line, headers[id(el)], f" VAR_EXTERNAL {writer.declarations} END_VAR")
    size = max(numbers, default=0) or 1
    writer.edits.at(configuration.span.line, header.end() + 1, f" VAR_GLOBAL {writer.declarations} END_VAR")
    writer.edits.at(1, 1, f"TYPE {writer.names.hits_type} : ARRAY [1..{size}] OF BOOL; END_TYPE ")
    return StSchema(writer.text(), frozenset(writer.switched), frozenset(numbers - writer.switched), size,
                    writer.names)


class _Writer:
    """The switches and probes of one schema, as insertions into the original text."""

    def __init__(self, st_text: str, mutations: Sequence[TextMutation], impure: frozenset[str]):
        self.lines = st_text.split("\n")
        self.names = _names(st_text)
        self.declarations = f"{self.names.mutant} : DINT; {self.names.hits} : {self.names.hits_type};"
        self.impure = impure
        self.edits = _Edits()
        self.switched: set[int] = set()
        self.by_number = {m.number: m for m in mutations}
        self.mutated: dict[int, list[str]] = {}
        self.probes: dict[int, tuple[object, list[str]]] = {}    # id(statement) -> (statement, probes before it)

    def text(self) -> str:
        mutant = self.names.mutant
        for owner, statements in self.probes.values():
            self.edits.before(owner.span, f"IF {mutant} < 0 THEN {' '.join(statements)} END_IF; ")
        return self.edits.apply("\n".join(self.lines))

    def variant_text(self, v: Variant, node: object) -> str:
        """The text of `node`, a part of the parse of mutation v's text."""
        if v.number not in self.mutated:
            copy = list(self.lines)
            for index, new in self.by_number[v.number].changes:
                copy[index] = new
            self.mutated[v.number] = copy
        return _slice(self.mutated[v.number], node.span)

    def probe(self, owner: object, number: int, condition: str | None = None, unless: Sequence[str] = ()) -> None:
        """Before `owner` in a probing run: mark mutant `number` (where `condition` holds, and only where none of
        the conditions `unless` holds: an ELSIF's condition is computed only where its IF would compute it)."""
        statement = f"{self.names.hits}[{number}] := TRUE;"
        if condition is not None:
            statement = f"IF {condition} THEN {statement} END_IF;"
        for earlier in reversed(unless):
            statement = f"IF NOT ({earlier}) THEN {statement} END_IF;"
        self.probes.setdefault(id(owner), (owner, []))[1].append(statement)

    def switch(self, place: _Place, variants: list[Variant]) -> bool:
        """Write the switch of a place; False (nothing written) where an expression calls a stateful POU, which
        every mutant's SEL would call."""
        if place.kind != "stmt":
            expression = place.node.selector if place.kind == "case" else place.node
            if calls_impure(expression, self.impure) or any(calls_impure(v.node, self.impure)
                                                             for v in variants if v.swap is None):
                return False
        self.switched.update(v.number for v in variants)
        if place.kind == "stmt":
            self.statement(place.node, variants)
        elif place.kind == "case":
            self.swaps(place.node, variants)
        else:
            self.expression(place, variants)
        return True

    def statement(self, s: n.Stmt, variants: list[Variant]) -> None:
        """`IF mutant = k THEN <variant k> ELSIF ... ELSE <probes> <original> END_IF;` around the statement; a
        variant that stores another value into the same target is probed by comparing the values."""
        mutant = self.names.mutant
        head = " ELSIF ".join(f"{mutant} = {v.number} THEN {self.variant_text(v, v.node)}" for v in variants)
        valued = isinstance(s, n.Assign) and not calls_impure(s, self.impure)
        probes = []
        for v in variants:
            mark = f"{self.names.hits}[{v.number}] := TRUE;"
            if valued and isinstance(v.node, n.Assign) and v.node.target == s.target \
                    and not calls_impure(v.node, self.impure):
                probes.append(f"IF ({self.variant_text(v, v.node.value)}) <> ({_slice(self.lines, s.value.span)}) "
                              f"THEN {mark} END_IF;")
            else:
                probes.append(mark)
        # the original keeps its own place (and lines), after the ELSE
        self.edits.before(s.span, f"IF {head} ELSE IF {mutant} < 0 THEN {' '.join(probes)} END_IF; ")
        self.edits.after(s.span, " END_IF;")

    def swaps(self, case: n.Case, variants: list[Variant]) -> None:
        """The selector's two values exchanged for each swap of two labels."""
        selector = _slice(self.lines, case.selector.span)
        chain = ""
        for v in variants:
            a, b = v.swap
            chain += f"SEL({self.names.mutant} <> {v.number}, SEL(({selector}) = {a}, SEL(({selector}) = {b}, " \
                     f"{selector}, {a}), {b}), "
            self.probe(case, v.number, f"(({selector}) = {a}) OR (({selector}) = {b})")
        self.edits.before(case.selector.span, chain)
        self.edits.after(case.selector.span, ")" * len(variants))

    def expression(self, place: _Place, variants: list[Variant]) -> None:
        """A condition or selector chosen by SEL; probed by value before its statement, a loop's by running."""
        original = _slice(self.lines, place.node.span)
        unless: list[str] = []
        if isinstance(place.owner, n.If):
            for cond, _stmts in place.owner.branches:
                if cond is place.node:
                    break
                unless.append(_slice(self.lines, cond.span))
        chain = ""
        for v in variants:
            text = self.variant_text(v, v.node)
            chain += f"SEL({self.names.mutant} <> {v.number}, {text}, "
            self.probe(place.owner, v.number, f"({text}) <> ({original})" if place.kind == "cond" else None, unless)
        self.edits.before(place.node.span, chain)
        self.edits.after(place.node.span, ")" * len(variants))


def checked_schema(st_text: str, mutations: Sequence[TextMutation], filename: str = "project.st",
                   leave_out: Iterable[int] = (), impure: Iterable[str] = (), mends: int = 3) -> StSchema:
    """build_schema, then the built-in executor's checker (as strict as matiec) on the result: the mutations on
    the lines it rejects are left out and the schema built again, up to `mends` times; a schema that still fails
    (or fails at a line holding no mutation) is given up for one holding none."""
    from transpiler.exec.stexec import load_st
    left_out = set(leave_out)
    for _ in range(mends + 1):
        schema = build_schema(st_text, mutations, filename, left_out, impure)
        try:
            load_st(schema.text, filename)
            return schema
        except StError as exc:
            more = leave_out_at(schema, st_text, mutations, {d.span.line for d in exc.diagnostics}, filename)
            if not more:
                break
            left_out |= more
    return dataclasses.replace(build_schema(st_text, [], filename),
                               unswitched=frozenset(m.number for m in mutations))


def leave_out_at(schema: StSchema, st_text: str, mutations: Sequence[TextMutation], bad_lines: Iterable[int],
                 filename: str = "project.st") -> Optional[set[int]]:
    """The mutations whose places lie on `bad_lines` (lines a tool rejected in the schema), or None when a bad
    line holds none of them (the schema cannot be mended by leaving mutations out)."""
    try:
        tree = parse(st_text, filename)
    except StError:
        return None
    found = plan(tree, st_text, [m for m in mutations if m.number in schema.switched])
    owners: dict[int, tuple[int, int]] = {}
    for el in tree.elements:
        if isinstance(el, n.Pou):
            for place in _places(el):
                span = place.node.span
                lines = (min(span.line, place.owner.span.line), span.end_line or span.line)
                for v in found.variants.get(id(place.node), []):
                    owners[v.number] = lines
    out: set[int] = set()
    for line in bad_lines:
        hits = {k for k, (lo, hi) in owners.items() if lo <= line <= hi}
        if not hits:
            return None
        out |= hits
    return out
