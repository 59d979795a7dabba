"""Translates the IR program ONCE into Python source (one function per file, a block dispatch loop inside) and compiles it.

Op codes handled (the `code` field of ir.Op, as lowered by transpiler/resolve.py):
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
next block costs one comparison. The fast variant counts instructions per straight-line block
(a pre-count that may only over-estimate); the exact variant counts and checks every instruction
and can record coverage. Every generated line maps back to its op, so a fault raised anywhere
below a line is located from the traceback at no run-time cost.
"""

from __future__ import annotations

import dataclasses
import sys
import types
from typing import Callable

from transpiler.ir import FileCode, Op, Operand, Program
from transpiler.language.semantics import Semantics
from transpiler.exec.interp.state import space_size

GENERATED_FILENAME = "<hh2iec-interp>"
_GROUP = 8                      # blocks per leaf of the dispatch tree
_H, _M32 = 2147483648, 4294967295
_REL = {"==": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}
_LOGIC_OPS = ("A", "AN", "O", "ON", "XO", "XON")
_EXITS_COND = frozenset({"JPT", "JPF", "EMT", "EMF"})
_EXITS_UNCOND = frozenset({"JP", "EM"})
_NOT_COUNTED = frozenset({"LBL", "KFIELD"})


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

    def make(self, env: dict[str, object]) -> tuple[tuple[Callable[[int], None], ...], Callable, Callable]:
        """Instantiate against a machine: (file functions, get_registers, set_registers)."""
        namespace: dict[str, object] = {"__builtins__": __builtins__}
        exec(self.code, namespace)  # noqa: S102 - our own generated source
        return namespace["_factory"](env)  # type: ignore[operator]

    def op_of_line(self, lineno: int) -> int:
        return self.line_ops[lineno - 1] if 0 < lineno <= len(self.line_ops) else -1


def compile_program(program: Program, *, exact: bool = False, coverage: bool = False) -> CompiledProgram:
    """Generate and compile the program: `exact` counts every instruction, `coverage` (implies exact) records ops and branches."""
    # Native memoryview casts when the host byte order is the profile's, struct calls otherwise.
    native = (sys.byteorder == "little") == program.semantics.little_endian
    gen = _Generator(program, exact=exact or coverage, coverage=coverage, native=native)
    source = gen.generate()
    code = compile(source, GENERATED_FILENAME, "exec")
    return CompiledProgram(source, code, tuple(gen.line_ops), tuple(gen.op_index), exact or coverage, coverage)


def _entries(program: Program) -> list[set[int]]:
    """Block starts per file: the main entry, every jump target, every call/CASE/SUBM target."""
    entries: list[set[int]] = [set() for _ in program.files]
    if program.files and program.files[0].ops:
        entries[0].add(0)
    for f, code in enumerate(program.files):
        for op in code.ops:
            if op.code in ("JP", "JPT", "JPF") and op.target is not None:
                entries[f].add(op.target)
            if op.call is not None and not op.call.is_module and op.call.file >= 0:
                entries[op.call.file].add(op.call.index)
            for t in op.case_targets:
                if t is not None and t.file >= 0:
                    entries[t.file].add(t.index)
    return entries


