"""Differences between two words (or a word and the index register X, or a word and the constant 0) that hold at a
compare, so that a boundary value no run can give is explained as infeasible instead of counted as missing. Two
cases it is made for:

- the counting loop: `L K0` `= W6` ... `L W6` `< W30` `WHILET` `L W6` `+ K1` `= W6` `L W6` `< W30` `ENDW`: the body
  runs only with W6 < W30 and adds 1, so at the test at its end W6 - W30 is at most 0, never +1;
- the count kept beside X: `L K0` `= X` `= W6`, a loop over X (`INCX` `L X` `< K8` `JPT`) whose body INCs W6 at
  most once per pass: W6 - X stays at most 0 (set together, an INC raises the bound by 1, INCX lowers it by 1), so
  after the loop W6 is at most X's bound there (8) and at least 0, and a compare of W6 with a constant never sees
  -1.

A forward dataflow over each file's ops, from every entry (a file's start, a subprogram, a CASE entry, a submitted
job) with nothing known, keeps facts `A - B <= k` between cells: named words (bytes, words, double words; values as
loaded), X and the constant 0 (so `A - 0 <= k` bounds A). It learns them:
- where a conditional jump goes on a compare of two words of one kind, of a word or X with a constant (`L A` `< B`
  `JPT`/`JPF`, `L X` `< K8` `JPT`, WHILE and UNTIL included: on the way taken where `A < B` is 1, A - B <= -1, and
  so on);
- at a store of a constant that the cell holds exactly (`L K0` `= X` `= W6`: each equals 0, and so W6 - X = 0),
  and at a store of a cell's value into another of a width that holds it exactly (`L X` `= W8`: W8 = X, with what
  was known of X);
(and, through a marker assigned from such a compare, `L W6` `> K0` `= M50` ... `L M50` `IFT`, where the marker is
read before it or the compared cells are written again) and keeps them over a step of one cell by a constant (`L A` `+ K1` `= A`, +/- of constants and INCW/DECW on the
way; INC and DEC of a word; INCX and DECX) where the bounds the facts give it (with X's interval from index_range
and each cell's type range) show the step cannot wrap: a fact about the cell moves with it (A - B <= k becomes
k + d). Beside the facts it keeps implications between bounds by 0 (`W6 >= 1 => W8 >= 0`): formed where two ways join
and one has the first bound with the second while the other denies the first (the IFT that INCs the count and sets
the word, joined with the way that does neither, at whose start the implication held or the count was 0), kept at
a join where each way has it, has the second bound or denies the first, carried over a copy of one of the words,
applied where a jump learns the first bound, dropped at any write of either word. Anything else that writes a cell
drops every fact about it (a store of another value, a pull, a store of
another width over its bytes, PLX, a store into X of a value not followed); a call, a CASE, a job submission, a PLC
module or a store through the index register drops every fact. Paths join keeping the facts both have (the weaker
bound); a bound still moving after a few visits is dropped. Nothing is carried from one run of the code to the
next: facts start empty at every entry, so what a scenario, the NC or a data table writes between cycles does not
matter.

Sound, not complete; with unsigned compares (A-13), zero-extended loads or the shared accumulator (A-05) it claims
nothing."""

from __future__ import annotations

import dataclasses
from typing import Mapping

from transpiler.exec.interp.gen_exprs import int32
from transpiler.frontend.opcodes import implicit_writes
from transpiler.ir import BYTES, Op, Program
from transpiler.verify.index_range import entry_points, index_ranges

Cell = tuple[str, int]              # (kind, byte address) of a named B/W/D operand; X_CELL; ZERO
Facts = Mapping[tuple[Cell, Cell], int]     # (A, B) -> k: load(A) - load(B) <= k

