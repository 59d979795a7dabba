"""Run-time helpers that generated code calls: data stack, indexed operands, division, shifts, strings, modules, submit jobs."""

from __future__ import annotations

import collections
from typing import Callable

from transpiler.ir import sext
from transpiler.language.semantics import Semantics
from transpiler.exec.interp.compile import CompiledProgram
from transpiler.exec.interp.coverage import CoverageMarks
from transpiler.exec.interp.sysmodel import SysContext
from transpiler.exec.interp.faults import BudgetExceeded, Fault, JobCancelled
from transpiler.exec.interp.state import INT32_MIN, MEM_WIDTH, MachineState
from transpiler.exec.interp.pure_modules import PURE_MODULES, PureEnv, written as pure_written
from transpiler.exec.interp.submit import SubmitQueue
from transpiler.language.module_table import MODULE_TABLE

_TO_CHARS = bytes.maketrans(b"\x00\x01", b"01")
_FROM_CHARS = bytes.maketrans(b"01", b"\x00\x01")

Warn = Callable[[str, str, int], None]        # code, message, op id



def divide(a: int, b: int, floor: bool, min_flag: int) -> tuple[int, int]:
    """`a / b` of two 32-bit values and its error flag (A-11 floor or truncating, A-12 the flag of -2^31 / -1):
    the interpreter's division, and the one the coverage analyses work constant word arithmetic out with."""
    if b == 0:
        return (0 if floor else a), 1
    if floor:
        q = a // b
    else:
        q = abs(a) // abs(b)
        if (a < 0) != (b < 0):
            q = -q
    if q == -INT32_MIN:                 # -2^31 / -1
        return INT32_MIN, min_flag
    return q, 0


def remainder(a: int, b: int, floor: bool, min_flag: int) -> tuple[int, int]:
    """`a MOD b` of two 32-bit values and its error flag, as divide."""
    if b == 0:
        return (0 if floor else a), 1
    if floor:
        r = a % b
    else:
        r = abs(a) % abs(b)
        if a < 0:
            r = -r
    return r, (min_flag if (a == INT32_MIN and b == -1) else 0)


