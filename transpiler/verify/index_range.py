"""The values the index register X can hold before each op, found statically over the IR (an interval analysis), so
that a write through X (`= M4800[X]`, `S M4800[X]`) is known to reach base + [min X, max X] only, not any operand of
its kind.

The analysis follows each file's control flow (jumps both ways, conditional module ends) with one interval each
for X and WA, intervals learned for memory words, and what LA says about them: a compare of WA loaded from X or a
word with a constant tells, on the jump taken and on the one not taken, that X (or the word) lies on one side of the
constant, also through logic brackets (AND of two compares: both hold where LA is 1). It knows constant loads
(`L K`), loads of X, of a word (its learned range, else its type's), of a KF table (its smallest to largest entry:
a read outside the table faults), `+`/`-` of a constant and `INCX`/`DECX` (wrapping at X's width makes X anything).
Everything else it is not sure of makes the register anything: every entry (a file's start, a subprogram, CASE
entry or submitted job) starts with X unknown, a call or module call forgets X, WA and the learned words, `PLX`
and any op it does not model forget X, a write of a word forgets what was learned of the bytes it overlaps (a
write through an index: of every word). With A-05 shared_bit7 (LA is bit 7 of WA) it learns nothing from compares.
Loops end by widening a bound that keeps moving to the next constant the file compares with (or the type's limit).

Beside each interval, X and WA carry a congruence (index_values): the value is r modulo m (m = 0: exactly r;
m = 1: nothing known), so that a loop stepping X by 2 or 4 (`INCX` `INCX`, `L X` `+ K4` `= X`) from an even start
is known never to hold an odd value. Constants, loads of X, `+`/`-` of a constant and INCX/DECX keep it (a step that
may wrap forgets it); a join keeps the largest modulus both sides share.

Sound, not complete: an op it finds no path to gets no range (a caller treats X there as unknown), and an unknown X
is the full range of the register."""

from __future__ import annotations

import bisect
import dataclasses
import math
from typing import Mapping, NamedTuple

from transpiler.exec.interp.decisions import BRACKET_GATES
from transpiler.ir import FileCode, Op, Program

Interval = tuple[int, int]

_INT32 = (-(1 << 31), (1 << 31) - 1)
_MEM = {"B": 1, "W": 2, "D": 4}
_LOGIC_LOADS = frozenset({"LD", "LDN", "BT", "PLL", "SCMP"})
_GATES_AND = frozenset({"AND", "ANDN"})
_GATES_OR = frozenset({"OR", "ORN"})
_GATES_XOR = frozenset({"XOR", "XORN"})
_BIT_ONLY = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN", "NOP", "LBL", "PSX", "PUSH", "PSW", "PSL"})
_WA_WRITERS = frozenset({"WLDN", "WNEG", "LDBITS", "WAND", "WANDN", "WOR", "WORN", "WXOR", "WXORN", "MUL", "DIV",
                         "MOD", "SHL", "SHR", "BS", "BC", "TWOC", "NOTW", "PLW", "RPLY", "SUBM", "SLD", "SCAT"})
_CALLS = frozenset({"CALL", "CALLT", "CALLF", "CASE"})
_WIDEN_AFTER = 3            # visits of an op before its changing bounds are widened


Facts = Mapping[object, Interval]    # "X" or a memory word (kind, byte address) -> the interval it lies in
Congruence = tuple[int, int]         # (m, r): the value is r modulo m; m = 0: exactly r; (1, 0): nothing known
_ANY_MOD: Congruence = (1, 0)


class XValues(NamedTuple):
    """What X can hold before an op: lo..hi, and only values that are `residue` modulo `modulus` (0: exactly
    `residue`; 1: any)."""

    lo: int
    hi: int
    modulus: int
    residue: int

    def holds(self, value: int) -> bool:
        if not self.lo <= value <= self.hi:
            return False
        return value == self.residue if self.modulus == 0 else (value - self.residue) % self.modulus == 0


def _exactly(interval: Interval) -> Congruence:
    """The congruence an interval alone gives: its value where it holds one."""
    return (0, interval[0]) if interval[0] == interval[1] else _ANY_MOD


def _join_mod(a: Congruence, b: Congruence) -> Congruence:
    m = math.gcd(a[0], b[0], a[1] - b[1])
    return (0, a[1]) if m == 0 else (m, a[1] % m)


def _shift(a: Congruence, d: int) -> Congruence:
    return (0, a[1] + d) if a[0] == 0 else (a[0], (a[1] + d) % a[0])


@dataclasses.dataclass(frozen=True)
class _LA:
    """What LA tells: `true` holds where LA is 1, `false` where it is 0."""

    true: Facts
    false: Facts

    def negated(self) -> "_LA":
        return _LA(self.false, self.true)


_NOTHING = _LA({}, {})


