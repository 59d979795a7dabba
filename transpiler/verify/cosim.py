"""Co-simulation: the reference interpreter and an ST executor driven in lockstep by one stimulus; every compared operand is checked after every cycle."""

from __future__ import annotations

import dataclasses
import re
import time
from typing import Callable, Iterable, Mapping, Protocol, Sequence

from transpiler.exec.interp import CompiledProgram
from transpiler.exec.interp.machine import Coverage, Machine
from transpiler.exec.interp.state import byte_cells
from transpiler.exec.st_lines import st_origin
from transpiler.diagnostics import Diagnostics, Span
from transpiler.backends.report.iomap import Accessor, IoMap, Place
from transpiler.ir import Program
from transpiler.verify import pipeline
from transpiler.verify.rundata import DataWrite, run_data, write_data
from transpiler.verify.recording import RecordedReference, Recording, record
from transpiler.verify.scenario import NameTable, OperandRef, Scenario
from transpiler.exec.compiled.shim import HandshakeTimeout, NcModel
from transpiler.verify.simulate import (apply_machine_data, build_machine, effective_machine_parameters, operand_writers,
                                       program_operands, table_values)
from transpiler.verify.stimulus import ExpectationFailure, Stimulus, build_stimulus, check_expectations


class StSide(Protocol):
    """An executor of the translated program (built-in ST interpreter or matiec-compiled C)."""

    name: str

    def get(self, path: str): ...
    def set(self, path: str, value) -> None: ...
    def run_cycle(self) -> None: ...
    # Optional: `bulk_reader(places) -> () -> list` reads all compared places at once (the matiec side has one);
    # `snapshot(places) -> list` reads many places one time (the built-in executor has one).


@dataclasses.dataclass(frozen=True)
class Divergence:
    cycle: int
    operand: str
    name: str
    original: int | str
    translated: int | str


@dataclasses.dataclass(frozen=True)
class MissingOperand:
    """An operand the original program writes that the translation does not hold: a divergence of its own kind."""

    operand: str
    name: str
    written_at: tuple[Span, ...]

    def render(self) -> str:
        if not self.written_at:
            return (f"{self.name} ({self.operand}) is written by the original (through the index register or a PLC "
                    "module) but missing in the translation")
        where = ", ".join(str(s) for s in self.written_at[:3])
        more = f" and {len(self.written_at) - 3} more" if len(self.written_at) > 3 else ""
        return f"{self.name} ({self.operand}) is written by the original at {where}{more} but missing in the translation"


@dataclasses.dataclass
class CosimResult:
    scenario: str
    backend: str
    cycles_run: int
    divergence: Divergence | None
    compared: int                       # operands compared each cycle (the static columns of comparison_for)
    error: str | None = None            # runtime fault or harness problem (not a divergence)
    error_side: str | None = None       # "original" (reference interpreter), "translated", or "machine data": the
                                        # run was refused before cycle 0 (verify/rundata.py), `error_code` says why
    error_code: str | None = None       # the diagnostic code of `error` where it has one of its own
    seconds: float = 0.0
    machine: Machine | None = None
    compared_indexed: int = 0           # addresses added because the program stored to them through the index
    compared_operands: tuple[str, ...] = ()                 # the static columns, by operand
    missing: tuple[MissingOperand, ...] = ()                # written by the original, not held by the translation
    excluded: tuple[tuple[str, str], ...] = ()              # (operand, reason) written by the original, not compared
    expectation_failures: tuple[ExpectationFailure, ...] = ()   # the scenario's `expect` entries, on the original
    coverage: Coverage | None = None    # of the reference over the compared cycles, when asked for
    swept: int = 0                      # addresses compared once after the last cycle (sweep_refs), if it came to that

    @property
    def equivalent(self) -> bool:
        return self.divergence is None and self.error is None and not self.missing