X_CELL: Cell = ("X", 0)             # the index register
ZERO: Cell = ("K", 0)               # the constant 0: A - ZERO <= k bounds A from above
_BITS = {"B": 8, "W": 16, "D": 32}
_INT32 = (-(1 << 31), (1 << 31) - 1)
_WIDEN_AFTER = 4                    # visits of an op before bounds that keep moving are dropped
_MAX_STEP = 1 << 16                 # constants added to WA on the way from a load to a store, at most (no 32-bit wrap)
_MEM_WRITERS = frozenset({"WST", "INC", "DEC", "POP"})
_BARRIERS = frozenset({"CALL", "CALLT", "CALLF", "CASE", "SUBM", "KFIELD"})
_BIT_WRITERS = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN", "POP", "INC", "DEC", "STBITS"})
# ops after which WA is what it was (the logic ones: not under the shared accumulator, where no claim is made)
_KEEP_WA = frozenset({"WST", "NOP", "LBL", "JP", "JPT", "JPF", "CMP", "LD", "LDN", "AND", "ANDN", "OR", "ORN",
                      "XOR", "XORN", "ST", "STN", "SET", "RES", "SETN", "RESN", "NOTL"})
# the facts a compare's outcome gives: rel -> ((facts where it is 1), (facts where it is 0)), each (A-first, k)
# with A-first True for load(A) - load(B) <= k, False for load(B) - load(A) <= k
_LEARNED = {"<": (((True, -1),), ((False, 0),)), "<=": (((True, 0),), ((False, -1),)),
            ">": (((False, -1),), ((True, 0),)), ">=": (((False, 0),), ((True, -1),)),
            "==": (((True, 0), (False, 0)), ()), "<>": ((), ((True, 0), (False, 0)))}


Atom = tuple[tuple[Cell, Cell], int]    # ((A, B), k): load(A) - load(B) <= k
Compared = tuple[Cell, Cell, str, int]  # (A, B, rel, c): load(A) rel load(B) + c
_NEGATED = {"<": ">=", ">=": "<", ">": "<=", "<=": ">", "==": "<>", "<>": "=="}


@dataclasses.dataclass(frozen=True)
class _State:
    facts: Facts
    wa: tuple[Cell, int] | None         # WA = load(cell) + d (ZERO: WA = d)
    la: Compared | None                 # LA is that compare, neither cell written since
    implied: frozenset = frozenset()    # (P, Q) atoms: where P holds, Q holds (both bounds of a cell by 0)
    marks: frozenset = frozenset()      # (marker, Compared, same): the marker is the compare's result (same) or
                                        # its negation, neither the marker nor the cells written since


def _entails(facts: Facts, atom: Atom) -> bool:
    pair, k = atom
    return pair in facts and facts[pair] <= k


def _negation(atom: Atom) -> Atom:
    """A - B <= k is false exactly where B - A <= -k - 1."""
    (a, b), k = atom
    return (b, a), -k - 1


def _holds(s: _State, rule: tuple[Atom, Atom]) -> bool:
    p, q = rule
    return rule in s.implied or _entails(s.facts, q) or _entails(s.facts, _negation(p))


def _join(a: _State, b: _State) -> _State:
    facts = {pair: max(k, b.facts[pair]) for pair, k in a.facts.items() if pair in b.facts}
    implied = {rule for rule in a.implied | b.implied if _holds(a, rule) and _holds(b, rule)}
    # a bound by 0 one side has and the other's facts deny: where it holds, what that side knows holds too
    for one, other in ((a, b), (b, a)):
        bounds = [(pair, k) for pair, k in one.facts.items() if ZERO in pair]
        for p in bounds:
            if not _entails(other.facts, _negation(p)):
                continue
            implied.update((p, q) for q in bounds if q[0] != p[0] and not _entails(facts, q))
    marks = a.marks & b.marks
    return _State(facts, a.wa if a.wa == b.wa else None, a.la if a.la == b.la else None, frozenset(implied), marks)


