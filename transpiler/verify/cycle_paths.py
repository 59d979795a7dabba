"""The condition vectors a decision can see, found by running the code that leads to it in the cycle on every path:
from the entry of the subprogram every run of the decision starts in, through the calls and CASE entries it makes,
each path with the values that path gives the markers and words it reads.

implication.py follows bits symbolically over a straight stretch before a chain; this follows words and control too,
case by case, which is what a step chain needs: `L B10` `<> K0` `A[` `L B10` `<> K16` `]` `= M1`, an abort request
`ON M2` `A M1` that sets the step word to a constant (`IFT` `L K16` `= B10`), then `CASE B10`: with M2 = 0 no path
reaches the step subprograms other than 0 and 16, so a chain in them never sees M2 = 0.

The run: every bit operand starts unknown (any value), every byte, word and double word at any value its width
allows; nothing of a previous cycle is assumed, so the start state covers every state control can arrive in. A path
forks where it reads an operand of the decision's chain whose value it does not know yet (one path per value),
where a word it knows a range of is compared with a constant or dispatched on by CASE (one path per outcome, each
with the word's range narrowed: `<> K0` taken leaves the word without 0, not taken makes it 0), and where a jump,
conditional call or module end depends on a logic accumulator it does not know. Bits otherwise follow three-valued
logic (unknown AND 0 is 0); B=/W=/D= of a known WA, the data stack (PS/PL, PSL/PLL, PSW/PLW: known entries above
an unknown bottom) and word stores of known values are followed too. A subprogram the decision cannot be reached
from is run with its paths joined where they meet (its inner paths do not matter, only the state it returns with);
where it reads a bit of the chain whose value at the start is not known yet, the path calling it forks on that bit
first; where it jumps back, it is run again from the loop's head, from the state the head was entered with less
what the ops of the loop and their callees may write (a state every pass starts from), and a later jump back
to that head adds nothing. Anything else not followed exactly makes
what it may write unknown: a PLC module its error marker and code word (all of memory where it writes to an
address it is given), a write through the index register the operands index_range lets it reach, an op of a kind
not modelled all of memory. A path that ends the start subprogram ends, and so does one that can no longer come to
the chain. The run gives up (no claim) at a jump back on the way to the chain (a loop), deep calls, or when the
paths or steps exceed their limits, and for semantics in which words or LA are not followed so (shared
accumulator, zero extension, unsigned compares, dynamic chains).

A run from the main program's start may assume what holds when every cycle but the first begins (start_relations:
a marker a step chain works out from its step word at the end of every cycle, nothing writing either after it):
it starts from one state per outcome of those relations, and from any state with the first-cycle marker 1 for the
first cycle.

Where every run of the decision starts: the subprogram whose code reaches the chain without a call between (its
entry: the main program's start, a called or CASE-entered label, a submitted job); where all the calls of that
entry are in the code of one other entry, that one too, up to _UP levels (the farthest start sees the most)."""

from __future__ import annotations

import dataclasses
from typing import Callable, Sequence

from transpiler.exec.interp.decisions import BRACKET_GATES, GATES, KEEPS_LA, WORD_WRITERS, Decision
from transpiler.exec.interp.gen_exprs import int32
from transpiler.exec.interp.support import saturate
from transpiler.frontend.flow import RoutineBodies
from transpiler.frontend.opcodes import implicit_writes
from transpiler.ir import BYTES, CallTarget, Op, Program, sext
from transpiler.language.module_table import writes_anywhere
from transpiler.verify.implication import cycle_order
from transpiler.verify.index_range import index_ranges
from transpiler.verify.nc_facts import NC_MODEL_OWNED

MAX_STEPS = 200_000         # ops run over all paths of one start, at most
MAX_PATHS = 4_000           # paths alive at once, at most
_DEPTH = 16                 # calls one inside another, at most
_UP = 3                     # entries above the one whose code reaches the chain, at most
_UNKNOWN_CONDITIONS = 12    # unknown conditions of one arrival at most (each doubles the vectors)
_READS = frozenset({"LD", "LDN", *GATES})
_BIT_STORES = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN"})
_MEMORY_WRITERS = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN", "WST", "STBITS", "INC", "DEC", "POP"})
# ops that leave WA as it is (LA apart from WA)
_KEEPS_WA = frozenset({*_READS, *_BIT_STORES, "CMP", "SCMP", "BT", "WST", "NOTL", "NOP", "LBL", "JP", "JPT", "JPF",
                       "PSL", "PLL", "PSW", "PUSH", "PSX", "PLX", "STBITS", "INC", "DEC", "POP", "EMT", "EMF"})
# ops whose writes havoc knows (any other op makes all of memory unknown)
_MODELLED = KEEPS_LA | WORD_WRITERS | _READS | _BIT_STORES | {"CMP", "SCMP", "BT", "BOPEN", "BCLOSE", "NOTL"}
_RELATIONS = {"==": lambda a, b: a == b, "<>": lambda a, b: a != b, "<": lambda a, b: a < b,
              "<=": lambda a, b: a <= b, ">": lambda a, b: a > b, ">=": lambda a, b: a >= b}
_NEGATED = frozenset({"LDN", "ANDN", "ORN", "XORN"})
_STACK_OPS = frozenset({"PSL", "PSW", "PUSH", "PSX", "PLL", "PLW", "POP", "PLX"})
Key = tuple[str, int]


class _GiveUp(Exception):
    """The run cannot follow this code (a loop, deep calls, too many paths or steps)."""


class _NeedSplit(Exception):
    """A subprogram run with its paths joined reads a bit of the chain whose start value is not known: the path
    that calls it splits on that bit first."""

    def __init__(self, key: Key):
        super().__init__(key)
        self.key = key


class _NotJoined(Exception):
    """A subprogram whose paths cannot be joined so (a loop, running off its file, deep calls)."""


_RETURN = (-1, -1)              # where a subprogram run with its paths joined returns to
_DEEP = ("deep",)               # the bottom of a data stack whose lower entries are not known
_LISTED = 64                    # values a word's known values are listed up to


