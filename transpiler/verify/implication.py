"""The condition vectors a decision can see, given the code before it in the same cycle: a condition whose value is
fixed or tied to another condition's by straight-line code before its chain (`R X` earlier on every path, `S X`
under the same inputs, a marker assigned from the chain's other conditions) can be infeasible for MC/DC although
its operand takes both values over a run.

The analysis runs the code of one region symbolically: from a start op to the decision's consumer, within one
file, reached only from its start (every jump into it comes from inside it and goes forward; no CASE or indexed bit
write inside it). A call of a subprogram (CM, CMT, CMF) inside it is followed into the callee where the callee can be
run the same way (`Callee`: forward jumps only, no CASE, indexed bit write, module call or call of a subprogram that
cannot, at most _CALL_DEPTH calls deep): its paths up to each EM are run and joined at the return; a call of any
other subprogram ends the region there. Every bit operand's value at the start is a free variable (or a constant where the
program's own logic fixes it, see mcdc.constant_bits, or a consumed timer/counter start no earlier write can have
set in this cycle, see consumed_start_zero), and so is every value the analysis does not follow (a word compare, LA
after a join). Values are truth tables over those variables (a Python int with one bit per assignment), so a
join of two paths is exact and the values a chain sees are over-approximated only by the free variables: a
vector not among them can never occur, which is what an infeasible claim needs.

WA is followed too where it is a constant (loaded from one and computed with constants, straight-line since):
a compare or bit test of it with a constant is then a constant, and so are the error markers x, / and MOD set
from it (`L K100` `/ K0` sets the division marker). Any other op that writes WA, a join or a call makes it unknown.

Facts of the NC model (nc_facts.NC_FACTS, where they apply) narrow the free variables further: the start values of
the NC's markers the region reads, and the outcomes of its compares of the NC's words with a constant (`L W262`
`== K-1`), can only take the combinations some state of those operands that satisfies every fact gives. The NC
writes between cycles only and nothing else writes those operands, so a read anywhere in the cycle sees that
state."""

from __future__ import annotations

import dataclasses
import itertools
from typing import Callable, Mapping, Sequence

from transpiler.exec.interp.decisions import BRACKET_GATES, GATES, KEEPS_LA, WORD_WRITERS, Decision
from transpiler.frontend.opcodes import implicit_writes
from transpiler.exec.interp.gen_exprs import int32
from transpiler.exec.interp.support import divide, remainder
from transpiler.ir import Op, Program
from transpiler.verify.index_range import index_ranges
from transpiler.verify.nc_facts import NcFact

MAX_VARS = 18                   # free variables per region (truth tables of 2**18 bits)
_ALL = (1 << (1 << MAX_VARS)) - 1


def _variable(k: int) -> int:
    """The truth table of variable k: 1 in the assignments whose bit k is 1."""
    table, width = ((1 << (1 << k)) - 1) << (1 << k), 2 << k
    while width < 1 << MAX_VARS:
        table |= table << width
        width *= 2
    return table


_VAR = tuple(_variable(k) for k in range(MAX_VARS))

_BARRIERS = frozenset({"CALL", "CALLT", "CALLF", "CASE", "SUBM", "KFIELD"})
_CALLS = frozenset({"CALL", "CALLT", "CALLF"})
_CALL_DEPTH = 4                 # calls followed one inside another, at most
_INDEXED_SPAN = 4096            # values of X up to which an indexed write counts as a write of each operand it reaches
_READS = frozenset({"LD", "LDN", *GATES, "LDBITS"})
_WRITES = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN"})
# ops that leave WA as it is (with LA apart from WA)
_KEEPS_WA = frozenset({*_READS - {"LDBITS"}, *_WRITES, "CMP", "SCMP", "BT", "WST", "NOTL", "NOP", "LBL", "JPT", "JPF"})
_WA_FEEDS = frozenset({"WLD", "ADD", "SUB", "MUL", "DIV", "MOD"})      # followed back from a compare of WA
_KEEP = -1                      # an error marker an op leaves as it is
Key = tuple[str, int]
FactsAt = Callable[[int, int], Sequence[NcFact]]     # the NC facts that hold at a region start (file, op index)


@dataclasses.dataclass(frozen=True)
class Tied:
    """What the code before a decision allows: the condition `vectors` it can see (bit i = condition i), the op
    its region starts at, and the region's writes of bit operands and calls it followed (op indices in the file)."""

    vectors: frozenset[int]
    start: int
    writes: tuple[int, ...]


class _TooMany(Exception):
    """The region reads more free values than MAX_VARS."""


@dataclasses.dataclass
class _Path:
    reach: int                      # the assignments that take this path
    values: dict[Key, int | None]   # None: any value (a write not followed), a variable made when it is read
    la: int | None                  # None: not known here (a variable made when it is used)
    frames: list
    wa: int | None = None           # WA where the ops since its last load are constants (None: not known)