@dataclasses.dataclass(frozen=True)
class Comparison:
    """What the harness compares and drives: (display name, operand) pairs mapped to ST accessors."""

    columns: tuple[tuple[str, OperandRef], ...]
    inputs: tuple[OperandRef, ...]
    missing: tuple[MissingOperand, ...] = ()
    # (operand, reason) of operands the original writes that are deliberately not compared; none today: an operand
    # the translation lacks is `missing`, never excluded.
    excluded: tuple[tuple[str, str], ...] = ()
    sweep: tuple[OperandRef, ...] = ()      # compared once after the last cycle (sweep_refs)
    accessors: tuple[Accessor, ...] = ()    # of the columns, in order
    sweep_accessors: tuple[Accessor, ...] = ()


def comparison_for(program: Program, names: NameTable, iomap: IoMap) -> Comparison:
    """Every operand the program writes plus all outputs (timers and counters included), as far as the map has them.

    These are the static columns: operands named in the program text. Operands reached only through the index
    register (`= M100[X]`, `= W4[X]`, `= S2[X]`) depend on X at run time and are not listed here; cosimulate adds
    each of them from the cycle the reference interpreter first stores to it through an index (_IndexedColumns)."""
    used, written, outputs = program_operands(program)
    prof = program.semantics.profile
    refs = set(written) | set(outputs)
    for r in used:
        if r.kind == "T" and prof.timer_running[0] <= r.addr <= prof.timer_running[1]:
            refs.add(r)
        if r.kind == "C" and prof.counter_running[0] <= r.addr <= prof.counter_running[1]:
            refs.add(r)
    ordered = sorted(refs, key=lambda r: ("IOMTCBWDS".index(r.kind), r.addr))
    cols = [(names.display_name(r), r) for r in ordered if iomap.accessor(str(r)) is not None]
    writers = operand_writers(program)
    missing = tuple(MissingOperand(str(r), names.display_name(r), tuple(writers.get(r, ())))
                    for r in ordered if iomap.accessor(str(r)) is None and r.kind != "I")
    inputs = tuple(sorted((r for r in used if r.kind == "I"), key=lambda r: r.addr))
    sweep = sweep_refs(program, iomap, (ref for _, ref in cols))
    return Comparison(tuple(cols), inputs, missing, sweep=sweep,
                      accessors=tuple(iomap.accessor(str(ref)) for _, ref in cols),
                      sweep_accessors=tuple(iomap.accessor(str(ref)) for ref in sweep))


def sweep_refs(program: Program, iomap: IoMap, static: Iterable[OperandRef]) -> tuple[OperandRef, ...]:
    """Every address of each operand space the translation holds as a whole array (its io map has a row `M*`,
    `B*`, `S*`, ...), except the static columns. They are compared once, after the last cycle of a run: a
    translation that stores where the original never does (an index one too far) shows there, although no
    column names that address. Bytes of a W or D operand that has a variable of its own are left out: the
    array's slot of such a byte is never used."""
    static = set(static)
    skip = {OperandRef(kind, addr) for ref in static for kind, addr in byte_cells(ref.kind, ref.addr)} | static
    for row in iomap.rows:
        m = re.fullmatch(r"([BWD])(\d+)", row.operand)
        if m is not None and "@" not in row.iec_type:
            skip.update(OperandRef(kind, addr) for kind, addr in byte_cells(m.group(1), int(m.group(2))))
    ranges = program.semantics.profile.ranges
    refs = []
    for kind in "IOMTCBS":
        if f"{kind}*" not in iomap.by_operand:
            continue
        for lo, hi in getattr(ranges, kind):
            refs.extend(ref for ref in (OperandRef(kind, addr) for addr in range(lo, hi + 1))
                        if ref not in skip and iomap.accessor(str(ref)) is not None)
    return tuple(refs)


