"""Translates the IR program ONCE into Python source (one function per file, a block dispatch loop inside) and compiles it.

Op codes handled (the `code` field of ir.Op, as lowered by transpiler/frontend/resolve.py):
  logic     LD LDN AND ANDN OR ORN XOR XORN ST STN SET RES SETN RESN NOTL
  word      WLD WLDN WNEG LDBITS WST STBITS WAND WANDN WOR WORN WXOR WXORN ADD SUB MUL DIV MOD CMP
            SHL SHR BS BC BT INCW DECW TWOC NOTW INC DEC INCX DECX
  brackets  BOPEN BCLOSE (static frames: brackets never span control flow, A-59)
  stack     PUSH POP PSW PLW PSL PLL PSX PLX
  control   JP JPT JPF CALL CALLT CALLF EM EMT EMF CASE NOP LBL KFIELD
  strings   SLD SCAT SST SCMP
  jobs      SUBM RPLY CAN

Design (why it is fast): LA, WA, X, SA, the instruction counter n and the call depth d are cells
shared by all generated functions, so they behave like CPU registers; memory is accessed through
bytearrays and native memoryview casts with constant addresses folded in. Each file is one
function `F<f>(b)`: `b` selects the block (a jump target or call entry) through a binary dispatch
tree whose leaves are short runs of sequential `if b == k` tests, so falling through into the
next block costs one comparison, and so does a jump to a later block of the same leaf (the rest of
the jumping block becomes an else branch); a loop head starts a leaf, and a test that always holds
(b can hold no other value there, _untested_blocks) is left out. The fast variant counts instructions per
straight-line stretch (a pre-count that may only over-estimate) and checks the count where
execution can come round again (a jump back, a call) and before module calls, folds runs of bit
logic into one expression of LA and checks a run of pushes against the stack capacity once; the
exact variant counts and checks every instruction. Either can record coverage, with one list item
store per mark (coverage.CoverageMarks). Every generated line maps back to its op, so a fault
raised anywhere below a line is located from the traceback at no run-time cost.
"""

from __future__ import annotations

import bisect
import dataclasses
import sys
import types
from typing import Callable

from transpiler.exec.interp.decisions import decision_table
from transpiler.exec.interp.gen_access import CHAIN_OPS, AccessCode
from transpiler.exec.interp.gen_flow import FlowCode
from transpiler.exec.interp.gen_stack import StackStringCode
from transpiler.exec.interp.gen_word import WordCode
from transpiler.exec.interp.state import every_address_valid, space_size
from transpiler.ir import FileCode, Op, Program
from transpiler.language.semantics import Semantics

GENERATED_FILENAME = "<hh2iec-interp>"
_GROUP = 16                     # blocks per leaf of the dispatch tree (at most)
_MAX_INDENT = 60                # deepest nesting of generated code (the tokenizer allows 100 levels)
_EXITS_COND = frozenset({"JPT", "JPF", "EMT", "EMF"})
_EXITS_UNCOND = frozenset({"JP", "EM"})
_NOT_COUNTED = frozenset({"LBL", "KFIELD"})
_CONDITIONAL = frozenset({"JPT", "JPF", "CALLT", "CALLF", "EMT", "EMF"})


def counts_as_instruction(op: Op) -> bool:
    """Labels (and never-executed KFIELD tables) do not count towards the watchdog budget (17b.11)."""
    return op.code not in _NOT_COUNTED