class _Run:
    """One symbolic run of ops[start:consumer] (see the module docstring); `skip`: writes treated as absent (to
    find the writes an infeasible claim rests on). Only the statements that can matter to the decision are
    followed (`_relevant`): the others read no variables."""

    def __init__(self, program: Program, f: int, start: int, consumer: int, reads: set[int],
                 entry: Callable[[str, int, int, int], int | None], skip: frozenset[int] = frozenset(),
                 callees: Mapping[tuple[int, int], Callee] | None = None, keep: frozenset[Key] = frozenset()):
        self.program = program
        self.f = f
        self.start = start
        self.consumer = consumer
        self.entry = entry
        self.skip = skip
        self.callees = callees if callees is not None else program_entries(program).callees
        self.depth = 0                  # calls entered (reads and skipped writes count in the region itself only)
        self.vars = 0
        self.entries: dict[Key, int] = {}
        self.reads: dict[int, int] = {}
        self.shared = program.semantics["accumulator_model"] == "shared_bit7"
        self.flag = program.semantics["add_overflow"] == "flag"
        self.followed, self.needed = _relevant(program, f, start, consumer, reads, self.callees, keep)

    def fresh(self) -> int:
        if self.vars == MAX_VARS:
            raise _TooMany
        self.vars += 1
        return _VAR[self.vars - 1]

    def value(self, path: _Path, key: Key) -> int:
        if key in path.values:
            found = path.values[key]
            if found is None:
                found = path.values[key] = self.fresh()
            return found
        return self.at_start(key)

    def at_start(self, key: Key) -> int:
        found = self.entries.get(key)
        if found is None:
            fixed = self.entry(key[0], key[1], self.f, self.start)
            found = self.fresh() if fixed is None else (_ALL if fixed else 0)
            self.entries[key] = found
        return found

    def run(self) -> _Path | None:
        return self.flow(self.f, self.start, self.consumer, _Path(_ALL, {}, None, []), None)

    def flow(self, f: int, start: int, stop: int | None, path: _Path | None,
             returned: list[_Path] | None) -> _Path | None:
        """Runs file f's ops from `start`: up to `stop` (the path there), or, in a callee (`stop` None), until no
        path is left, each path that ends the subprogram added to `returned`."""
        ops = self.program.files[f].ops
        pending: dict[int, list[_Path]] = {}
        i = start
        while stop is None or i <= stop:
            joining = pending.pop(i, [])
            if joining:
                path = self.join(([path] if path is not None else []) + joining)
            if path is None or not path.reach:
                path = None
                if stop is None and not pending:
                    return None
                i += 1
                continue
            if i == stop:
                return path
            if i >= len(ops):
                raise _TooMany              # ran off the file: Callee rules this out, so never here
            if (f, i) in self.followed:
                path = self.step(f, i, ops[i], path, pending, returned)
            else:
                self.havoc(ops[i], path)
            i += 1
        return None

    def call(self, op: Op, path: _Path, absent: bool) -> _Path | None:
        """A call: the callee run on the paths that call it (`Callee`), joined with those that do not; `absent`: a
        call treated as not there (to find what an infeasible claim rests on): what it writes is any value."""
        c = op.code
        if c == "CALL":
            taken = _ALL
        else:
            path.la = path.la if path.la is not None else self.fresh()
            taken = path.la if c == "CALLT" else _ALL ^ path.la
        taken &= path.reach
        callee = self.callees[op.call.key]
        called = _Path(taken, dict(path.values), None, [])
        rest = _Path(path.reach & ~taken, path.values, path.la, path.frames)
        if absent or path.frames or self.depth >= _CALL_DEPTH:
            # brackets open across the call, or calls too deep: what it may write is any value
            for key in callee.writes:
                called.values[key] = None
            back: _Path | None = called
        else:
            returned: list[_Path] = []
            self.depth += 1
            try:
                self.flow(callee.file, callee.entry, None, called, returned)
            finally:
                self.depth -= 1
            back = self.join(returned) if returned else None
        paths = [p for p in (back, rest) if p is not None and p.reach]
        if not paths:
            return None
        return paths[0] if len(paths) == 1 and paths[0] is back else self.join(paths)

    def havoc(self, op: Op, path: _Path) -> None:
        """An op of a statement that cannot matter: what it may write is any value, read lazily."""
        for key in _bit_writes(op, self.program, self.flag):
            path.values[key] = None
        if op.code in _CALLS and op.call is not None and op.call.key in self.callees:
            for key in self.callees[op.call.key].writes:
                path.values[key] = None
        path.la = None
        path.wa = None

    def join(self, paths: list[_Path]) -> _Path:
        reach = 0
        for p in paths:
            reach |= p.reach
        keys = {k for p in paths for k in p.values}
        values: dict[Key, int | None] = {}
        for key in keys:
            if key not in self.needed or any(key in p.values and p.values[key] is None for p in paths):
                values[key] = None
                continue
            v = 0
            for p in paths:
                v |= p.reach & self.value(p, key)
            values[key] = v
        return _Path(reach, values, None, [])

    def step(self, f: int, i: int, op: Op, path: _Path, pending: dict[int, list[_Path]],
             returned: list[_Path] | None) -> _Path | None:
        c = op.code
        o = op.operand
        top = self.depth == 0
        if c in ("JP", "JPT", "JPF", "EM", "EMT", "EMF"):
            la = path.la if path.la is not None or c in ("JP", "EM") else self.fresh()
            path.la = la
            taken = {"JP": _ALL, "EM": _ALL, "JPT": la, "EMT": la, "JPF": _ALL ^ (la or 0),
                     "EMF": _ALL ^ (la or 0)}[c] & path.reach
            if c.startswith("JP") and taken and op.target is not None and op.target > i:
                pending.setdefault(op.target, []).append(_Path(taken, dict(path.values), path.la, []))
            elif c.startswith("EM") and taken and returned is not None:
                returned.append(_Path(taken, dict(path.values), None, []))
            # a jump back leaves the region (a new pass starts from free values again); EM leaves it too (in a
            # callee: returns to the caller)
            path.reach &= ~taken
            return path if path.reach else None
        if c in _CALLS and op.call is not None and op.call.key in self.callees:
            return self.call(op, path, top and i in self.skip)
        flags = self.word(op, path, top and i in self.skip)
        for kind, addr in implicit_writes(op, self.program.semantics.profile.interface, self.flag):
            found = flags.get((kind, addr))
            if found != _KEEP:
                path.values[(kind, addr)] = found
        if c in _READS and o is not None and o.is_bit:
            if c == "LDBITS":
                path.la = None if self.shared else path.la
                return path
            read = self.fresh() if o.indexed else self.value(path, (o.kind, o.addr))
            if top:
                self.reads[i] = read
            value = _ALL ^ read if c in ("LDN", "ANDN", "ORN", "XORN") else read
            if c in ("LD", "LDN"):
                path.la = value
            else:
                la = path.la if path.la is not None else self.fresh()
                path.la = _combine(GATES[c], la, value)
            return path
        if c in _WRITES and o is not None and o.is_bit:
            la = path.la if path.la is not None else self.fresh()
            path.la = la
            if top and i in self.skip:
                return path
            key = (o.kind, o.addr)
            if c in ("ST", "STN"):
                path.values[key] = la if c == "ST" else _ALL ^ la
                return path
            old = self.value(path, key)
            path.values[key] = {"SET": old | la, "RES": old & ~la, "SETN": old | (_ALL ^ la), "RESN": old & la}[c]
            return path
        if o is not None and o.is_bit:
            # any other op naming a bit operand (PL, INC, DEC, B=, ...): it may write it in a way not followed here
            for key in _bit_writes(op, self.program, self.flag):
                path.values[key] = None
            path.la = None
            return path
        if c in ("CMP", "SCMP", "BT", "PLL"):
            known = self.tested(op, path.wa) if c in ("CMP", "BT") else None
            path.la = self.fresh() if known is None else _ALL if known else 0
            if top:
                self.reads[i] = path.la
        elif c == "NOTL":
            path.la = None if path.la is None else _ALL ^ path.la
        elif c == "BOPEN":
            br = op.bracket
            if br.mode == "LOGIC" and br.op in BRACKET_GATES:
                path.frames.append("load" if br.load else path.la if path.la is not None else self.fresh())
                path.la = None
            else:
                path.frames.append(("wa", path.wa))
        elif c == "BCLOSE":
            self.close(i, op, path, top)
        elif c not in KEEPS_LA or (self.shared and c in WORD_WRITERS):
            path.la = None
        if c == "LBL":
            path.frames = []
        return path

    def word(self, op: Op, path: _Path, skipped: bool) -> dict[Key, int | None]:
        """Follows WA through `op` where it is a constant (`L K100` `x K3`; any other value, a non-constant operand
        or an op not followed here makes it unknown), and gives the error markers `op` sets where the operands fix
        them (`/ K0` sets the division marker; `L K65536` `x K65536` the multiplication one): _KEEP where `op`
        leaves the marker as it was. `skipped`: the op treated as absent, its markers any value."""
        c, o = op.code, op.operand
        wa, path.wa = path.wa, None
        if self.shared:
            return {}                       # LA is bit 7 of WA there: not followed
        if c in _KEEPS_WA or c in ("BOPEN", "BCLOSE"):
            path.wa = wa                    # (a bracket's close works out WA itself, close)
            return {}
        k = int32(o.addr) if o is not None and o.kind == "K" and not o.indexed else None
        if c == "WLD":
            path.wa = k
            return {}
        if c not in ("ADD", "SUB", "MUL", "DIV", "MOD") or skipped:
            return {}
        itf = self.program.semantics.profile.interface
        sem = self.program.semantics
        if c in ("DIV", "MOD"):
            flag = itf.div_err if c == "DIV" else itf.mod_err
            if k is None:
                return {}
            if wa is None:
                # the divisor alone: 0 sets the marker, -1 may (-2^31 / -1, A-12), any other clears it
                return {("M", flag): _ALL} if k == 0 else {} if k == -1 else {("M", flag): 0}
            # the interpreter's own division
            path.wa, error = (divide if c == "DIV" else remainder)(
                wa, k, sem["div_semantics"] == "floor", 1 if sem["div_min_by_minus_one"] == "flag" else 0)
            return {("M", flag): _ALL if error else 0}
        if wa is None or k is None:
            return {}
        exact = wa + k if c == "ADD" else wa - k if c == "SUB" else wa * k
        result = int32(exact)
        if c == "MUL":
            over = result != exact
            path.wa = wa if over and sem["mul_overflow_result"] == "unchanged" else result
            return {("M", itf.mul_err): _ALL if over else 0}
        path.wa = result
        return {("M", itf.mul_err): _ALL} if result != exact else {("M", itf.mul_err): _KEEP}

    def tested(self, op: Op, wa: int | None) -> int | None:
        """The outcome of a compare or bit test of a known WA with a constant (None: not known)."""
        o = op.operand
        if wa is None or o is None or o.kind != "K" or o.indexed:
            return None
        if op.code == "BT":
            return (wa >> (o.addr & 31)) & 1
        return _compare_value(self.program.semantics, "D", wa, op.rel, o.addr)

    def close(self, i: int, op: Op, path: _Path, top: bool) -> None:
        saved = path.frames.pop() if path.frames else None
        br = op.bracket
        saved_wa = saved[1] if isinstance(saved, tuple) else None
        inner_wa, path.wa = path.wa, None
        if br.mode == "LOGIC" and br.op in BRACKET_GATES:
            inner = path.la if path.la is not None else self.fresh()
            if br.op in ("AN", "ON", "XON"):
                inner = _ALL ^ inner
            if saved == "load":
                path.la = inner
            elif saved is None:
                path.la = None
            else:
                path.la = _combine(BRACKET_GATES[br.op], saved, inner)
        elif op.rel:
            known = None
            if saved_wa is not None and inner_wa is not None and self.program.semantics["bracket_width"] == 32:
                known = _compare_value(self.program.semantics, "D", saved_wa, op.rel, inner_wa)
            path.la = self.fresh() if known is None else _ALL if known else 0
            if top:
                self.reads[i] = path.la
        elif self.shared:
            path.la = None