class _StDriver:
    """Applies stimulus, NC model writes and the input latch to an ST side through the io map."""

    def __init__(self, side: StSide, iomap: IoMap, program: Program, cycle_time_ms: int,
                 inputs: Iterable[OperandRef], data: Sequence[DataWrite] = ()):
        self.side = side
        self.data = tuple(data)
        self.mp_restart = program.semantics.profile.interface.mp_restart
        self.iomap = iomap
        self.program = program
        self.nc = NcModel(cycle_time_ms, program.semantics.profile.name,
                          first_cycle_marker=int(program.semantics["first_cycle_marker"]))
        # The input latch rewrites every input the program reads, every cycle, as the interpreter's phase 2 does:
        # a program write to an input is lost, also for inputs the stimulus never drives.
        self.process_inputs: dict[str, int] = {str(ref): 0 for ref in inputs}
        self._latched: tuple[list[str], list[Accessor], Callable[[], list]] | None = None

    def write(self, operand: str, value) -> None:
        acc = self.iomap.accessor(operand)
        if acc is not None:
            acc.write(self.side, value)

    def read(self, operand: str):
        acc = self.iomap.accessor(operand)
        return acc.read(self.side) if acc is not None else 0

    def latch_input(self, operand: str, value: int) -> None:
        """Also rewrite `operand` every cycle from now on (unless it is latched already): an input the program stored
        to through the index is compared, and the interpreter's latch restores it from the process image."""
        if operand not in self.process_inputs:
            self.process_inputs[operand] = value
            self._latched = None

    def _latch(self) -> None:
        """Phase 2 on the ST side: every input back to its process-image value. The inputs are read in one call
        and only the ones that differ (the stimulus changed them, or the program wrote one) are written: the same
        state as writing all of them, without one executor call per input and cycle."""
        if self._latched is None:
            operands = [op for op in self.process_inputs if self.iomap.accessor(op) is not None]
            accessors = [self.iomap.accessor(op) for op in operands]
            self._latched = (operands, accessors, side_reader(self.side, accessors))
        operands, accessors, read = self._latched
        wanted = self.process_inputs
        for operand, acc, held in zip(operands, accessors, read()):
            value = wanted[operand]
            if held != value:
                acc.write(self.side, value)

    def cycle(self, cycle: int, writes: Iterable, actions: Iterable) -> None:
        for w in writes:
            ref = w.ref
            if ref.kind == "I":
                operand = str(ref)
                if operand not in self.process_inputs:
                    self._latched = None
                self.process_inputs[operand] = int(w.value)
            else:
                self.write(str(ref), w.value)
        for action in actions:
            self.nc.enqueue(action)
        for kind, addr, value in self.nc.phase(cycle, lambda m: int(self.read(f"M{m}") or 0)):
            self.write(f"{kind}{addr}", value)
            if kind == "M" and addr == self.mp_restart and value:
                # The NC reads the machine data again before the cycle that sees M4174 (as on the reference).
                write_data(self.side, self.iomap, self.data)
        self._latch()
        self.side.run_cycle()


@dataclasses.dataclass(frozen=True)
class NewColumn:
    """An address the original stored to through the index register or a PLC module, compared from now on;
    `latch` is an input's process-image value, which the translated side's input latch keeps from now on."""

    display: str
    ref: OperandRef
    latch: int | None = None