class _Generator:
    def __init__(self, program: Program, *, exact: bool, coverage: bool, native: bool):
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
        self.scale = self.sem["index_scaling"] == "elements"
        for f, code in enumerate(program.files):
            self.op_base.append(len(self.op_index))
            self.op_index.extend((f, i) for i in range(len(code.ops)))

    # ------------------------------------------------------------------ output

    def out(self, indent: int, text: str, opid: int = -1) -> None:
        self.lines.append("    " * indent + text)
        self.line_ops.append(opid)

    def generate(self) -> str:
        entries = _entries(self.program)
        starts = [sorted(e for e in entries[f] if e <= len(code.ops)) for f, code in enumerate(self.program.files)]
        self.seg_maps = [{s: k for k, s in enumerate(st)} for st in starts]
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
                   "sat", "ps16", "ps32", "pl16", "pl32", "module", "subm", "rply", "can", "scat", "six", "srx",
                   "watchdog", "depth_fault", "case_fault", "falloff", "BudgetExceeded", "hit", "branch", "ixw")
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
        groups = [list(range(i, min(i + _GROUP, len(starts)))) for i in range(0, len(starts), _GROUP)]
        self._dispatch(f, code, starts, groups, 3)

    def _dispatch(self, f: int, code: FileCode, starts: list[int], groups: list[list[int]], indent: int) -> None:
        if len(groups) == 1:
            for k in groups[0]:
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
        self.brackets = []
        ops = code.ops[first:end]
        if not self.exact:
            self._precount(ops, 0, indent, base + first)
        for offset, op in enumerate(ops):
            opid = base + first + offset
            if counts_as_instruction(op):
                if self.exact:
                    self.out(indent, "n += 1", opid)
                    self.out(indent, f"if n > {self.budget}: _watchdog()", opid)
                if self.coverage:
                    self.out(indent, f"_hit[{opid}] = 1", opid)
            self._op(op, opid, f, seg_of, indent)
            if op.code in _EXITS_UNCOND:
                return                       # the rest of the block is unreachable
            if op.code in _EXITS_COND and not self.exact and offset + 1 < len(ops):
                self._precount(ops, offset + 1, indent, opid + 1)
        if k + 1 < len(starts):
            self.out(indent, f"b = {k + 1}")
        else:
            self.out(indent, "_falloff()")

    def _precount(self, ops: tuple[Op, ...], start: int, indent: int, opid: int) -> None:
        """Fast variant: count the straight-line instructions up to the next exit once, before running them."""
        count = 0
        for op in ops[start:]:
            count += counts_as_instruction(op)
            if op.code in _EXITS_COND or op.code in _EXITS_UNCOND:
                break
        if count:
            self.out(indent, f"n += {count}", opid)
            self.out(indent, f"if n > {self.budget}: raise _BudgetExceeded", opid)

    # ------------------------------------------------------------------ registers

    def la(self) -> str:
        return "((WA >> 7) & 1)" if self.shared else "LA"

    def set_la(self, indent: int, expr: str, opid: int) -> None:
        if self.shared:
            # A-05 shared_bit7: the logic result is bit 7 of WA, the other bits stay.
            self.out(indent, f"WA = (WA & -129) | (({expr}) << 7)", opid)
        else:
            self.out(indent, f"LA = {expr}", opid)

    def x_store(self, expr: str) -> str:
        # Every write of X wraps to its width here (Machine.write too), so reads use X as it is.
        return f"X = (((({expr}) + 32768) & 65535) - 32768)" if self.x16 else f"X = {_norm(expr)}"

    # ------------------------------------------------------------------ operands

    def width(self, o: Operand) -> int:
        if o.kind == "X":
            return 16 if self.x16 else 32
        return {"B": 8, "W": 16}.get(o.kind, 32)

    def _ix(self, o: Operand) -> str:
        """Effective address of an indexed operand (A-21): base + X, W/D scaled by the element size if set."""
        size = {"W": 2, "D": 4}.get(o.kind, 1)
        return f"X * {size} + {o.addr}" if self.scale and size > 1 else f"X + {o.addr}"

    def _ix_ok(self, o: Operand) -> str:
        # The inline test covers the valid case only; the helper raises the fault (or reads 0, A-22).
        return f"0 <= (_a := {self._ix(o)}) < {self.sizes[o.kind]} and V{o.kind}[_a]"

    def bit(self, o: Operand) -> str:
        if o.indexed:
            return f"({o.kind}[_a] if {self._ix_ok(o)} else _rb({o.kind!r}, {o.addr}, X))"
        return f"{o.kind}[{o.addr}]"

    def bit_store(self, indent: int, o: Operand, expr: str, opid: int) -> None:
        if o.indexed:
            # The inline store records its address (Runtime.indexed_writes); the helper records its own.
            self.out(indent, f"if {self._ix_ok(o)}: {o.kind}[_a] = {expr}; _ixw(({o.kind!r}, _a))", opid)
            self.out(indent, f"else: _wb({o.kind!r}, {o.addr}, X, {expr})", opid)
        else:
            self.out(indent, f"{o.kind}[{o.addr}] = {expr}", opid)

    def value(self, o: Operand, ext: str = "sign") -> str:
        """read_val (5.5): ext 'sign' = sign-extended, 'zero' = zero-extended, 'mask' = the low n bits (u = v & m)."""
        k = o.kind
        if k == "K":
            return _signed_literal(_int32(o.addr))
        if k == "KF":
            return f"_kf({self._kf_name(o.kfield)}, X, {o.text!r})"
        if k == "X":
            return "(X & 65535)" if (ext in ("zero", "mask") and self.x16) else "X"
        signed = ext == "sign" or k == "D"
        if o.indexed:
            slow = f"_rx({k!r}, {o.addr}, X, {signed})"
            if k != "B" and not self.native:
                return slow
            return f"({self._mem_at(k, '_a', signed)} if {self._ix_ok(o)} else {slow})"
        return self._mem_at(k, o.addr, signed)

    def _mem_at(self, k: str, a: int | str, signed: bool) -> str:
        """Read of B/W/D at byte address `a` (a constant or the name of a variable)."""
        shift = lambda n: str(a >> n) if isinstance(a, int) else f"{a} >> {n}"  # noqa: E731
        if k == "B":
            return f"mb[{a}]" if signed else f"mem[{a}]"
        if self.native:
            if k == "W":
                return f"mw[{shift(1)}]" if signed else f"mwu[{shift(1)}]"
            return f"md[{shift(2)}]"
        if k == "W":
            return f"_uh(mem, {a})[0]" if signed else f"_uH(mem, {a})[0]"
        return f"_ui(mem, {a})[0]"

    def load_value(self, o: Operand) -> str:
        """Word loads honour A-06 load_extension for B and W."""
        return self.value(o, "zero" if self.sem["load_extension"] == "zero" else "sign")

    def store(self, indent: int, o: Operand, expr: str, opid: int, saturate: bool = False) -> None:
        """write_val (5.5): truncating to the operand width (or saturating, A-08)."""
        k = o.kind
        if k == "X":
            self.out(indent, self.x_store(expr), opid)
            return
        if saturate and k in ("B", "W"):
            expr = f"_sat({expr}, {8 if k == 'B' else 16})"
        if o.indexed:
            slow = f"_wx({k!r}, {o.addr}, X, {expr})"
            if k != "B" and not self.native:
                self.out(indent, slow, opid)
                return
            self.out(indent, f"if {self._ix_ok(o)}: {self._mem_store(k, '_a', expr)}; _ixw(({k!r}, _a))", opid)
            self.out(indent, f"else: {slow}", opid)
            return
        self.out(indent, self._mem_store(k, o.addr, expr), opid)

    def _mem_store(self, k: str, a: int | str, expr: str) -> str:
        mask = {"B": 255, "W": 65535, "D": _M32}[k]
        if k == "B":
            return f"mem[{a}] = ({expr}) & 255"
        if self.native:
            index = (a >> (1 if k == "W" else 2)) if isinstance(a, int) else f"{a} >> {1 if k == 'W' else 2}"
            return f"{'mwu' if k == 'W' else 'mdu'}[{index}] = ({expr}) & {mask}"
        return f"_p{'H' if k == 'W' else 'I'}(mem, {a}, ({expr}) & {mask})"

    def string(self, o: Operand, write: bool = False) -> str:
        if o.kind == "STR":
            return repr(o.text)
        if o.indexed:
            return f"S[_six({o.addr}, X)]" if write else f"_srx({o.addr}, X)"
        return f"S[{o.addr}]"

    def _kf_name(self, values: tuple[int, ...]) -> str:
        values = tuple(_int32(v) for v in values)
        name = self.kf_tables.get(values)
        if name is None:
            name = self.kf_tables[values] = f"_KF{len(self.kf_tables)}"
        return name

    # ------------------------------------------------------------------ instructions

    def _op(self, op: Op, opid: int, f: int, seg_of: dict[int, int], ind: int) -> None:
        c = op.code
        o = op.operand
        handler = getattr(self, f"_op_{c}", None)
        if handler is not None:
            handler(op, opid, ind, f, seg_of)
            return
        if c in ("LD", "LDN", "AND", "ANDN", "OR", "ORN", "XOR", "XORN"):
            b = self.bit(o)
            if c.endswith("N"):
                b = f"({b} ^ 1)"
            sym = {"LD": "", "AND": "&", "OR": "|", "XOR": "^"}[c.rstrip("N")]
            if not sym:
                self.set_la(ind, b, opid)
            elif self.shared:
                self.set_la(ind, f"{self.la()} {sym} {b}", opid)
            else:
                self.out(ind, f"LA {sym}= {b}", opid)
        elif c in ("ST", "STN"):
            self.bit_store(ind, o, self.la() if c == "ST" else f"({self.la()} ^ 1)", opid)
        elif c in ("SET", "RES", "SETN", "RESN"):
            cond = self.la() if c in ("SET", "RES") else f"not {self.la()}"
            self.out(ind, f"if {cond}:", opid)
            self.bit_store(ind + 1, o, "1" if c in ("SET", "SETN") else "0", opid)
        elif c in ("WAND", "WANDN", "WOR", "WORN", "WXOR", "WXORN"):
            self._word_gate(c, o, opid, ind)
        elif c in ("ADD", "SUB", "MUL", "DIV", "MOD"):
            self._arith(c, "WA", self.value(o), opid, ind)
        elif c in ("NOP", "LBL", "KFIELD"):
            pass
        else:
            raise NotImplementedError(f"interpreter: no code generation for op {c}")

    # loads and stores

    def _op_WLD(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {self.load_value(op.operand)}", opid)

    def _op_WLDN(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if self.sem["ln_word"] == "operand_width" and self.width(o) < 32:
            # A-07 alternative: the complement over the operand width only (upper bits 0).
            self.out(ind, f"WA = ~{self.value(o, 'mask')} & {(1 << self.width(o)) - 1}", opid)
        else:
            self.out(ind, f"WA = ~{self.load_value(o)}", opid)

    def _op_WNEG(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {_norm('-' + self.load_value(op.operand))}", opid)

    def _op_LDBITS(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if o.indexed:
            self.out(ind, f"WA = _packx({o.kind!r}, {o.addr}, X, {op.nbits})", opid)
        else:
            self.out(ind, f"WA = _pack({o.kind}, {o.addr}, {op.nbits})", opid)

    def _op_STBITS(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if o.indexed:
            self.out(ind, f"_unpackx({o.kind!r}, {o.addr}, X, {op.nbits}, WA)", opid)
        else:
            self.out(ind, f"_unpack({o.kind}, {o.addr}, {op.nbits}, WA)", opid)

    def _op_WST(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.store(ind, op.operand, "WA", opid, saturate=self.sem["store_truncation"] == "saturate")

    # word logic, arithmetic, comparisons

    def _word_gate(self, c: str, o: Operand, opid: int, ind: int) -> None:
        n = self.width(o)
        m = -1 if n == 32 else (1 << n) - 1
        u = self.value(o, "mask" if n < 32 else "sign")
        if c == "WAND":
            expr = f"WA & ({u} | {~m})" if n < 32 else f"WA & {u}"
        elif c == "WANDN":
            expr = f"WA & ~{u}"
        elif c == "WOR":
            expr = f"WA | {u}"
        elif c == "WORN":
            expr = f"WA | ({u} ^ {m})"
        elif c == "WXOR":
            expr = f"WA ^ {u}"
        else:
            expr = f"WA ^ ({u} ^ {m})"
        self.out(ind, f"WA = {expr}", opid)

    def _arith(self, c: str, left: str, right: str, opid: int, ind: int) -> None:
        """WA := left OP right with the flags of 6.5 (left is WA, or the saved value of a bracket)."""
        if c in ("ADD", "SUB"):
            sym = "+" if c == "ADD" else "-"
            if self.sem["add_overflow"] == "flag":
                # A-09 alternative: an overflow sets the multiplication error marker
                self.out(ind, f"_r = {left} {sym} {right}", opid)
                self.out(ind, f"WA = {_norm('_r')}", opid)
                self.out(ind, f"if WA != _r: M[{self.itf.mul_err}] = 1", opid)
            else:
                self.out(ind, f"WA = {_norm(f'{left} {sym} {right}')}", opid)
        elif c == "MUL":
            self.out(ind, f"_p = {left} * {right}", opid)
            self.out(ind, f"_r = {_norm('_p')}", opid)
            self.out(ind, f"M[{self.itf.mul_err}] = _r != _p", opid)
            if self.sem["mul_overflow_result"] == "unchanged":
                self.out(ind, f"WA = _r if _r == _p else {left}", opid)
            else:
                self.out(ind, "WA = _r", opid)
        else:
            flag = self.itf.div_err if c == "DIV" else self.itf.mod_err
            self.out(ind, f"WA, M[{flag}] = _{c.lower()}({left}, {right})", opid)

    def _op_CMP(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        n = self.width(o)
        rel = _REL[op.rel]
        if self.sem["compare_signedness"] == "unsigned":
            m = (1 << n) - 1
            right = self.value(o, "mask") if n < 32 else f"({self.value(o)} & {m})"
            expr = f"(WA & {m}) {rel} {right}"
        else:
            expr = f"{_sext_expr('WA', n)} {rel} {self.value(o)}"
        self.set_la(ind, expr, opid)

    def _op_SHL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        if self.sem["shift_semantics"] == "fault":
            self.out(ind, f"WA = _shl(WA, {self.value(op.operand)})", opid)
        elif op.operand.kind == "K":
            self.out(ind, f"WA = {_norm(f'WA << {op.operand.addr & 31}')}", opid)
        else:
            self.out(ind, f"WA = {_norm(f'WA << ({self.value(op.operand)} & 31)')}", opid)

    def _op_SHR(self, op: Op, opid: int, ind: int, *_: object) -> None:
        if self.sem["shift_semantics"] == "fault":
            self.out(ind, f"WA = _shr(WA, {self.value(op.operand)})", opid)
        elif op.operand.kind == "K":
            self.out(ind, f"WA >>= {op.operand.addr & 31}", opid)
        else:
            self.out(ind, f"WA >>= ({self.value(op.operand)} & 31)", opid)

    def _bitmask(self, o: Operand) -> str:
        if o.kind == "K":
            return _signed_literal(_bit_mask(o.addr & 31))
        return f"(-2147483648 if ({self.value(o)} & 31) == 31 else 1 << ({self.value(o)} & 31))"

    def _op_BS(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA |= {self._bitmask(op.operand)}", opid)

    def _op_BC(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA &= ~{self._bitmask(op.operand)}", opid)

    def _op_BT(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        k = str(o.addr & 31) if o.kind == "K" else f"({self.value(o)} & 31)"
        self.set_la(ind, f"(WA >> {k}) & 1", opid)

    # extended instructions

    def _op_INC(self, op: Op, opid: int, ind: int, *_: object, step: int = 1) -> None:
        o = op.operand
        if o.is_bit:
            # a bit operand counts modulo 2 (own reading of "op := op + 1 (wrap)")
            self.bit_store(ind, o, f"{self.bit(o)} ^ 1", opid)
        else:
            self.store(ind, o, f"{self.value(o)} {'+' if step > 0 else '-'} 1", opid)

    def _op_DEC(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self._op_INC(op, opid, ind, step=-1)

    def _op_INCW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {_norm('WA + 1')}", opid)

    def _op_DECW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {_norm('WA - 1')}", opid)

    def _op_INCX(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, self.x_store("X + 1"), opid)

    def _op_DECX(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, self.x_store("X - 1"), opid)

    def _op_NOTL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.set_la(ind, f"{self.la()} ^ 1", opid)

    def _op_NOTW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, "WA = ~WA", opid)

    def _op_TWOC(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {_norm('-WA')}", opid)

    # brackets (6.9, 17b.4, A-04, A-18)

    def _op_BOPEN(self, op: Op, opid: int, ind: int, f: int, *_: object) -> None:
        saved = f"_b{len(self.brackets)}"
        width = 32
        if self.sem["bracket_width"] == "operand":
            width = self._first_inner_load_width(f, opid)
        self.brackets.append((op, saved, width))
        self.out(ind, f"{saved} = {self.la() if op.bracket.mode == 'LOGIC' else 'WA'}", opid)

    def _first_inner_load_width(self, f: int, opid: int) -> int:
        """A-18 alternative: the width of the first word load inside the bracket."""
        ops = self.program.files[f].ops
        depth = 0
        for op in ops[self.op_index[opid][1] + 1:]:
            if op.code == "BOPEN":
                depth += 1
            elif op.code == "BCLOSE":
                if depth == 0:
                    break
                depth -= 1
            elif op.code in ("WLD", "WLDN", "WNEG") and op.operand is not None:
                return self.width(op.operand)
            elif op.code == "LDBITS":
                return op.nbits
        return 32

    def _op_BCLOSE(self, op: Op, opid: int, ind: int, *_: object) -> None:
        opened, s, width = self.brackets.pop()
        br = opened.bracket
        kind = br.op
        if kind in _LOGIC_OPS and br.mode == "LOGIC":
            inner = self.la()
            if br.load:
                self.set_la(ind, inner if kind in ("A", "O", "XO") else f"({inner} ^ 1)", opid)
            else:
                self.set_la(ind, _gate(kind, s, inner, "(({}) ^ 1)"), opid)
        elif kind in _LOGIC_OPS:
            combined = _gate(kind, s, "WA", "~{}")
            if width < 32:
                m = (1 << width) - 1
                combined = f"({s} & {~m}) | (({combined}) & {m})"
            self.out(ind, f"WA = {combined}", opid)
        elif kind in ("+", "-", "x", "/", "MOD"):
            code = {"+": "ADD", "-": "SUB", "x": "MUL", "/": "DIV", "MOD": "MOD"}[kind]
            self._arith(code, s, "WA", opid, ind)
        else:
            rel = _REL[kind]
            if self.sem["compare_signedness"] == "unsigned":
                m = (1 << width) - 1
                self.set_la(ind, f"({s} & {m}) {rel} (WA & {m})", opid)
            else:
                self.set_la(ind, f"{_sext_expr(s, width)} {rel} {_sext_expr('WA', width)}", opid)

    # data stack (6.10, A-19, A-20)

    def _op_PUSH(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if o.is_bit:
            self.out(ind, f"_ps16({self.bit(o)} << 7)", opid)
        else:
            self.out(ind, f"_ps32({self.value(o)})", opid)

    def _op_POP(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if o.is_bit:
            self.bit_store(ind, o, "(_pl16() >> 7) & 1", opid)
        else:
            self.store(ind, o, "_pl32()", opid)

    def _op_PSW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, "_ps32(WA)", opid)

    def _op_PLW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, "WA = _pl32()", opid)

    def _op_PSL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"_ps16({self.la()} << 7)", opid)

    def _op_PLL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.set_la(ind, "(_pl16() >> 7) & 1", opid)

    def _op_PSX(self, op: Op, opid: int, ind: int, *_: object) -> None:
        if int(self.sem["psx_width"]) == 16:
            self.out(ind, "_ps16(X & 65535)", opid)
        else:
            self.out(ind, "_ps32(X)", opid)

    def _op_PLX(self, op: Op, opid: int, ind: int, *_: object) -> None:
        if int(self.sem["psx_width"]) == 16:
            self.out(ind, self.x_store("_pl16()"), opid)
        else:
            self.out(ind, self.x_store("_pl32()"), opid)

    # control flow

    def _cover(self, ind: int, opid: int, outcome: str) -> None:
        if self.coverage:
            self.out(ind, f"_branch(({opid}, {outcome}))", opid)

    def _op_JP(self, op: Op, opid: int, ind: int, f: int, seg_of: dict[int, int]) -> None:
        self.out(ind, f"b = {seg_of[op.target]}", opid)
        self.out(ind, "continue", opid)

    def _op_JPT(self, op: Op, opid: int, ind: int, f: int, seg_of: dict[int, int], negate: bool = False) -> None:
        self.out(ind, f"if {'not ' if negate else ''}{self.la()}:", opid)
        self._cover(ind + 1, opid, "1")
        self.out(ind + 1, f"b = {seg_of[op.target]}", opid)
        self.out(ind + 1, "continue", opid)
        self._cover(ind, opid, "0")

    def _op_JPF(self, op: Op, opid: int, ind: int, f: int, seg_of: dict[int, int]) -> None:
        self._op_JPT(op, opid, ind, f, seg_of, negate=True)

    def _call(self, op: Op, opid: int, ind: int) -> None:
        call = op.call
        if call is None or (not call.is_module and call.file < 0):
            self.out(ind, "_falloff()", opid)       # unresolved target: the front end reported it
            return
        if call.is_module:
            self.out(ind, f"_module({call.module}, {opid})", opid)
            return
        self._nested(ind, opid, f"F{call.file}({self.seg_maps[call.file][call.index]})")

    def _nested(self, ind: int, opid: int, *call: str) -> None:
        """A call one level deeper (CM and CASE), checked against call_depth (A-29)."""
        self.out(ind, "d += 1", opid)
        self.out(ind, f"if d > {self.depth_limit}: _depth_fault(d)", opid)
        for line in call:
            self.out(ind, line, opid)
        self.out(ind, "d -= 1", opid)

    def _op_CALL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self._call(op, opid, ind)

    def _op_CALLT(self, op: Op, opid: int, ind: int, *_: object, negate: bool = False) -> None:
        self.out(ind, f"if {'not ' if negate else ''}{self.la()}:", opid)
        self._cover(ind + 1, opid, "1")
        self._call(op, opid, ind + 1)
        if self.coverage:
            self.out(ind, "else:", opid)
            self._cover(ind + 1, opid, "0")

    def _op_CALLF(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self._op_CALLT(op, opid, ind, negate=True)

    def _op_EM(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"_em = {opid}", opid)
        self.out(ind, "return", opid)

    def _op_EMT(self, op: Op, opid: int, ind: int, *_: object, negate: bool = False) -> None:
        self.out(ind, f"if {'not ' if negate else ''}{self.la()}:", opid)
        self._cover(ind + 1, opid, "1")
        self.out(ind + 1, f"_em = {opid}", opid)
        self.out(ind + 1, "return", opid)
        self._cover(ind, opid, "0")

    def _op_EMF(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self._op_EMT(op, opid, ind, negate=True)

    def _op_CASE(self, op: Op, opid: int, ind: int, *_: object) -> None:
        targets = []
        for t in op.case_targets:
            if t is None or t.file < 0:
                targets.append("None")
            else:
                targets.append(f"(F{t.file}, {self.seg_maps[t.file][t.index]})")
        table = f"_CT{opid}"
        self.case_tables.append(f"{table} = ({', '.join(targets)}{',' if targets else ''})")
        count = len(targets)
        self.out(ind, f"_s = {self.value(op.operand)}", opid)
        self.out(ind, f"if 0 <= _s < {count}:", opid)
        self._cover(ind + 1, opid, "_s")
        self._nested(ind + 1, opid, f"_f, _g = {table}[_s]", "_f(_g)")
        if self.coverage or self.sem["case_out_of_range"] == "fault":
            self.out(ind, "else:", opid)
            self._cover(ind + 1, opid, "-1")
            if self.sem["case_out_of_range"] == "fault":
                self.out(ind + 1, f"_case_fault(_s, {count})", opid)

    # strings (6.16, A-50)

    def _op_SLD(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"SA = {self.string(op.operand)}", opid)

    def _op_SCAT(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"SA = _scat(SA + {self.string(op.operand)}, {opid})", opid)

    def _op_SST(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"{self.string(op.operand, write=True)} = SA", opid)

    def _op_SCMP(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.set_la(ind, f"SA {_REL[op.rel]} {self.string(op.operand)}", opid)

    # submit jobs (section 15, A-45)

    def _op_SUBM(self, op: Op, opid: int, ind: int, *_: object) -> None:
        call = op.call
        if call is None or call.file < 0:
            self.out(ind, "_falloff()", opid)
            return
        seg = self.seg_maps[call.file][call.index]
        self.out(ind, f"WA = _subm(F{call.file}, {seg}, {call.label!r})", opid)

    def _op_RPLY(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = _rply({self.value(op.operand)})", opid)

    def _op_CAN(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"_can({self.value(op.operand)})", opid)


def _gate(kind: str, left: str, right: str, negate_fmt: str) -> str:
    neg = negate_fmt.format(right)
    return {"A": f"{left} & {right}", "AN": f"{left} & {neg}", "O": f"{left} | {right}",
            "ON": f"{left} | {neg}", "XO": f"{left} ^ {right}", "XON": f"{left} ^ {neg}"}[kind]


def _norm(expr: str) -> str:
    """Reduce to int32 (two's complement wrap)."""
    return f"((({expr}) + {_H}) & {_M32}) - {_H}"


def _sext_expr(expr: str, bits: int) -> str:
    if bits >= 32:
        return expr
    half = 1 << (bits - 1)
    return f"((({expr}) + {half}) & {(1 << bits) - 1}) - {half}"


def _int32(value: int) -> int:
    value &= _M32
    return value - (1 << 32) if value > 2147483647 else value


def _signed_literal(value: int) -> str:
    return f"({value})" if value < 0 else str(value)


def _bit_mask(k: int) -> int:
    """2^k as an int32 (bit 31 is the sign bit)."""
    return -(1 << 31) if k == 31 else 1 << k