def _bit_writes(op: Op, program: Program, flag: bool) -> list[Key]:
    """The bit operands `op` may write (named or implicit)."""
    found = [(k, a) for k, a in implicit_writes(op, program.semantics.profile.interface, flag)]
    o = op.operand
    if o is not None and o.is_bit and op.code not in _READS:
        found += [(o.kind, o.addr + n) for n in range(op.nbits if op.code == "STBITS" else 1)]
    return found


def _statements(ops: Sequence[Op], start: int, consumer: int) -> list[tuple[int, int]]:
    """ops[start:consumer] cut into statements: a new one begins at each load outside brackets."""
    cuts = [start]
    depth = 0
    for i in range(start, consumer):
        op = ops[i]
        if i > start and depth == 0 and (op.code in ("LD", "LDN", "CMP", "SCMP", "BT", "PLL", "LBL")
                                          or op.code == "BOPEN" and op.bracket.load):
            cuts.append(i)
        if op.code == "BOPEN":
            depth += 1
        elif op.code == "BCLOSE":
            depth = max(0, depth - 1)
        elif op.code == "LBL":
            depth = 0
    cuts.append(consumer)
    return [(a, b) for a, b in zip(cuts, cuts[1:]) if a < b]


def _relevant(program: Program, f: int, start: int, consumer: int, reads: set[int],
              callees: Mapping[tuple[int, int], Callee], keep: frozenset[Key] = frozenset()
              ) -> tuple[set[tuple[int, int]], set[Key]]:
    """The ops (file, index) of the statements that can matter to the decision's conditions (read at `reads`):
    those that read them, call or end the module, jump back, out or over such a statement (_jump_matters), or
    write an operand a later such statement reads, in the
    region and in the subprograms it calls (a callee's statements judged by what the caller needs after the call);
    and the operands they read. `keep`: operands whose values at the consumer matter too."""
    needed: set[Key] = set(keep)
    followed: set[tuple[int, int]] = set()
    _mark(program, f, start, consumer, reads, callees, followed, needed, 0)
    # a compare or bit test of WA: the loads and constant arithmetic that give WA its value there
    ops = program.files[f].ops
    for i in reads:
        if ops[i].code in ("CMP", "BT"):
            j = i - 1
            while j >= start and ops[j].code in _WA_FEEDS:
                followed.add((f, j))
                if ops[j].code == "WLD":
                    break
                j -= 1
    return followed, needed


