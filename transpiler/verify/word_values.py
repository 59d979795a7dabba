"""The values a byte, word or double word can hold at each compare of it with a constant, found statically over the
IR, so that a boundary value no run can give the word there (a step number the program never writes, or one the
dispatch before the compare has already jumped away on) is explained as infeasible instead of counted as missing.

The analysis works on bit patterns of memory operands (B/W/D named without an index), each a set of patterns or
"any" (a set larger than _MAX_VALUES is "any"):

- What the program can store: every `=` of the operand with a value the analysis knows (a constant, a copy of a
  word whose values it knows, plus or minus, times, divided by or modulo a constant; RPLY's answers, without
  "running" where no submitted job reaches the RPLY) adds its values; anything else that writes memory makes
  the operand "any": a store of an unknown value, INC, DEC, a pull from the data stack, a write of another operand
  that shares one of its bytes (B, W and D overlap), a write through the index register that can reach one of its
  bytes (index_range gives X there; unknown: all memory), a PLC module that takes a memory address or is not in
  the module table (all memory), the NC model's words and the NC interface bytes, the module error-code word, a
  data-table row, and every operand a scenario sets after power-on. A pull (`PL`) right after a module call that
  takes the module's error result stores the codes its row states (Module.error_values), unless a scenario
  replaces that module's results (`module_results`: driven as ("module", number)); less the code of a call in the
  wrong context where the call runs only in the module's own one (a submit-only module called only from submitted
  jobs: no path of the cyclic program's calls reaches it; a cyclic-only one never reached from a job).
- The power-on value: 0, or any value for an operand a scenario sets before cycle 0 (`initial`); none at all where
  the first cycle stores the operand before anything reads it (first_cycle: the main program followed with every
  call inlined and the first-cycle marker 1), since no read can see it then.
- What a compare sees: a forward dataflow over each file's ops from every entry (the file's start, a subprogram, a
  CASE entry, a submitted job), where an operand holds, on entry, what the program can store anywhere plus its
  power-on value; a store replaces its values; a call adds what the routines it reaches can store to the operands
  they write. A conditional jump or module end keeps, on each of its two ways, the values that go that way where
  LA there is a compare of the operand with a constant (`L B10`, `<> K3`, `JPT`), or an AND (an OR) of such
  compares and of markers assigned from one (`L B10`, `< K5`, `= M1`, ... `L M1`, `A I1`, `IFT`; a write of the
  marker or of the word forgets that). Paths join at every op with more than one way in. WA itself is followed too:
  a compare of WA computed before it (`L W1032`, `A K15`, `== K0`) sees the values the word operations leave.

The stores and the dataflow are one fixpoint (a copy stores what its source holds there). Sound, not complete: every
way memory can change is "any" unless the analysis knows the value, so a value it leaves out no run can give the
operand at that compare; a compare the analysis finds no path to gets no claim."""

from __future__ import annotations

import dataclasses
from typing import Iterable, Mapping

from transpiler.exec.interp.decisions import Compare
from transpiler.exec.interp.submit import REPLY_STATES
from transpiler.exec.interp.support import divide, remainder, saturate
from transpiler.frontend.flow import RoutineBodies, routines_entered
from transpiler.frontend.opcodes import implicit_writes
from transpiler.ir import BYTES, CallTarget, Op, Program, sext
from transpiler.language.module_table import MODULE_TABLE, writes_anywhere
from transpiler.verify.nc_facts import NC_MODEL_OWNED
from transpiler.verify.index_range import index_ranges

_MAX_VALUES = 64            # patterns per operand above which it is "any"
_FIRST_CYCLE_VISITS = 200_000   # op visits of the first-cycle pass before it gives up
_FIRST_CYCLE_DEPTH = 64         # call depth of the first-cycle pass before it gives up
_BITS = {"B": 8, "W": 16, "D": 32}
_MEM_WRITERS = frozenset({"WST", "INC", "DEC", "POP"})
_CALLS = frozenset({"CALL", "CALLT", "CALLF", "CASE"})
# Ops after which WA is what it was (LA apart from WA); in the shared_bit7 model the logic ops change WA's bit 7.
_KEEP_WA = frozenset({"WST", "STBITS", "NOP", "LBL", "JP", "JPT", "JPF", "EMT", "EMF", "PUSH", "PSW", "PSL", "PSX",
                      "INC", "DEC", "INCX", "DECX", "SST", "SLD", "SCAT", "POP", "PLX"})
_LOGIC = frozenset({"LD", "LDN", "AND", "ANDN", "OR", "ORN", "XOR", "XORN", "ST", "STN", "SET", "RES", "SETN", "RESN",
                    "NOTL", "CMP", "BT", "SCMP", "PLL", "BOPEN"})
_BIT_WRITERS = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN", "POP", "INC", "DEC", "STBITS"})
_RELATIONS = {"==": lambda a, b: a == b, "<>": lambda a, b: a != b, "<": lambda a, b: a < b,
              "<=": lambda a, b: a <= b, ">": lambda a, b: a > b, ">=": lambda a, b: a >= b}

OVERRIDDEN_MODULE = "module"    # kind of a driven entry (kind, number): a scenario replaces that module's results
Cell = tuple[str, int]          # (kind, byte address) of a named B/W/D operand
Values = frozenset | None       # bit patterns, or None: any