@dataclasses.dataclass(frozen=True)
class CompiledProgram:
    """Generated source and code object of one program variant, plus the maps back to the IR."""

    source: str
    code: types.CodeType
    line_ops: tuple[int, ...]                       # generated line number - 1 -> op id, or -1
    op_index: tuple[tuple[int, int], ...]           # op id -> (file index, op index)
    exact: bool
    coverage: bool
    # Coverage marks (see CoverageMarks): branch slot -> (op id, outcome), the same in every variant of a program;
    # branch slot -> op ids its mark also shows as executed; stretch mark -> the op ids it stands for.
    branch_slots: tuple[tuple[int, int], ...] = ()
    branch_ops: tuple[tuple[int, ...], ...] = ()
    stretch_ops: tuple[tuple[int, ...], ...] = ()
    # Value-profile slots (compiled with value_profile only, see value_slots): bit gates, divisors.
    value_slots: tuple[tuple[int, int], ...] = ()
    # With coverage: boundary slots of the word compares (boundary_slots) and how many decisions record their
    # condition vectors (decisions.decision_table; a vector is recorded as decision + (vector << decision_shift)).
    bound_slots: tuple[tuple[int, int], ...] = ()
    decision_ops: tuple[int, ...] = ()             # decision number -> op id of its consumer

    @property
    def decision_count(self) -> int:
        return len(self.decision_ops)

    @property
    def decision_shift(self) -> int:
        return decision_shift(self.decision_count)

    def make(self, env: dict[str, object]) -> tuple[tuple[Callable[[int], None], ...], Callable, Callable]:
        """Instantiate against a machine: (file functions, get_registers, set_registers)."""
        namespace: dict[str, object] = {"__builtins__": __builtins__}
        exec(self.code, namespace)  # noqa: S102 - our own generated source
        return namespace["_factory"](env)  # type: ignore[operator]

    def op_of_line(self, lineno: int) -> int:
        return self.line_ops[lineno - 1] if 0 < lineno <= len(self.line_ops) else -1


def decision_shift(count: int) -> int:
    """Bits of a recorded condition vector's key that number its decision (the vector is shifted past them): the
    generated code packs, CoverageMarks unpacks, both with this."""
    return max(1, count).bit_length()


def compile_program(program: Program, *, exact: bool | None = None, coverage: bool = False,
                    value_profile: bool = False) -> CompiledProgram:
    """Generate and compile the program: `exact` counts every instruction, `coverage` records ops and branches.
    `exact` defaults to `coverage`. Coverage is exact in either variant: with exact=False the ops of a straight-line
    stretch are marked together when it ends and the watchdog budget is pre-counted, and the machine re-runs a cycle
    that overruns or faults with an exact variant that also records coverage (Machine.program_phase), so coverage
    costs little more than the fast variant.

    With coverage the code also marks each word compare whose operands come out one apart or equal (boundary_slots),
    and records the distinct vectors of condition values and outcome of every decision (decisions.py, MC/DC); bit
    logic is then not folded into one expression per run, each condition is read into a local of its own.

    `value_profile` (with coverage) also marks each pair of values a bit gate combines, each zero or non-zero
    divisor and each entry of a constant table read (see value_slots): a stimulus search counts those as features
    of their own, since a mutated gate, divisor or index differs from the original only there. The exact re-run of
    a cycle does not mark them."""
    if exact is None:
        exact = coverage
    # Native memoryview casts when the host byte order is the profile's, struct calls otherwise.
    native = (sys.byteorder == "little") == program.semantics.little_endian
    gen = _Generator(program, exact=exact, coverage=coverage, native=native, value_profile=value_profile and coverage)
    source = gen.generate()
    code = compile(source, GENERATED_FILENAME, "exec")
    branch_ops = tuple(gen.branch_ops.get(opid, ()) for opid, _ in gen.branch_slots)
    return CompiledProgram(source, code, tuple(gen.line_ops), tuple(gen.op_index), exact, coverage,
                           tuple(gen.branch_slots), branch_ops, tuple(gen.stretch_ops), tuple(gen.value_slots),
                           tuple(gen.bound_slots), tuple(gen.decision_ops))


def branch_slots(program: Program) -> list[tuple[int, int]]:
    """Every (op id, outcome) that coverage records, in op order: 1 and 0 of each conditional jump, call and module
    end, then each entry of a CASE followed by its -1 (no entry). A CASE's entry slots are consecutive so that the
    generated code finds the slot of entry s by adding s."""
    slots: list[tuple[int, int]] = []
    opid = 0
    for code in program.files:
        for op in code.ops:
            if op.code in _CONDITIONAL:
                slots += [(opid, 1), (opid, 0)]
            elif op.code == "CASE":
                slots += [(opid, entry) for entry in range(len(op.case_targets))] + [(opid, -1)]
            opid += 1
    return slots