def _mark(program: Program, f: int, start: int, end: int, reads: set[int], callees: Mapping[tuple[int, int], Callee],
          followed: set[tuple[int, int]], needed: set[Key], depth: int) -> None:
    ops = program.files[f].ops
    for a, b in reversed(_statements(ops, start, end)):
        span = range(a, b)
        calls = [ops[i].call for i in span if ops[i].code in _CALLS and ops[i].call is not None
                 and ops[i].call.key in callees]
        matters = calls or any(i in reads for i in span) or any(
            ops[i].code in ("EM", "EMT", "EMF") or ops[i].code in ("JP", "JPT", "JPF") and _jump_matters(
                f, i, ops[i].target, end, followed) for i in span) or any(
            ops[i].operand is not None and ops[i].operand.is_bit and not ops[i].operand.indexed
            and ops[i].code not in _READS and (ops[i].operand.kind, ops[i].operand.addr) in needed for i in span) or any(
            key in needed for i in span for key in implicit_writes(ops[i], program.semantics.profile.interface,
                                                                    program.semantics["add_overflow"] == "flag"))
        if not matters:
            continue
        if depth < _CALL_DEPTH:
            for target in reversed(calls):
                callee = callees[target.key]
                _mark(program, callee.file, callee.entry, callee.end + 1, set(), callees, followed, needed, depth + 1)
        followed.update((f, i) for i in span)
        for i in span:
            o = ops[i].operand
            if o is not None and o.is_bit and not o.indexed:
                needed.add((o.kind, o.addr))


def _jump_matters(f: int, i: int, target: int | None, end: int, followed: set[tuple[int, int]]) -> bool:
    """Whether a jump can change what the followed statements see: it goes back or out of the stretch, or skips
    one of them (a forward jump over ops that are not followed only spares writes taken as any value anyway)."""
    return target is None or target <= i or target > end or any((f, j) in followed for j in range(i + 1, target))


def _combine(gate: str, a: int, b: int) -> int:
    return a & b if gate == "and" else a | b if gate == "or" else a ^ b


@dataclasses.dataclass(frozen=True)
class Callee:
    """A subprogram a region can run through (see the module docstring): its file, entry op (its LBL) and last op
    (the EM no forward jump passes), and the bit operands it or what it calls may write (named and implicit)."""

    file: int
    entry: int
    end: int
    writes: frozenset[Key]


@dataclasses.dataclass(frozen=True)
class Entries:
    """Where control comes to an op other than from the op before it: the ops called or entered through CASE (file,
    index), and per file the jumps to each op (target -> the ops jumping there); and the subprograms a region can
    run through (`callees`, by entry). The same for every decision of a program: made once (program_entries) and
    handed to every region_starts."""

    called: frozenset[tuple[int, int]]
    jumps: tuple[dict[int, list[int]], ...]
    callees: Mapping[tuple[int, int], Callee] = dataclasses.field(default_factory=dict)