def _int32(v: int) -> int:
    return ((v + (1 << 31)) % (1 << 32)) - (1 << 31)


def _bytes(cell: Cell) -> range:
    return range(cell[1], cell[1] + BYTES[cell[0]])


def _union(a: Values, b: Values) -> Values:
    if a is None or b is None:
        return None
    out = a | b
    return out if len(out) <= _MAX_VALUES else None


def _masked(wa: frozenset | None, mask: int) -> frozenset | None:
    """WA after `A K<mask>` (a word AND): each known value masked; from any value, every value made of the mask's
    bits where they are few."""
    if wa is not None:
        return frozenset(v & mask for v in wa)
    if mask < 0 or bin(mask).count("1") > 6:
        return None
    bits = [1 << b for b in range(mask.bit_length()) if mask >> b & 1]
    values = {0}
    for bit in bits:
        values |= {v | bit for v in values}
    return frozenset(values)


def _spans(values: Iterable[int]) -> str:
    """`0..5`, `1, 3, 7..9`: sorted values with runs joined."""
    ordered = sorted(values)
    if not ordered:
        return "nothing"
    parts: list[str] = []
    start = prev = ordered[0]
    for v in ordered[1:] + [None]:
        if v is not None and v == prev + 1:
            prev = v
            continue
        parts.append(str(start) if start == prev else f"{start}, {prev}" if prev == start + 1 else f"{start}..{prev}")
        if v is not None:
            start = prev = v
    return ", ".join(parts)


class _GiveUp(Exception):
    """The first-cycle pass is too long or too deep: it claims nothing."""


@dataclasses.dataclass(frozen=True)
class Held:
    """What a compare's word can hold there: `values` as the compare reads them, the program's stores of it (spans)
    and the conditional jumps that narrowed it on the way (spans)."""

    word: str
    values: frozenset[int]
    stored: frozenset[int]
    writes: tuple[str, ...]
    narrowed: tuple[str, ...]
    start: int | None                   # the power-on value (None: the first cycle writes it before any read)
    note: str = ""                      # WA only: what gives it its values where that is not word operations

    def reason(self, value: int) -> str:
        """Why the word cannot hold `value` at this compare."""
        if self.word == "WA" and self.note:
            return f"WA holds only {_spans(self.values)} here, not {value}: {self.note}"
        if self.word == "WA":
            return (f"WA holds only {_spans(self.values)} here, not {value}: the word operations before the compare "
                    "(a mask with a constant, constants and the words they are loaded from) leave no other value")
        shown = ", ".join(self.writes[:3]) + (", ..." if len(self.writes) > 3 else "")
        wrote = (f"the program writes only {_spans(self.stored)} to it ({shown})" if self.writes else
                 "the program never writes it")
        start = (f"it starts at {self.start}" if self.start is not None else
                 "the first cycle writes it before anything reads it")
        text = (f"{self.word} holds only {_spans(self.values)} here, not {value}: {wrote}, {start}, and no NC, "
                "interface, data table or scenario sets it after power-on")
        if self.narrowed and self.values != self.stored | ({self.start} if self.start is not None else set()):
            text += f"; the compares and jumps at {', '.join(self.narrowed[:3])}" + \
                (", ..." if len(self.narrowed) > 3 else "") + " take the other values elsewhere on every path here"
        return text


@dataclasses.dataclass(frozen=True)
class WordValues:
    """The result: compare key (file, op index) -> Held, for each compare of a named word with a constant that the
    analysis reaches and whose word it knows."""

    held: Mapping[tuple[int, int], Held]

    def at(self, cmp: Compare) -> Held | None:
        return self.held.get(cmp.key)


@dataclasses.dataclass
class _Flow:
    """The state before one op: values of the cells that differ from their entry values (absent: the entry value),
    with the jumps that narrowed each; WA's values (None: any) and what is known of markers assigned from compares."""

    cells: dict[Cell, tuple[Values, frozenset[str]]]
    wa: frozenset | None
    facts: frozenset        # (marker, cell, relation, constant, same): marker == (load(cell) rel constant) == same;
                            # (marker, None, None, None, value): the marker is `value`
    fresh: frozenset = frozenset()      # first cycle only: cells that may still hold their power-on value