@dataclasses.dataclass(frozen=True)
class Word:
    """The values a word can hold on one path, as a load reads it (sign-extended): lo..hi without `out`, or where
    `some` is given, just those (a join of a few values keeps them apart)."""

    lo: int
    hi: int
    out: frozenset = frozenset()
    some: frozenset | None = None

    @staticmethod
    def of(values: frozenset) -> Word:
        return Word(min(values), max(values), frozenset(), values)

    @property
    def value(self) -> int | None:
        return self.lo if self.lo == self.hi else None

    def holds(self, v: int) -> bool:
        if self.some is not None:
            return v in self.some
        return self.lo <= v <= self.hi and v not in self.out

    def listed(self) -> frozenset | None:
        """Every value, where there are at most _LISTED."""
        if self.some is not None:
            return self.some
        if self.hi - self.lo < _LISTED:
            return frozenset(v for v in range(self.lo, self.hi + 1) if v not in self.out)
        return None

    def meet(self, lo: int, hi: int, out: frozenset = frozenset()) -> Word | None:
        """The values also in lo..hi without `out` (None: none)."""
        if self.some is not None:
            kept = frozenset(v for v in self.some if lo <= v <= hi and v not in out)
            return Word.of(kept) if kept else None
        lo, hi = max(self.lo, lo), min(self.hi, hi)
        gone = self.out | out
        while lo <= hi and lo in gone:
            lo += 1
        while hi >= lo and hi in gone:
            hi -= 1
        if lo > hi:
            return None
        return Word(lo, hi, frozenset(v for v in gone if lo < v < hi))

    def split(self, rel: str, k: int) -> tuple[Word | None, Word | None]:
        """(the values for which `word rel k` holds, those for which it does not)."""
        low, high = -(1 << 40), 1 << 40
        if rel in ("==", "<>"):
            equal, other = self.meet(k, k), self.meet(low, high, frozenset({k}))
            return (equal, other) if rel == "==" else (other, equal)
        below, rest = (self.meet(low, k - 1), self.meet(k, high)) if rel in ("<", ">=") else \
            (self.meet(low, k), self.meet(k + 1, high))
        return (below, rest) if rel in ("<", "<=") else (rest, below)

    def join(self, other: Word) -> Word:
        """The values either holds."""
        if self == other:
            return self
        mine, theirs = self.listed(), other.listed()
        if mine is not None and theirs is not None and len(mine | theirs) <= _LISTED:
            return Word.of(mine | theirs)
        lo, hi = min(self.lo, other.lo), max(self.hi, other.hi)
        return Word(lo, hi, frozenset(v for v in (self.out | other.out) if lo < v < hi and not self.holds(v)
                                      and not other.holds(v)))


def _full(kind: str) -> Word:
    half = 1 << (8 * BYTES[kind] - 1)
    return Word(-half, half - 1)


@dataclasses.dataclass
class _Path:
    bits: dict[Key, int]                # known bit values (absent: unknown)
    words: dict[Key, Word]              # known word values (absent: any value of its width)
    la: int | None = None
    wa: Word | None = None              # None: unknown
    source: Key | None = None           # the word WA was loaded from, while it still holds what WA holds
    frames: list = dataclasses.field(default_factory=list)
    stack: list = dataclasses.field(default_factory=list)      # the data stack, top last (see pushed)
    calls: tuple = ()                   # return points (file, op index)
    reads: dict[int, int | None] = dataclasses.field(default_factory=dict)     # condition op -> value read
    written: set[Key] = dataclasses.field(default_factory=set)     # the chain's bits written since the start

    def copy(self) -> _Path:
        return _Path(dict(self.bits), dict(self.words), self.la, self.wa, self.source, list(self.frames),
                     list(self.stack), self.calls, dict(self.reads), set(self.written))


@dataclasses.dataclass(frozen=True)
class Seen:
    """What the runs found: the condition vectors the decision can see (bit i = condition i) and the entry (file,
    op index) of the start subprogram."""

    vectors: frozenset[int]
    start: tuple[int, int]


def followable(program: Program) -> bool:
    sem = program.semantics
    return (sem["chain_model"] == "static" and sem["accumulator_model"] != "shared_bit7"
            and sem["load_extension"] == "sign" and sem["compare_signedness"] != "unsigned")