def program_entries(program: Program) -> Entries:
    jumps: list[dict[int, list[int]]] = []
    for code in program.files:
        sources: dict[int, list[int]] = {}
        for j, op in enumerate(code.ops):
            if op.code in ("JP", "JPT", "JPF") and op.target is not None:
                sources.setdefault(op.target, []).append(j)
        jumps.append(sources)
    called = frozenset((t.file, t.index) for code in program.files for op in code.ops
                       for t in (op.call, *op.case_targets) if t is not None and not t.is_module and t.file >= 0)
    found: dict[tuple[int, int], Callee | None] = {}
    for code in program.files:
        for op in code.ops:
            if op.code in _CALLS and op.call is not None and not op.call.is_module and op.call.file >= 0:
                _callee(program, op.call.key, found, ())
    return Entries(called, tuple(jumps), {k: c for k, c in found.items() if c is not None})


def _callee(program: Program, key: tuple[int, int], found: dict[tuple[int, int], Callee | None],
            stack: tuple[tuple[int, int], ...]) -> Callee | None:
    """The subprogram entered at `key` as a Callee, or None where a region cannot run through it (recursion, a jump
    back, CASE, a module call, an indexed bit write, an op that is no code, running off the file)."""
    if key in found:
        return found[key]
    if key in stack or len(stack) >= _CALL_DEPTH:
        return None
    f, entry = key
    ops = program.files[f].ops
    flag = program.semantics["add_overflow"] == "flag"
    writes: set[Key] = set()
    furthest = entry
    result = None
    for i in range(entry, len(ops)):
        op = ops[i]
        o = op.operand
        if op.code in ("CASE", "SUBM", "KFIELD") or (o is not None and o.is_bit and o.indexed
                                                     and op.code not in _READS):
            break
        if op.code in ("JP", "JPT", "JPF"):
            if op.target is None or op.target <= i:
                break
            furthest = max(furthest, op.target)
        if op.code in _CALLS:
            inner = None if op.call is None or op.call.is_module or op.call.file < 0 else \
                _callee(program, op.call.key, found, stack + (key,))
            if inner is None:
                break
            writes |= inner.writes
        writes.update(_bit_writes(op, program, flag))
        if op.code == "EM" and i >= furthest:
            result = Callee(f, entry, i, frozenset(writes))
            break
    if not stack or result is not None:
        found[key] = result             # a failure inside a call chain may be the chain's depth, not the callee's
    return result


def region_starts(program: Program, f: int, first: int, consumer: int, entries: Entries | None = None) -> list[int]:
    """The op indices a region ending at `consumer` can start at (see the module docstring), nearest first, none
    after `first` (the decision's first condition)."""
    ops = program.files[f].ops
    entries = entries or program_entries(program)
    sources, called = entries.jumps[f], entries.called
    starts = []
    lowest_source = consumer + 1
    for s in range(consumer, -1, -1):
        # s becomes the start: ops[s] itself may be entered from anywhere; ops[s + 1 .. consumer] may not
        if s < consumer:
            t = s + 1
            if (f, t) in called or any(j >= t for j in sources.get(t, ())):
                break
            lowest_source = min([lowest_source, *sources.get(t, ())])
        op = ops[s]
        runs_through = op.code in _CALLS and op.call is not None and op.call.key in entries.callees
        if s < consumer and op.code in _BARRIERS and not runs_through or (
                op.operand is not None and op.operand.is_bit and op.operand.indexed and op.code not in _READS):
            break
        if s <= first and lowest_source >= s:
            starts.append(s)
    return starts


def tied_vectors(program: Program, decision: Decision, entry: Callable[[str, int, int, int], int | None],
                 skip: frozenset[int] = frozenset(), start: int | None = None,
                 entries: Entries | None = None, facts: Sequence[NcFact] | FactsAt = (),
                 invariants: Sequence[Invariant] = ()) -> Tied | None:
    """The condition vectors `decision` can see (see Tied), from the longest region before it whose free values
    fit MAX_VARS; `entry(kind, addr, file, start)`: the operand's value at the region start (file, op index) where
    the program fixes it there, else None; `facts`: the NC model's facts that hold in this program (see the module
    docstring), or a function of the region's start (file, op index) giving the ones that hold there;
    `invariants`: relations between bit operands that hold at every observed point (inductive_invariants). None
    where no region covers all its conditions (or the decision is not reached in it)."""
    if program.semantics["chain_model"] != "static":
        return None             # gates whose load/gate role is decided at run time: not followed here
    f = decision.file
    if any(c.file != f for c in decision.conditions):
        return None
    first = min(c.index for c in decision.conditions)
    reads = {c.index for c in decision.conditions}
    entries = entries or program_entries(program)
    starts = [start] if start is not None else region_starts(program, f, first, decision.index, entries)
    callees = entries.callees
    best = _attempt(program, f, starts, len(starts) - 1, decision.index, reads, entry, skip, callees)
    if best is None:                        # the farthest start whose region fits MAX_VARS, by bisection
        low, high = 0, len(starts) - 2
        while low <= high:
            mid = (low + high) // 2
            found = _attempt(program, f, starts, mid, decision.index, reads, entry, skip, callees)
            if found is None:
                high = mid - 1
            else:
                best, low = found, mid + 1
    if best is None:
        return None
    s, run, path = best
    if path is None or any(c.index not in run.reads for c in decision.conditions):
        return None
    tables = [run.reads[c.index] for c in decision.conditions]
    found: set[int] = set()
    held = facts(f, s) if callable(facts) else facts
    _split(tables, 0, path.reach & _facts_allow(run, held) & _invariants_allow(run, invariants, entries), 0, found)
    ops = program.files[f].ops
    interface = program.semantics.profile.interface
    writes = tuple(j for g, j in sorted(run.followed) if g == f and s <= j < decision.index and (
        ops[j].code in _WRITES and ops[j].operand is not None and ops[j].operand.is_bit
        or ops[j].code in _CALLS and ops[j].call is not None and ops[j].call.key in callees
        or ops[j].code in _WA_FEEDS and implicit_writes(ops[j], interface, run.flag)))
    return Tied(frozenset(found), s, writes)