class _Analysis:
    def __init__(self, program: Program, driven: set[tuple[str, int]], power_on: set[tuple[str, int]]):
        self.program = program
        sem = program.semantics
        self.zero_load = sem["load_extension"] == "zero"
        self.saturate = sem["store_truncation"] == "saturate"
        self.refine = sem["compare_signedness"] != "unsigned" and sem["accumulator_model"] != "shared_bit7"
        self.shared = sem["accumulator_model"] == "shared_bit7"
        self.scale = sem["index_scaling"] == "elements"
        self.ranges = index_ranges(program)
        self.cells: set[Cell] = set()
        for code in program.files:
            for op in code.ops:
                o = op.operand
                if o is not None and o.kind in _BITS and not o.indexed:
                    self.cells.add((o.kind, o.addr))
        self.by_byte: dict[int, list[Cell]] = {}
        for cell in self.cells:
            for b in _bytes(cell):
                self.by_byte.setdefault(b, []).append(cell)
        self.ops = [(f, i, op) for f, code in enumerate(program.files) for i, op in enumerate(code.ops)]
        self.entries = {(f, op.target) for f, i, op in self.ops if op.code in ("JP", "JPT", "JPF")
                        and op.target is not None}
        self.entries |= {(t.file, t.index) for _, _, op in self.ops for t in (op.call, *op.case_targets)
                         if t is not None and not t.is_module and t.file >= 0}
        self.outside = self._outside_bytes(driven - power_on)
        self.overridden = {number for kind, number in driven if kind == OVERRIDDEN_MODULE}
        self.dirty = {b for kind, addr in power_on if kind in _BITS for b in _bytes((kind, addr))}
        self.contexts = self._contexts()
        self.callees = self._callee_writes()
        self.linked = self._linked()
        self.interface = sem.profile.interface
        self.flag = sem["add_overflow"] == "flag"

    # ------------------------------------------------------------------------------------ what memory the program
    # does not own

    def _outside_bytes(self, driven: set[tuple[str, int]]) -> set[int]:
        """Bytes something other than the program's stores can change: scenarios, data tables, the NC model and
        interface, the module error-code word."""
        itf = self.program.semantics.profile.interface
        found: set[int] = set(itf.interface_bytes)
        words = [(k, a) for k, a in driven if k in _BITS] + [(k, a) for k, a in NC_MODEL_OWNED if k in _BITS]
        words += [(row.kind, row.addr) for row in self.program.data_rows if row.kind in _BITS]
        if itf.module_err_code_word is not None:
            words.append(("W", itf.module_err_code_word))
        for cell in words:
            found.update(_bytes(cell))
        return found

    def overlapping(self, lo: int, hi: int) -> set[Cell]:
        """Cells sharing a byte with lo..hi-1."""
        out: set[Cell] = set()
        for b in range(lo, hi):
            out.update(self.by_byte.get(b, ()))
        return out

    def written_by(self, f: int, i: int, op: Op) -> tuple[Cell | None, set[Cell] | None]:
        """(the cell `op` stores into by name, or None; the cells it may change otherwise, None: every cell)."""
        o = op.operand
        if op.code in _CALLS and op.call is not None and op.call.is_module:
            return (None, None) if writes_anywhere(op.call.module) else (None, set())
        if op.code not in _MEM_WRITERS or o is None or o.kind not in _BITS:
            return None, set()
        size = BYTES[o.kind]
        if o.indexed:
            x = self.ranges.get((f, i))
            if x is None:
                return None, None
            step = size if self.scale else 1
            return None, self.overlapping(o.addr + x[0] * step, o.addr + x[1] * step + size)
        cell = (o.kind, o.addr)
        others = self.overlapping(o.addr, o.addr + size) - {cell}
        if op.code != "WST" and (op.code != "POP" or self.error_codes(f, i) is None):
            others.add(cell)
            return None, others
        return cell, others

    def error_codes(self, f: int, i: int) -> frozenset[int] | None:
        """The values the pull at op i can take where it is the k-th pull right after a call of a module whose k-th
        result is its error result with stated values (Module.error_values, less the wrong context's result where
        the call runs only in the module's own context), nothing entering in between and no scenario replacing the
        module's results; None otherwise."""
        row = self.pulled_module(f, i)
        return None if row is None else row.error_values_in(self.call_context(f, self.pulls_from(f, i)))

    def pulls_from(self, f: int, i: int) -> int:
        """The op index of the call whose results the pull at op i takes (pulled_module found it)."""
        ops = self.program.files[f].ops
        j = i
        while ops[j - 1].code == "POP":
            j -= 1
        return j - 1

    def pulled_from(self, f: int, i: int) -> str:
        """What the pull at op i takes, for the reason: the module's error result, and where the call runs when
        that leaves the wrong context's result out."""
        row = self.pulled_module(f, i)
        where = ""
        if self.error_codes(f, i) != row.error_values:
            where = (", called only in a submitted job" if self.call_context(f, self.pulls_from(f, i)) else
                     ", called only in the cyclic program")
        return f"the error result of module {row.number}{where}"

    def call_context(self, f: int, i: int) -> bool | None:
        """True where op i runs only inside submitted jobs, False where only in the cyclic program, None where both
        may run it (or the A-46q context rule is off: no call fails for its context then, and no claim is made)."""
        if self.program.semantics["module_context"] != "enforce":
            return None
        cyclic, job = (f, i) in self.contexts[0], (f, i) in self.contexts[1]
        return None if cyclic == job else job

    def _contexts(self) -> tuple[set[tuple[int, int]], set[tuple[int, int]]]:
        """(file, op index) of the ops the cyclic program can run (the main program from its start and every
        routine it calls, through CASE tables and falls into other labels too) and of those a submitted job can run
        (every SUBM target and what it calls), whatever the values: the machine runs nothing else, and a job's
        code runs with the in-job flag set, the cyclic program's without it."""
        bodies = RoutineBodies.of(self.program)

        def reach(roots: list[CallTarget]) -> set[tuple[int, int]]:
            found: set[tuple[int, int]] = set()
            seen: set[tuple[int, int]] = set()
            while roots:
                r = roots.pop()
                if r.key in seen:
                    continue
                seen.add(r.key)
                for i in bodies(r):
                    found.add((r.file, i))
                    roots.extend(routines_entered(self.program.files[r.file].ops[i]))
            return found
        jobs = [op.call for _, _, op in self.ops if op.code == "SUBM" and op.call is not None
                and not op.call.is_module and op.call.file >= 0]
        return reach([CallTarget(file=0, index=0)]), reach(jobs)

    def pulled_module(self, f: int, i: int):
        """The module row whose error result the pull at op i takes (see error_codes), or None."""
        ops = self.program.files[f].ops
        j = i
        while j > 0 and ops[j - 1].code == "POP" and not self.entered(f, j):
            j -= 1
        call = ops[j - 1] if j > 0 and not self.entered(f, j) else None
        if call is None or call.code != "CALL" or call.call is None or not call.call.is_module:
            return None
        row = MODULE_TABLE.get(call.call.module)
        if row is None or row.error_values is None or row.error_result != i - j or row.number in self.overridden \
                or self.program.semantics.profile.name not in row.profiles:
            return None
        return row

    def stored_values(self, f: int, i: int, op: Op, cell: Cell, wa: frozenset | None) -> Values:
        """The patterns op i stores into `cell` (its named store): WA's values, or a module's error codes."""
        values = self.error_codes(f, i) if op.code == "POP" else wa
        return None if values is None else frozenset(self.store(cell, v) for v in values)

    def _linked(self) -> set[tuple[int, int]]:
        """(file, op index) of every op a path of jumps and calls leads to from an entry, whatever the values."""
        found: set[tuple[int, int]] = set()
        todo = [(f, 0) for f in range(len(self.program.files))]
        todo += [(t.file, t.index) for _, _, op in self.ops for t in (op.call, *op.case_targets)
                 if t is not None and not t.is_module and t.file >= 0]
        while todo:
            f, i = todo.pop()
            ops = self.program.files[f].ops
            if (f, i) in found or not 0 <= i < len(ops):
                continue
            found.add((f, i))
            op = ops[i]
            if op.code in ("JP", "JPT", "JPF") and op.target is not None:
                todo.append((f, op.target))
            if op.code not in ("JP", "EM"):
                todo.append((f, i + 1))
        return found

    def _callee_writes(self) -> dict[tuple[int, int], set[Cell] | None]:
        """Subprogram entry -> the cells it and what it calls may write (None: every cell)."""
        direct: dict[tuple[int, int], set[Cell] | None] = {}
        calls: dict[tuple[int, int], set[tuple[int, int]]] = {}
        entries = {(t.file, t.index) for code in self.program.files for op in code.ops
                   for t in (op.call, *op.case_targets) if t is not None and not t.is_module and t.file >= 0}
        bodies = RoutineBodies.of(self.program)
        for entry in entries:
            f, start = entry
            ops = self.program.files[f].ops
            written: set[Cell] | None = set()
            called: set[tuple[int, int]] = set()
            for i in bodies(CallTarget(file=f, index=start)):
                op = ops[i]
                cell, others = self.written_by(f, i, op)
                if others is None:
                    written = None
                elif written is not None:
                    written |= others | ({cell} if cell else set())
                if op.code in _CALLS:
                    called |= {(t.file, t.index) for t in (op.call, *op.case_targets)
                               if t is not None and not t.is_module and t.file >= 0}
            direct[entry], calls[entry] = written, called
        total = dict(direct)
        changed = True
        while changed:
            changed = False
            for entry, called in calls.items():
                acc = total[entry]
                for other in called:
                    more = total.get(other, None)
                    if acc is None:
                        break
                    acc = None if more is None else acc | more
                if acc != total[entry]:
                    total[entry] = acc
                    changed = True
        return total

    # ------------------------------------------------------------------------------------ the first cycle

    def first_cycle(self) -> set[Cell]:
        """The cells the first cycle writes before anything reads them, on every path: their power-on value (0, or
        what a scenario's `initial` set) is never seen. The main program is followed from its start with every call
        inlined, the first-cycle marker 1 (the NC sets it in cycle 0 only, unless the program writes it) and every
        cell at its power-on value; a read of a cell that may not have been written yet (or of bytes it shares)
        shows its power-on value. Nothing is claimed where the pass gives up (too deep, too long, no way out)."""
        first = self.program.semantics["first_cycle_marker"]
        facts: frozenset = frozenset()
        if first is not None and not any(self.may_write_bit(f, i, op, ("M", int(first))) for f, i, op in self.ops):
            facts = frozenset({(("M", int(first)), None, None, None, 1)})
        start = {c: None if any(b in self.dirty or b in self.outside for b in _bytes(c)) else frozenset({0})
                 for c in self.cells}
        exposed: set[Cell] = set()
        budget = [_FIRST_CYCLE_VISITS]
        try:
            end = self.inline(0, 0, _Flow({}, None, facts, frozenset(self.cells)), start, exposed, budget, 0)
        except _GiveUp:
            return set()
        if end is None:
            return set()
        return self.cells - exposed - end.fresh

    def may_write_bit(self, f: int, i: int, op: Op, bit: tuple[str, int]) -> bool:
        """Whether op i may write the bit operand `bit` (by name, through the index register, a call of a module)."""
        o = op.operand
        if op.code in _CALLS and op.call is not None and op.call.is_module:
            return bit in implicit_writes(op, self.interface, self.flag)
        if bit in implicit_writes(op, self.interface, self.flag):
            return True
        if op.code not in _BIT_WRITERS or o is None or o.kind != bit[0]:
            return False
        width = max(op.nbits, 1) if op.code == "STBITS" else 1
        if not o.indexed:
            return o.addr <= bit[1] < o.addr + width
        x = self.ranges.get((f, i))
        return x is None or o.addr + x[0] <= bit[1] < o.addr + x[1] + width

    def inline(self, f: int, start: int, flow: _Flow, entry: dict[Cell, Values], exposed: set[Cell],
               budget: list[int], depth: int) -> _Flow | None:
        """The state at the routine's end (joined over its ways out) when it is entered at ops[start] with `flow`;
        None where no way out is found. Reads of fresh cells go to `exposed`."""
        if depth > _FIRST_CYCLE_DEPTH:
            raise _GiveUp
        ops = self.program.files[f].ops
        local: dict[int, _Flow] = {start: flow}
        pending = {start}
        out: _Flow | None = None

        def join(a: _Flow | None, b: _Flow | None) -> _Flow | None:
            return b if a is None else a if b is None else self.join(a, b, entry)
        while pending:
            budget[0] -= 1
            if budget[0] < 0:
                raise _GiveUp
            i = min(pending)
            pending.discard(i)
            if not 0 <= i < len(ops):
                continue                    # off the end of the file: a fault, the machine stops
            state = local[i]
            op = ops[i]
            c = op.code
            self.expose(f, i, op, state, exposed)
            nexts: list[tuple[int, _Flow | None]]
            if c == "EM":
                out = join(out, state)
                continue
            if c in ("JPT", "JPF", "EMT", "EMF"):
                on_true, on_false = self.narrow(f, i, state, entry)
                go, stay = (on_true, on_false) if c in ("JPT", "EMT") else (on_false, on_true)
                if c in ("EMT", "EMF"):
                    out = join(out, go)
                    nexts = [(i + 1, stay)]
                else:
                    nexts = [(op.target, go), (i + 1, stay)]
            elif c in _CALLS and not (op.call is not None and op.call.is_module):
                if c in ("CALLT", "CALLF"):
                    on_true, on_false = self.narrow(f, i, state, entry)
                    called, skipped = (on_true, on_false) if c == "CALLT" else (on_false, on_true)
                else:
                    called, skipped = state, (state if c == "CASE" else None)   # a CASE selector out of range
                after = skipped
                if called is not None:
                    for t in (op.call, *op.case_targets):
                        if t is not None and not t.is_module and t.file >= 0:
                            after = join(after, self.inline(t.file, t.index, called, entry, exposed, budget,
                                                            depth + 1))
                nexts = [(i + 1, after)]
            else:
                after = dataclasses.replace(self.step(f, i, op, state, entry, {}), fresh=self.unfresh(op, state.fresh))
                nexts = [(op.target if c == "JP" else i + 1, after)]
            for j, new in nexts:
                if new is None:
                    continue
                old = local.get(j)
                merged = new if old is None else self.join(old, new, entry)
                if old is None or merged != old:
                    local[j] = merged
                    pending.add(j)
        return out

    def expose(self, f: int, i: int, op: Op, state: _Flow, exposed: set[Cell]) -> None:
        """The fresh cells op i reads (or reads bytes of)."""
        if not state.fresh:
            return
        o = op.operand
        if op.code in _CALLS and op.call is not None and op.call.is_module:
            if writes_anywhere(op.call.module):
                exposed.update(state.fresh)
            return
        if o is None or o.kind not in _BITS or op.code in ("WST", "POP"):
            return
        size = BYTES[o.kind]
        if o.indexed:
            x = self.ranges.get((f, i))
            if x is None:
                exposed.update(state.fresh)
                return
            step = size if self.scale else 1
            lo, hi = o.addr + x[0] * step, o.addr + x[1] * step + size
        else:
            lo, hi = o.addr, o.addr + size
        exposed.update(self.overlapping(lo, hi) & state.fresh)

    def unfresh(self, op: Op, fresh: frozenset) -> frozenset:
        """`fresh` after op: a store by name writes every cell whose bytes it covers."""
        o = op.operand
        if not fresh or op.code not in _MEM_WRITERS or o is None or o.kind not in _BITS or o.indexed:
            return fresh
        lo, hi = o.addr, o.addr + BYTES[o.kind]
        return fresh - {c for c in self.overlapping(lo, hi) if lo <= c[1] and c[1] + BYTES[c[0]] <= hi}

    # ------------------------------------------------------------------------------------ value conversions

    def load(self, cell: Cell, pattern: int) -> int:
        bits = _BITS[cell[0]]
        return pattern if self.zero_load and bits < 32 else sext(pattern, bits)

    def read(self, cell: Cell, pattern: int) -> int:
        """The value of a word as a compare's own operand (sign-extended, signed compares)."""
        return sext(pattern, _BITS[cell[0]])

    def store(self, cell: Cell, wa: int) -> int:
        bits = _BITS[cell[0]]
        if self.saturate and bits < 32:
            return saturate(wa, bits)
        return wa & ((1 << bits) - 1)

    # ------------------------------------------------------------------------------------ the fixpoint

    def run(self) -> tuple[dict[tuple[int, int], _Flow], dict[Cell, Values], dict[Cell, list[str]],
                           dict[Cell, Values]]:
        """(state before each op, what the program stores per cell (None: any), the stores' spans, entry values)."""
        stored: dict[Cell, Values] = {c: frozenset() for c in self.cells}
        for c in self.cells:
            if any(b in self.outside for b in _bytes(c)):
                stored[c] = None
        cleared = self.first_cycle()
        self.start = {c: frozenset() if c in cleared else None if any(b in self.dirty for b in _bytes(c))
                      else frozenset({0}) for c in self.cells}
        while True:
            entry = {c: None if v is None else _union(v, self.start[c]) for c, v in stored.items()}
            before: dict[tuple[int, int], _Flow] = {}
            found: dict[Cell, Values] = dict(stored)
            writes: dict[Cell, list[str]] = {}
            for f, code in enumerate(self.program.files):
                self._file(f, entry, stored, before)
            for f, i, op in self.ops:
                flow = before.get((f, i))
                cell, others = self.written_by(f, i, op)
                if flow is None and (f, i) not in self.linked and cell is not None and others is not None:
                    # no jump or call leads to it: a store of anything, to be safe (a store the values found so far
                    # do not reach yet counts once they do)
                    others, cell = others | {cell}, None
                elif flow is None:
                    continue
                if others is None:
                    found = {c: None for c in found}
                    continue
                for c in others:
                    found[c] = None
                if cell is not None:
                    found[cell] = _union(found[cell], self.stored_values(f, i, op, cell, flow.wa))
                    pulled = f" ({self.pulled_from(f, i)})" if op.code == "POP" else ""
                    writes.setdefault(cell, []).append(f"{op.span}{pulled}")
            if found == stored:
                return before, stored, writes, entry
            stored = {c: _union(stored[c], found[c]) for c in self.cells}

    def _file(self, f: int, entry: dict[Cell, Values], stored: dict[Cell, Values],
              before: dict[tuple[int, int], _Flow]) -> None:
        ops = self.program.files[f].ops
        if not ops:
            return
        starts = {0} | {t.index for code in self.program.files for op in code.ops
                        for t in (op.call, *op.case_targets) if t is not None and not t.is_module and t.file == f}
        local: dict[int, _Flow] = {}
        pending: set[int] = set()
        for s in starts:
            if 0 <= s < len(ops):
                local[s] = _Flow({}, None, frozenset())
                pending.add(s)
        while pending:
            i = min(pending)
            pending.discard(i)
            for j, flow in self.successors(f, i, ops[i], local[i], entry, stored):
                if flow is None or not 0 <= j < len(ops):
                    continue
                old = local.get(j)
                new = flow if old is None else self.join(old, flow, entry)
                if old is None or new != old:
                    local[j] = new
                    pending.add(j)
        before.update({(f, i): flow for i, flow in local.items()})

    def get(self, flow: _Flow, cell: Cell, entry: dict[Cell, Values]) -> tuple[Values, frozenset[str]]:
        return flow.cells.get(cell, (entry[cell], frozenset()))

    def join(self, a: _Flow, b: _Flow, entry: dict[Cell, Values]) -> _Flow:
        cells = {}
        for cell in a.cells.keys() | b.cells.keys():
            va, na = self.get(a, cell, entry)
            vb, nb = self.get(b, cell, entry)
            cells[cell] = (_union(va, vb), na | nb)
        wa = None if a.wa is None or b.wa is None else _union(a.wa, b.wa)
        return _Flow(cells, wa, a.facts & b.facts, a.fresh | b.fresh)

    def successors(self, f: int, i: int, op: Op, flow: _Flow, entry: dict[Cell, Values],
                   stored: dict[Cell, Values]) -> list[tuple[int, _Flow | None]]:
        c = op.code
        if c == "EM":
            return []
        if c in ("JPT", "JPF", "EMT", "EMF"):
            on_true, on_false = self.narrow(f, i, flow, entry)
            go, stay = (on_true, on_false) if c in ("JPT", "EMT") else (on_false, on_true)
            if c in ("EMT", "EMF"):
                return [(i + 1, stay)]
            return [(op.target, go), (i + 1, stay)]
        after = self.step(f, i, op, flow, entry, stored)
        if c == "JP":
            return [(op.target, after)]
        return [(i + 1, after)]

    def literals(self, f: int, i: int) -> tuple[list[tuple], str] | None:
        """The chain that gives LA at op i as its literals and gate: ([("cmp", cell, rel, k, True) or ("bit", kind,
        addr, positive)], "and" / "or"); None where it is no single compare and no plain AND or OR of named
        bits and compares (entered from elsewhere in between, brackets, other ops)."""
        ops = self.program.files[f].ops
        found: list[tuple] = []
        gates: set[str] = set()
        j = i - 1
        while j >= 0:
            op = ops[j]
            o = op.operand
            if self.entered(f, j + 1):
                return None
            if op.code in ("AND", "ANDN", "OR", "ORN") and o is not None and o.is_bit and not o.indexed:
                found.append(("bit", o.kind, o.addr, not op.code.endswith("N")))
                gates.add("and" if op.code.startswith("AND") else "or")
                j -= 1
                continue
            if op.code in ("LD", "LDN") and o is not None and o.is_bit and not o.indexed:
                found.append(("bit", o.kind, o.addr, op.code == "LD"))
                break
            if op.code == "CMP" and o is not None and o.kind == "K" and j > 0 and not self.entered(f, j):
                load = ops[j - 1]
                w = load.operand
                if load.code == "WLD" and w is not None and w.kind in _BITS and not w.indexed:
                    found.append(("cmp", (w.kind, w.addr), op.rel, _int32(o.addr), True))
                    break
            return None
        if j < 0 or len(gates) > 1:
            return None
        return found, gates.pop() if gates else "and"

    def narrow(self, f: int, i: int, flow: _Flow, entry: dict[Cell, Values]) -> tuple[_Flow | None, _Flow | None]:
        """The states where LA is 1 and where it is 0 at the conditional op i: where LA is an AND of literals, each
        is true where LA is 1; of an OR, each is false where it is 0. A compare of a named word with a constant
        keeps the word's values that give it that result, and so does a marker assigned from such a compare
        (_Flow.facts) that nothing has written since."""
        chain = self.literals(f, i) if self.refine else None
        if chain is None:
            return flow, flow
        literals, gate = chain
        where = str(self.program.files[f].ops[i].span)
        out: list[_Flow | None] = []
        for la in (1, 0):
            if (gate == "and") != (la == 1) and len(literals) > 1:
                out.append(flow)
                continue
            state: _Flow | None = flow
            for lit in literals:
                if state is None:
                    break
                if lit[0] == "cmp":
                    _, cell, rel, k, _ = lit
                    state = self.keep(state, cell, rel, k, la == 1, where, entry)
                    continue
                _, kind, addr, positive = lit
                bit = la if positive else 1 - la
                for marker, cell, rel, k, same in state.facts:
                    if marker != (kind, addr) or state is None:
                        continue
                    if cell is None:
                        state = state if bit == same else None
                    else:
                        state = self.keep(state, cell, rel, k, (bit == 1) == same, where, entry)
            out.append(state)
        return out[0], out[1]

    def keep(self, flow: _Flow, cell: Cell, rel: str, k: int, outcome: bool, where: str,
             entry: dict[Cell, Values]) -> _Flow | None:
        """`flow` where `load(cell) rel k` is `outcome` (None: nowhere)."""
        values, narrowed = self.get(flow, cell, entry)
        if values is None:
            return flow
        test = _RELATIONS[rel]
        kept = frozenset(p for p in values if test(self.load(cell, p), k) == outcome)
        if not kept:
            return None
        if kept == values:
            return flow
        return dataclasses.replace(flow, cells={**flow.cells, cell: (kept, narrowed | {where})})

    def entered(self, f: int, i: int) -> bool:
        """Whether op i of file f can be reached other than from op i-1."""
        return (f, i) in self.entries

    def step(self, f: int, i: int, op: Op, flow: _Flow, entry: dict[Cell, Values],
             stored: dict[Cell, Values]) -> _Flow:
        c = op.code
        o = op.operand
        cells = flow.cells
        wa = flow.wa
        facts = flow.facts
        cell, others = self.written_by(f, i, op)
        if others is None:
            cells = {k: (None, frozenset()) for k in self.cells}
            facts = frozenset()
        elif others or cell is not None:
            cells = dict(cells)
            for k in others:
                cells[k] = (None, frozenset())
            if cell is not None:
                cells[cell] = (self.stored_values(f, i, op, cell, wa), frozenset())
            changed = others | {cell}
            facts = frozenset(fact for fact in facts if fact[1] not in changed)
        facts = self.facts_after(f, i, op, facts)
        if c in _CALLS and op.call is not None and not op.call.is_module or c == "CASE":
            reached: set[Cell] | None = set()
            for t in (op.call, *op.case_targets):
                if t is None or t.is_module or t.file < 0:
                    continue
                more = self.callees.get((t.file, t.index))
                reached = None if reached is None or more is None else reached | more
            cells = dict(cells)
            for k in (self.cells if reached is None else reached):
                values, narrowed = self.get(flow, k, entry)
                cells[k] = (_union(values, stored[k]), narrowed)
            return _Flow(cells, None, frozenset())
        if c == "WLD":
            if o.kind == "K":
                return _Flow(cells, frozenset({_int32(o.addr)}), facts)
            if o.kind in _BITS and not o.indexed:
                values, _ = self.get(_Flow(cells, None, facts), (o.kind, o.addr), entry)
                loaded = None if values is None else frozenset(self.load((o.kind, o.addr), p) for p in values)
                return _Flow(cells, loaded, facts)
            return _Flow(cells, None, facts)
        if c in ("ADD", "SUB", "INCW", "DECW"):
            if c in ("INCW", "DECW"):
                d = 1 if c == "INCW" else -1
            elif o is not None and o.kind == "K":
                d = _int32(o.addr) if c == "ADD" else -_int32(o.addr)
            else:
                return _Flow(cells, None, facts)
            return _Flow(cells, None if wa is None else frozenset(_int32(v + d) for v in wa), facts)
        if c == "WAND" and o is not None and o.kind == "K":
            return _Flow(cells, _masked(wa, _int32(o.addr)), facts)
        if c in ("MUL", "DIV", "MOD"):
            return _Flow(cells, self.times_constant(c, o, wa), facts)
        if c == "RPLY":
            return _Flow(cells, self.replies(f, i), facts)
        if c in _KEEP_WA or (c in _LOGIC and not self.shared):
            return _Flow(cells, wa, facts)
        return _Flow(cells, None, facts)

    def times_constant(self, c: str, o, wa: frozenset | None) -> frozenset | None:
        """WA after `x`, `/` or `MOD` of a constant (`L W10` `x K2`), each known value worked out as the interpreter
        works it out (A-10: an overflowing product wraps or leaves WA; A-11/A-12: divide, remainder); None (any) where
        WA or the operand is not known."""
        if wa is None or o is None or o.kind != "K" or o.indexed:
            return None
        k = _int32(o.addr)
        sem = self.program.semantics
        if c == "MUL":
            keep = sem["mul_overflow_result"] == "unchanged"
            return frozenset(v if keep and _int32(v * k) != v * k else _int32(v * k) for v in wa)
        work = divide if c == "DIV" else remainder
        floor, flag = sem["div_semantics"] == "floor", 1 if sem["div_min_by_minus_one"] == "flag" else 0
        return frozenset(work(v, k, floor, flag)[0] for v in wa)

    def replies(self, f: int, i: int) -> frozenset:
        """WA after the RPLY at op i: its states (0 finished or unknown, 1 running, 2 waiting), without 1 where no
        submitted job reaches the op: a job is running only while its own code (and what it calls) runs, so RPLY
        elsewhere never finds the job it asks about running."""
        states = frozenset(REPLY_STATES)
        return states if (f, i) in self.contexts[1] else states - {REPLY_STATES[1]}

    def facts_after(self, f: int, i: int, op: Op, facts: frozenset) -> frozenset:
        """The marker facts after op i: a write of a bit forgets what was known of it (a call or module call, an
        indexed write or a write of unknown bits: everything), `= M` right after a compare of a named word with a
        constant (and other `=` of the same result) knows M from then on."""
        c = op.code
        o = op.operand
        if c in _CALLS or c in ("SUBM", "KFIELD"):
            return frozenset()
        written: set[tuple[str, int]] = set(implicit_writes(op, self.interface, self.flag))
        if c in _BIT_WRITERS and o is not None and o.is_bit:
            if o.indexed:
                return frozenset()
            width = op.nbits if c == "STBITS" else 1
            written |= {(o.kind, a) for a in range(o.addr, o.addr + width)}
        if written:
            facts = frozenset(fact for fact in facts if fact[0] not in written)
        if c in ("ST", "STN") and o is not None and o.kind == "M" and not o.indexed:
            ops = self.program.files[f].ops
            j = i - 1
            while j >= 0 and ops[j].code in ("ST", "STN") and not self.entered(f, j + 1):
                j -= 1
            chain = self.literals(f, j + 1) if j >= 0 and not self.entered(f, j + 1) else None
            if chain is not None and len(chain[0]) == 1 and chain[0][0][0] == "cmp":
                _, cell, rel, k, _ = chain[0][0]
                facts = facts | {((o.kind, o.addr), cell, rel, k, c == "ST")}
        return facts