class Runtime:
    """Per-machine state the generated code reaches through helpers (stack, jobs, modules) and the helpers themselves."""

    def __init__(self, state: MachineState, semantics: Semantics, sys: SysContext, jobs: SubmitQueue, warn: Warn):
        self.state = state
        self.sem = semantics
        self.sys = sys
        self.jobs = jobs
        self.warn = warn
        self.profile = semantics.profile
        self.stack: list[int] = []
        self.capacity = int(semantics["data_stack_words"])
        self.elements = semantics["index_scaling"] == "elements"
        self.read_check = bool(semantics["index_read_check"])
        self.div_floor = semantics["div_semantics"] == "floor"
        self.min_flag = 1 if semantics["div_min_by_minus_one"] == "flag" else 0
        self.cycle = 0
        self.in_job = False
        self.module_log: list[tuple[tuple[int, tuple[int, ...]], tuple[list[int], int, int | None]]] = []
        self.replay: collections.deque | None = None
        self.unknown_modules: dict[int, int] = {}
        mp7280 = sys.get_mp(7280, 0)
        self.pure_env = PureEnv(lambda: len(self.stack), "," if mp7280 is not None and mp7280 == 0 else ".")
        self.marks: CoverageMarks | None = None
        # (kind, address) of every store made through an indexed operand, in first-write order (a dict is an
        # ordered set): co-simulation compares these operands from then on. W/D stores record their kind and
        # first byte. Stores to named operands never get here, so a program without indexed stores pays nothing.
        self.indexed_writes: dict[tuple[str, int], None] = {}

    def env(self, compiled: CompiledProgram, coverage: bool) -> dict[str, object]:
        """The names the generated code of `compiled` binds; with coverage, the first program sets up the marks
        that later variants of it write into as well."""
        st = self.state
        hits: list[int] | None = None
        branch_hits: list[int] | None = None
        stretch_hits: list[int] | None = None
        value_hits: list[int] | None = None
        bound_hits: list[int] | None = None
        vectors: dict[int, int] | None = None
        if coverage:
            if self.marks is None:
                self.marks = CoverageMarks(compiled)
            hits, branch_hits, stretch_hits, value_hits, bound_hits, vectors = self.marks.arrays_for(compiled)
        env: dict[str, object] = {
            "M": st.M, "I": st.I, "O": st.O, "T": st.T, "C": st.C, "mem": st.mem, "mb": st.mb, "S": st.S,
            "stk": self.stack, "valid": st.valid, "st_h": st.st_h, "st_H": st.st_H, "st_i": st.st_i, "st_I": st.st_I,
            "rb": self.read_bit_indexed, "wb": self.write_bit_indexed, "rx": self.read_val_indexed,
            "wx": self.write_val_indexed, "packx": self.pack_indexed, "unpackx": self.unpack_indexed,
            "pack": pack_bits, "unpack": unpack_bits, "kf": kf_read, "div": self.div, "mod": self.mod,
            "shl": shl_checked, "shr": shr_checked, "sat": saturate, "overflow": self.stack_overflow,
            "underflow": self.stack_underflow, "module": self.module, "subm": self.submit,
            "rply": self.jobs.reply, "can": self.cancel, "scat": self.concat, "six": self.string_index,
            "srx": self.read_string_indexed,
            "watchdog": self.watchdog, "depth_fault": self.depth_fault, "case_fault": case_fault,
            "falloff": falloff, "BudgetExceeded": BudgetExceeded, "hit": hits, "bh": branch_hits,
            "sh": stretch_hits, "vp": value_hits, "bd": bound_hits, "mc": vectors,
            "ixw": self.indexed_writes.setdefault,
        }
        if st.native:
            env.update(mw=st.mw, mwu=st.mwu, md=st.md, mdu=st.mdu)
        return env

    # ---- data stack: 16-bit words, a 32-bit value is two words with the high word on top

    # The generated code pushes and pulls inline (gen_stack) and calls the two faults below; modules use these.

    def push32(self, value: int) -> None:
        if len(self.stack) + 2 > self.capacity:
            self.stack_overflow()
        self.stack.append(value & 0xFFFF)
        self.stack.append((value >> 16) & 0xFFFF)

    def pop32(self) -> int:
        if len(self.stack) < 2:
            self.stack_underflow(2)
        high = self.stack.pop()
        low = self.stack.pop()
        return sext((high << 16) | low, 32)

    def stack_overflow(self) -> None:
        raise Fault("E-RT-STACK-OVERFLOW", f"data stack overflow (capacity {self.capacity} words)")

    def stack_underflow(self, words: int) -> int:
        """The fault of a pull of `words` (1 or 2) words that the stack does not hold."""
        if words == 1:
            raise Fault("E-RT-STACK-UNDERFLOW", "pull from an empty data stack")
        raise Fault("E-RT-STACK-UNDERFLOW", f"a 32-bit pull needs 2 words, the data stack holds {len(self.stack)}")

    # ---- indexed operands (6.13, A-21, A-22, A-53)

    def _address(self, kind: str, base: int, x: int, count: int, write: bool) -> int | None:
        """Effective address of kind<base>[X]; None for an unchecked out-of-range read (index_read_check = false)."""
        st = self.state
        if kind in MEM_WIDTH:
            size = MEM_WIDTH[kind]
            addr = base + x * (size if self.elements else 1)
            if addr % size:
                raise Fault("E-RT-ALIGN", f"{kind}{base}[X] with X = {x} addresses {kind}{addr}, "
                            f"which is not aligned to {size} bytes")
            table, span = st.valid["B"], size
        else:
            addr, table, span = base + x, st.valid[kind], count
        if addr >= 0 and addr + span <= len(table) and table.count(1, addr, addr + span) == span:
            return addr
        if write or self.read_check:
            what = f"{kind}{addr}" if span == 1 or kind in MEM_WIDTH else f"{kind}{addr}..{kind}{addr + span - 1}"
            raise Fault("E-RT-INDEX", f"{kind}{base}[X] with X = {x} addresses {what}, outside the operand range "
                        f"of profile {self.profile.name}")
        return None

    def read_bit_indexed(self, kind: str, base: int, x: int) -> int:
        addr = self._address(kind, base, x, 1, False)
        return 0 if addr is None else self.state.bits(kind)[addr]

    def write_bit_indexed(self, kind: str, base: int, x: int, value: int) -> None:
        addr = self._address(kind, base, x, 1, True)
        self.state.bits(kind)[addr] = 1 if value else 0  # type: ignore[index]
        self.indexed_writes.setdefault((kind, addr))  # type: ignore[arg-type]

    def read_val_indexed(self, kind: str, base: int, x: int, signed: bool) -> int:
        addr = self._address(kind, base, x, 1, False)
        return 0 if addr is None else self.state.read_mem(kind, addr, signed)

    def write_val_indexed(self, kind: str, base: int, x: int, value: int) -> None:
        addr = self._address(kind, base, x, 1, True)
        self.state.write_mem(kind, addr, value)  # type: ignore[arg-type]
        self.indexed_writes.setdefault((kind, addr))  # type: ignore[arg-type]

    def pack_indexed(self, kind: str, base: int, x: int, nbits: int) -> int:
        addr = self._address(kind, base, x, nbits, False)
        return 0 if addr is None else pack_bits(self.state.bits(kind), addr, nbits)

    def unpack_indexed(self, kind: str, base: int, x: int, nbits: int, value: int) -> None:
        addr: int = self._address(kind, base, x, nbits, True)  # type: ignore[assignment]
        unpack_bits(self.state.bits(kind), addr, nbits, value)
        for bit in range(addr, addr + nbits):
            self.indexed_writes.setdefault((kind, bit))

    def string_index(self, base: int, x: int) -> int:
        """Address of an indexed string store (generated code only uses it to write S[...])."""
        addr: int = self._address("S", base, x, 1, True)  # type: ignore[assignment]
        self.indexed_writes.setdefault(("S", addr))
        return addr

    def read_string_indexed(self, base: int, x: int) -> str:
        addr = self._address("S", base, x, 1, False)
        return "" if addr is None else self.state.S[addr]

    # ---- division (A-11, A-12, 17b.4): (result, flag)

    def div(self, a: int, b: int) -> tuple[int, int]:
        return divide(a, b, self.div_floor, self.min_flag)

    def mod(self, a: int, b: int) -> tuple[int, int]:
        return remainder(a, b, self.div_floor, self.min_flag)

    # ---- strings

    def concat(self, text: str, opid: int) -> str:
        limit = self.state.string_len
        if len(text) > limit:
            self.warn("E-RT-STRING", f"string result of {len(text)} characters truncated to {limit}", opid)
            return text[:limit]
        return text

    # ---- PLC modules (14.1, 14.3, A-46)

    def module(self, number: int, opid: int) -> None:
        itf = self.profile.interface
        info = self.sys.info(number)
        row = MODULE_TABLE.get(number)
        if not info.known or row is None or self.profile.name not in row.profiles:
            first = number not in self.unknown_modules
            self.unknown_modules[number] = self.unknown_modules.get(number, 0) + 1
            if first:
                self.warn("E-RT-MODULE", f"PLC module {number} is not in the module table of profile "
                          f"{self.profile.name}: it ran as a stub without parameters or results (A-46)", opid)
            self.state.M[itf.module_err] = 0
            return
        params = [0] * info.nparams
        for i in range(info.nparams - 1, -1, -1):
            params[i] = self.pop32()
        key = (number, tuple(params))
        if self.replay:
            logged_key, outcome = self.replay.popleft()
            results, status, code = outcome if logged_key == key else self._run_module(number, params)
        else:
            results, status, code = self._run_module(number, params)
            self.module_log.append((key, (list(results), status, code)))
        for value in reversed(results):
            self.push32(value)
        self.state.M[itf.module_err] = 1 if status else 0
        if status and itf.module_err_code_word is not None and code is not None:
            self.state.write_mem("W", itf.module_err_code_word, code)

    def _run_module(self, number: int, params: list[int]) -> tuple[list[int], int, int | None]:
        """Pure modules here (they read and write PLC memory), the others in the shim; both with the context rule."""
        pure = PURE_MODULES.get(number)
        if pure is None:
            if self.sem["module_context"] == "ignore":
                return self.sys.call(number, params)
            return self.sys.call_in(number, params, self.in_job)
        row = MODULE_TABLE[number]          # pure modules may be called anywhere: no context rule
        results, code = pure(self.state, params, self.pure_env)
        if not code:
            for place in pure_written(number, self.state, params):
                self.indexed_writes.setdefault(place)
        results = results or [0] * row.nresults
        return results, 1 if code else 0, code or None

    # ---- submit jobs (15, A-45)

    def submit(self, func: Callable[[int], None], block: int, label: str) -> int:
        if self.in_job:
            return 0                         # nesting is not allowed
        return self.jobs.submit(func, block, label, self.cycle)

    def cancel(self, ident: int) -> None:
        if self.jobs.cancel(ident) and self.in_job:
            raise JobCancelled(ident)

    # ---- faults raised from generated code

    def watchdog(self) -> None:
        budget = int(self.sem["max_instructions_per_cycle"])
        raise Fault("E-RT-WATCHDOG", f"the cycle exceeded its budget of {budget} instructions "
                    "(max_instructions_per_cycle, A-57)")

    def depth_fault(self, depth: int) -> None:
        raise Fault("E-RT-CALL-DEPTH", f"call depth {depth} exceeds the limit {self.sem['call_depth']} (A-29)")