_FACT_SLOTS = 12              # reads tied by one group of the NC model's facts in a region, at most (else none are)


def _facts_allow(run: _Run, facts: Sequence[NcFact]) -> int:
    """The assignments of the run's free values that `facts` allow (every one where they tie no read): its reads of
    a fact's bit operands (their start values) and its compares of a fact's word with a constant, each tried over
    every state of the facts' operands that satisfies them all. Facts that share no operand are independent: each
    group of facts linked by shared operands is tried on its own."""
    result = _ALL
    for group in _groups(facts):
        result &= _group_allows(run, group)
    return result


def _groups(facts: Sequence[NcFact]) -> list[list[NcFact]]:
    groups: list[list[NcFact]] = []
    for fact in facts:
        linked = [g for g in groups if any(set(fact.operands) & set(f.operands) for f in g)]
        merged = [fact] + [f for g in linked for f in g]
        groups = [g for g in groups if g not in linked] + [merged]
    return groups


def _group_allows(run: _Run, facts: Sequence[NcFact]) -> int:
    bits = sorted({k for fact in facts for k in fact.bits})
    words = sorted({k for fact in facts for k in fact.words})
    slots: list[tuple[int, Callable[[dict], int]]] = []
    for key in bits:
        if key in run.entries:
            slots.append((run.entries[key], lambda state, key=key: state[key]))
    ops = run.program.files[run.f].ops
    edges = {k: {e for fact in facts if k in fact.words for e in fact.edges} for k in words}
    sem = run.program.semantics
    for i, table in run.reads.items():
        op, prev = ops[i], ops[i - 1] if i > run.start else None
        # WA is the word loaded just before only where nothing jumps to the compare itself (the region is entered
        # at its start alone, see region_starts)
        word = prev.operand if prev is not None and prev.code == "WLD" and not any(
            ops[j].target == i for j in range(run.start, i)) else None
        if op.code != "CMP" or op.operand is None or op.operand.kind != "K" or word is None or word.indexed \
                or (word.kind, word.addr) not in edges:
            continue
        key = (word.kind, word.addr)
        edges[key].add(int32(op.operand.addr))
        slots.append((table, lambda state, key=key, op=op: _compare_value(sem, key[0], state[key], op.rel,
                                                                          op.operand.addr)))
    if not slots or len(slots) > _FACT_SLOTS:
        return _ALL
    points = {}
    for key, found in edges.items():
        half = 1 << (8 * {"B": 1, "W": 2, "D": 4}[key[0]] - 1)
        low, high = -half, half - 1           # memory holds every bit pattern once: signed values are all of them
        points[key] = sorted({min(high, max(low, e + d)) for e in found for d in (-1, 0, 1)} | {low, high})
    allowed: set[tuple[int, ...]] = set()
    for state in _states(bits, words, points):
        if all(fact.holds(state) for fact in facts):
            allowed.add(tuple(read(state) for _, read in slots))
    result = 0
    for values in allowed:
        term = _ALL
        for (table, _), v in zip(slots, values):
            term &= table if v else _ALL ^ table
        result |= term
    return result


def _states(bits: list[Key], words: list[Key], points: dict[Key, list[int]]):
    """Every combination of bit values and word points, as dicts."""
    for values in itertools.product(*([(0, 1)] * len(bits)), *(points[k] for k in words)):
        yield dict(zip([*bits, *words], values))


def _compare_value(sem, kind: str, word: int, rel: str, constant: int) -> int:
    """The outcome of `L <word>` `<rel> K<constant>` for the word's value (signed in its width), as the interpreter
    computes it (A-06 load extension, the compare's signedness; a constant operand compares at 32 bits)."""
    if sem["load_extension"] == "zero" and kind != "D":
        word &= (1 << (8 * {"B": 1, "W": 2}[kind])) - 1
    left, right = word, int32(constant)
    if sem["compare_signedness"] == "unsigned":
        left, right = left & 0xFFFFFFFF, right & 0xFFFFFFFF
    return int({"==": left == right, "<>": left != right, "<": left < right, ">": left > right,
                "<=": left <= right, ">=": left >= right}[rel])


def _attempt(program: Program, f: int, starts: list[int], k: int, consumer: int, reads: set[int],
             entry: Callable[[str, int, int, int], int | None], skip: frozenset[int],
             callees: Mapping[tuple[int, int], Callee]) -> tuple[int, _Run, _Path | None] | None:
    """The run of the region from starts[k], or None where it needs more than MAX_VARS free values."""
    if k < 0:
        return None
    run = _Run(program, f, starts[k], consumer, reads, entry, skip, callees)
    try:
        return starts[k], run, run.run()
    except _TooMany:
        return None