class _ReferenceHalf:
    """The original program's half: its machine, the scenario's machine data and expectations, and the values
    compared each cycle (the static columns, then the addresses reached through the index register).

    The reference interpreter records the address of every indexed store (Machine.indexed_writes); comparing whole
    operand spaces every cycle instead would cost thousands of reads per cycle. The set only grows, so an address
    stays compared after X has moved on, as a static column would."""

    def __init__(self, machine: Machine, stimulus: Stimulus, scenario: Scenario, comparison: Comparison,
                 iomap: IoMap, names: NameTable):
        self.machine = machine
        self.sweep = comparison.sweep
        self.stimulus = stimulus
        self.scenario = scenario
        self.iomap = iomap
        self.names = names
        static = [ref for _, ref in comparison.columns]
        self.static = machine.reader([(ref.kind, ref.addr) for ref in static])
        # The static columns already compare these; indexed stores come as bytes, and a static W/D column
        # compares its bytes.
        self.seen = {OperandRef(kind, addr) for ref in static for kind, addr in byte_cells(ref.kind, ref.addr)}
        self.seen.update(static)
        self.records = 0                           # interpreter records consumed so far
        self.columns: list[tuple[str, OperandRef]] = []
        self.indexed: Callable[[], list] = list
        self._news: tuple[list[NewColumn], list[MissingOperand], list[ExpectationFailure]] = ([], [], [])
        self._read = lambda ref: machine.read(ref.kind, ref.addr)

    def step(self, cycle: int) -> str | None:
        """Run one cycle: the fault's text when the original faults in it, else None."""
        machine = self.machine
        for data in self.stimulus.machine_updates(cycle):
            apply_machine_data(machine.sys, data)
        report = machine.run_cycle(cycle, self.stimulus.writes(cycle), self.stimulus.nc_actions(cycle))
        if report.faults:
            fault = report.faults[0]
            return f"{fault.code} in cycle {cycle}: {fault.message}"
        if self.scenario.expect:
            self._news[2].extend(check_expectations(self.scenario, cycle, self._read))
        self._update()
        return None

    def values(self) -> tuple[list, list]:
        return self.static(), self.indexed()

    def take_news(self) -> tuple[list[NewColumn], list[MissingOperand], list[ExpectationFailure]]:
        """Indexed columns, missing operands and expectation failures found since the last call."""
        news, self._news = self._news, ([], [], [])
        return news

    def coverage(self):
        return self.machine.coverage if self.machine.coverage_enabled else None

    def final_values(self) -> list:
        """The values of the sweep's addresses (see sweep_refs), read once after the last cycle."""
        read = self.machine.read
        return [read(ref.kind, ref.addr) for ref in self.sweep]

    def _update(self) -> None:
        """Take the indexed stores recorded since the last call; O(1) when there are none."""
        count = self.machine.indexed_write_count
        if count == self.records:
            return
        before = len(self.columns)
        for kind, addr in self.machine.indexed_writes(self.records):
            self._add(OperandRef(kind, addr))
        self.records = count
        if len(self.columns) != before:
            self.indexed = self.machine.reader([(ref.kind, ref.addr) for _, ref in self.columns])

    def _add(self, ref: OperandRef) -> None:
        if ref in self.seen:
            return
        self.seen.add(ref)
        if self.iomap.accessor(str(ref)) is None:
            # The translation has no place for an operand the original wrote: a finding, never skipped.
            self._news[1].append(MissingOperand(str(ref), self.names.display_name(ref), ()))
            return
        display = self.names.display_name(ref)
        self.columns.append((display, ref))
        latch = self.machine.state.process_inputs[ref.addr] if ref.kind == "I" else None
        self._news[0].append(NewColumn(display, ref, latch))


class _TranslatedHalf:
    """The translated program's half: its driver and the values it holds at the compared places."""

    def __init__(self, side: StSide, driver: "_StDriver", stimulus: Stimulus, accessors: list[Accessor]):
        self.side = side
        self.driver = driver
        self.stimulus = stimulus
        self.static = side_reader(side, accessors)
        self.columns: list[tuple[str, OperandRef]] = []
        self.accessors: list[Accessor] = []
        self.indexed: Callable[[], list] = list

    def step(self, cycle: int) -> None:
        """The scenario's machine data for this side's own system context, then one cycle through the driver."""
        translated = getattr(self.side, "sys", None)
        if translated is not None and translated.sys is not None:
            for data in self.stimulus.machine_updates(cycle):
                apply_machine_data(translated.sys, data)
        self.driver.cycle(cycle, self.stimulus.writes(cycle), self.stimulus.nc_actions(cycle))

    def add(self, columns: list[NewColumn]) -> None:
        if not columns:
            return
        for column in columns:
            self.columns.append((column.display, column.ref))
            self.accessors.append(self.driver.iomap.accessor(str(column.ref)))
            if column.latch is not None:
                self.driver.latch_input(str(column.ref), column.latch)
        self.indexed = side_reader(self.side, self.accessors)

    def values(self) -> tuple[list, list]:
        return self.static(), self.indexed()

    def final_values(self, accessors: Sequence[Accessor]) -> list:
        """The values at the accessors' places, read once: in one call where the side can (its snapshot or bulk
        reader)."""
        snapshot = getattr(self.side, "snapshot", None)
        if snapshot is not None:
            return snapshot([acc.place for acc in accessors])
        return side_reader(self.side, accessors)()


