"""Differences between two words that hold at a compare of them, so that a boundary value of a two-word compare
no run can give is explained as infeasible instead of counted as missing. The case it is made for is the counting
loop: `L K0` `= W6` ... `L W6` `< W30` `WHILET` `L W6` `+ K1` `= W6` `L W6` `< W30` `ENDW`: the body runs only
with W6 < W30 and adds 1, so at the test at its end W6 - W30 is at most 0, never +1.

A forward dataflow over each file's ops, from every entry (a file's start, a subprogram, a CASE entry, a submitted
job) with nothing known, keeps facts `A - B <= k` between named words (bytes, words, double words of one kind;
values as loaded). It learns them where a conditional jump goes on a compare of two such words (`L A` `< B`
`JPT`/`JPF`, WHILE and UNTIL included: on the way taken where the compare is 1, A - B <= -1, and so on), and keeps
them over a step of one of them by a constant (`L A` `+ K1` `= A`, +/- of constants and INCW/DECW on the way)
where a fact shows the step cannot wrap the word: A grows by d >= 0 from A - B <= k with k + d <= 0, so it stays
at most B. Anything else that writes a word drops every fact about it (a store of another value, INC, DEC, a pull,
a store of another width over its bytes); a call, a CASE, a job submission, a PLC module or a store through the
index register drops every fact. Paths join keeping the facts both have (the weaker bound); a bound still moving
after a few visits is dropped. Nothing is carried from one run of the code to the next: facts start empty at
every entry, so what a scenario, the NC or a data table writes between cycles does not matter.

Sound, not complete; with unsigned compares (A-13), zero-extended loads or the shared accumulator (A-05) it claims
nothing."""

from __future__ import annotations

import dataclasses
from typing import Mapping

from transpiler.exec.interp.gen_exprs import int32
from transpiler.ir import BYTES, Op, Program

Cell = tuple[str, int]              # (kind, byte address) of a named B/W/D operand
Facts = Mapping[tuple[Cell, Cell], int]     # (A, B) -> k: load(A) - load(B) <= k

_BITS = {"B": 8, "W": 16, "D": 32}
_WIDEN_AFTER = 4                    # visits of an op before bounds that keep moving are dropped
_MAX_STEP = 1 << 16                 # constants added to WA on the way from a load to a store, at most (no 32-bit wrap)
_MEM_WRITERS = frozenset({"WST", "INC", "DEC", "POP"})
_BARRIERS = frozenset({"CALL", "CALLT", "CALLF", "CASE", "SUBM", "KFIELD"})
# ops after which WA is what it was (the logic ones: not under the shared accumulator, where no claim is made)
_KEEP_WA = frozenset({"WST", "NOP", "LBL", "JP", "JPT", "JPF", "CMP", "LD", "LDN", "AND", "ANDN", "OR", "ORN",
                      "XOR", "XORN", "ST", "STN", "SET", "RES", "SETN", "RESN", "NOTL"})
# the facts a compare's outcome gives: rel -> ((facts where it is 1), (facts where it is 0)), each (A-first, k)
# with A-first True for load(A) - load(B) <= k, False for load(B) - load(A) <= k
_LEARNED = {"<": (((True, -1),), ((False, 0),)), "<=": (((True, 0),), ((False, -1),)),
            ">": (((False, -1),), ((True, 0),)), ">=": (((False, 0),), ((True, -1),)),
            "==": (((True, 0), (False, 0)), ()), "<>": ((), ((True, 0), (False, 0)))}


@dataclasses.dataclass(frozen=True)
class _State:
    facts: Facts
    wa: tuple[Cell, int] | None         # WA = load(cell) + d
    la: tuple[Cell, Cell, str] | None   # LA = load(A) rel load(B), neither written since


def _join(a: _State, b: _State) -> _State:
    facts = {pair: max(k, b.facts[pair]) for pair, k in a.facts.items() if pair in b.facts}
    return _State(facts, a.wa if a.wa == b.wa else None, a.la if a.la == b.la else None)