def _split(tables: Sequence[int], n: int, mask: int, vector: int, out: set[int]) -> None:
    if not mask:
        return
    if n == len(tables):
        out.add(vector)
        return
    _split(tables, n + 1, mask & tables[n], vector | 1 << n, out)
    _split(tables, n + 1, mask & ~tables[n], vector, out)


# ------------------------------------------------------------------------------- consumed starts and cycle order

class _Unordered(Exception):
    """The program's call structure gives no order of its ops within a cycle (recursion, a very long trace)."""


_TRACE_LIMIT = 200_000
_STARTS_WRITTEN = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN", "STBITS", "POP", "INC", "DEC"})


@dataclasses.dataclass(frozen=True)
class CycleOrder:
    """The order in which the main program runs its ops in a cycle, calls inlined (`positions`: (file, op) -> its
    positions), the backward jumps as (target position, jump position), and the ops a submitted job runs (after
    the main program)."""

    positions: dict[tuple[int, int], list[int]]
    loops: tuple[tuple[int, int], ...]
    in_jobs: frozenset[tuple[int, int]]

    def may_precede(self, writer: tuple[int, int], reader: tuple[int, int]) -> bool:
        """Whether `writer` can run before `reader` in the same cycle (reader run by the main program)."""
        for pr in self.positions.get(reader, ()):
            for pw in self.positions.get(writer, ()):
                if pw < pr or any(pt <= pr and pj >= pw for pt, pj in self.loops):
                    return True
        return False


def cycle_order(program: Program) -> CycleOrder | None:
    positions: dict[tuple[int, int], list[int]] = {}
    loops: list[tuple[int, int]] = []
    trace: list[tuple[int, int]] = []

    def walk(f: int, start: int, stack: tuple[tuple[int, int], ...]) -> None:
        if (f, start) in stack:
            raise _Unordered
        ops = program.files[f].ops
        here: dict[int, int] = {}
        furthest = start
        for i in range(start, len(ops)):
            op = ops[i]
            if len(trace) > _TRACE_LIMIT:
                raise _Unordered
            here[i] = len(trace)
            positions.setdefault((f, i), []).append(len(trace))
            trace.append((f, i))
            if op.code in ("JP", "JPT", "JPF") and op.target is not None:
                if op.target > i:
                    furthest = max(furthest, op.target)
                else:
                    loops.append((here.get(op.target, -1), len(trace) - 1))
            for target in (op.call, *op.case_targets):
                if target is not None and not target.is_module and target.file >= 0:
                    walk(target.file, target.index, stack + ((f, start),))
            if op.code == "EM" and i >= furthest:
                return

    try:
        walk(0, 0, ())
        main_end = len(trace)
        for f, code in enumerate(program.files):
            for op in code.ops:
                if op.code == "SUBM" and op.call is not None and op.call.file >= 0:
                    walk(op.call.file, op.call.index, ())
        jobs = set(trace[main_end:])
    except _Unordered:
        return None
    for f_i in jobs:
        positions[f_i] = [p for p in positions[f_i] if p < main_end]
    return CycleOrder(positions, tuple(loops), frozenset(jobs))


def consumed_start_zero(program: Program, driven: set[tuple[str, int]]) -> Callable[[str, int, int, int], bool]:
    """Whether a timer or counter start operand still holds 0 at op (file, index): the service consumes every
    start after the cycle (A-34a, A-36a), power-on memory is 0, no scenario sets it, and no write of it can run
    before that op in the same cycle (cycle_order); the op is run by the main program, not by a submitted job."""
    sem = program.semantics
    profile = sem.profile
    ranges = []
    if sem["timer_start_consumed"]:
        ranges.append(("T", *profile.timer_start))
    if sem["counter_start_consumed"]:
        ranges.append(("C", *profile.counter_start))
    writers: dict[tuple[str, int], list[tuple[int, int]]] = {}
    free: set[str] = set()
    for f, code in enumerate(program.files):
        for i, op in enumerate(code.ops):
            o = op.operand
            if o is None or not o.is_bit or op.code not in _STARTS_WRITTEN:
                continue
            if o.indexed:
                free.add(o.kind)
                continue
            for n in range(op.nbits if op.code == "STBITS" else 1):
                writers.setdefault((o.kind, o.addr + n), []).append((f, i))
    order = cycle_order(program) if ranges else None

    def zero(kind: str, addr: int, f: int, index: int) -> bool:
        if order is None or kind in free or (kind, addr) in driven:
            return False
        if not any(kind == k and first <= addr <= last for k, first, last in ranges):
            return False
        if (f, index) in order.in_jobs or (f, index) not in order.positions:
            return False
        return not any(order.may_precede(w, (f, index)) for w in writers.get((kind, addr), ()))
    return zero


# ---------------------------------------------------------------------------------------- invariants across cycles

@dataclasses.dataclass(frozen=True)
class Invariant:
    """Two bit operands never hold `values` (their values, in order) together at any point of any cycle but
    between two stores of one chain (`observed`): it holds at power-on (both 0, and nothing but the program's named
    writes ever changes them, see inductive_invariants) and every write of either keeps it, given it held before
    (`writes`: where those writes are)."""

    operands: tuple[Key, Key]
    values: tuple[int, int]
    names: tuple[str, str]
    writes: tuple[str, ...] = ()

    def forbids(self, a: int, b: int) -> int:
        """The assignments (truth table) in which the operands with values `a`, `b` break it."""
        x, y = self.values
        return (a if x else _ALL ^ a) & (b if y else _ALL ^ b)

    def text(self) -> str:
        (a, b), (x, y) = self.names, self.values
        if x and y:
            return f"never {a} = 1 and {b} = 1 together"
        return f"{a} = 1 only with {b} = 1" if x else f"{b} = 1 only with {a} = 1"