@dataclasses.dataclass(frozen=True)
class _State:
    x: Interval
    wa: Interval
    source: object | None           # what WA was loaded from ("X" or a word key) while it still holds it
    la: _LA
    words: Facts
    frames: tuple                   # per open bracket: (saved LA, gate, load) or None (a word bracket)
    mod: Congruence = _ANY_MOD      # of X
    wa_mod: Congruence = _ANY_MOD   # of WA


def _hull(a: Interval, b: Interval) -> Interval:
    return (min(a[0], b[0]), max(a[1], b[1]))


def _meet(a: Interval, b: Interval) -> Interval | None:
    lo, hi = max(a[0], b[0]), min(a[1], b[1])
    return (lo, hi) if lo <= hi else None


def _both(a: Facts, b: Facts) -> dict:
    """Facts that hold where a and b hold (an empty interval stands for a path that cannot happen)."""
    out = dict(a)
    for key, value in b.items():
        out[key] = (_meet(out[key], value) or (1, 0)) if key in out else value
    return out


def _either(a: Facts, b: Facts) -> dict:
    """Facts that hold where a or b holds."""
    return {key: _hull(a[key], b[key]) for key in a.keys() & b.keys()}


def _and(a: _LA, b: _LA) -> _LA:
    return _LA(_both(a.true, b.true), _either(a.false, b.false))


def _or(a: _LA, b: _LA) -> _LA:
    return _LA(_either(a.true, b.true), _both(a.false, b.false))


def _refine(rel: str, c: int) -> tuple[Interval | None, Interval | None]:
    """The values v with `v rel c` true, and with it false (None: no restriction)."""
    lo, hi = _INT32
    below, upto, from_, above = (lo, c - 1), (lo, c), (c, hi), (c + 1, hi)
    return {"<": (below, from_), "<=": (upto, above), ">": (above, upto), ">=": (from_, below),
            "==": ((c, c), None), "<>": (None, (c, c))}.get(rel, (None, None))