class _LocalReference:
    """The reference half run in this process, cycle by cycle beside the translated one."""

    def __init__(self, half: _ReferenceHalf):
        self.half = half
        self.missing: list = []
        self.failures: list = []
        self._new: list[NewColumn] = []
        self._values: tuple[list, list] = ([], [])

    def fault(self, cycle: int) -> str | None:
        fault = self.half.step(cycle)
        if fault is None:
            self._values = self.half.values()
            self._new, missing, failures = self.half.take_news()
            self.missing += [(cycle, m) for m in missing]
            self.failures += failures
        return fault

    def new_columns(self, cycle: int) -> list[NewColumn]:
        return self._new

    def agrees(self, cycle: int, values: tuple[list, list]) -> bool:
        return self._values == values

    def values(self, cycle: int) -> tuple[list, list]:
        return self._values

    def coverage(self):
        return self.half.coverage()

    def final_values(self) -> list:
        return self.half.final_values()

    def close(self) -> None:
        pass


def first_divergence(cycle: int, columns: Sequence[tuple[str, OperandRef]], a_values: list,
                     b_values: list) -> Divergence | None:
    """The first column whose original and translated values differ (None when all agree)."""
    if a_values == b_values:
        return None
    return next(Divergence(cycle, str(ref), display, a, b)
                for (display, ref), a, b in zip(columns, a_values, b_values) if a != b)


def side_reader(side: StSide, accessors: list[Accessor]) -> Callable[[], list]:
    """Reads the accessors' values from the ST side in one call where the side can (matiec), else one by one."""
    bulk_reader = getattr(side, "bulk_reader", None)
    if bulk_reader is not None:
        return bulk_reader([acc.place for acc in accessors])
    return lambda: [acc.read(side) for acc in accessors]


