"""Simulation: runs the original program on the reference interpreter against a scenario, with traces and expectations."""

from __future__ import annotations

import dataclasses
import time
from decimal import Decimal
from pathlib import Path
from typing import Any, Callable, Mapping

import yaml

from transpiler.diagnostics import CompileFailed, Diagnostics, Span
from transpiler.exec.interp import CompiledProgram, Machine, MachineConfigError, RuntimeFault
from transpiler.ir import Program
from transpiler.frontend.parse import MpParser
from transpiler.frontend.opcodes import implicit_writes
from transpiler.verify.index_range import index_ranges
from transpiler.verify.scenario import TABLE_FILES, MachineData, NameTable, OperandRef, Scenario, compose_yaml, \
    normalize_value
from transpiler.language.semantics import PROFILES
from transpiler.exec.compiled.shim import NcActionError, UnknownModule
from transpiler.verify.stimulus import ExpectationFailure, Stimulus, build_stimulus, check_expectations, observed_operands
from transpiler.verify.traces import TraceRecorder

_WRITES = {"ST", "STN", "SET", "RES", "SETN", "RESN", "STBITS", "WST", "POP", "INC", "DEC", "SST"}
_NAMED_KINDS = frozenset("MIOTCBWDS")


# ---------------------------------------------------------------------------------------------
# names and operands of a program


def _operand_refs(op) -> list[OperandRef]:   # noqa: ANN001 - ir.Op
    o = op.operand
    if o is None or o.indexed or o.kind not in _NAMED_KINDS:
        return []
    count = op.nbits if op.code in ("LDBITS", "STBITS") else 1
    return [OperandRef(o.kind, o.addr + i) for i in range(count)]


def operand_writers(program: Program) -> dict[OperandRef, list[Span]]:
    """Every operand an instruction writes, with the source lines that write it: the targets it names, and the
    error markers and error-code word arithmetic and PLC module calls set without naming them."""
    writers: dict[OperandRef, list[Span]] = {}
    interface = program.semantics.profile.interface
    flag = program.semantics["add_overflow"] == "flag"
    for code in program.files:
        for op in code.ops:
            refs = _operand_refs(op) if op.code in _WRITES else []
            refs += [OperandRef(kind, addr) for kind, addr in implicit_writes(op, interface, flag)]
            for ref in refs:
                writers.setdefault(ref, []).append(op.span)
    return writers


def program_operands(program: Program) -> tuple[set[OperandRef], set[OperandRef], set[OperandRef]]:
    """(every operand named by an instruction, the ones the program writes, the outputs it uses)."""
    used = {ref for code in program.files for op in code.ops for ref in _operand_refs(op)}
    written = set(operand_writers(program))     # one rule for "written" (the index register X is never named here)
    outputs = {r for r in used if r.kind == "O"}
    return used, written, outputs


def indexed_operands(program: Program, span: int = 64) -> tuple[set[OperandRef], set[OperandRef]]:
    """(the operands instructions through the index register read, the ones they write): base + X for the values X
    can hold at the instruction (verify/index_range), where those are known and at most `span` apart; B/W/D
    operands step by their width from base + the smallest X (the index counts bytes)."""
    ranges = index_ranges(program)
    read: set[OperandRef] = set()
    written: set[OperandRef] = set()
    for f, code in enumerate(program.files):
        for i, op in enumerate(code.ops):
            o = op.operand
            x = ranges.get((f, i))
            if o is None or not o.indexed or o.kind not in _NAMED_KINDS or o.kind == "S" or x is None \
                    or x[1] - x[0] > span:
                continue
            step = {"W": 2, "D": 4}.get(o.kind, 1)
            refs = {OperandRef(o.kind, a) for a in range(o.addr + x[0], o.addr + x[1] + 1, step) if a >= 0}
            (written if op.code in _WRITES else read).update(refs)
    return read, written


def project_names(program: Program) -> NameTable:
    """Scenario names: every .def symbol (aliases included) plus every raw operand the program uses."""
    symbols: dict[str, OperandRef] = {}
    constants: set[str] = set()
    non_toggle: set[str] = set()
    for name, sym in program.symbols.items():
        if sym.kind == "K":
            constants.add(name)
            non_toggle.add(name)
            continue
        symbols[name] = OperandRef(sym.kind, sym.addr)
        if sym.alias_of:
            non_toggle.add(name)
    used, _, _ = program_operands(program)
    for ref in used:
        symbols.setdefault(str(ref), ref)
    rows = {row.symbol: OperandRef(row.kind, row.addr) for row in program.data_rows}
    return NameTable.for_profile(symbols, program.semantics.profile.name, non_toggle=frozenset(non_toggle),
                                 constants=frozenset(constants), table_rows=rows)