class _Analysis:
    def __init__(self, program: Program, f: int, entries: set[int], xs: Mapping[tuple[int, int], tuple[int, int]]):
        self.f = f
        self.ops = program.files[f].ops
        self.entries = entries
        self.xs = xs
        self.interface = program.semantics.profile.interface
        self.flag = program.semantics["add_overflow"] == "flag"
        bits = 16 if int(program.semantics["index_register_width"]) == 16 else 32
        self.x_full = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)

    def cell(self, op: Op) -> Cell | None:
        o = op.operand
        if o is None or o.kind not in _BITS or o.indexed:
            return None
        return (o.kind, o.addr)

    def run(self) -> dict[int, _State]:
        before: dict[int, _State] = {i: _State({}, None, None) for i in self.entries if 0 <= i < len(self.ops)}
        visits: dict[int, int] = {}
        pending = set(before)
        while pending:
            i = min(pending)
            pending.discard(i)
            for j, state in self.successors(i, before[i]):
                if state is None or not 0 <= j < len(self.ops):
                    continue
                old = before.get(j)
                new = state if old is None else _join(old, state)
                if old is not None and new == old:
                    continue
                visits[j] = visits.get(j, 0) + 1
                if old is not None and visits[j] > _WIDEN_AFTER:
                    new = dataclasses.replace(new, facts={p: k for p, k in new.facts.items() if old.facts.get(p) == k},
                                              implied=new.implied & old.implied)
                before[j] = new
                pending.add(j)
        return before

    def successors(self, i: int, s: _State) -> list[tuple[int, _State | None]]:
        op = self.ops[i]
        c = op.code
        if c in ("EM",):
            return []
        if c == "JP":
            return [(op.target, s)]
        if c in ("JPT", "JPF", "EMT", "EMF"):
            on_true, on_false = self.learn(s, True), self.learn(s, False)
            go, stay = (on_true, on_false) if c in ("JPT", "EMT") else (on_false, on_true)
            if c in ("EMT", "EMF"):
                return [(i + 1, stay)]
            return [(op.target, go), (i + 1, stay)]
        return [(i + 1, self.step(i, op, s))]

    def learn(self, s: _State, outcome: bool) -> _State:
        """`s` on the way where LA is `outcome`, with what the compare LA holds says then."""
        if s.la is None:
            return s
        a, b, rel, shift = s.la
        facts = dict(s.facts)
        for a_first, k in _LEARNED[rel][0 if outcome else 1]:
            # load(A) - load(B) - shift rel 0: A - B <= k + shift, B - A <= k - shift
            pair, bound = ((a, b), k + shift) if a_first else ((b, a), k - shift)
            facts[pair] = min(bound, facts.get(pair, bound))
        for _ in range(2):
            for p, (pair, k) in s.implied:
                if _entails(facts, p):
                    facts[pair] = min(k, facts.get(pair, k))
        return dataclasses.replace(s, facts=facts)

    # ------------------------------------------------------------------------------------------- bounds

    def range_of(self, cell: Cell) -> tuple[int, int]:
        """The values the cell's type can hold (as loaded, sign-extended)."""
        if cell == ZERO:
            return (0, 0)
        if cell == X_CELL:
            return self.x_full
        bits = _BITS[cell[0]]
        return (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)

    def direct(self, i: int, facts: Facts, cell: Cell) -> tuple[int, int]:
        """The bounds of `cell` before op i from its type, X's interval (index_range) and its facts with 0."""
        lo, hi = self.range_of(cell)
        if cell == X_CELL and (self.f, i) in self.xs:
            x = self.xs[(self.f, i)]
            lo, hi = max(lo, x[0]), min(hi, x[1])
        if cell != ZERO:
            if (cell, ZERO) in facts:
                hi = min(hi, facts[(cell, ZERO)])
            if (ZERO, cell) in facts:
                lo = max(lo, -facts[(ZERO, cell)])
        return lo, hi

    def bounds(self, i: int, facts: Facts, cell: Cell) -> tuple[int, int]:
        """The bounds of `cell` before op i: its direct bounds, narrowed by each fact with another cell and that
        cell's direct bounds (A - B <= k: A is at most k + B's largest value)."""
        lo, hi = self.direct(i, facts, cell)
        for (a, b), k in facts.items():
            if a == cell and b != ZERO:
                hi = min(hi, k + self.direct(i, facts, b)[1])
            elif b == cell and a != ZERO:
                lo = max(lo, self.direct(i, facts, a)[0] - k)
        return lo, hi

    # ------------------------------------------------------------------------------------------- one op

    def step(self, i: int, op: Op, s: _State) -> _State:
        """The state after op i: facts, WA and LA (facts_step), the implications and marker facts that survive it."""
        after = self.facts_step(i, op, s)
        c = op.code
        o = op.operand
        if c in _BARRIERS or (op.call is not None and op.call.is_module) or o is not None and o.indexed and \
                c in _MEM_WRITERS and not o.is_bit:
            return dataclasses.replace(after, implied=frozenset(), marks=frozenset())
        if o is not None and o.indexed and c in _BIT_WRITERS and o.is_bit:
            # a bit written through X: any marker of its kind may be the one
            return dataclasses.replace(after, implied=s.implied, marks=frozenset(m for m in s.marks
                                                                                 if m[0][0] != o.kind))
        written: set[Cell] = set()
        if c in ("INCX", "DECX", "PLX") or c in _MEM_WRITERS and o is not None and o.kind == "X":
            written.add(X_CELL)
        elif c in _MEM_WRITERS and o is not None and o.kind in _BITS:
            written.add((o.kind, o.addr))
        implied = {rule for rule in s.implied
                   if not any(self.touches(cell, w) for w in written for atom in rule for cell in atom[0])}
        if c == "WST" and s.wa is not None and written and s.wa[0] != next(iter(written)) and \
                after.facts.get((next(iter(written)), s.wa[0])) == s.wa[1]:
            # a copy the facts follow (copied): what held of the source holds of the copy
            implied |= {self.substituted(rule, s.wa[0], next(iter(written)), s.wa[1]) for rule in implied
                        if any(s.wa[0] in atom[0] for atom in rule)}
        bits = set(implicit_writes(op, self.interface, self.flag))
        if c in _BIT_WRITERS and o is not None and o.is_bit:
            width = max(op.nbits, 1) if c == "STBITS" else 1
            bits |= {(o.kind, a) for a in range(o.addr, o.addr + width)}
        marks = {m for m in s.marks if m[0] not in bits and not any(self.touches(cell, w) for w in written
                                                                      for cell in m[1][:2])}
        if c in ("ST", "STN") and o is not None and o.kind == "M" and not o.indexed and s.la is not None:
            marks.add(((o.kind, o.addr), s.la, c == "ST"))
        la = after.la
        if c in ("LD", "LDN") and o is not None and not o.indexed:
            for marker, compared, same in marks:
                if marker == (o.kind, o.addr):
                    a, b, rel, k = compared
                    la = compared if same == (c == "LD") else (a, b, _NEGATED[rel], k)
        return dataclasses.replace(after, la=la, implied=frozenset(implied), marks=frozenset(marks))

    @staticmethod
    def substituted(rule: tuple[Atom, Atom], source: Cell, cell: Cell, d: int) -> tuple[Atom, Atom]:
        """`rule` about `cell` = load(source) + d instead of source."""
        def atom(one: Atom) -> Atom:
            (a, b), k = one
            if a == source:
                return (cell, b), k + d
            if b == source:
                return (a, cell), k - d
            return one
        return atom(rule[0]), atom(rule[1])

    def facts_step(self, i: int, op: Op, s: _State) -> _State:
        c = op.code
        o = op.operand
        if c in _BARRIERS or (op.call is not None and op.call.is_module):
            return _State({}, None, None)
        facts = s.facts
        wa = s.wa if c in _KEEP_WA else None
        la = s.la if c in ("NOP", "JP") or c in ("ST", "STN", "SET", "RES", "SETN", "RESN") else None
        if c in ("INCX", "DECX"):
            kept = self.stepped(i, facts, X_CELL, 1 if c == "INCX" else -1)
            return _State(self.forget(facts, X_CELL) if kept is None else kept, None, None)
        if c == "PLX":
            return _State(self.forget(facts, X_CELL), None, None)
        if c in _MEM_WRITERS and o is not None and (o.kind in _BITS or o.kind == "X"):
            if o.indexed:
                # the store may hit the cell WA was loaded from: WA then no longer equals it
                return _State({}, wa if wa is not None and wa[0] == ZERO else None, None)
            cell = X_CELL if o.kind == "X" else (o.kind, o.addr)
            if c in ("INC", "DEC"):
                kept = self.stepped(i, facts, cell, 1 if c == "INC" else -1)
                return _State(self.forget(facts, cell) if kept is None else kept, None, None)
            if c == "WST" and s.wa is not None:
                if s.wa[0] == cell:
                    kept = self.stepped(i, facts, cell, s.wa[1])
                    if kept is not None:
                        # WA is the value stored, and the cell holds it unwrapped
                        return _State(kept, (cell, 0), la)
                else:
                    copied = self.copied(i, facts, cell, s.wa)
                    if copied is not None:
                        return _State(copied, s.wa, la)
            if wa is not None and self.touches(wa[0], cell):
                wa = None
            return _State(self.forget(facts, cell), wa, la)
        if c == "WLD":
            if o is not None and o.kind == "K" and not o.indexed:
                return _State(facts, (ZERO, int32(o.addr)), None)
            if o is not None and o.kind == "X":
                return _State(facts, (X_CELL, 0), None)
            cell = self.cell(op)
            return _State(facts, (cell, 0) if cell is not None else None, None)
        if c in ("ADD", "SUB", "INCW", "DECW") and s.wa is not None:
            if c in ("INCW", "DECW"):
                d = 1 if c == "INCW" else -1
            elif o is not None and o.kind == "K" and not o.indexed:
                d = int32(o.addr) if c == "ADD" else -int32(o.addr)
            else:
                d = None
            total = None if d is None else s.wa[1] + d
            if total is not None and (abs(total) <= _MAX_STEP or s.wa[0] == ZERO and int32(total) == total):
                wa = (s.wa[0], total)
            else:
                wa = None
            return _State(facts, wa, None)
        if c == "CMP" and s.wa is not None and o is not None and not o.indexed and op.rel in _LEARNED:
            left, d = s.wa
            right = self.cell(op)
            if left != ZERO and d == 0 and right is not None and right[0] == left[0] and right != left:
                la = (left, right, op.rel, 0)
            elif left != ZERO and d == 0 and o.kind == "K":
                la = (left, ZERO, op.rel, int32(o.addr))
        return _State(facts, wa, la)

    @staticmethod
    def touches(a: Cell, b: Cell) -> bool:
        """Whether two cells share a byte (X and 0 share none with memory)."""
        if a[0] not in _BITS or b[0] not in _BITS:
            return a == b
        return a[1] < b[1] + BYTES[b[0]] and b[1] < a[1] + BYTES[a[0]]

    def forget(self, facts: Facts, cell: Cell) -> dict:
        """The facts that survive a write of `cell` with a value not followed."""
        return {(a, b): k for (a, b), k in facts.items() if not self.touches(a, cell) and not self.touches(b, cell)}

    def stepped(self, i: int, facts: Facts, cell: Cell, d: int) -> dict | None:
        """The facts after op i steps `cell` by d (its value + d stored back), shifted by d, where the bounds before
        the op show the new value stays in the cell's range (so it is exactly the old one + d); None where it may
        wrap."""
        if d == 0:
            return dict(facts)
        lo, hi = self.bounds(i, facts, cell)
        low, high = self.range_of(cell)
        if not (low <= lo + d and hi + d <= high):
            return None
        kept = self.forget(facts, cell)
        for (a, b), k in facts.items():
            if a == cell and not self.touches(b, cell):
                kept[(a, b)] = k + d
            elif b == cell and not self.touches(a, cell):
                kept[(a, b)] = k - d
        return kept

    def copied(self, i: int, facts: Facts, cell: Cell, wa: tuple[Cell, int]) -> dict | None:
        """The facts after op i stores WA = load(source) + d into `cell`, another cell, where the value fits the cell
        (it then loads back as exactly that value): cell - source = d, and what was known of the source holds of
        the cell shifted by d (its facts with X and 0 only, so that a run of constant stores stays small); None
        where the value may not fit."""
        source, d = wa
        if source != ZERO and (self.touches(source, cell) or abs(d) > _MAX_STEP):
            return None
        lo, hi = self.bounds(i, facts, source)
        low, high = self.range_of(cell)
        if not (low <= lo + d and hi + d <= high):
            return None
        kept = self.forget(facts, cell)
        kept[(cell, source)] = d
        kept[(source, cell)] = -d
        for (a, b), k in facts.items():
            if a == source and b in (X_CELL, ZERO) and b != cell:
                kept[(cell, b)] = min(k + d, kept.get((cell, b), k + d))
            elif b == source and a in (X_CELL, ZERO) and a != cell:
                kept[(a, cell)] = min(k - d, kept.get((a, cell), k - d))
        return kept