def word_values(program: Program, compares: Iterable[Compare], driven: set[tuple[str, int]] = frozenset(),
                power_on: set[tuple[str, int]] = frozenset()) -> WordValues:
    """What each compare of a named word with a constant in `compares` can see (see the module docstring); `driven`:
    the operands scenarios set, `power_on`: those of them set only before cycle 0."""
    if program.semantics["compare_signedness"] == "unsigned":
        return WordValues({})       # the compare sees bit patterns, not the values followed here
    analysis = _Analysis(program, set(driven), set(power_on) & set(driven))
    before, stored, writes, entry = analysis.run()
    held: dict[tuple[int, int], Held] = {}
    for cmp in compares:
        if cmp.constant is None or cmp.constants_only:
            continue
        ops = program.files[cmp.file].ops
        word = ops[cmp.index].operand if cmp.constant_left else ops[cmp.index - 1].operand
        if not cmp.constant_left and ops[cmp.index - 1].code != "WLD":
            # WA computed before the compare (`L W1032` `A K15` `== K0`): the values the flow gives it
            flow = before.get(cmp.key)
            if flow is not None and flow.wa is not None and not analysis.shared:
                held[cmp.key] = Held("WA", flow.wa, flow.wa, (), (), 0, _reply_note(ops[cmp.index - 1], flow.wa))
            continue
        if word is None or word.kind not in _BITS or word.indexed:
            continue
        bits = _BITS[word.kind]
        if cmp.constant_left and not -(1 << (bits - 1)) <= cmp.constant < 1 << (bits - 1):
            continue        # `L K256` `== B2` compares the constant's low byte, sign-extended: not c itself
        flow = before.get(cmp.key)
        if flow is None:
            continue
        cell = (word.kind, word.addr)
        values, narrowed = analysis.get(flow, cell, entry)
        if values is None or stored[cell] is None:
            continue
        read = analysis.read if cmp.constant_left else analysis.load
        held[cmp.key] = Held(word.display(), frozenset(read(cell, p) for p in values),
                             frozenset(read(cell, p) for p in stored[cell]), tuple(writes.get(cell, ())),
                             tuple(sorted(narrowed)), 0 if analysis.start[cell] else None)
    return WordValues(held)


def _reply_note(op: Op, wa: frozenset) -> str:
    """Why WA holds only `wa` right after `op` where `op` is a RPLY (the Held.note), else ""."""
    if op.code != "RPLY":
        return ""
    if REPLY_STATES[1] in wa:
        return "RPLY gives only 0 (finished or unknown), 1 (running) or 2 (waiting)"
    return ("RPLY gives only 0 (finished or unknown), 1 (running) or 2 (waiting), and 1 only inside the job it asks "
            "about: no submitted job (nor anything one calls) reaches this RPLY, so it runs while no job does")