# ---------------------------------------------------------------------------------------------
# machine parameters


def machine_parameters(scenario: Scenario, diags: Diagnostics) -> tuple[dict[tuple[int, int], Decimal], dict]:
    """The MP file of the scenario, overridden by its inline `mp`; with the span of every value."""
    mp: dict[tuple[int, int], Decimal] = {}
    spans: dict[tuple[int, int], Span] = {}
    path = scenario.machine_parameters
    if path is not None:
        try:
            lines = tuple(Path(path).read_text(encoding="latin-1").splitlines())
        except OSError as exc:
            diags.report("E-SCENARIO", scenario.span_of("machine_parameters"), f"cannot read {path}: {exc}")
            lines = ()
        for p in MpParser().parse_lines(str(path), lines, diags):
            mp[(p.number, p.index)] = p.value
            spans[(p.number, p.index)] = p.span
    for (number, index), value in scenario.mp.items():
        key = (number, index or 0)
        mp[key] = value
        spans[key] = scenario.span_of("mp", (number, index))
    return mp, spans


# ---------------------------------------------------------------------------------------------
# running a scenario


class _Trace(TraceRecorder):
    """TraceRecorder fed by Machine.reader, whose values are already in canonical form (bits 0/1, signed B/W/D).

    Normalizing every value again dominated long simulations with wide default observations.
    """

    def record_canonical(self, cycle: int, values: list[int | str]) -> None:
        self.rows.append((cycle, tuple(values)))


@dataclasses.dataclass
class SimulationResult:
    trace: TraceRecorder
    failures: list[ExpectationFailure]
    fault: RuntimeFault | None
    warnings: list[RuntimeFault]
    cycles_run: int
    instructions: int
    seconds: float
    machine: Machine
    fault_span: Span | None = None          # where to point for a fault without a program location


def effective_machine_parameters(scenario: Scenario, diags: Diagnostics, base_mp: Mapping | None = None
                                 ) -> tuple[dict[tuple[int, int], Decimal], dict]:
    """The machine parameters a scenario runs with: its MP file where it names one, else `base_mp` (the ones the
    translation was made with), and its inline `mp` values over either. A file replaces the base as a whole: a
    machine whose parameter file lacks an entry (module 9032 then reports an error) is a scenario of its own."""
    mp, spans = machine_parameters(scenario, diags)
    if scenario.machine_parameters is not None:
        return mp, spans
    return {**(base_mp or {}), **mp}, spans


def build_machine(program: Program, scenario: Scenario, diags: Diagnostics, *, coverage: bool = False,
                  compiled: CompiledProgram | None = None, base_mp: Mapping | None = None,
                  parameters: tuple[dict, dict] | None = None) -> Machine:
    """A machine set up from the scenario (MPs, cycle time, module results); raises CompileFailed on bad input.
    `compiled` (the program compiled once by the caller) saves compiling it again for every scenario; `base_mp`
    (the project's machine parameters) applies where the scenario sets no value of its own; `parameters` are
    those already read by effective_machine_parameters (so the MP file is read once per run)."""
    mp, spans = parameters if parameters is not None else effective_machine_parameters(scenario, diags, base_mp)
    diags.raise_if_errors()
    cycle_time = scenario.cycle_time_ms if "cycle_time_ms" in scenario.model_fields_set else None
    try:
        machine = Machine(program, mp, cycle_time, coverage=coverage, module_results=scenario.module_results,
                          mp_spans=spans, compiled=compiled, number_mp4111=int(program.semantics["number_mp4111"]),
                          data=table_values(program, scenario))
        if scenario.machine is not None:
            apply_machine_data(machine.sys, scenario.machine)
        return machine
    except MachineConfigError:
        raise
    except (UnknownModule, ValueError) as exc:
        diags.report("E-SCENARIO", scenario.span_of("module_results"), str(exc))
        raise CompileFailed(diags.items) from None