_GATES = frozenset({"AND", "ANDN", "OR", "ORN"})
_LA_CONDITIONS = frozenset({"CMP", "SCMP", "BT", "PLL", "BCLOSE"})    # conditions whose value is the LA they make


def boundary_slots(program: Program) -> list[tuple[int, int]]:
    """The boundary slots in op order: (op id, left - right) for -1, 0 and 1 of every word compare (the generated
    code finds the slot of a difference d by adding d + 1 to the first)."""
    slots: list[tuple[int, int]] = []
    opid = 0
    for code in program.files:
        for op in code.ops:
            if op.code == "CMP":
                slots += [(opid, -1), (opid, 0), (opid, 1)]
            opid += 1
    return slots


def value_slots(program: Program) -> list[tuple[int, int]]:
    """The value profile's slots in op order: (op id, LA) for LA 0 and 1 of every AND/OR gate whose operand differs
    from LA (an AND that became an OR differs only there), (op id, divisor != 0) of every DIV and MOD (the
    translation checks the divisor where the original has no branch), and (op id, X) of every entry X of a constant
    table (KF) an op reads (a mutated index or table differs only in the entries read). Word compares have
    boundary_slots."""
    slots: list[tuple[int, int]] = []
    opid = 0
    for code in program.files:
        for op in code.ops:
            if op.code in _GATES or op.code in ("DIV", "MOD"):
                slots += [(opid, 0), (opid, 1)]
            elif op.operand is not None and op.operand.kind == "KF" and op.operand.kfield:
                slots += [(opid, entry) for entry in range(len(op.operand.kfield))]
            opid += 1
    return slots


def _entries(program: Program) -> tuple[list[set[int]], list[set[int]]]:
    """Block starts per file: every jump target, and the entries a call enters by (the main entry, every
    call/CASE/SUBM target); (starts, entries)."""
    starts: list[set[int]] = [set() for _ in program.files]
    entries: list[set[int]] = [set() for _ in program.files]
    if program.files and program.files[0].ops:
        entries[0].add(0)
    for f, code in enumerate(program.files):
        for op in code.ops:
            if op.code in ("JP", "JPT", "JPF") and op.target is not None:
                starts[f].add(op.target)
            if op.call is not None and not op.call.is_module and op.call.file >= 0:
                entries[op.call.file].add(op.call.index)
            for t in op.case_targets:
                if t is not None and t.file >= 0:
                    entries[t.file].add(t.index)
    return [s | e for s, e in zip(starts, entries)], entries


def _untested_blocks(code: FileCode, seg_of: dict[int, int], entries: set[int], groups: list[list[int]],
                     leaf_of: dict[int, int]) -> tuple[set[int], set[int]]:
    """(blocks whose `if b == k` test can go, blocks the dispatch loop may be entered with) of one file, given its
    block starts (`seg_of`: op index -> block) and dispatch leaves (`groups`, and `leaf_of`: block -> leaf).

    The tests of a leaf run in order, so the values b can hold at the test of block k are known: at the leaf's top
    the blocks of the leaf the dispatch loop enters (entries, targets of jumps that go round the loop, the first
    block of every leaf), then after each block the values before it except its own plus the later blocks of the
    leaf it falls or jumps to. Where that is k alone, the test always holds and block k's code runs unconditionally.
    """
    falls: list[set[int]] = [set() for _ in seg_of]
    dispatched = {seg_of[e] for e in entries if e in seg_of} | {group[0] for group in groups}
    k = -1
    for i, op in enumerate(code.ops):
        k = seg_of.get(i, k)
        if k < 0 or op.code not in ("JP", "JPT", "JPF") or op.target not in seg_of:
            continue
        target = seg_of[op.target]
        if k < target and leaf_of[target] == leaf_of[k]:
            falls[k].add(target)
        else:
            dispatched.add(target)
    untested = set()
    for group in groups:
        possible = dispatched.intersection(group)
        for k in group:
            if possible == {k}:
                untested.add(k)
            possible.discard(k)
            possible |= falls[k]
            if k + 1 in leaf_of and leaf_of[k + 1] == leaf_of[k]:
                possible.add(k + 1)
    return untested, dispatched