class Runner:
    """The runs of one program (entries worked out once); `relations`: what holds at the start of every cycle but
    the first (start_relations), assumed where a run starts at the main program's start (see start_paths)."""

    def __init__(self, program: Program, relations: Sequence[StartRelation] = ()):
        self.program = program
        self.relations = tuple(relations)[:_MAX_RELATIONS]
        self.saturate = program.semantics["store_truncation"] == "saturate"
        self.case_fault = program.semantics["case_out_of_range"] == "fault"
        self.interface = program.semantics.profile.interface
        self.flag = program.semantics["add_overflow"] == "flag"
        self.entries, self.callers = self._entries()
        self.ranges = index_ranges(program)
        self.joining = 0
        self.fork_joined = False        # runs joined where they meet fork on `split` too (cycle_states)
        self.max_steps = MAX_STEPS
        self.steps = 0
        self.split: set[Key] = set()
        self._writes: dict[tuple[int, int], tuple[frozenset, frozenset, frozenset | None, bool]] = {}
        self.target: tuple[int, int] = (-1, -1)
        self.leading: set[tuple[int, int]] = set()
        self._reach: dict[tuple[int, int], frozenset[tuple[int, int]]] = {}
        self._bodies = RoutineBodies.of(program)

    # ---------------------------------------------------------------------------------------- where runs start

    def _entries(self) -> tuple[set[tuple[int, int]], dict[tuple[int, int], list[tuple[int, int]]]]:
        entries = {(0, 0)}
        callers: dict[tuple[int, int], list[tuple[int, int]]] = {}
        for f, code in enumerate(self.program.files):
            for i, op in enumerate(code.ops):
                for t in (op.call, *op.case_targets):
                    if t is not None and not t.is_module and t.file >= 0:
                        entries.add(t.key)
                        # a submitted job is started by no op of the cycle: an entry nothing above
                        callers.setdefault(t.key, []).append((-1, -1) if op.code == "SUBM" else (f, i))
        return entries, callers

    def reach(self, entry: tuple[int, int]) -> frozenset[tuple[int, int]]:
        """The ops control comes to from `entry` without a call between (falling through, jumping, past calls)."""
        if entry not in self._reach:
            f, start = entry
            self._reach[entry] = frozenset((f, i) for i in self._bodies(CallTarget(file=f, index=start)))
        return self._reach[entry]

    def starts(self, f: int, i: int) -> list[tuple[int, int]]:
        """The entries a run may start at to see every run of op (f, i), farthest first (empty: none)."""
        found = [e for e in self.entries if e[0] == f and (f, i) in self.reach(e)]
        if len(found) != 1:
            return []
        chain = [found[0]]
        while len(chain) <= _UP and chain[-1] != (0, 0):
            callers = self.callers.get(chain[-1], [])
            above = {e for c in callers for e in self.entries if c[0] >= 0 and c[0] == e[0] and c in self.reach(e)}
            if not callers or any(c[0] < 0 for c in callers) or len(above) != 1 or next(iter(above)) in chain:
                break
            chain.append(next(iter(above)))
        return list(reversed(chain))

    # ---------------------------------------------------------------------------------------- the run

    def seen(self, decision: Decision, start: tuple[int, int]) -> frozenset[int] | None:
        """The condition vectors `decision` can see on the paths from `start` (None: the run gave up)."""
        split = {(c.operand.kind, c.operand.addr) for c in decision.conditions
                 if c.operand is not None and c.operand.is_bit and not c.operand.indexed}
        reads = {c.index for c in decision.conditions}
        f = decision.file
        self.split = split
        self.target = (f, min(reads))
        self.leading = self._leading(self.target)
        self._leads: dict[tuple[int, int], bool] = {}
        arrivals: set[tuple] = set()
        todo: list[tuple[int, int, _Path]] = [(start[0], start[1], p) for p in self.start_paths(start)]
        self.steps = 0
        try:
            while todo:
                g, i, path = todo.pop()
                while True:
                    self.count()
                    if len(todo) > MAX_PATHS:
                        raise _GiveUp
                    ops = self.program.files[g].ops
                    if not 0 <= i < len(ops):
                        raise _GiveUp           # ran off the file
                    if g == f and i == decision.index:
                        arrivals.add(tuple(path.reads.get(c.index) for c in decision.conditions))
                    nexts = self.step(g, i, ops[i], path, split, reads if g == f else set())
                    if not nexts:
                        break
                    g, i, path = nexts[0]
                    todo.extend(nexts[1:])
        except _GiveUp:
            return None
        return condition_vectors(arrivals)

    def start_paths(self, start: tuple[int, int]) -> list[_Path]:
        """The states a run from `start` begins in: any state; from the main program's start with relations, one
        state per outcome of the relations (each marker and its word narrowed to agree), for every cycle but the
        first, and any state with the first-cycle marker 1 for the first cycle (the NC sets it there, where the
        program never writes it)."""
        if start != (0, 0) or not self.relations:
            return [_Path({}, {})]
        paths = [_Path({}, {})]
        for rel in self.relations:
            grown = []
            for path in paths:
                holds, fails = path.words.get(rel.word, _full(rel.word[0])).split(rel.rel, rel.constant)
                for value, word in ((1, holds), (0, fails)):
                    if word is None or path.bits.get(rel.flag, value) != value:
                        continue
                    p = path.copy()
                    p.bits[rel.flag] = value
                    p.words[rel.word] = word
                    grown.append(p)
            paths = grown
        marker = self.first_cycle_marker()
        return paths + [_Path({} if marker is None else {marker: 1}, {})]

    def first_cycle_marker(self) -> Key | None:
        """The first-cycle marker, where the program never writes it (the NC's 1 in the first cycle stands)."""
        marker = self.program.semantics["first_cycle_marker"]
        if marker is None or any(_may_write(self.program, f, i, op, ("M", int(marker)), None, self.ranges)
                                 for f, code in enumerate(self.program.files) for i, op in enumerate(code.ops)):
            return None
        return ("M", int(marker))

    def count(self) -> None:
        self.steps += 1
        if self.steps > self.max_steps:
            raise _GiveUp

    def summarize(self, f: int, entry: int, path: _Path, depth: int) -> _Path | None:
        """Runs the subprogram entered at (f, entry) from `path`, its paths joined where they meet (forward jumps
        only: _NotJoined otherwise), the subprograms it calls likewise: the state it returns with (None: it never
        returns). Used for a subprogram from which the decision cannot be reached: its inner paths do not matter."""
        if depth > _DEPTH:
            raise _NotJoined
        ops = self.program.files[f].ops
        path.calls = (_RETURN,)
        pending: dict[int, _Path] = {entry: path}
        returned: list[_Path] = []
        heads = {op.target for op in ops if op.code in ("JPT", "JPF", "JP") and op.target is not None}
        entered: dict[int, _Path] = {}          # the state a loop head was last run from
        widened: set[int] = set()               # loop heads run from a state that covers every pass
        self.joining += 1
        try:
            while pending:
                i = min(pending)
                here = pending.pop(i)
                self.count()
                if not 0 <= i < len(ops):
                    raise _NotJoined
                if i in heads:
                    entered[i] = here.copy()
                for g, j, q in self.step(f, i, ops[i], here, self.split, set()):
                    if (g, j) == _RETURN:
                        returned.append(q)
                        continue
                    if len(q.calls) > 1:            # a call entered: run it joined too, then go on after it
                        back, q.calls = q.calls[-1], (_RETURN,)
                        q = self.summarize(g, j, q, depth + 1)
                        if q is None:
                            continue
                        q.calls = (_RETURN,)
                        g, j = back
                    if g != f or j not in entered and j <= i:
                        raise _NotJoined
                    if j <= i:
                        # a jump back: the subprogram again from the loop's head, from the state it was entered with
                        # less what the ops of the loop (loop_ops: from the head to the last jump back into it) and
                        # their callees may write (pass_start): every pass starts from such a state, so a later jump
                        # back to a head run so adds nothing (until a head before it is run again so)
                        if j in widened:
                            continue
                        widened = {a for a in widened if a < j} | {j}
                        q = self.pass_start([entered[j]], f, entry, j, i)[0]
                    pending[j] = q if j not in pending else _join(pending[j], q)
        finally:
            self.joining -= 1
        if not returned:
            return None
        result = returned[0]
        for other in returned[1:]:
            result = _join(result, other)
        return result

    def pass_start(self, entered: Sequence[_Path], f: int, entry: int, head: int, back: int) -> list[_Path]:
        """The states every pass of the loop from op `head` back to it (the jump at `back`) in the subprogram entered
        at (f, entry) starts from: each of `entered` (the states the head was entered with) less what the loop's
        ops (loop_ops) and their callees may write, LA unknown, and the data stack unknown where they move it."""
        ops = self.program.files[f].ops
        reach = sorted(k for _, k in self.reach((f, entry)))
        later = loop_ops(ops, reach, head, back, f)
        end = later[-1][1] if later else back
        if any(k < head and ops[k].code in ("JP", "JPT", "JPF") and ops[k].target is not None
               and head < ops[k].target <= end for k in reach):
            # a loop entered past its head (a jump forward into its body): its passes may start from what that
            # path holds, which no state the head was entered with covers
            raise _GiveUp
        written = self.collect(later)
        deep = any(ops[k].code in _STACK_OPS or ops[k].code in ("CALL", "CALLT", "CALLF", "CASE") for _, k in later)
        out = []
        for old in entered:
            again = old.copy()
            self.forget(again, written)
            again.la, again.frames = None, []
            if deep:
                again.stack = [_DEEP]
            out.append(again)
        return out

    def bit(self, path: _Path, key: Key, split: set[Key]) -> list[tuple[_Path, int | None]]:
        """The value of bit `key` on `path`: forked into 0 and 1 where it is an operand of the chain not known."""
        if key in path.bits:
            return [(path, path.bits[key])]
        if key not in split:
            return [(path, None)]
        if self.joining and not self.fork_joined:
            if key in path.written:
                return [(path, None)]
            raise _NeedSplit(key)       # its value at the start matters: the caller's path splits on it
        other = path.copy()
        path.bits[key], other.bits[key] = 0, 1
        return [(path, 0), (other, 1)]

    def step(self, f: int, i: int, op: Op, path: _Path, split: set[Key], reads: set[int]
             ) -> list[tuple[int, int, _Path]]:
        c, o = op.code, op.operand
        nxt = [(f, i + 1, path)]
        if c in _READS and o is not None and o.is_bit:
            out = []
            for p, v in (self.bit(path, (o.kind, o.addr), split) if not o.indexed else [(path, None)]):
                if i in reads:
                    p.reads[i] = v
                v = None if v is None else 1 - v if c in _NEGATED else v
                p.la = v if c in ("LD", "LDN") else _gate(GATES[c], p.la, v)
                out.append((f, i + 1, p))
            return out
        if c in _BIT_STORES and o is not None and o.is_bit and not o.indexed:
            key, la = (o.kind, o.addr), path.la
            old = path.bits.get(key)
            new = {"ST": la, "STN": None if la is None else 1 - la,
                   "SET": 1 if la == 1 or old == 1 else old if la == 0 else None,
                   "RES": 0 if la == 1 or old == 0 else old if la == 0 else None,
                   "SETN": 1 if la == 0 or old == 1 else old if la == 1 else None,
                   "RESN": 0 if la == 0 or old == 0 else old if la == 1 else None}[c]
            self.put(path, key, new)
            return nxt
        if c in ("JP", "JPT", "JPF", "EM", "EMT", "EMF", "CALL", "CALLT", "CALLF"):
            return self.control(f, i, op, path)
        if c == "CASE":
            return self.case(f, i, op, path)
        if c == "WLD" and o is not None and not o.indexed and o.kind in ("K", "B", "W", "D"):
            if o.kind == "K":
                path.wa, path.source = Word(int32(o.addr), int32(o.addr)), None
            else:
                path.wa, path.source = path.words.get((o.kind, o.addr), _full(o.kind)), (o.kind, o.addr)
            return nxt
        if c == "CMP" and o is not None and o.kind == "K" and not o.indexed:
            return [(f, i + 1, p) for p in self.compare(path, op.rel, int32(o.addr), i in reads, i)]
        if c == "WST" and o is not None and not o.indexed and o.kind in ("B", "W", "D"):
            self.store(path, (o.kind, o.addr), path.wa)
            return nxt
        if c == "STBITS" and o is not None and o.is_bit and not o.indexed:
            # B=/W=/D=: bit n of WA goes to the operand n places on
            v = path.wa.value if path.wa is not None else None
            for n in range(op.nbits):
                self.put(path, (o.kind, o.addr + n), None if v is None else (v >> n) & 1)
            return nxt
        if c == "LDBITS" and o is not None and o.is_bit and not o.indexed:
            got = [path.bits.get((o.kind, o.addr + n)) for n in range(op.nbits)]
            known = None not in got and not got[-1]     # (the top bit 0: signed or not, the same value)
            v = sum(b << n for n, b in enumerate(got)) if known else 0
            path.wa, path.source = (Word(v, v) if known else None), None
            return nxt
        if c in ("PSL", "PSW", "PUSH", "PSX"):
            path.stack = self.pushed(path, op)
            return nxt
        if c in ("PLL", "PLW", "POP", "PLX"):
            return self.pulled(f, i, op, path, reads)
        if c == "NOTL":
            path.la = None if path.la is None else 1 - path.la
            return nxt
        if c == "BOPEN" and op.bracket is not None:
            br = op.bracket
            if br.mode == "LOGIC" and br.op in BRACKET_GATES:
                path.frames.append(("load",) if br.load else ("la", path.la))
            else:
                path.frames.append(("wa", path.wa))
            return nxt
        if c == "BCLOSE" and op.bracket is not None:
            self.close(op, path)
            if i in reads:
                path.reads[i] = path.la
            return nxt
        if c == "LBL" or c == "NOP":
            path.frames = [] if c == "LBL" else path.frames
            return nxt
        self.havoc(f, i, op, path)
        if i in reads:
            path.reads[i] = None
        return nxt

    def leads_to(self, point: tuple[int, int]) -> bool:
        """Whether control at `point` can come to the decision run for (self.target) in this cycle: the code it
        reaches without a call reads the decision's first condition, or calls an entry whose code can."""
        if point in self._leads:
            return self._leads[point]
        reached = self.reach(point)
        self._leads[point] = self.target in reached or any(
            t is not None and not t.is_module and t.file >= 0 and t.key in self.leading
            for g, j in reached for op in (self.program.files[g].ops[j],) for t in (op.call, *op.case_targets))
        return self._leads[point]

    def _leading(self, target: tuple[int, int]) -> set[tuple[int, int]]:
        """The entries whose code, with the calls it makes, can come to op `target`."""
        found = {e for e in self.entries if target in self.reach(e)}
        while True:
            more = {e for e in self.entries - found if any(
                t is not None and not t.is_module and t.key in found for g, j in self.reach(e)
                for t in (self.program.files[g].ops[j].call, *self.program.files[g].ops[j].case_targets))}
            if not more:
                return found
            found |= more

    def pushed(self, path: _Path, op: Op) -> list | None:
        """The data stack after a push: entries (width in bits, value) on top of what is known of it (_DEEP at
        its bottom: what lies below is not known)."""
        c, o = op.code, op.operand
        if c == "PSL":
            entry = (16, path.la)
        elif c == "PSW":
            entry = (32, path.wa)
        elif c == "PSX":
            entry = (int(self.program.semantics["psx_width"]), None)
        elif o is not None and o.is_bit:
            entry = (16, None if o.indexed else path.bits.get((o.kind, o.addr)))
        elif o is not None and o.kind == "K" and not o.indexed:
            entry = (32, Word(int32(o.addr), int32(o.addr)))
        else:
            known = o is not None and not o.indexed and o.kind in ("B", "W", "D")
            entry = (32, path.words.get((o.kind, o.addr), _full(o.kind)) if known else None)
        return path.stack + [entry]

    def pulled(self, f: int, i: int, op: Op, path: _Path, reads: set[int]) -> list[tuple[int, int, _Path]]:
        """A pull: the value on top where its width matches (else unknown, and the stack's contents with it)."""
        c, o = op.code, op.operand
        width = 32 if c in ("PLW",) or c == "POP" and o is not None and not o.is_bit else 16 if c != "PLX" else \
            int(self.program.semantics["psx_width"])
        value = None
        if path.stack and path.stack[-1] != _DEEP and path.stack[-1][0] == width:
            value = path.stack[-1][1]
            path.stack = path.stack[:-1]
        elif path.stack != [_DEEP]:
            path.stack = [_DEEP]        # another width than pushed, or below what is known: its layout is lost
        if c == "PLL":
            path.la = value if isinstance(value, int) else None
            if i in reads:
                path.reads[i] = path.la
        elif c == "PLW":
            path.wa, path.source = (value if isinstance(value, Word) else None), None
        elif c == "POP" and o is not None:
            if o.indexed:
                self.forget_indexed(f, i, op, path)
            elif o.is_bit:
                self.put(path, (o.kind, o.addr), value if isinstance(value, int) else None)
            elif o.kind in ("B", "W", "D"):
                self.store(path, (o.kind, o.addr), value if isinstance(value, Word) else None)
        return [(f, i + 1, path)]

    def control(self, f: int, i: int, op: Op, path: _Path) -> list[tuple[int, int, _Path]]:
        c = op.code
        la = path.la
        if c in ("JP", "EM", "CALL"):
            taken: tuple[int, ...] = (1,)
        elif la is None:
            taken = (0, 1)
        else:
            taken = (int(la == 1) if c in ("JPT", "EMT", "CALLT") else int(la == 0),)
        out = []
        for n, go in enumerate(taken):
            p = path if n == len(taken) - 1 else path.copy()
            if c in ("JPT", "JPF", "EMT", "EMF", "CALLT", "CALLF") and la is None:
                # the fork decides LA on each way (the chain's value goes on after a conditional op)
                p.la = go if c in ("JPT", "EMT", "CALLT") else 1 - go
            if not go:
                out.append((f, i + 1, p))
            elif c.startswith("JP"):
                if op.target is None:
                    return []           # the program faults there
                if op.target <= i and not self.joining:      # (summarize runs a loop again from its head)
                    # a jump back: a loop, which the run does not follow; a path that can no longer come to the
                    # decision from there (nor from where its calls return to) does not matter
                    if any(self.leads_to(point) for point in ((f, op.target), *p.calls)):
                        raise _GiveUp
                    continue
                out.append((f, op.target, p))
            elif c.startswith("EM"):
                if not p.calls:
                    continue            # the start subprogram ends
                (g, j), p.calls = p.calls[-1], p.calls[:-1]
                p.frames = []
                out.append((g, j, p))
            else:
                out.extend(self.call(f, i, op.call, p))
        if c in ("CALLT", "CALLF") and len(taken) == 2 and not self.joining and op.call is not None \
                and op.call.key not in self.leading and all((g, j) == (f, i + 1) for g, j, _ in out):
            # a conditional call of a subprogram the decision is not reached from: its two ways joined (each
            # call of the cycle's modules would double the paths otherwise)
            joined = out[0][2]
            for _, _, other in out[1:]:
                joined = _join(joined, other)
            joined.calls = path.calls
            return [(f, i + 1, joined)]
        return out

    def call(self, f: int, i: int, target, path: _Path) -> list[tuple[int, int, _Path]]:
        if target is not None and target.is_module:
            # a PLC module: what it pulls and pushes is not followed, nor what it writes: its error marker and
            # code word (havoc), or anything where it writes to an address it is given (or is not in the table)
            if writes_anywhere(target.module):
                self.forget_all(path)
            for key in implicit_writes(self.program.files[f].ops[i], self.interface, self.flag):
                self.put(path, key, None) if key[0] not in ("B", "W", "D") else self.forget_word(path, key)
            path.la, path.wa, path.source, path.stack = None, None, None, [_DEEP]
            return [(f, i + 1, path)]
        if target is None or target.file < 0:
            return []                   # the program faults there
        if len(path.calls) >= _DEPTH:
            raise _GiveUp
        if not self.joining and target.key not in self.leading:
            # the decision cannot be reached from this subprogram: its paths joined, or what it may write unknown;
            # a path that cannot come to the decision after it either ends here
            if not any(self.leads_to(point) for point in ((f, i + 1), *path.calls)):
                return []
            calls, reads = path.calls, path.reads
            try:
                back = self.summarize(target.file, target.index, path.copy(), 1)
            except _NeedSplit as need:
                out = []
                for value in (0, 1):
                    branch = path.copy()
                    branch.bits[need.key] = value
                    out += self.call(f, i, target, branch)
                return out
            except _NotJoined:
                self.forget_written(path, target.key)
                # it may load WA too, writing nothing
                path.la, path.wa, path.source, path.stack, path.frames = None, None, None, [_DEEP], []
                return [(f, i + 1, path)]
            if back is None:
                return []
            back.calls, back.reads, back.frames = calls, reads, []
            return [(f, i + 1, back)]
        path.calls = path.calls + ((f, i + 1),)
        path.frames = []
        return [(target.file, target.index, path)]

    def case(self, f: int, i: int, op: Op, path: _Path) -> list[tuple[int, int, _Path]]:
        o = op.operand
        count = len(op.case_targets)
        if o is None or o.indexed or o.kind not in ("B", "W", "D"):
            value, key = Word(-(1 << 31), (1 << 31) - 1), None
        else:
            key = (o.kind, o.addr)
            value = path.words.get(key, _full(o.kind))
        ways: list[tuple[Word, int | None]] = []
        for k in range(count):
            if value.holds(k):
                ways.append((Word(k, k), k))
        for rest in (value.meet(-(1 << 40), -1), value.meet(count, 1 << 40)):
            if rest is not None and not self.case_fault:
                ways.append((rest, None))
        out = []
        for n, (narrowed, k) in enumerate(ways):
            p = path if n == len(ways) - 1 else path.copy()
            if key is not None:
                p.words[key] = narrowed
                if p.source == key:
                    p.wa = narrowed
            if k is None:
                out.append((f, i + 1, p))
            else:
                out.extend(self.call(f, i, op.case_targets[k], p))
        return out

    def compare(self, path: _Path, rel: str, k: int, record: bool, i: int) -> list[_Path]:
        wa = path.wa
        if wa is None:
            path.la = None
            if record:
                path.reads[i] = None
            return [path]
        yes, no = wa.split(rel, k)
        out = []
        for narrowed, outcome in ((yes, 1), (no, 0)):
            if narrowed is None:
                continue
            p = path if not out else path.copy()
            p.la = outcome
            p.wa = narrowed
            if p.source is not None:
                p.words[p.source] = narrowed
            if record:
                p.reads[i] = outcome
            out.append(p)
        if len(out) == 2:
            out.reverse()       # the copy first: `path` itself goes on last (either order is fine)
        return out

    def close(self, op: Op, path: _Path) -> None:
        saved = path.frames.pop() if path.frames else None
        br = op.bracket
        inner_wa, path.wa, path.source = path.wa, None, None
        if br.mode == "LOGIC" and br.op in BRACKET_GATES:
            inner = path.la
            if br.op in ("AN", "ON", "XON") and inner is not None:
                inner = 1 - inner
            if saved is None or saved[0] == "wa":
                path.la = None
            elif saved[0] == "load":
                path.la = inner
            else:
                path.la = _gate(BRACKET_GATES[br.op], saved[1], inner)
            return
        outer = saved[1] if saved is not None and saved[0] == "wa" else None
        if not op.rel:
            return                      # a word bracket leaves LA as it is
        path.la = None
        if self.program.semantics["bracket_width"] == 32 and outer is not None and inner_wa is not None \
                and outer.value is not None and inner_wa.value is not None:
            path.la = int(_RELATIONS[op.rel](outer.value, inner_wa.value))

    def store(self, path: _Path, key: Key, wa: Word | None) -> None:
        self.forget_word(path, key)
        bits = 8 * BYTES[key[0]]
        if wa is not None and wa.value is not None:
            v = sext(saturate(wa.value, bits) if self.saturate and bits < 32 else wa.value & ((1 << bits) - 1), bits)
            path.words[key] = Word(v, v)
        elif wa is not None and _full(key[0]).lo <= wa.lo and wa.hi <= _full(key[0]).hi:
            path.words[key] = wa
        path.source = key if key in path.words and wa is path.words[key] else None

    def forget_word(self, path: _Path, key: Key) -> None:
        """A write of `key`: every known word sharing a byte with it is any value."""
        lo, hi = key[1], key[1] + BYTES[key[0]]
        for other in [k for k in path.words if k[1] < hi and lo < k[1] + BYTES[k[0]]]:
            del path.words[other]
        if path.source is not None and path.source[1] < hi and lo < path.source[1] + BYTES[path.source[0]]:
            path.source = None

    def writes(self, entry: tuple[int, int], inside: tuple = ()
               ) -> tuple[frozenset, frozenset, frozenset | None, bool]:
        """What a subprogram and those it calls may write: (bit operands, kinds of bits written through an index
        register of unknown reach, the words written by name (None: any word), whether anything at all)."""
        if entry in self._writes:
            return self._writes[entry]
        if entry in inside:
            return frozenset(), frozenset(), None, True         # (recursion: anything)
        found = self.collect(sorted(self.reach(entry)), inside + (entry,))
        if not inside or not found[3]:
            self._writes[entry] = found
        return found

    def collect(self, points: Sequence[tuple[int, int]], inside: tuple = ()
                ) -> tuple[frozenset, frozenset, frozenset | None, bool]:
        """What the ops at `points` (file, op index) and the subprograms they call may write (as `writes`)."""
        keys: set[Key] = set()
        kinds: set[str] = set()
        everything = False
        words: set[Key] | None = set()
        for g, j in points:
            op = self.program.files[g].ops[j]
            c, o = op.code, op.operand
            implicit = implicit_writes(op, self.interface, self.flag)
            keys.update(k for k in implicit if k[0] not in ("B", "W", "D"))
            if words is not None:
                words.update(k for k in implicit if k[0] in ("B", "W", "D"))
            for t in (op.call, *op.case_targets):
                if t is None:
                    continue
                if t.is_module:
                    everything |= writes_anywhere(t.module)
                elif t.file >= 0:
                    more = self.writes(t.key, inside)
                    keys |= more[0]
                    kinds |= more[1]
                    words = None if words is None or more[2] is None else words | more[2]
                    everything |= more[3]
            if c not in _MODELLED and c not in ("CALL", "CALLT", "CALLF", "CASE", "JP", "JPT", "JPF", "EM", "EMT",
                                                  "EMF", "LBL"):
                everything = True
            elif c in _MEMORY_WRITERS and o is not None and o.is_bit:
                width = op.nbits if c == "STBITS" else 1
                x = self.ranges.get((g, j)) if o.indexed else (0, 0)
                if x is None or x[1] - x[0] > 4096:
                    kinds.add(o.kind)
                else:
                    keys.update((o.kind, a) for a in range(o.addr + x[0], o.addr + x[1] + width))
            elif c in _MEMORY_WRITERS and o is not None and o.kind in ("B", "W", "D"):
                words = None if words is None or o.indexed else words | {(o.kind, o.addr)}
        return frozenset(keys), frozenset(kinds), None if words is None else frozenset(words), everything

    def forget_written(self, path: _Path, entry: tuple[int, int]) -> None:
        """What the subprogram entered at `entry` may write is unknown, and so is WA after it."""
        self.forget(path, self.writes(entry))

    def forget(self, path: _Path, found: tuple[frozenset, frozenset, frozenset | None, bool]) -> None:
        """What `found` (writes, collect) says may be written is unknown, and so is WA."""
        keys, kinds, words, everything = found
        if everything:
            self.forget_all(path)
            return
        for key in keys:
            self.put(path, key, None)
        for key in [k for k in path.bits if k[0] in kinds]:
            del path.bits[key]
        path.written |= {k for k in self.split if k[0] in kinds}
        if words is None:
            path.words.clear()
        else:
            for key in words:
                self.forget_word(path, key)
        path.wa, path.source = None, None

    def put(self, path: _Path, key: Key, value: int | None) -> None:
        """A write of bit `key` (None: a value not known)."""
        if value is None:
            path.bits.pop(key, None)
        else:
            path.bits[key] = value
        if key in self.split:
            path.written.add(key)

    def forget_indexed(self, f: int, i: int, op: Op, path: _Path) -> None:
        """A write through the index register: the bits of its kind it can reach (those base + X reaches for the
        values index_range finds X can hold there; all of the kind where that is not known), or every word."""
        o = op.operand
        if not o.is_bit:
            path.words.clear()
            path.wa, path.source = (path.wa, None) if op.code in _KEEPS_WA else (None, None)
            return
        x = self.ranges.get((f, i))
        width = op.nbits if op.code == "STBITS" else 1
        for key in [k for k in path.bits if k[0] == o.kind and (
                x is None or o.addr + x[0] <= k[1] < o.addr + x[1] + width)]:
            self.put(path, key, None)
        path.written |= {k for k in self.split if k[0] == o.kind and (
            x is None or o.addr + x[0] <= k[1] < o.addr + x[1] + width)}

    def forget_all(self, path: _Path) -> None:
        path.bits.clear()
        path.written |= self.split
        path.words.clear()
        path.wa, path.source = None, None

    def havoc(self, f: int, i: int, op: Op, path: _Path) -> None:
        """An op not followed exactly: what it may write is unknown."""
        c, o = op.code, op.operand
        for key in implicit_writes(op, self.interface, self.flag):
            self.put(path, key, None) if key[0] not in ("B", "W", "D") else self.forget_word(path, key)
        if c not in _MODELLED:
            # an op of a kind not modelled here (a submitted job runs after the program: SUBM, RPLY and CAN
            # write no memory the cycle's program reads after them)
            self.forget_all(path)
        elif c in _MEMORY_WRITERS and o is not None:
            if o.indexed:
                self.forget_indexed(f, i, op, path)
            elif o.is_bit:
                for n in range(op.nbits if c == "STBITS" else 1):
                    self.put(path, (o.kind, o.addr + n), None)
            elif o.kind in ("B", "W", "D"):
                self.forget_word(path, (o.kind, o.addr))
        if c == "BT" and path.wa is not None and path.wa.value is not None and o is not None and o.kind == "K":
            path.la = (path.wa.value >> (o.addr & 31)) & 1
        elif c not in KEEPS_LA:
            path.la = None
        if c not in _KEEPS_WA:
            path.wa, path.source = None, None