def _run(program: Program):
    """(file, op index, analysis, state before the op) of every op the analysis reaches; nothing under the models
    where a compare would not see the loaded values followed here."""
    sem = program.semantics
    if sem["compare_signedness"] == "unsigned" or sem["accumulator_model"] == "shared_bit7" or \
            sem["load_extension"] == "zero":
        return
    entries = entry_points(program)
    xs = index_ranges(program)
    for f, code in enumerate(program.files):
        if not code.ops:
            continue
        analysis = _Analysis(program, f, entries[f], xs)
        for i, state in analysis.run().items():
            yield f, i, analysis, state


def word_relations(program: Program) -> dict[tuple[int, int], tuple[int | None, int | None]]:
    """(file, op index) of each compare of two named words of one kind -> (the least, the greatest) difference
    left - right it can see there (None: no bound known); only compares with a bound are listed."""
    out: dict[tuple[int, int], tuple[int | None, int | None]] = {}
    for f, i, analysis, state in _run(program):
        op = analysis.ops[i]
        right = analysis.cell(op) if op.code == "CMP" else None
        if right is None or state.wa is None or state.wa[1] != 0 or state.wa[0][0] != right[0]:
            continue
        left = state.wa[0]
        high = state.facts.get((left, right))
        low = state.facts.get((right, left))
        if high is not None or low is not None:
            out[(f, i)] = (None if low is None else -low, high)
    return out


def word_bounds(program: Program) -> dict[tuple[int, int], tuple[int, int]]:
    """(file, op index) of each compare of a named word loaded right before it with a constant (`L W6` `> K0`) ->
    (the least, the greatest) value the word can hold there by its facts with X, 0 and other words; only compares
    where that is narrower than the word's type are listed."""
    out: dict[tuple[int, int], tuple[int, int]] = {}
    for f, i, analysis, state in _run(program):
        op = analysis.ops[i]
        o = op.operand
        if op.code != "CMP" or o is None or o.kind != "K" or o.indexed or state.wa is None or state.wa[1] != 0 \
                or state.wa[0][0] not in _BITS or i == 0 or analysis.ops[i - 1].code != "WLD":
            continue
        cell = state.wa[0]
        found = analysis.bounds(i, state.facts, cell)
        if found != analysis.range_of(cell):
            out[(f, i)] = found
    return out