class _Analysis:
    def __init__(self, program: Program, f: int, entries: set[int]):
        self.ops = program.files[f].ops
        self.entries = entries

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
                    new = dataclasses.replace(new, facts={p: k for p, k in new.facts.items() if old.facts.get(p) == k})
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
        return [(i + 1, self.step(op, s))]

    def learn(self, s: _State, outcome: bool) -> _State:
        """`s` on the way where LA is `outcome`, with what the compare LA holds says then."""
        if s.la is None:
            return s
        a, b, rel = s.la
        facts = dict(s.facts)
        for a_first, k in _LEARNED[rel][0 if outcome else 1]:
            pair = (a, b) if a_first else (b, a)
            facts[pair] = min(k, facts.get(pair, k))
        return dataclasses.replace(s, facts=facts)

    def step(self, op: Op, s: _State) -> _State:
        c = op.code
        o = op.operand
        if c in _BARRIERS or (op.call is not None and op.call.is_module):
            return _State({}, None, None)
        facts = s.facts
        wa = s.wa if c in _KEEP_WA else None
        la = s.la if c in ("NOP", "JP") or c in ("ST", "STN", "SET", "RES", "SETN", "RESN") else None
        if c in _MEM_WRITERS and o is not None and o.kind in _BITS:
            if o.indexed:
                return _State({}, wa, None)
            cell = (o.kind, o.addr)
            step = s.wa[1] if c == "WST" and s.wa is not None and s.wa[0] == cell else None
            kept = self.stepped(facts, cell, step) if step is not None else None
            if kept is not None:
                # WA is the value stored, and the word holds it unwrapped
                return _State(kept, (cell, 0), la)
            if wa is not None and self.touches(wa[0], cell):
                wa = None
            return _State(self.forget(facts, cell), wa, la)
        if c == "WLD":
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
            wa = (s.wa[0], total) if total is not None and abs(total) <= _MAX_STEP else None
            return _State(facts, wa, None)
        if c == "CMP" and s.wa is not None and s.wa[1] == 0:
            cell = self.cell(op)
            if cell is not None and cell[0] == s.wa[0][0] and cell != s.wa[0] and op.rel in _LEARNED:
                la = (s.wa[0], cell, op.rel)
        return _State(facts, wa, la)

    @staticmethod
    def touches(a: Cell, b: Cell) -> bool:
        """Whether two cells share a byte."""
        return a[1] < b[1] + BYTES[b[0]] and b[1] < a[1] + BYTES[a[0]]

    def forget(self, facts: Facts, cell: Cell) -> dict:
        """The facts that survive a write of `cell` with a value not followed."""
        return {(a, b): k for (a, b), k in facts.items() if not self.touches(a, cell) and not self.touches(b, cell)}

    def stepped(self, facts: Facts, cell: Cell, d: int) -> dict | None:
        """The facts after `= cell` of load(cell) + d, shifted by d, where a fact shows the store cannot wrap (d >= 0
        and cell - B <= k with k + d <= 0 for a B of the same kind apart from the cell: the new value is at most B's,
        and B is no more than the word holds); None where it may."""
        if d == 0:
            return dict(facts)
        if d < 0 or not any(a == cell and b[0] == cell[0] and not self.touches(b, cell) and k + d <= 0
                            for (a, b), k in facts.items()):
            return None
        kept = self.forget(facts, cell)
        for (a, b), k in facts.items():
            if a == cell and not self.touches(b, cell):
                kept[(a, b)] = k + d
            elif b == cell and not self.touches(a, cell):
                kept[(a, b)] = k - d
        return kept


def word_relations(program: Program) -> dict[tuple[int, int], tuple[int | None, int | None]]:
    """(file, op index) of each compare of two named words of one kind -> (the least, the greatest) difference
    left - right it can see there (None: no bound known); only compares with a bound are listed."""
    sem = program.semantics
    if sem["compare_signedness"] == "unsigned" or sem["accumulator_model"] == "shared_bit7" or \
            sem["load_extension"] == "zero":
        return {}           # the compare would not see the loaded values followed here
    entries: dict[int, set[int]] = {f: {0} for f in range(len(program.files))}
    for code in program.files:
        for op in code.ops:
            for target in (op.call, *op.case_targets):
                if target is not None and not target.is_module and target.file >= 0:
                    entries.setdefault(target.file, set()).add(target.index)
    out: dict[tuple[int, int], tuple[int | None, int | None]] = {}
    for f, code in enumerate(program.files):
        if not code.ops:
            continue
        analysis = _Analysis(program, f, entries[f])
        for i, state in analysis.run().items():
            op = code.ops[i]
            right = analysis.cell(op) if op.code == "CMP" else None
            if right is None or state.wa is None or state.wa[1] != 0 or state.wa[0][0] != right[0]:
                continue
            left = state.wa[0]
            high = state.facts.get((left, right))
            low = state.facts.get((right, left))
            if high is not None or low is not None:
                out[(f, i)] = (None if low is None else -low, high)
    return out
