"""The reference machine: the PLC cycle's phases around the generated program code, runtime faults, coverage.

Co-simulation (issue 7) drives the phases one by one instead of run_cycle:

    m.apply_writes(writes)            # scenario step 1: non-input operands now, inputs into the process image
    nc = m.nc_phase(cycle, actions)   # phase 1: the NC model's writes, [(kind, addr, value)]; raises HandshakeTimeout
    m.input_latch()                   # phase 2
    m.timer_service()                 # phase 3 (after the program when cycle_phases = timers_after_main)
    m.program_phase(cycle, report)    # phases 4 and 5: main program, then submit jobs
    m.output_flush(); m.end_cycle()   # phase 6, then the simulated clock advances

The ST side can apply exactly the same `nc` write list (the NC model's decisions of the
reference run), or own a second NcModel that reads its own acknowledgement markers; both see
the same scenario actions. run_cycle does all of this and turns faults into a CycleReport.
"""

from __future__ import annotations

import collections
import dataclasses
import itertools
import operator
from decimal import Decimal, InvalidOperation
from typing import Any, Callable, Iterable, Mapping, Sequence

from transpiler.diagnostics import Diagnostics, Span
from transpiler.ir import Program, sext
from transpiler.exec.compiled.shim import HandshakeTimeout, NcModel
from transpiler.exec.interp.sysmodel import SysContext
from transpiler.exec.interp.compile import GENERATED_FILENAME, CompiledProgram, compile_program
from transpiler.exec.interp.faults import BudgetExceeded, CycleReport, Fault, JobCancelled, MachineConfigError, MachineHalted, RuntimeFault
from transpiler.exec.interp.state import MachineState, Snapshot, byte_cells, nonzero_positions
from transpiler.exec.interp.submit import SubmitQueue
from transpiler.exec.interp.support import Runtime
from transpiler.language.presets import load_presets
from transpiler.exec.interp.timers import TimerService

PSEUDO = ("LA", "WA", "X", "SA")
WriteLike = Any   # stimulus.Write (ref, value, name), or a (kind, addr, value) tuple


@dataclasses.dataclass(frozen=True)
class Coverage:
    """Executed ops and the outcomes seen at each conditional jump/call/EM (0/1) and CASE (entry, -1 = none)."""

    executed: frozenset[tuple[int, int]]
    branches: Mapping[tuple[int, int], frozenset[int]]
    # MC/DC: the consumer (file, op index) of each decision -> the distinct vectors recorded (bit i = condition i of
    # decisions.Decision, the bit above them the outcome); boundaries: each compare -> the values of left - right
    # among -1, 0, 1 it took
    vectors: Mapping[tuple[int, int], frozenset[int]] = dataclasses.field(default_factory=dict)
    bounds: Mapping[tuple[int, int], frozenset[int]] = dataclasses.field(default_factory=dict)
    # timer running bits (T addresses) the run's timer service never sets: their timer's preset is 0 in this run
    idle_timers: frozenset[int] = frozenset()


def normalize_mp(mp: Mapping[Any, Any] | None) -> dict[tuple[int, int], Decimal]:
    """Machine parameters keyed (number, index) with Decimal values; index None counts as 0."""
    result: dict[tuple[int, int], Decimal] = {}
    for key, value in (mp or {}).items():
        if isinstance(key, str):
            number, _, index = key.partition(".")
            key = (int(number), int(index) if index else 0)
        number, index = key
        if isinstance(value, bool):
            raise ValueError(f"machine parameter {number}.{index}: {value!r} is not a number")
        try:
            dec = value if isinstance(value, Decimal) else Decimal(repr(value) if isinstance(value, float) else str(value))
        except InvalidOperation:
            raise ValueError(f"machine parameter {number}.{index}: {value!r} is not a number") from None
        result[(int(number), int(index or 0))] = dec
    return result