def loop_ops(ops, reach: list[int], head: int, back: int, f: int) -> list[tuple[int, int]]:
    """The ops of `reach` (a subprogram's op indices, sorted) a pass of the loop from `head` back to it (the jump at
    `back`) may run: from the head to the jump, and on to any later jump back to them or before them (a way around
    through code after the jump) and so on."""
    end = back
    for k in reach:
        if k > end and ops[k].code in ("JP", "JPT", "JPF") and ops[k].target is not None and ops[k].target <= end:
            end = k
    return [(f, k) for k in reach if head <= k <= end]


def condition_vectors(arrivals) -> frozenset[int] | None:
    """The condition vectors (bit i = condition i) of the values paths read arriving at a decision, one tuple per
    arrival (None: not known, either value); None where an arrival has too many unknown conditions."""
    vectors: set[int] = set()
    for arrival in arrivals:
        unknown = [n for n, v in enumerate(arrival) if v is None]
        if len(unknown) > _UNKNOWN_CONDITIONS:
            return None
        base = sum(1 << n for n, v in enumerate(arrival) if v)
        for bits in range(1 << len(unknown)):
            vectors.add(base | sum(1 << n for k, n in enumerate(unknown) if bits >> k & 1))
    return frozenset(vectors)


def _join(a: _Path, b: _Path) -> _Path:
    """A state that holds what either of `a` and `b` may hold."""
    words = {}
    for key in a.words.keys() & b.words.keys():
        words[key] = a.words[key].join(b.words[key])
    same = a.wa == b.wa and a.source == b.source
    return _Path({k: v for k, v in a.bits.items() if b.bits.get(k) == v}, words,
                 a.la if a.la == b.la else None, a.wa if same else None, a.source if same else None,
                 a.frames if a.frames == b.frames else [], a.stack if a.stack == b.stack else [_DEEP], a.calls,
                 {k: v for k, v in a.reads.items() if b.reads.get(k, -1) == v}, a.written | b.written)