def cosimulate(program: Program, make_side: Callable[[], StSide], iomap: IoMap, scenario: Scenario, names: NameTable,
               stimulus: Stimulus | None = None, *, cycles: int | None = None, coverage: bool = False,
               progress: Callable[[int, int], None] | None = None,
               record: Callable[[int, list, list], None] | None = None,
               compiled: CompiledProgram | None = None, base_mp: Mapping | None = None,
               pipelined: bool = False, inspect: Callable[[int, Callable, Callable], None] | None = None,
               recording: Recording | None = None, comparison: Comparison | None = None) -> CosimResult:
    """Run both programs on one stimulus; stop at the first divergence, runtime fault or after `cycles`. Callers
    that co-simulate one program many times pass it `compiled` once (see build_machine).

    Compared after every cycle: the static columns of comparison_for (one bulk read where the side can; `record`
    sees only these), then every address the original has written through the index register or a PLC module so
    far, from that cycle on (result.compared_indexed); one the translation has no place for is result.missing.
    After the last cycle of a run that agreed so far, every other address of the spaces the translation holds as
    arrays (sweep_refs, result.swept).

    `pipelined` runs the reference interpreter in a forked process of its own, ahead of the translated side
    (pipeline.py), where the platform can fork and no `record` wants every cycle's values; the result is the same
    as in lockstep. It pays where a second CPU is free (pipeline.worthwhile).

    `base_mp` are the project's machine parameters (None: it has no MP file), which the ST must hold as shipped
    (else rundata.SHIPPED); the scenario's own are written into its globals before cycle 0 and at an MP restart
    (rundata.run_data; what it cannot hold: rundata.UNREPRESENTABLE). `expect` is checked on the original.

    `inspect(cycle, original, translated)` is called after each cycle both sides ran, with a lookup `(kind, addr) ->
    value` into each side (None where the translation holds no such operand); it runs the halves in lockstep.

    `recording` (record_reference of this scenario) replays the reference half instead of running it: the result
    is the one the run with the reference interpreter gives (recording.py), without coverage and without
    `inspect`; `comparison` is comparison_for(program, names, iomap), for callers that run one program many times."""
    diags = Diagnostics()
    stimulus = stimulus or build_stimulus(scenario, names)
    parameters = effective_machine_parameters(scenario, diags, base_mp)
    machine = build_machine(program, scenario, diags, coverage=coverage, compiled=compiled, parameters=parameters)
    side = make_side()
    getattr(side, "attach_machine", lambda m: None)(machine)    # HH_Sys models: a copy of the machine's context
    cycle_time = machine.cycle_time_ms
    comparison = comparison or comparison_for(program, names, iomap)
    data = run_data(side, iomap, program, parameters[0], cycle_time, base_mp, table_values(program, scenario))
    accessors = list(comparison.accessors)
    driver = _StDriver(side, iomap, program, cycle_time, comparison.inputs, data.writes)
    translated = _TranslatedHalf(side, driver, stimulus, accessors)
    total = min(stimulus.cycles, cycles) if cycles is not None else stimulus.cycles
    result = CosimResult(scenario.name or "scenario", side.name, 0, None, len(comparison.columns), machine=machine,
                         compared_operands=tuple(str(ref) for _, ref in comparison.columns),
                         missing=comparison.missing, excluded=comparison.excluded)
    if data.refusal is not None:
        result.error_code, result.error = data.refusal
        result.error_side = "machine data"
        return result
    write_data(side, iomap, data.writes)        # power-on: the run's machine data, before cycle 0
    start = time.perf_counter()
    sweep = comparison.sweep
    half = _ReferenceHalf(machine, stimulus, scenario, comparison, iomap, names)
    if inspect is not None:
        if recording is not None:
            raise ValueError("a replayed reference has no machine to inspect")
        record = _with_inspection(record, inspect, machine.read, st_lookup(side, iomap))
    pipelined = (pipelined and record is None and recording is None and total > pipeline.BATCH
                 and pipeline.fork_available())
    reference = _reference(half, total, pipelined, recording)
    try:
        _compare_cycles(result, reference, translated, comparison, total, progress, record)
        complete = result.cycles_run == total
        if complete and result.divergence is None and result.error is None:
            result.swept = len(sweep)
            result.divergence = _swept_divergence(total - 1, sweep, reference.final_values(),
                                                  translated.final_values(comparison.sweep_accessors), names)
        if coverage and recording is None and (complete or not pipelined):
            result.coverage = reference.coverage()
    finally:
        reference.close()
    result.seconds = time.perf_counter() - start
    last = result.cycles_run - 1
    result.missing += tuple(m for cycle, m in reference.missing if cycle <= last)
    result.expectation_failures = tuple(f for f in reference.failures if f.cycle <= last)
    result.compared_indexed = len(translated.columns)
    if pipelined:
        _after_pipelined(result, half, machine, coverage and not complete)
    return result


def _after_pipelined(result: CosimResult, half: _ReferenceHalf, machine, rerun: bool) -> None:
    """This process's machine did not run; with `rerun` (coverage of a run that ended early) the reference process
    ran on beyond the end, and coverage counts the cycles it ran before the run ended (the cycle that ended it by a
    fault included), as in lockstep, so they run again here."""
    result.machine = None
    if rerun:
        for cycle in range(result.cycles_run + (result.error is not None)):
            half.step(cycle)
        result.coverage = half.coverage()
        result.machine = machine


def st_lookup(side: StSide, iomap: IoMap) -> Callable[[str, int], object]:
    """`(kind, addr) -> value` of an operand in the ST side through the io map's accessors, None where the map has
    no place for it."""
    def read(kind: str, addr: int):
        acc = iomap.accessor(f"{kind}{addr}")
        return acc.read(side) if acc is not None else None
    return read