def case_fault(selector: int, entries: int) -> None:
    raise Fault("E-RT-INDEX", f"CASE selector {selector} is outside 0..{entries - 1} (case_out_of_range = fault, A-24)")


def falloff() -> None:
    raise Fault("E-FALL-OFF-END", "execution reached the end of the file without EM")


def kf_read(table: tuple[int, ...], x: int, name: str) -> int:
    if 0 <= x < len(table):
        return table[x]
    raise Fault("E-RT-INDEX", f"KF {name}[X] with X = {x} is outside 0..{len(table) - 1}")


def pack_bits(bits: bytearray, addr: int, nbits: int) -> int:
    """LB/LW/LD: operand addr is bit 0; the result is sign-filled from the top bit."""
    value = int(bits[addr:addr + nbits][::-1].translate(_TO_CHARS), 2)
    return sext(value, nbits)


def unpack_bits(bits: bytearray, addr: int, nbits: int, value: int) -> None:
    """B=/W=/D=: bit i of WA goes to operand addr + i."""
    bits[addr:addr + nbits] = format(value & ((1 << nbits) - 1), f"0{nbits}b")[::-1].encode().translate(_FROM_CHARS)


def saturate(value: int, bits: int) -> int:
    """A-08 alternative: clamp to the signed range of the operand, then store its bit pattern."""
    low, high = -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    return min(max(value, low), high) & ((1 << bits) - 1)


def shl_checked(wa: int, count: int) -> int:
    """A-14 alternative (shift_semantics = fault): a count outside 0..31 or lost significant bits fault."""
    if not 0 <= count <= 31:
        raise Fault("E-RT-SHIFT", f"shift count {count} is outside 0..31 (shift_semantics = fault, A-14)")
    result = wa << count
    if sext(result, 32) != result:
        raise Fault("E-RT-SHIFT", f"{wa} << {count} does not fit in 32 bits (shift_semantics = fault, A-14)")
    return result


def shr_checked(wa: int, count: int) -> int:
    if not 0 <= count <= 31:
        raise Fault("E-RT-SHIFT", f"shift count {count} is outside 0..31 (shift_semantics = fault, A-14)")
    return wa >> count