def _gate(gate: str, a: int | None, b: int | None) -> int | None:
    if gate == "and":
        return 0 if a == 0 or b == 0 else None if a is None or b is None else 1
    if gate == "or":
        return 1 if a == 1 or b == 1 else None if a is None or b is None else 0
    return None if a is None or b is None else a ^ b


def seen_vectors(runner: Runner, decision: Decision) -> Seen | None:
    """The vectors `decision` can see on every path of the cycle that reaches it, from the farthest start whose run
    does not give up (None: none covers every run of it, or every run gave up)."""
    if not followable(runner.program) or any(c.file != decision.file for c in decision.conditions):
        return None
    starts = runner.starts(decision.file, min(c.index for c in decision.conditions))
    if starts != runner.starts(decision.file, decision.index):
        return None
    for start in starts:
        vectors = runner.seen(decision, start)
        if vectors is not None:
            return Seen(vectors, start)
    return None


def start_name(program: Program, start: tuple[int, int]) -> str:
    ops: Sequence[Op] = program.files[start[0]].ops
    op = ops[start[1]]
    if start == (0, 0):
        return f"the start of the main program ({op.span})"
    return f"LBL {op.label} ({op.span})" if op.code == "LBL" and op.label else f"{op.span}"


# ------------------------------------------------------------------------------------- state at a cycle's start