def _with_inspection(record, inspect, original, translated):
    def both(cycle: int, a: list, b: list) -> None:
        if record is not None:
            record(cycle, a, b)
        inspect(cycle, original, translated)
    return both


def _reference(half: _ReferenceHalf, total: int, pipelined: bool, recording: Recording | None):
    """The reference half as the cycle loop reads it: replayed, in a process of its own, or in this one."""
    if recording is not None:
        return RecordedReference(recording)
    if pipelined:
        return pipeline.PipelinedReference(half, total)
    return _LocalReference(half)


def record_reference(program: Program, iomap: IoMap, scenario: Scenario, names: NameTable,
                     stimulus: Stimulus | None = None, *, compiled: CompiledProgram | None = None,
                     base_mp: Mapping | None = None, comparison: Comparison | None = None) -> Recording:
    """The reference half of cosimulate's run of `scenario`, run once through all its cycles and kept, for
    cosimulate(..., recording=) to replay against many translated sides."""
    diags = Diagnostics()
    stimulus = stimulus or build_stimulus(scenario, names)
    parameters = effective_machine_parameters(scenario, diags, base_mp)
    machine = build_machine(program, scenario, diags, compiled=compiled, parameters=parameters)
    comparison = comparison or comparison_for(program, names, iomap)
    return record(_ReferenceHalf(machine, stimulus, scenario, comparison, iomap, names), stimulus.cycles)


def _swept_divergence(cycle: int, refs: tuple[OperandRef, ...], a_values: list, b_values: list,
                      names: NameTable) -> Divergence | None:
    if a_values == b_values:
        return None
    ref, a, b = next((ref, a, b) for ref, a, b in zip(refs, a_values, b_values) if a != b)
    return Divergence(cycle, str(ref), names.display_name(ref), a, b)


def _compare_cycles(result: CosimResult, reference, translated: _TranslatedHalf, comparison: Comparison,
                    total: int, progress: Callable[[int, int], None] | None,
                    record: Callable[[int, list, list], None] | None) -> None:
    """The cycle loop: both halves run each cycle, then their compared values meet (see cosimulate)."""
    for cycle in range(total):
        fault = reference.fault(cycle)
        if fault is not None:
            result.error, result.error_side = fault, "original"
            return
        try:
            translated.step(cycle)
        except HandshakeTimeout as exc:
            result.error = f"E-SIM-HANDSHAKE-TIMEOUT on the translated side in cycle {exc.cycle}"
            result.error_side = "translated"
            return
        except Exception as exc:  # noqa: BLE001 - an executor fault is a result, reported with its message
            result.error = f"translated program failed in cycle {cycle}: {type(exc).__name__}: {exc}"
            result.error_side = "translated"
            return
        result.cycles_run = cycle + 1
        translated.add(reference.new_columns(cycle))
        b_values = translated.values()
        if record is not None:
            record(cycle, reference.values(cycle)[0], b_values[0])
        if not reference.agrees(cycle, b_values):
            a_values = reference.values(cycle)
            result.divergence = (first_divergence(cycle, comparison.columns, a_values[0], b_values[0])
                                 or first_divergence(cycle, translated.columns, a_values[1], b_values[1]))
            if result.divergence is not None:
                return
        if progress is not None:
            progress(cycle + 1, total)


def _read_plan(places: list[Place]) -> tuple[list[str], list[tuple[int, int, bool, bool]]]:
    """The variables to read for `places` and, per place, (first variable, width, big endian, text)."""
    paths: list[str] = []
    plan: list[tuple[int, int, bool, bool]] = []
    for place in places:
        plan.append((len(paths), place.width, place.big_endian, place.text))
        if place.width == 0:
            paths.append(place.path)
        else:
            array, base = place.path[:-1].split("[")
            paths.extend(f"{array}[{int(base) + k}]" for k in range(place.width))
    return paths, plan