def table_values(program: Program, scenario: Scenario) -> dict[str, int | str]:
    """The value of every data-table row in a run: the table's, or the scenario's `mp_data` (normalised to the
    operand's width as the interpreter holds it)."""
    values: dict[str, int | str] = {}
    for row in program.data_rows:
        value = scenario.mp_data.get(row.symbol, row.value)
        values[row.symbol] = normalize_value(row.kind, value)
    return values


def apply_machine_data(sys, data: MachineData) -> None:
    """Load `data` (axes, drives, table elements, NC status) into a system context of the PLC module models."""
    for number, value in data.status.items():
        sys.set_status(number, value)
    for axis, values in data.axes.items():
        sys.set_axis(axis, values.active, values.position)
    if data.drives is not None:
        sys.set_drives(data.drives.available, data.drives.switching_off)
    for entry in data.tables:
        sys.set_table(TABLE_FILES[entry.table], entry.line, entry.element, entry.value)


def run_scenario(program: Program, scenario: Scenario, names: NameTable, stimulus: Stimulus | None = None, *,
                 machine: Machine | None = None, diags: Diagnostics | None = None,
                 after_cycle: Callable[[int, Machine], None] | None = None) -> SimulationResult:
    """Run every cycle of the scenario; stops at the first runtime fault. Raises CompileFailed on bad input.
    `after_cycle(cycle, machine)` sees the machine after each cycle that ran without a fault."""
    diags = diags or Diagnostics()
    stimulus = stimulus or build_stimulus(scenario, names)
    machine = machine or build_machine(program, scenario, diags)
    used, written, outputs = program_operands(program)
    # Without `observe` the trace shows what the program reads from the machine (its inputs) beside what it writes:
    # a trace of outputs alone cannot tell why they changed.
    inputs = {r for r in used if r.kind == "I"}
    columns = observed_operands(scenario, names, written, outputs | inputs, diags)
    trace = _Trace(columns)
    read: Callable[[OperandRef], Any] = lambda ref: machine.read(ref.kind, ref.addr)  # noqa: E731
    observed = machine.reader([(ref.kind, ref.addr) for _, ref in columns])
    failures: list[ExpectationFailure] = []
    fault: RuntimeFault | None = None
    start = time.perf_counter()
    cycles_run = 0
    for cycle in range(stimulus.cycles):
        for data in stimulus.machine_updates(cycle):
            apply_machine_data(machine.sys, data)
        try:
            report = machine.run_cycle(cycle, stimulus.writes(cycle), stimulus.nc_actions(cycle))
        except NcActionError as exc:
            diags.report("E-SCENARIO", _nc_event_span(scenario, cycle), str(exc))
            raise CompileFailed(diags.items) from None
        cycles_run = cycle + 1
        trace.record_canonical(cycle, observed())
        if report.faults:
            fault = report.faults[0]
            break
        if after_cycle is not None:
            after_cycle(cycle, machine)
        failures += check_expectations(scenario, cycle, read)
    seconds = time.perf_counter() - start
    fault_span = _nc_event_span(scenario, fault.cycle) if fault is not None and fault.span is None else None
    return SimulationResult(trace, failures, fault, list(machine.warnings), cycles_run, machine.instructions, seconds,
                            machine, fault_span)


def _nc_event_span(scenario: Scenario, cycle: int) -> Span:
    """The nc event at or before `cycle` that a NC problem most likely belongs to."""
    best = None
    for i, event in enumerate(scenario.events):
        if event.nc is not None and event.cycle <= cycle:
            best = i
    return scenario.span_of("events", best, "nc") if best is not None else scenario.span_of()


def scenario_settings(path: Path) -> tuple[str | None, dict, Span | None]:
    """The scenario's `profile` and `semantics` (needed before compiling), and where `semantics` is written."""
    try:
        node = compose_yaml(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return None, {}, None          # load_scenario reports it with its line
    profile, semantics, where = None, {}, None
    if isinstance(node, yaml.MappingNode):
        for key, value in node.value:
            if not isinstance(key, yaml.ScalarNode):
                continue
            if key.value == "profile" and isinstance(value, yaml.ScalarNode) and value.value in PROFILES:
                profile = value.value
            elif key.value == "semantics" and isinstance(value, yaml.MappingNode):
                where = Span(str(path), key.start_mark.line + 1, key.start_mark.column + 1)
                data = yaml.safe_load(yaml.serialize(value))
                semantics = data if isinstance(data, dict) else {}
    return profile, semantics, where