@dataclasses.dataclass(frozen=True)
class StartRelation:
    """At the start of every cycle but the first, bit `flag` holds whether `word rel constant` holds (the word as a
    load reads it): the store `= flag` of that compare (`at`) runs in every cycle, nothing writes either after it in
    the cycle or in a submitted job, and only the program writes them (see start_relations)."""

    flag: Key
    word: Key
    rel: str
    constant: int
    at: str                 # the store's place and text, for the reason
    names: tuple[str, str]

    def text(self) -> str:
        return (f"{self.names[0]} = ({self.names[1]} {self.rel} {self.constant}) at the start of every cycle but the "
                f"first: {self.at} stores it in every cycle, nothing writes either after it, and only the program "
                "writes them")


_MAX_RELATIONS = 4          # relations a run starts from at most (each doubles the start paths)
_CONTROL = frozenset({"CALL", "CALLT", "CALLF", "CASE", "JP", "JPT", "JPF", "EM", "EMT", "EMF", "LBL"})
# ops that write no memory (the data stack, LA, WA, a constant field, a job submitted or asked about: a job's own
# ops are looked at where they are)
_NO_MEMORY = frozenset({"PSL", "PSW", "PUSH", "PSX", "PLL", "PLW", "PLX", "KFIELD", "SUBM", "RPLY", "CAN"})