def observed(ops: Sequence[Op], s: int, entries: Entries, f: int) -> bool:
    """Whether the point before ops[s] is one an invariant holds at: not between two stores of one chain (a store
    entered from elsewhere starts a new stretch of stores)."""
    return not (0 < s < len(ops) and ops[s - 1].code in _WRITES and ops[s].code in _WRITES
                and not entries.jumps[f].get(s) and (f, s) not in entries.called)


def _invariants_allow(run: _Run, invariants: Sequence[Invariant], entries: Entries) -> int:
    """The assignments the invariants allow at the run's start (every one where its start is no observed point):
    for each invariant both of whose operands the run read at its start."""
    if not invariants or not observed(run.program.files[run.f].ops, run.start, entries, run.f):
        return _ALL
    allowed = _ALL
    for inv in invariants:
        a, b = inv.operands
        if a in run.entries and b in run.entries:
            allowed &= _ALL ^ inv.forbids(run.entries[a], run.entries[b])
    return allowed


def write_sites(program: Program) -> tuple[dict[Key, list[tuple[int, int]]], set[Key], set[str]]:
    """Every named, unindexed write of a bit operand (file, op index), by operand; the operands written another way
    too (implicitly: error markers; through the index register where the values it can hold there are known,
    index_range); the kinds written through the index register where they are not."""
    sites: dict[Key, list[tuple[int, int]]] = {}
    other: set[Key] = set()
    indexed: set[str] = set()
    ranges = index_ranges(program)
    flag = program.semantics["add_overflow"] == "flag"
    interface = program.semantics.profile.interface
    for f, code in enumerate(program.files):
        for i, op in enumerate(code.ops):
            other.update(implicit_writes(op, interface, flag))
            o = op.operand
            if o is None or not o.is_bit or op.code in _READS:
                continue
            if o.indexed:
                x = ranges.get((f, i))
                if x is None or x[1] - x[0] > _INDEXED_SPAN:
                    indexed.add(o.kind)
                else:
                    width = op.nbits if op.code == "STBITS" else 1
                    other.update((o.kind, a) for a in range(o.addr + x[0], o.addr + x[1] + width))
                continue
            for key in _bit_writes(op, program, flag):
                if key not in implicit_writes(op, interface, flag):
                    sites.setdefault(key, []).append((f, i))
    return sites, other, indexed


def inductive_invariants(program: Program, candidates: Sequence[Invariant],
                         entry: Callable[[str, int, int, int], int | None], entries: Entries | None = None
                         ) -> list[Invariant]:
    """The candidates that hold at every observed point (Invariant), proved together (each may be assumed where
    another is checked; one that fails is dropped and the rest checked again). A candidate's operands must be
    ones no scenario, NC, input or service writes, with power-on value 0 (the caller picks them); here they must
    also have only named writes (no index register, no implicit write), and each stretch of stores with a write
    of either must keep it: run symbolically from a region start before it, assuming every live candidate there."""
    entries = entries or program_entries(program)
    sites, other, indexed = write_sites(program)
    alive = [c for c in candidates if c.values != (0, 0) and c.operands[0] != c.operands[1]
             and not any(k in other or k[0] in indexed for k in c.operands)]
    stretches: dict[Key, set[tuple[int, int, int]]] = {}
    for key in {k for c in alive for k in c.operands}:
        for f, i in sites.get(key, ()):
            ops = program.files[f].ops
            first, last = i, i
            while not observed(ops, first, entries, f):
                first -= 1
            while not observed(ops, last + 1, entries, f):
                last += 1
            stretches.setdefault(key, set()).add((f, first, last))
    while True:
        kept = [c for c in alive if all(_keeps_after(program, f, first, last, c, alive, entry, entries)
                                        for k in c.operands for f, first, last in sorted(stretches.get(k, ())))]
        if len(kept) == len(alive):
            break
        alive = kept
    def said(f: int, i: int) -> str:
        op = program.files[f].ops[i]
        return f"{op.span} {op.mnemonic} {op.operand.display()}"
    return [dataclasses.replace(c, writes=tuple(said(f, i) for f, i in sorted({
        site for k in c.operands for site in sites.get(k, ())}))) for c in alive]


def _keeps_after(program: Program, f: int, first: int, last: int, candidate: Invariant,
                 assumed: Sequence[Invariant], entry: Callable[[str, int, int, int], int | None],
                 entries: Entries) -> bool:
    """Whether the stretch of stores ops[first..last] leaves `candidate` true where it and `assumed` held at the
    start of a region before it (the farthest observed start whose run fits MAX_VARS)."""
    ops = program.files[f].ops
    starts = [s for s in region_starts(program, f, first, last, entries) if observed(ops, s, entries, f)]
    a, b = candidate.operands
    for s in reversed(starts):                  # farthest first: the most code before the stores is seen
        run = _Run(program, f, s, last + 1, set(), entry, frozenset(), entries.callees, frozenset({a, b}))
        try:
            path = run.run()
            if path is None:
                return True                     # no path reaches the stores from here
            start_a, start_b = run.at_start(a), run.at_start(b)
            end_a, end_b = run.value(path, a), run.value(path, b)
        except _TooMany:
            continue
        allowed = _invariants_allow(run, assumed, entries) & (_ALL ^ candidate.forbids(start_a, start_b))
        return not path.reach & allowed & candidate.forbids(end_a, end_b)
    return False