class _Generator(AccessCode, WordCode, FlowCode, StackStringCode):
    """Generates the source: output, files, blocks and dispatch here; the code of each op in the mixins
    (gen_access: operands, loads, stores, bit logic; gen_word; gen_flow; gen_stack: data stack, strings)."""

    def __init__(self, program: Program, *, exact: bool, coverage: bool, native: bool, value_profile: bool = False):
        self.program = program
        self.sem: Semantics = program.semantics
        self.itf = self.sem.profile.interface
        self.exact = exact
        self.coverage = coverage
        self.native = native
        self.budget = int(self.sem["max_instructions_per_cycle"])
        self.depth_limit = int(self.sem["call_depth"])
        self.shared = self.sem["accumulator_model"] == "shared_bit7"
        self.x16 = int(self.sem["index_register_width"]) == 16
        self.lines: list[str] = []
        self.line_ops: list[int] = []
        self.op_index: list[tuple[int, int]] = []
        self.op_base: list[int] = []                # file index -> op id of its first op
        self.seg_maps: list[dict[int, int]] = []    # file index -> {op index of a block start: block id}
        self.kf_tables: dict[tuple[int, ...], str] = {}
        self.case_tables: list[str] = []
        self.brackets: list[tuple[Op, str, int]] = []
        self.sizes = {k: space_size(self.sem.profile, k) for k in "MIOTCBWDS"}
        self.every_valid = {k: every_address_valid(self.sem.profile, k) for k in "MIOTCBWD"}
        self.scale = self.sem["index_scaling"] == "elements"
        self.leaf_of: dict[int, int] = {}           # block -> its dispatch leaf, in the file being generated
        self.entries: list[set[int]] = []           # file index -> op indices a call enters by
        self.untested: set[int] = set()             # blocks of the file being generated without `if b == k`
        self.dispatched: set[int] = set()           # blocks of the file the dispatch loop may be entered with
        self.tests_broken = False
        self.max_indent = _MAX_INDENT
        self.block = 0                              # the block being generated
        # Bit logic folds into one expression of LA in the fast variant (gen_access._chain); the exact variant counts
        # and checks every op, and with the shared accumulator LA is a bit of WA.
        self.fuse_la = not exact and not self.shared and not value_profile
        self.la_chain = None
        for f, code in enumerate(program.files):
            self.op_base.append(len(self.op_index))
            self.op_index.extend((f, i) for i in range(len(code.ops)))
        self.bound_slots = boundary_slots(program) if coverage else []
        self.bound_slot = {key: slot for slot, key in enumerate(self.bound_slots)}
        # MC/DC (with coverage): op id of a condition read -> its slot `_q<slot>` in its chain; op id of a decision's
        # consumer -> (decision number, the slots of its conditions in order)
        self.cond_slot: dict[int, int] = {}
        self.record: dict[int, tuple[int, tuple[str, ...]]] = {}
        self.decision_ops: list[int] = []
        if coverage:
            self._decisions(program)
        self.decision_shift = decision_shift(len(self.decision_ops))
        self.branch_slots = branch_slots(program)
        self.branch_slot = {key: slot for slot, key in enumerate(self.branch_slots)}
        self.value_slots = value_slots(program) if value_profile else []
        self.value_slot = {key: slot for slot, key in enumerate(self.value_slots)}
        self.branch_ops: dict[int, tuple[int, ...]] = {}    # op id of a conditional exit -> its stretch's op ids
        self.stretch_ops: list[tuple[int, ...]] = []

    def _decisions(self, program: Program) -> None:
        """The MC/DC recording: per decision, the expressions of its condition values at its consumer. A chain of
        named bit loads and gates alone (the common case) writes nothing between its reads and its consumer, so the
        consumer reads its operands again (and the fast variant still folds it into one expression); any other
        chain reads each condition into a local `_q<slot>` where the condition is evaluated."""
        table = decision_table(program)
        for d in table.decisions:
            ops = program.files[d.file].ops
            base = self.op_base[d.file]
            first = min(c.index for c in d.conditions)
            plain = all(op.code in CHAIN_OPS and not op.operand.indexed for op in ops[first:d.index])
            if plain:
                values = tuple(self.bit(c.operand) for c in d.conditions)
            else:
                slots = table.records[d.key][1]
                values = tuple(f"_q{slot}" for slot in slots)
                for c, slot in zip(d.conditions, slots):
                    self.cond_slot[base + c.index] = slot
            self.record[base + d.index] = (len(self.decision_ops), values)
            self.decision_ops.append(base + d.index)

    # ------------------------------------------------------------------ output

    def out(self, indent: int, text: str, opid: int = -1) -> None:
        if self.la_chain is not None:
            self.flush_la()
        self.lines.append("    " * indent + text)
        self.line_ops.append(opid)

    def generate(self) -> str:
        block_starts, entries = _entries(self.program)
        starts = [sorted(e for e in block_starts[f] if e <= len(code.ops)) for f, code in enumerate(self.program.files)]
        self.seg_maps = [{s: k for k, s in enumerate(st)} for st in starts]
        self.entries = entries
        self.out(0, "def _factory(env):")
        for name in ("M", "I", "O", "T", "C", "mem", "mb", "S", "stk"):
            self.out(1, f"{name} = env[{name!r}]")
        for kind in "MIOTCBWD":
            self.out(1, f"V{kind} = env['valid'][{kind!r}]")
        if self.native:
            for name in ("mw", "mwu", "md", "mdu"):
                self.out(1, f"{name} = env[{name!r}]")
        else:
            for name in ("st_h", "st_H", "st_i", "st_I"):
                self.out(1, f"_u{name[3]} = env[{name!r}].unpack_from")
                self.out(1, f"_p{name[3]} = env[{name!r}].pack_into")
        helpers = ("rb", "wb", "rx", "wx", "packx", "unpackx", "pack", "unpack", "kf", "div", "mod", "shl", "shr",
                   "sat", "overflow", "underflow", "module", "subm", "rply", "can", "scat", "six", "srx",
                   "watchdog", "depth_fault", "case_fault", "falloff", "BudgetExceeded", "hit", "bh", "sh", "vp", "ixw",
                   "bd", "mc")
        for name in helpers:
            self.out(1, f"_{name} = env[{name!r}]")
        self.out(1, "LA = 0; WA = 0; X = 0; SA = ''; n = 0; d = 0; _em = -1")
        for f, code in enumerate(self.program.files):
            self._file(f, code, starts[f])
        # constant tables: cells of the factory, assigned once the functions they name exist
        for values, name in self.kf_tables.items():
            self.out(1, f"{name} = {values!r}")
        for text in self.case_tables:
            self.out(1, text)
        regs = "LA, WA, X, SA, n, d, _em"
        self.out(1, "def _get():")
        self.out(2, f"return {regs}")
        self.out(1, "def _set(la, wa, x, sa, n_, d_, em_):")
        self.out(2, f"nonlocal {regs}")
        self.out(2, "LA = la; WA = wa; X = x; SA = sa; n = n_; d = d_; _em = em_")
        funcs = ", ".join(f"F{f}" for f in range(len(self.program.files)))
        self.out(1, f"return ({funcs},), _get, _set")
        return "\n".join(self.lines) + "\n"

    # ------------------------------------------------------------------ files and blocks

    def _file(self, f: int, code: FileCode, starts: list[int]) -> None:
        self.out(1, f"def F{f}(b):")
        self.out(2, "nonlocal LA, WA, X, SA, n, d, _em")
        if not starts:
            self.out(2, "_falloff()")
            return
        self.out(2, "while True:")
        # Generated without the tests that always hold first; a jump that has to go round the dispatch loop after
        # all (nesting at its cap) may find no test of its target there, so the file is generated again with all.
        rollback = (len(self.lines), len(self.stretch_ops), len(self.case_tables))
        groups = self._leaves(f, code, starts)
        self.leaf_of = {k: leaf for leaf, group in enumerate(groups) for k in group}
        omitted = _untested_blocks(code, self.seg_maps[f], self.entries[f], groups, self.leaf_of)
        for untested, dispatched in (omitted, (set(), set(range(len(starts))))):
            self.untested, self.dispatched, self.tests_broken = untested, dispatched, False
            self._dispatch(f, code, starts, groups, 3)
            if not self.tests_broken:
                return
            del self.lines[rollback[0]:], self.line_ops[rollback[0]:]
            del self.stretch_ops[rollback[1]:], self.case_tables[rollback[2]:]

    def _leaves(self, f: int, code: FileCode, starts: list[int]) -> list[list[int]]:
        """The blocks split into dispatch leaves of at most _GROUP consecutive blocks. A loop head (the target of a
        jump from itself or a later block) starts a leaf: going round the loop then tests it first in its leaf."""
        seg_of = self.seg_maps[f]
        heads = set()
        for i, op in enumerate(code.ops):
            if op.code in ("JP", "JPT", "JPF") and op.target in seg_of:
                target = seg_of[op.target]
                if target <= bisect.bisect_right(starts, i) - 1:
                    heads.add(target)
        leaves: list[list[int]] = []
        for k in range(len(starts)):
            if not leaves or len(leaves[-1]) == _GROUP or k in heads:
                leaves.append([k])
            else:
                leaves[-1].append(k)
        return leaves

    def _dispatch(self, f: int, code: FileCode, starts: list[int], groups: list[list[int]], indent: int) -> None:
        if len(groups) == 1:
            for k in groups[0]:
                if k in self.untested:
                    self._segment(f, code, starts, k, indent)
                else:
                    self.out(indent, f"if b == {k}:")
                    self._segment(f, code, starts, k, indent + 1)
            return
        mid = len(groups) // 2
        self.out(indent, f"if b < {groups[mid][0]}:")
        self._dispatch(f, code, starts, groups[:mid], indent + 1)
        self.out(indent, "else:")
        self._dispatch(f, code, starts, groups[mid:], indent + 1)

    def _segment(self, f: int, code: FileCode, starts: list[int], k: int, indent: int) -> None:
        first = starts[k]
        end = starts[k + 1] if k + 1 < len(starts) else len(code.ops)
        seg_of = self.seg_maps[f]
        base = self.op_base[f]
        self.block = k
        self.brackets = []
        ops = code.ops[first:end]
        if not self.exact:
            self._precount(ops, 0, indent, base + first)
        # The fast variant marks the ops of a straight-line stretch as executed with one store just before its exit
        # (each op on its own in the exact variant): a fault inside the stretch leaves its ops unmarked, so coverage
        # may miss ops of a faulting cycle but never claims an op that did not run. A stretch that ends in a
        # conditional exit needs no store of its own: either branch mark of the exit, set right after the stretch,
        # stands for it (a stretch has one entry, so reaching its exit means all of it ran, in either variant).
        pending: list[int] = []
        run_end = 0                 # the ops before it form a run of pushes (fast variant)
        for offset, op in enumerate(ops):
            opid = base + first + offset
            if counts_as_instruction(op):
                if self.exact:
                    self.out(indent, "n += 1", opid)
                    self.out(indent, f"if n > {self.budget}: _watchdog()", opid)
                if self.coverage:
                    if self.exact:
                        self.out(indent, f"_hit[{opid}] = 1", opid)
                    else:
                        pending.append(opid)
            # CAN may end the running job from inside the stretch (JobCancelled): its marks go first as well
            if pending and op.code in _EXITS_COND:
                self.branch_ops[opid] = tuple(pending)
                pending = []
            elif pending and (op.code in _EXITS_UNCOND or op.code == "CAN"):
                self._mark(indent, pending)
                pending = []
            if not self.exact and offset >= run_end:
                run = self._push_run(ops, offset)
                if run is not None:
                    # one capacity check and one extend for the whole run; without room for all of it, the ops one
                    # by one, so that the push that overflows faults
                    count, words = run
                    self.out(indent, f"if len(stk) <= {int(self.sem['data_stack_words']) - len(words)}: "
                                     f"stk.extend(({', '.join(words)},))", opid)
                    self.out(indent, "else:", opid)
                    run_end = offset + count
            if op.operand is not None and op.operand.kind == "KF" and (opid, 0) in self.value_slot:
                # the value profile: which entry of the table is read (a read outside it faults in the op)
                self.out(indent + (offset < run_end), f"if 0 <= X < {len(op.operand.kfield)}: "
                                                      f"_vp[{self.value_slot[opid, 0]} + X] = 1", opid)
            if offset < run_end:
                self._op(op, opid, f, seg_of, indent + 1)
            else:
                indent = self._op(op, opid, f, seg_of, indent)
            if op.code in _EXITS_UNCOND:
                return                       # the rest of the block is unreachable
            if op.code in _EXITS_COND and not self.exact and offset + 1 < len(ops):
                self._precount(ops, offset + 1, indent, opid + 1)
        if pending:
            self._mark(indent, pending)
        if k + 1 < len(starts):
            self.goto(indent, k + 1)
        else:
            self.out(indent, "_falloff()")

    def goto(self, indent: int, block: int, opid: int = -1) -> None:
        """Select `block`, a later one of the leaf, as the next to run: the next block, if untested, runs anyway."""
        nxt = block == self.block + 1 and block in self.untested and self.leaf_of[block] == self.leaf_of[self.block]
        self.out(indent, "pass" if nxt else f"b = {block}", opid)

    def _mark(self, indent: int, opids: list[int]) -> None:
        """The coverage mark of a stretch: one item store, the stretch's op ids go to the table."""
        self.out(indent, f"_sh[{len(self.stretch_ops)}] = 1", opids[0])
        self.stretch_ops.append(tuple(opids))

    def _precount(self, ops: tuple[Op, ...], start: int, indent: int, opid: int) -> None:
        """Fast variant: count the straight-line instructions up to the next exit once, before running them."""
        count = 0
        for op in ops[start:]:
            count += counts_as_instruction(op)
            if op.code in _EXITS_COND or op.code in _EXITS_UNCOND:
                break
        if count:
            self.out(indent, f"n += {count}", opid)

    def budget_check(self, indent: int, opid: int) -> None:
        """Fast variant: raise to the exact re-run once the pre-count has passed the budget. Checked only where
        execution can come round again (a jump back, a call) and before a module call, whose effects outside the
        machine's state a re-run would not undo; straight-line code between checks is finite, and the machine checks
        the count once more after the cycle (Machine.program_phase)."""
        if not self.exact:
            self.out(indent, f"if n > {self.budget}: raise _BudgetExceeded", opid)
    # ------------------------------------------------------------------ instructions

    def _op(self, op: Op, opid: int, f: int, seg_of: dict[int, int], ind: int) -> int:
        """Generate the op; returns the indentation of the code that follows (deeper after a jump that nests it)."""
        c = op.code
        o = op.operand
        if opid in self.record:
            # MC/DC: the chain's condition values and its outcome (LA), before the consumer acts on it
            number, values = self.record[opid]
            bits = " | ".join([value + (f" << {n}" if n else "") for n, value in enumerate(values)]
                              + [f"{self.la()} << {len(values)}"])
            self.out(ind, f"_mc[({bits}) << {self.decision_shift} | {number}] = 1", opid)
        handler = getattr(self, f"_op_{c}", None)
        if handler is not None:
            follow = handler(op, opid, ind, f, seg_of)
            if opid in self.cond_slot and c in _LA_CONDITIONS:
                self.out(ind, f"_q{self.cond_slot[opid]} = {self.la()}", opid)
            return ind if follow is None else follow
        if c in ("LD", "LDN", "AND", "ANDN", "OR", "ORN", "XOR", "XORN", "ST", "STN", "SET", "RES", "SETN", "RESN"):
            self._bit_logic(c, o, opid, ind)
        elif c in ("WAND", "WANDN", "WOR", "WORN", "WXOR", "WXORN"):
            self._word_gate(c, o, opid, ind)
        elif c in ("ADD", "SUB", "MUL", "DIV", "MOD"):
            self._arith(c, "WA", self.value(o), opid, ind)
        elif c not in ("NOP", "LBL", "KFIELD"):
            raise NotImplementedError(f"interpreter: no code generation for op {c}")
        return ind