def kept_between_cycles(program: Program, outside: set[Key]) -> Callable[[Key], bool]:
    """Whether an operand keeps between two cycles what the program's cycle left in it: a marker or output bit, or
    a byte, word or double word, that is no NC, interface, data-table or `outside` operand (what a scenario sets
    after power-on). What a submitted job or a later op of the cycle writes, the caller looks at itself."""
    profile = program.semantics.profile
    itf = profile.interface
    tables = {(row.kind, row.addr) for row in program.data_rows}
    foreign_words = [k for k in (*outside, *tables, *NC_MODEL_OWNED) if k[0] in ("B", "W", "D")]

    def kept(key: Key) -> bool:
        if key in outside or key in tables or key in NC_MODEL_OWNED:
            return False
        if key[0] in ("B", "W", "D"):
            span = range(key[1], key[1] + BYTES[key[0]])
            return not any(b in itf.interface_bytes for b in span) and not any(
                k[1] < span.stop and span.start < k[1] + BYTES[k[0]] for k in foreign_words)
        return key[0] in ("M", "O") and not profile.is_interface(*key)
    return kept


def start_relations(program: Program, outside: set[Key]) -> tuple[StartRelation, ...]:
    """The relations between a marker and a word that hold at the start of every cycle after the first (see
    StartRelation): `L W` `rel K` `= M` (or `=N`) where control comes to the compare and the store only from the load,
    the store runs on every path of every cycle (_always_runs: from the main program's start through unconditional
    calls, forward jumps only, no module end before it), no op that may write M or a byte of W (named, through the
    index register, a PLC module that writes anywhere, an op not modelled) can run after it in the same cycle or in a
    submitted job (implication.cycle_order), and M and W are no NC, interface, data-table or `outside` operand
    (operands scenarios set after power-on): between two cycles nothing but the program changes them."""
    if not followable(program):
        return ()
    kept = kept_between_cycles(program, outside)
    entries: set[tuple[int, int]] = set()
    for code in program.files:
        for op in code.ops:
            for t in (op.call, *op.case_targets):
                if t is not None and not t.is_module and t.file >= 0:
                    entries.add(t.key)
    targets = {(f, op.target) for f, code in enumerate(program.files) for op in code.ops
               if op.code in ("JP", "JPT", "JPF") and op.target is not None}
    found: list[tuple[tuple[int, int], StartRelation]] = []
    for f, code in enumerate(program.files):
        ops = code.ops
        for i in range(2, len(ops)):
            load, cmp = ops[i - 2], ops[i - 1]
            if load.code != "WLD" or cmp.code != "CMP" or not cmp.rel:
                continue
            w, k = load.operand, cmp.operand
            if w is None or w.indexed or w.kind not in ("B", "W", "D") or k is None or k.kind != "K" or k.indexed:
                continue
            word = (w.kind, w.addr)
            if not kept(word):
                continue
            if (f, i - 1) in targets or (f, i - 1) in entries:
                continue                    # the compare entered from elsewhere: WA there need not be the word
            j = i
            while j < len(ops) and ops[j].code in ("ST", "STN"):
                o = ops[j].operand
                if (f, j) in targets or (f, j) in entries:
                    break
                if o is not None and o.is_bit and not o.indexed:
                    flag = (o.kind, o.addr)
                    if kept(flag):
                        rel = cmp.rel if ops[j].code == "ST" else _NEGATED_REL[cmp.rel]
                        found.append(((f, j), StartRelation(flag, word, rel, int32(k.addr),
                                                            f"{ops[j].span} {ops[j].mnemonic} {o.display()}",
                                                            (o.display(), w.display()))))
                j += 1
    if not found:
        return ()
    order = cycle_order(program)
    if order is None:
        return ()
    ranges = index_ranges(program)
    holding = []
    for (f, j), rel in found:
        if not _always_runs(program, f, j, entries, ()):
            continue
        if any(_may_write(program, g, i, op, rel.flag, rel.word, ranges) and _after(order, (g, i), (f, j))
               for g, code in enumerate(program.files) for i, op in enumerate(code.ops)):
            continue
        holding.append(rel)
    return tuple(holding)