class _Analysis:
    def __init__(self, program: Program, code: FileCode, entries: set[int]):
        sem = program.semantics
        self.ops = code.ops
        self.entries = entries
        bits = 16 if int(sem["index_register_width"]) == 16 else 32
        self.x_full = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)
        self.zero = sem["load_extension"] == "zero"
        self.signed = sem["compare_signedness"] != "unsigned"
        self.shared = sem["accumulator_model"] == "shared_bit7"
        constants = {op.operand.addr for op in code.ops if op.code == "CMP" and op.operand is not None
                     and op.operand.kind == "K"}
        self.thresholds = sorted({*_INT32, *self.x_full, *(c + d for c in constants for d in (-1, 0, 1))})

    def unknown(self) -> _State:
        return _State(self.x_full, _INT32, None, _NOTHING, {}, ())

    def load_range(self, kind: str) -> Interval:
        if kind == "D":
            return _INT32
        bits = 8 * _MEM[kind]
        return (0, (1 << bits) - 1) if self.zero else (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)

    # ------------------------------------------------------------------------------------------- the fixpoint

    def run(self) -> dict[int, _State]:
        before: dict[int, _State] = {}
        visits: dict[int, int] = {}
        work = sorted(self.entries)
        for i in work:
            before[i] = self.unknown()
        pending = set(work)
        while pending:
            i = min(pending)
            pending.discard(i)
            for j, state in self.successors(i, before[i]):
                if j < 0 or j >= len(self.ops) or state is None:
                    continue
                old = before.get(j)
                if old is None:
                    before[j] = state
                    pending.add(j)
                    continue
                new = self.join(old, state)
                if new != old:
                    visits[j] = visits.get(j, 0) + 1
                    if visits[j] > _WIDEN_AFTER:
                        new = self.widen(old, new)
                    before[j] = new
                    pending.add(j)
        return before

    def join(self, a: _State, b: _State) -> _State:
        frames = a.frames if a.frames == b.frames else tuple(None for _ in a.frames)
        return _State(_hull(a.x, b.x), _hull(a.wa, b.wa), a.source if a.source == b.source else None,
                      _LA(_either(a.la.true, b.la.true), _either(a.la.false, b.la.false)),
                      _either(a.words, b.words), frames, _join_mod(a.mod, b.mod), _join_mod(a.wa_mod, b.wa_mod))

    def widen(self, old: _State, new: _State) -> _State:
        def w(a: Interval, b: Interval) -> Interval:
            lo = a[0] if b[0] >= a[0] else self.thresholds[max(bisect.bisect_right(self.thresholds, b[0]) - 1, 0)]
            hi = a[1] if b[1] <= a[1] else self.thresholds[min(bisect.bisect_left(self.thresholds, b[1]),
                                                               len(self.thresholds) - 1)]
            return (lo, hi)

        def wf(a: Facts, b: Facts) -> dict:
            return {k: w(a[k], b[k]) for k in a.keys() & b.keys()}
        # (the congruences need no widening: a modulus only ever shrinks to a divisor of itself)
        return _State(w(old.x, new.x), w(old.wa, new.wa), new.source, _LA(wf(old.la.true, new.la.true),
                      wf(old.la.false, new.la.false)), wf(old.words, new.words), new.frames, new.mod, new.wa_mod)

    # ------------------------------------------------------------------------------------------- one op

    def apply(self, state: _State, facts: Facts) -> _State | None:
        """`state` on a path where `facts` hold; None where they cannot."""
        x = state.x
        words = dict(state.words)
        for key, interval in facts.items():
            if key == "X":
                x = _meet(x, interval)
                if x is None:
                    return None
            else:
                current = words.get(key, self.load_range(key[0]))
                met = _meet(current, interval)
                if met is None:
                    return None
                words[key] = met
        return dataclasses.replace(state, x=x, words=words)

    def successors(self, i: int, s: _State) -> list[tuple[int, _State | None]]:
        op = self.ops[i]
        c = op.code
        if c == "JP":
            return [(op.target, s)]
        if c in ("JPT", "JPF"):
            taken, passed = (s.la.true, s.la.false) if c == "JPT" else (s.la.false, s.la.true)
            return [(op.target, self.apply(s, taken)), (i + 1, self.apply(s, passed))]
        if c == "EM":
            return []
        if c in ("EMT", "EMF"):
            return [(i + 1, self.apply(s, s.la.false if c == "EMT" else s.la.true))]
        return [(i + 1, self.step(op, s))]

    def forget_x(self, s: _State, x: Interval, mod: Congruence | None = None) -> _State:
        """X set to a value in `x` (congruent as `mod` says; None: as `x` alone says)."""
        la = _LA({k: v for k, v in s.la.true.items() if k != "X"}, {k: v for k, v in s.la.false.items() if k != "X"})
        return dataclasses.replace(s, x=x, la=la, source=None if s.source == "X" else s.source,
                                   mod=_exactly(x) if mod is None else mod)

    def forget_word(self, s: _State, kind: str, addr: int | None) -> _State:
        """A write of kind<addr> (None: through an index, any address)."""
        def overlaps(key) -> bool:
            if key == "X":
                return False
            if addr is None:
                return True
            return key[1] < addr + _MEM[kind] and addr < key[1] + _MEM[key[0]]

        def keep(facts: Facts) -> dict:
            return {k: v for k, v in facts.items() if not overlaps(k)}
        source = None if s.source is not None and overlaps(s.source) else s.source
        return dataclasses.replace(s, words=keep(s.words), la=_LA(keep(s.la.true), keep(s.la.false)), source=source)

    def step(self, op: Op, s: _State) -> _State:
        c = op.code
        o = op.operand
        if c in _CALLS or c == "KFIELD":
            return self.unknown()
        if self.shared and (c in _LOGIC_LOADS or c in _GATES_AND | _GATES_OR | _GATES_XOR
                            or c in ("CMP", "NOTL", "BCLOSE", "BOPEN")):
            s = dataclasses.replace(s, wa=_INT32, source=None, wa_mod=_ANY_MOD)      # LA is bit 7 of WA
        if c in ("WST", "INC", "DEC", "POP") and o is not None:
            if o.kind == "X":
                if c == "WST" and _meet(s.wa, self.x_full) == s.wa:
                    return dataclasses.replace(self.forget_x(s, s.wa, s.wa_mod), source="X")
                return self.forget_x(s, self.x_full)
            if o.kind in _MEM:
                written = self.forget_word(s, o.kind, None if o.indexed else o.addr)
                if c == "WST" and not o.indexed and _meet(s.wa, self.load_range(o.kind)) == s.wa:
                    written = dataclasses.replace(written, words={**written.words, (o.kind, o.addr): s.wa},
                                                  source=(o.kind, o.addr))
                return written
            return s if c != "POP" or o.is_bit else self.unknown()
        if c == "SST":
            return self.forget_word(s, "D", None)
        if c in _BIT_ONLY or c == "STBITS":
            return s
        if c in ("INCX", "DECX"):
            step = 1 if c == "INCX" else -1
            x = (s.x[0] + step, s.x[1] + step)
            if _meet(x, self.x_full) != x:
                return self.forget_x(s, self.x_full, _ANY_MOD)
            return self.forget_x(s, x, _shift(s.mod, step))
        if c == "PLX":
            return self.forget_x(s, self.x_full)
        if c == "WLD":
            wa, source = self.load(o, s)
            wa_mod = s.mod if source == "X" else _exactly(wa)
            return dataclasses.replace(s, wa=wa, source=source, wa_mod=wa_mod)
        if c in ("ADD", "SUB", "INCW", "DECW"):
            if c in ("INCW", "DECW"):
                d = 1 if c == "INCW" else -1
            elif o is not None and o.kind == "K":
                d = o.addr if c == "ADD" else -o.addr
            else:
                return dataclasses.replace(s, wa=_INT32, source=None, wa_mod=_ANY_MOD)
            wa = (s.wa[0] + d, s.wa[1] + d)
            if _meet(wa, _INT32) != wa:
                return dataclasses.replace(s, wa=_INT32, source=None, wa_mod=_ANY_MOD)
            return dataclasses.replace(s, wa=wa, source=None, wa_mod=_shift(s.wa_mod, d))
        if c in _WA_WRITERS:
            return dataclasses.replace(s, wa=_INT32, source=None, wa_mod=_ANY_MOD)
        if c == "CMP":
            return dataclasses.replace(s, la=self.compare(op, s))
        if c in _LOGIC_LOADS or c in _GATES_XOR:
            return dataclasses.replace(s, la=_NOTHING)
        if c in _GATES_AND:
            return dataclasses.replace(s, la=_LA(s.la.true, {}))
        if c in _GATES_OR:
            return dataclasses.replace(s, la=_LA({}, s.la.false))
        if c == "NOTL":
            return dataclasses.replace(s, la=s.la.negated())
        if c == "BOPEN":
            br = op.bracket
            if br is not None and br.mode == "LOGIC" and br.op in BRACKET_GATES:
                frame = (s.la, BRACKET_GATES[br.op], br.load)
            else:
                frame = None
            return dataclasses.replace(s, frames=s.frames + (frame,), la=_NOTHING)
        if c == "BCLOSE":
            return self.close(op, s)
        return self.unknown()

    def load(self, o, s: _State) -> tuple[Interval, object | None]:
        """WA and what it was loaded from after `L o`."""
        if o.kind == "K":
            v = ((o.addr + (1 << 31)) % (1 << 32)) - (1 << 31)
            return (v, v), None
        if o.kind == "X":
            if self.zero and self.x_full[1] < _INT32[1] and s.x[0] < 0:
                return (0, 2 * self.x_full[1] + 1), None      # a 16-bit X loaded zero-extended
            return s.x, "X"
        if o.kind == "KF":
            return ((min(o.kfield), max(o.kfield)) if o.kfield else _INT32), None
        if o.kind in _MEM and not o.indexed:
            key = (o.kind, o.addr)
            return s.words.get(key, self.load_range(o.kind)), key
        if o.kind in _MEM:
            return self.load_range(o.kind), None
        return _INT32, None

    def compare(self, op: Op, s: _State) -> _LA:
        o = op.operand
        if self.shared or not self.signed or s.source is None or o is None or o.kind != "K":
            return _NOTHING
        true, false = _refine(op.rel, o.addr)
        key = s.source
        return _LA({key: true} if true else {}, {key: false} if false else {})

    def close(self, op: Op, s: _State) -> _State:
        frame = s.frames[-1] if s.frames else None
        s = dataclasses.replace(s, frames=s.frames[:-1])
        br = op.bracket
        if frame is None or br is None or br.mode != "LOGIC":
            # a word or compare bracket: its result in WA (and LA) is not followed
            return dataclasses.replace(s, wa=_INT32, source=None, la=_NOTHING, wa_mod=_ANY_MOD)
        saved, gate, load = frame
        inner = s.la.negated() if br.op in ("AN", "ON", "XON") else s.la
        if load:
            la = inner
        elif gate == "and":
            la = _and(saved, inner)
        elif gate == "or":
            la = _or(saved, inner)
        else:
            la = _NOTHING
        return dataclasses.replace(s, la=la)


def index_ranges(program: Program) -> dict[tuple[int, int], Interval]:
    """(file, op index) -> the interval X lies in before that op, for every op the analysis reaches."""
    return {key: (v.lo, v.hi) for key, v in index_values(program).items()}


def entry_points(program: Program) -> dict[int, set[int]]:
    """file -> the op indices a run of it can start at: the file's start and every call or CASE target in it."""
    entries: dict[int, set[int]] = {f: {0} for f in range(len(program.files))}
    for code in program.files:
        for op in code.ops:
            for target in (op.call, *op.case_targets):
                if target is not None and not target.is_module and target.file >= 0:
                    entries.setdefault(target.file, set()).add(target.index)
    return entries


def index_values(program: Program) -> dict[tuple[int, int], XValues]:
    """(file, op index) -> what X can hold before that op (interval and congruence), for every op the analysis
    reaches."""
    entries = entry_points(program)
    out: dict[tuple[int, int], XValues] = {}
    for f, code in enumerate(program.files):
        if not code.ops:
            continue
        found = _Analysis(program, code, entries[f]).run()
        out.update({(f, i): XValues(*s.x, *s.mod) for i, s in found.items()})
    return out