def runtime_reader(rt, places: list[Place]) -> Callable[[], list]:
    """The values of `places` in the built-in executor's runtime as the io map's accessors read them (BOOL as 0/1,
    integers as they are, multi-byte operands combined from their bytes and sign-extended, texts as str), from one
    generated read of every variable involved instead of one path lookup per operand and cycle."""
    paths, plan = _read_plan(places)
    env, v = rt.read_expressions(paths)
    items = []
    for first, width, big, text in plan:
        if width == 0:
            # unary plus gives a BOOL as 1 or 0 and an integer as it is, without int()'s call
            items.append(f"str({v[first]})" if text else f"+{v[first]}")
            continue
        parts = [f"(({v[first + (width - 1 - k if big else k)]} & 255) << {8 * k})" for k in range(width)]
        sign = 1 << (8 * width - 1)
        items.append(f"((({' | '.join(parts)}) ^ {sign}) - {sign})")
    exec(compile("def read():\n    return [" + ", ".join(items) + "]\n", "<cosim-reader>", "exec"), env)
    return env["read"]


def runtime_snapshot(rt, places: list[Place]) -> list:
    """The values runtime_reader(rt, places)() gives, read once without generating a reader: for the sweep after
    the last cycle, where thousands of places are read one time."""
    paths, plan = _read_plan(places)
    v = rt.values(paths)
    out: list = []
    for first, width, big, text in plan:
        if width == 0:
            out.append(str(v[first]) if text else int(v[first]))
            continue
        word = 0
        for k in range(width):
            word |= (v[first + (width - 1 - k if big else k)] & 255) << (8 * k)
        sign = 1 << (8 * width - 1)
        out.append((word ^ sign) - sign)
    return out


def builtin_side_factory(st_text: str, filename: str = "project.st") -> Callable[[], StSide]:
    """The built-in ST executor: the ST text is parsed once, every call gives a fresh runtime."""
    from transpiler.exec.stexec import load_st
    return _builtin_sides(load_st(st_text, filename), st_text, 0)


class BuiltinSchema:
    """Many mutants of one ST text compiled once by the built-in executor (a mutant schema, stexec/schema.py):
    `factory(number)` gives fresh runtimes of mutant `number` (0 the original, stexec.PROBE the original recording
    the mutants it infects); `unswitched` are the mutants the schema does not hold."""

    def __init__(self, st_text: str, mutations: Sequence, filename: str = "project.st"):
        from transpiler.exec.stexec import load_st
        from transpiler.exec.compiled.sysfb import modules_in
        self.st_text = st_text
        self.project = load_st(st_text, filename, mutations=mutations, impure=modules_in(st_text))
        self.unswitched = self.project.unswitched

    def factory(self, number: int) -> Callable[[], StSide]:
        return _builtin_sides(self.project, self.st_text, number)


def _builtin_sides(project, st_text: str, mutant: int) -> Callable[[], StSide]:
    from transpiler.exec.stexec import StRuntimeError
    from transpiler.exec.compiled.sysfb import SysBinding

    class _Side:
        name = "builtin"

        def __init__(self) -> None:
            self.sys = SysBinding(st_text)
            self.rt = project.instantiate(self.sys.externals() or None, mutant)

        def attach_machine(self, machine) -> None:
            self.sys.attach(machine)

        @property
        def infected(self) -> set[int]:
            """The mutants this (probing) run has infected so far."""
            return self.rt.infected

        def get(self, path: str):
            return self.rt.get(path)

        def set(self, path: str, value) -> None:
            self.rt.set(path, value)

        def bulk_reader(self, places: list[Place]) -> Callable[[], list]:
            return runtime_reader(self.rt, places)

        def snapshot(self, places: list[Place]) -> list:
            return runtime_snapshot(self.rt, places)

        def run_cycle(self) -> None:
            try:
                self.rt.run_cycle()
            except StRuntimeError as exc:
                where = f" ({st_origin(st_text, exc.span.line)})" if exc.span is not None else ""
                raise StRuntimeError(f"{exc.message}{where}", exc.span) from None
            self.sys.tick()

    return _Side