_NEGATED_REL = {"==": "<>", "<>": "==", "<": ">=", ">=": "<", ">": "<=", "<=": ">"}


def _after(order, writer: tuple[int, int], store: tuple[int, int]) -> bool:
    """Whether `writer` may run after `store` in a cycle (later in the main program, in a loop with it, or in a
    submitted job)."""
    if writer in order.in_jobs:
        return True
    for ps in order.positions.get(store, ()):
        for pw in order.positions.get(writer, ()):
            if pw > ps or any(pt <= min(pw, ps) and pj >= max(pw, ps) for pt, pj in order.loops):
                return True
    return False


def _may_write(program: Program, f: int, i: int, op: Op, flag: Key, word: Key | None,
               ranges: dict[tuple[int, int], tuple[int, int]]) -> bool:
    """Whether op i of file f may write bit `flag` or a byte of `word` (None: no word; `ranges`: index_range's
    values of X)."""
    sem = program.semantics
    flagged = sem["add_overflow"] == "flag"
    lo, hi = (word[1], word[1] + BYTES[word[0]]) if word is not None else (0, 0)
    for key in implicit_writes(op, sem.profile.interface, flagged):
        if key == flag or key[0] in ("B", "W", "D") and key[1] < hi and lo < key[1] + BYTES[key[0]]:
            return True
    for t in (op.call, *op.case_targets):
        if t is not None and t.is_module and writes_anywhere(t.module):
            return True
    c, o = op.code, op.operand
    if c not in _MODELLED and c not in _CONTROL and c not in _NO_MEMORY:
        return True
    if c not in _MEMORY_WRITERS or o is None:
        return False
    if o.is_bit:
        if o.kind != flag[0]:
            return False
        width = op.nbits if c == "STBITS" else 1
        if not o.indexed:
            return o.addr <= flag[1] < o.addr + width
        x = ranges.get((f, i))
        return x is None or o.addr + x[0] <= flag[1] < o.addr + x[1] + width
    if o.kind not in ("B", "W", "D"):
        return False
    if o.indexed:
        return True
    return o.addr < hi and lo < o.addr + BYTES[o.kind]


def _always_runs(program: Program, f: int, i: int, entries: set[tuple[int, int]], seen: tuple) -> bool:
    """Whether op i of file f runs on every path of every cycle: the routine it is in (the nearest entry before it
    from which control comes to it going forward only) is the main program, or is called by a CM that always runs,
    and from that entry every path comes to op i (forward jumps that land at or before it, no module end, no jump
    back on the way)."""
    if len(seen) > _DEPTH:
        return False
    ops = program.files[f].ops
    start = i
    while start > 0 and (f, start) not in entries and not (f == 0 and start == 0):
        start -= 1
    if (f, start) in seen:
        return False
    for j in range(start, i):
        op = ops[j]
        if op.code in ("EM", "EMT", "EMF"):
            return False
        if op.code in ("JP", "JPT", "JPF") and (op.target is None or op.target <= j or op.target > i):
            return False
    # nothing may jump into start..i from outside it (control would skip the part before the landing point)
    for g, code in enumerate(program.files):
        for j, op in enumerate(code.ops):
            if g == f and op.code in ("JP", "JPT", "JPF") and op.target is not None and start < op.target <= i \
                    and not start <= j < i:
                return False
    if f == 0 and start == 0:
        return True
    return any(op.code == "CALL" and op.call is not None and not op.call.is_module and op.call.key == (f, start)
               and _always_runs(program, g, j, entries, seen + ((f, start),))
               for g, code in enumerate(program.files) for j, op in enumerate(code.ops))