class Machine:
    """Cycle-accurate executor of a resolved program."""

    def __init__(self, program: Program, mp: Mapping[Any, Any] | None = None, cycle_time_ms: int | None = None, *,
                 coverage: bool = False, number_mp4111: int = 0, module_results: Mapping[int, Iterable[int]] | None = None,
                 mp_spans: Mapping[tuple[int, int], Span] | None = None, compiled: CompiledProgram | None = None,
                 data: Mapping[str, int | str] | None = None):
        sem = program.semantics
        self.program = program
        self.semantics = sem
        self.profile = sem.profile
        self.cycle_time_ms = int(cycle_time_ms if cycle_time_ms is not None else sem["cycle_time_ms"])
        if self.cycle_time_ms <= 0:
            raise ValueError(f"cycle_time_ms must be positive, not {self.cycle_time_ms}")
        self.state = MachineState(self.profile, sem)
        mps = normalize_mp(mp)
        diags = Diagnostics()
        timer_presets, counter_presets = load_presets(mps, sem, self.cycle_time_ms, diags, mp_spans)
        self.sys = SysContext(self.cycle_time_ms, number_mp4111=number_mp4111, timer_unit=sem["timer_unit"],
                              timer_restart=bool(sem["timer_restart_while_running"]))
        self.sys.set_memory_size(self.state.mem_size)
        for (number, index), value in mps.items():
            try:
                self.sys.set_mp(number, index, value)
            except ValueError as exc:
                span = (mp_spans or {}).get((number, index), Span("<machine parameters>", 1, 1))
                diags.report("E-MP-VALUE", span, str(exc))
        if diags.has_errors():
            raise MachineConfigError(diags.items)
        for number, values in (module_results or {}).items():
            self.sys.set_module_results(number, list(values))
        self.timers = TimerService(sem, timer_presets, counter_presets)
        self.nc = NcModel(self.cycle_time_ms, self.profile.name, first_cycle_marker=int(sem["first_cycle_marker"]))
        self.jobs = SubmitQueue(sem["submit_model"])
        self.runtime = Runtime(self.state, sem, self.sys, self.jobs, self._warn)
        self.coverage_enabled = coverage
        op_count = sum(len(f.ops) for f in program.files)
        if compiled is None or compiled.coverage != coverage or len(compiled.op_index) != op_count:
            compiled = compile_program(program, coverage=coverage)
        self._primary = compiled
        self._primary_funcs, self._get, self._set = compiled.make(self.runtime.env(compiled, coverage))
        self._exact: tuple[CompiledProgram, tuple, Any, Any] | None = None
        self._snapshot: Snapshot | None = None          # of the cycle's memory; reused from cycle to cycle
        self._timers_first = sem["cycle_phases"] != "timers_after_main"
        self.halted = False
        self.next_cycle = 0
        self.faults: list[RuntimeFault] = []
        self.warnings: list[RuntimeFault] = []
        self.instructions = 0
        self._budget = int(self.semantics["max_instructions_per_cycle"])
        self.error_messages: dict[int, int] = {}     # PLC error-message marker -> first cycle it was set
        self._errors_seen: tuple[bytearray, int] | None = None
        self._report = CycleReport(-1)
        self._x_bits = int(sem["index_register_width"])
        # The PLC data tables (program.data_rows, with `data` overriding values by symbol): loaded before the
        # program of the first cycle and of every cycle that sees the MP-restart marker (data_phase).
        overrides = dict(data or {})
        self._data = tuple((row.kind, row.addr, overrides.get(row.symbol, row.value)) for row in program.data_rows)
        self._data_loaded = False
        self._mp_restart = self.profile.interface.mp_restart

    # ------------------------------------------------------------------ operand access

    def read(self, kind: str, addr: int = 0) -> int | str:
        """Any operand (bits 0/1, B/W/D signed per width, S text) or the main registers LA, WA, X, SA."""
        if kind in PSEUDO:
            la, wa, x, sa = self._get()[:4]
            if self.semantics["accumulator_model"] == "shared_bit7":
                la = (wa >> 7) & 1
            return {"LA": 1 if la else 0, "WA": wa, "X": x, "SA": sa}[kind]
        return self.state.read(kind, addr)

    def write(self, kind: str, addr: int, value: int | str) -> None:
        """Write an operand from outside the program; for I it is also what the process drives (latched in phase 2)."""
        if kind in PSEUDO:
            regs = list(self._get())
            index = PSEUDO.index(kind)
            if kind == "SA":
                regs[index] = str(value)
            elif kind == "LA":
                regs[index] = 1 if value else 0
            else:
                regs[index] = sext(int(value), self._x_bits if kind == "X" else 32)
            self._set(*regs)
            return
        self.state.write(kind, addr, value)

    def reader(self, operands: Sequence[tuple[str, int]]) -> Callable[[], list[int | str]]:
        """A function returning the current values of `operands` (as `read` would), compiled once: for traces."""
        st = self.state
        # (container, index) of each operand that is an element of one, else the expression that reads it
        items: list[tuple[str, int] | str] = []
        for kind, addr in operands:
            self.read(kind, addr)                         # validates kind, range and alignment
            if kind in PSEUDO:
                items.append({"LA": "((r[1] >> 7) & 1)" if self.semantics["accumulator_model"] == "shared_bit7"
                              else "(1 if r[0] else 0)", "WA": "r[1]", "X": "r[2]", "SA": "r[3]"}[kind])
            elif kind in "MIOTC" or kind == "S":
                items.append((kind, addr))
            elif kind == "B":
                items.append(("mb", addr))
            elif st.native:
                items.append(("mw", addr >> 1) if kind == "W" else ("md", addr >> 2))
            else:
                items.append(f"{'h' if kind == 'W' else 'i'}(mem, {addr})[0]")
        namespace: dict[str, Any] = {"get": self._get, "M": st.M, "I": st.I, "O": st.O, "T": st.T, "C": st.C,
                                     "S": st.S, "mb": st.mb, "mem": st.mem, "h": st.st_h.unpack_from,
                                     "i": st.st_i.unpack_from}
        if st.native:
            namespace.update(mw=st.mw, md=st.md)
        # A run of elements of one container is read by one itemgetter (in C) instead of one subscript each.
        parts = []
        for _, run in itertools.groupby(items, key=lambda item: item[0] if isinstance(item, tuple) else None):
            run = list(run)
            if not isinstance(run[0], tuple):
                parts += run
            elif len(run) == 1:
                parts.append(f"{run[0][0]}[{run[0][1]}]")
            else:
                getter = f"g{len(namespace)}"
                namespace[getter] = operator.itemgetter(*(index for _, index in run))
                parts.append(f"*{getter}({run[0][0]})")
        source = "def _reader():\n    r = get()\n    return [" + ", ".join(parts) + "]\n"
        exec(compile(source, "<hh2iec-reader>", "exec"), namespace)  # noqa: S102 - generated from validated operands
        return namespace["_reader"]

    @property
    def indexed_write_count(self) -> int:
        """How many distinct indexed stores were recorded so far (grows only): a cheap "anything new?" test."""
        return len(self.runtime.indexed_writes)

    def indexed_writes(self, start: int = 0) -> list[tuple[str, int]]:
        """Operands the program has written through the index register, from record `start` on (records keep their
        first-write order): bits M/I/O/T/C, strings S, and a B/W/D store as the bytes B<n> it covers, because the
        overlapping byte memory is compared byte by byte. May repeat a byte; the caller keeps its own set."""
        records = itertools.islice(self.runtime.indexed_writes, start, None)
        return [cell for kind, addr in records for cell in byte_cells(kind, addr)]

    @property
    def registers(self) -> dict[str, int | str]:
        return {name: self.read(name) for name in PSEUDO}

    # ------------------------------------------------------------------ the cycle

    def run_cycle(self, cycle: int, stimulus_writes: Iterable[WriteLike] = (),
                  nc_actions: Iterable[Mapping[str, Any]] = ()) -> CycleReport:
        """One PLC cycle after the scenario writes; faults stop the machine (see `halted`)."""
        if self.halted:
            raise MachineHalted(f"the PLC program stopped after a runtime fault; cannot run cycle {cycle}")
        if cycle != self.next_cycle:
            raise ValueError(f"cycles run 0, 1, 2, ...: expected cycle {self.next_cycle}, not {cycle}")
        report = CycleReport(cycle)
        self._report = report
        self.apply_writes(stimulus_writes)
        try:
            report.nc_writes = self.nc_phase(cycle, nc_actions)
        except HandshakeTimeout as exc:
            self._record(report, RuntimeFault(exc.code, str(exc), exc.cycle))
        if not self.halted:
            self.input_latch()
            self.data_phase()
            if self._timers_first:
                self.timer_service()
            self.program_phase(cycle, report)
            if not self.halted:
                if not self._timers_first:
                    self.timer_service()
                self.output_flush()
        self.end_cycle()
        return report

    def apply_writes(self, writes: Iterable[WriteLike]) -> None:
        for w in writes:
            if hasattr(w, "ref"):
                self.write(w.ref.kind, w.ref.addr, w.value)
            else:
                kind, addr, value = w
                self.write(kind, addr, value)

    def nc_phase(self, cycle: int, actions: Iterable[Mapping[str, Any]] = ()) -> list[tuple[str, int, int]]:
        """Phase 1: queue the actions, run the NC model, apply and return its writes; raises HandshakeTimeout."""
        for action in actions:
            self.nc.enqueue(action)
        writes = self.nc.phase(cycle, self._read_marker)
        for kind, addr, value in writes:
            self.state.write(kind, addr, value)
        return writes

    def _read_marker(self, marker: int) -> int:
        return self.state.M[marker] if 0 <= marker < len(self.state.M) else 0

    def input_latch(self) -> None:
        """Phase 2: the input image is refreshed from the process; program writes to I are lost (A-33)."""
        self.state.I[:] = self.state.process_inputs

    def data_phase(self) -> None:
        """The PLC data tables' values into their operands: at power-on (the first cycle) and, as the control reads
        the tables together with the machine parameters, in a cycle that sees the MP-restart marker (M4174)."""
        if self._data and (not self._data_loaded
                           or (self._mp_restart is not None and self._read_marker(self._mp_restart))):
            for kind, addr, value in self._data:
                self.state.write(kind, addr, value)
            self._data_loaded = True

    def timer_service(self) -> None:
        """Phase 3: timers T0-T47 and counters (9.2, 10.2) here, T96-T999 of module 9006 in the shim."""
        st = self.state
        self.timers.service(st.T, st.C)
        for _, addr, value in self.sys.service():
            if addr < len(st.T):
                st.T[addr] = value

    def output_flush(self) -> None:
        """Phase 6: the output image goes to the process."""
        self.state.process_outputs[:] = self.state.O

    def end_cycle(self) -> None:
        """Bookkeeping after the cycle: PLC error-message markers that are set (13.2), then the clock advances."""
        lo, hi = self.profile.interface.error_markers
        window = self.state.M[lo:hi + 1]
        # A window as it was when last looked at (with as many messages listed) has no marker to list anew: markers
        # tend to stay set for many cycles, and only the first cycle of each is listed.
        seen = (window, len(self.error_messages))
        if seen != self._errors_seen:
            if 1 in window:
                for offset in nonzero_positions(window):
                    self.error_messages.setdefault(lo + offset, self.next_cycle)
            self._errors_seen = (window, len(self.error_messages))
        self.sys.tick()
        self.next_cycle += 1

    def program_phase(self, cycle: int, report: CycleReport | None = None) -> None:
        """Phases 4 and 5. A budget overrun seen by the fast code (at a jump back, a call or a module call, or in
        its count after the cycle) re-runs both phases from a snapshot with per-instruction counting, replaying the
        module calls, so the watchdog fault is exact (with coverage, a cycle that faults is re-run the same way, so
        that coverage is exact up to the fault)."""
        report = report or self._report
        self._report = report
        self.runtime.cycle = cycle
        try:
            self._program_phase(cycle, report)
        finally:
            self.instructions += report.instructions

    def _program_phase(self, cycle: int, report: CycleReport) -> None:
        rt = self.runtime
        if self._primary.exact:
            self._run_programs(self._primary, self._primary_funcs, self._get, self._set, cycle, report)
            return
        self._snapshot = self.state.snapshot(self._snapshot)
        snap = (self._snapshot, self._get(), self.jobs.state(), dict(rt.unknown_modules), len(report.warnings),
                rt.marks.vector_count() if rt.marks is not None else 0)
        rt.module_log = []
        rt.replay = None
        faults = len(report.faults)
        try:
            self._run_programs(self._primary, self._primary_funcs, self._get, self._set, cycle, report)
            # The fast code checks its count only where it can loop (see budget_check): a cycle that passed the
            # budget in straight-line code, or faulted after passing it, is seen here. And it marks coverage per
            # straight-line stretch when the stretch ends; a fault inside one would leave the ops it ran unmarked.
            # Either way the cycle (a faulting one is at most one: the machine halts) runs again exactly, recording
            # every op up to the fault, and records the same fault or the watchdog's.
            if report.instructions <= self._budget and not (self.coverage_enabled and len(report.faults) > faults):
                return
            raise BudgetExceeded
        except BudgetExceeded:
            if len(report.faults) > faults:
                del self.faults[len(self.faults) - (len(report.faults) - faults):]
                del report.faults[faults:]
                self.halted = False
            state, regs, jobs, unknown, warned, vectors = snap
            if rt.marks is not None:
                # the fast code may have run past the budget before it noticed: its decisions there never happened
                rt.marks.forget_vectors_after(vectors)
            self.state.restore(state)
            self.jobs.restore(jobs)
            rt.unknown_modules = unknown
            del report.warnings[warned:]
            self.warnings = [w for w in self.warnings if w.cycle != cycle]
            compiled, funcs, get, set_ = self._exact_variant()
            set_(*regs)
            rt.replay = collections.deque(rt.module_log)
            try:
                self._run_programs(compiled, funcs, get, set_, cycle, report)
            finally:
                rt.replay = None
                self._set(*get())

    def _exact_variant(self) -> tuple[CompiledProgram, tuple, Any, Any]:
        if self._exact is None:
            # with coverage when the machine records it: the ops of the overrunning cycle's last blocks count too
            compiled = compile_program(self.program, exact=True, coverage=self.coverage_enabled)
            funcs, get, set_ = compiled.make(self.runtime.env(compiled, self.coverage_enabled))
            self._exact = (compiled, funcs, get, set_)
        return self._exact

    def _run_programs(self, compiled: CompiledProgram, funcs: tuple, get: Any, set_: Any, cycle: int,
                      report: CycleReport) -> None:
        rt = self.runtime
        la, wa, x, sa = get()[:4]
        set_(la, wa, x, sa, 0, 0, -1)
        rt.stack.clear()
        rt.in_job = False
        if self._execute(compiled, funcs[0], 0, report, cycle, None):
            if rt.stack:
                self._warn("E-RT-STACK-LEFTOVER", f"{len(rt.stack)} word(s) left on the data stack at the end of "
                           "the main program (A-19)", get()[6])
            self._run_jobs(compiled, funcs, get, set_, cycle, report)
        report.instructions = get()[4]

    def _run_jobs(self, compiled: CompiledProgram, funcs: tuple, get: Any, set_: Any, cycle: int,
                  report: CycleReport) -> None:
        rt = self.runtime
        while not self.halted:
            job = self.jobs.take(cycle)
            if job is None:
                return
            itf = self.profile.interface
            markers = (itf.mul_err, itf.div_err, itf.mod_err, itf.module_err)
            word = itf.module_err_code_word
            main_regs = get()
            M = self.state.M
            saved = ([M[m] for m in markers], bytes(self.state.mem[word:word + 2]) if word is not None else b"")
            for m in markers:                # the job's own copies of the error markers start at 0
                M[m] = 0
            if word is not None:
                self.state.mem[word:word + 2] = b"\0\0"
            set_(0, 0, 0, "", main_regs[4], 0, -1)
            rt.stack.clear()
            rt.in_job = True
            self.jobs.running = job
            try:
                self._execute(compiled, job.func, job.block, report, cycle, job.label)
            except JobCancelled:
                pass
            finally:
                self.jobs.running = None
                rt.in_job = False
                for m, value in zip(markers, saved[0]):
                    M[m] = value
                if word is not None:
                    self.state.mem[word:word + 2] = saved[1]
                set_(*main_regs[:4], get()[4], 0, main_regs[6])

    def _execute(self, compiled: CompiledProgram, func: Callable[[int], None], block: int, report: CycleReport,
                 cycle: int, job: str | None) -> bool:
        """Run generated code from `block`; False after a fault (recorded, the machine halts). BudgetExceeded and
        JobCancelled pass through to the caller that handles them."""
        try:
            func(block)
        except Fault as exc:
            self._fault(report, compiled, exc, cycle, job)
        except (BudgetExceeded, JobCancelled):
            raise
        except Exception as exc:  # noqa: BLE001 - a bug in the interpreter must not become a traceback
            self._fault(report, compiled, Fault("E-TOOL", f"internal interpreter error: {exc!r}"), cycle, job, exc)
        else:
            return True
        return False

    # ------------------------------------------------------------------ faults and warnings

    def op_span(self, opid: int) -> Span | None:
        if opid < 0:
            return None
        f, i = self._primary.op_index[opid]
        return self.program.files[f].ops[i].span

    def _fault(self, report: CycleReport, compiled: CompiledProgram, exc: Fault, cycle: int, job: str | None,
               cause: BaseException | None = None) -> None:
        opid = _locate(compiled, cause or exc)
        op = compiled.op_index[opid] if opid >= 0 else None
        self._record(report, RuntimeFault(exc.code, exc.message, cycle, self.op_span(opid), "error", op, job))

    def _record(self, report: CycleReport, fault: RuntimeFault) -> None:
        report.faults.append(fault)
        self.faults.append(fault)
        self.halted = True

    def _warn(self, code: str, message: str, opid: int) -> None:
        op = self._primary.op_index[opid] if opid >= 0 else None
        job = self.jobs.running.label if self.jobs.running is not None else None
        warning = RuntimeFault(code, message, self._report.cycle, self.op_span(opid), "warning", op, job)
        self._report.warnings.append(warning)
        self.warnings.append(warning)

    # ------------------------------------------------------------------ coverage and summaries

    @property
    def branch_outcome_count(self) -> int:
        """How many distinct (op, outcome) pairs of conditional jumps, calls, module ends and CASE entries this
        machine has taken so far; it only grows, so a caller watching for new outcomes compares it each cycle and
        asks for branch_outcomes() only when it changed (0 without coverage)."""
        marks = self.runtime.marks
        return 0 if marks is None else marks.branch_outcome_count()

    def branch_outcomes(self) -> frozenset[tuple[int, int]]:
        """The distinct (op id, outcome) pairs taken so far, as a snapshot (op ids as in the compiled program)."""
        marks = self.runtime.marks
        return frozenset() if marks is None else marks.branch_outcomes()

    @property
    def value_outcome_count(self) -> int:
        """How many distinct (op id, outcome) pairs of the value profile (compile.value_slots: bit gates,
        divisors) are marked (it only grows; 0 unless the program was compiled with value_profile)."""
        marks = self.runtime.marks
        return 0 if marks is None else marks.value_outcome_count()

    def value_outcomes(self) -> frozenset[tuple[int, int]]:
        marks = self.runtime.marks
        return frozenset() if marks is None else marks.value_outcomes()

    @property
    def boundary_outcome_count(self) -> int:
        """How many distinct (op id, left - right) of word compares within one of each other are marked (it only
        grows; 0 without coverage)."""
        marks = self.runtime.marks
        return 0 if marks is None else marks.boundary_outcome_count()

    def boundary_outcomes(self) -> frozenset[tuple[int, int]]:
        marks = self.runtime.marks
        return frozenset() if marks is None else marks.boundary_outcomes()

    @property
    def vector_count(self) -> int:
        """How many distinct condition vectors of decisions are recorded (MC/DC; it grows, 0 without coverage)."""
        marks = self.runtime.marks
        return 0 if marks is None else marks.vector_count()

    def decision_vectors_since(self, count: int) -> list[tuple[int, int]]:
        """(decision number, vector) of every vector recorded after the first `count` (see vector_count)."""
        marks = self.runtime.marks
        return [] if marks is None else marks.vectors_since(count)

    @property
    def coverage(self) -> Coverage:
        marks = self.runtime.marks
        if not self.coverage_enabled or marks is None:
            raise ValueError("the machine was created without coverage=True")
        index = self._primary.op_index
        executed = frozenset(index[i] for i in marks.executed())
        branches: dict[tuple[int, int], set[int]] = {}
        for opid, outcome in marks.branch_outcomes():
            branches.setdefault(index[opid], set()).add(outcome)
        bounds: dict[tuple[int, int], set[int]] = {}
        for opid, difference in marks.boundary_outcomes():
            bounds.setdefault(index[opid], set()).add(difference)
        consumers = self._primary.decision_ops
        vectors = {index[consumers[k]]: v for k, v in marks.decision_vectors().items()}
        return Coverage(executed, {k: frozenset(v) for k, v in branches.items()}, vectors,
                        {k: frozenset(v) for k, v in bounds.items()}, self.timers.idle_running_bits())

    @property
    def unknown_modules(self) -> dict[int, int]:
        """Module numbers without a table entry that ran as stubs, with how often (run summary, A-46)."""
        return dict(self.runtime.unknown_modules)


def _locate(compiled: CompiledProgram, exc: BaseException) -> int:
    """Op id of the innermost generated line in the traceback (every generated line belongs to one op)."""
    lineno = None
    tb = exc.__traceback__
    while tb is not None:
        if tb.tb_frame.f_code.co_filename == GENERATED_FILENAME:
            lineno = tb.tb_lineno
        tb = tb.tb_next
    return compiled.op_of_line(lineno) if lineno is not None else -1
