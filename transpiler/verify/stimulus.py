"""Scenario -> precomputed per-cycle stimulus (writes, NC actions); expectation checks, trace columns, YAML export."""

from __future__ import annotations

import dataclasses
import os
import random
from decimal import Decimal
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, NamedTuple

import yaml

from transpiler.diagnostics import Diagnostic, Diagnostics, Span
from transpiler.verify.scenario import (BIT_KINDS, KIND_ORDER, Event, MachineData, NameProblem, NameTable, OperandRef,
                                        Scenario, bind, is_glob, mp_key_text, parse_operand, values_equal)


class Write(NamedTuple):
    """One value the harness writes into an operand before the PLC cycle runs."""

    ref: OperandRef
    value: int | str
    name: str   # the scenario's name for the operand (for reproducers and messages)


@dataclasses.dataclass(frozen=True)
class CycleStimulus:
    """What happens at the start of one cycle: `sets` (initial, then events) before `toggles`; NC actions to queue."""

    sets: tuple[Write, ...] = ()
    toggles: tuple[Write, ...] = ()
    nc: tuple[dict[str, Any], ...] = ()
    machine: tuple[MachineData, ...] = ()     # axes, drives, tables the PLC modules read from now on

    @property
    def writes(self) -> tuple[Write, ...]:
        return self.sets + self.toggles


_QUIET = CycleStimulus()


@dataclasses.dataclass(frozen=True)
class Stimulus:
    """The executor-independent input of a whole run; rebuild it with build_stimulus after editing the scenario.

    `steps` holds only the cycles in which something happens (long runs stay small).
    """

    cycles: int
    cycle_time_ms: int
    steps: Mapping[int, CycleStimulus]
    toggled: tuple[tuple[str, OperandRef], ...]   # the random inputs after glob expansion, in draw order
    diagnostics: tuple[Diagnostic, ...] = ()

    def step(self, cycle: int) -> CycleStimulus:
        if not 0 <= cycle < self.cycles:
            raise IndexError(f"cycle {cycle} outside 0..{self.cycles - 1}")
        return self.steps.get(cycle, _QUIET)

    def writes(self, cycle: int) -> tuple[Write, ...]:
        return self.step(cycle).writes

    def nc_actions(self, cycle: int) -> tuple[dict[str, Any], ...]:
        return self.step(cycle).nc

    def machine_updates(self, cycle: int) -> tuple[MachineData, ...]:
        return self.step(cycle).machine

    @property
    def toggle_count(self) -> int:
        return sum(len(step.toggles) for step in self.steps.values())


def _expand_random(scenario: Scenario, names: NameTable, diags: Diagnostics) -> list[tuple[str, OperandRef]]:
    """Random inputs: globs expanded once over the name table, aliases/constants/non-bits dropped, sorted by name."""
    chosen: dict[str, OperandRef] = {}
    for i, pattern in enumerate(scenario.random.inputs if scenario.random else ()):
        if not is_glob(pattern):
            ref = names.resolve(pattern)   # bind() has already checked it
            if pattern not in names.non_toggle and ref.kind in BIT_KINDS:
                chosen[pattern] = ref
            continue
        matched = names.match(pattern)
        usable = [(n, r) for n, r in ((n, _resolve_quiet(names, n)) for n in matched)
                  if r is not None and r.kind in BIT_KINDS and n not in names.non_toggle]
        span = scenario.span_of("random", "inputs", i)
        if not matched:
            diags.report("E-SCENARIO-UNUSED", span, f"random input pattern '{pattern}' matches no name of the project")
        elif not usable:
            diags.report("E-SCENARIO-UNUSED", span,
                          f"random input pattern '{pattern}' matches only aliases, constants or non-bit operands")
        chosen.update(usable)
    expanded: list[tuple[str, OperandRef]] = []
    seen: set[OperandRef] = set()
    for name in sorted(chosen):
        # two names of one operand must not toggle it twice in a cycle
        if chosen[name] not in seen:
            seen.add(chosen[name])
            expanded.append((name, chosen[name]))
    return expanded


def _resolve_quiet(names: NameTable, name: str) -> OperandRef | None:
    try:
        return names.resolve(name)
    except NameProblem:
        return None


def _bit(value: int | str) -> int:
    return 1 if value else 0


def build_stimulus(scenario: Scenario, names: NameTable) -> Stimulus:
    """Precompute every cycle's writes and NC actions; raises ScenarioError when a name or value is unusable."""
    bound = bind(scenario, names)
    diags = Diagnostics()
    diags.extend(bound.warnings)
    toggles = _expand_random(bound, names, diags) if bound.random else []
    rng = random.Random(bound.random.seed) if bound.random else None
    probability = bound.random.toggle_probability if bound.random else 0.0
    by_cycle: dict[int, list[Event]] = {}
    for event in bound.events:
        by_cycle.setdefault(event.cycle, []).append(event)
    # The stimulus is the process outside the PLC: it remembers what it last drove onto each operand.
    driven: dict[OperandRef, int | str] = {}
    steps: dict[int, CycleStimulus] = {}
    for cycle in range(bound.cycles):
        sets: list[Write] = []
        if cycle == 0:
            sets += [Write(bound.ref(n), v, n) for n, v in bound.initial.items()]
        events = by_cycle.get(cycle, [])
        for event in events:
            sets += [Write(bound.ref(n), v, n) for n, v in event.set.items()]
        for write in sets:
            driven[write.ref] = write.value
        flips: list[Write] = []
        if rng is not None:
            for name, ref in toggles:
                # draw for every input every cycle, so one toggle never shifts the draws of the others
                if rng.random() < probability:
                    driven[ref] = 1 - _bit(driven.get(ref, 0))
                    flips.append(Write(ref, driven[ref], name))
        nc = tuple(event.nc.as_dict() for event in events if event.nc is not None)
        machine = tuple(event.machine for event in events if event.machine is not None)
        if sets or flips or nc or machine:
            steps[cycle] = CycleStimulus(tuple(sets), tuple(flips), nc, machine)
    return Stimulus(bound.cycles, bound.cycle_time_ms, steps, tuple(toggles), tuple(diags.items))


def materialize_random(scenario: Scenario, names: NameTable) -> Scenario:
    """The same stimulus with every random toggle turned into an explicit `set` event (so each can be removed)."""
    stimulus = build_stimulus(scenario, names)
    extra = [Event(cycle=c, set={w.name: w.value for w in step.toggles})
             for c, step in sorted(stimulus.steps.items()) if step.toggles]
    # sorted() is stable: at equal cycles the original events keep applying before the former toggles
    events = sorted([*scenario.events, *extra], key=lambda e: e.cycle)
    return bind(scenario.model_copy(update={"events": events, "random": None}), names)


# ---------------------------------------------------------------------------------------------
# Expectations


class ExpectationFailure(NamedTuple):
    cycle: int
    name: str
    expected: int | str
    actual: int | str
    span: Span | None = None

    def message(self) -> str:
        return f"cycle {self.cycle}: {self.name} expected {self.expected!r}, got {self.actual!r}"


def check_expectations(scenario: Scenario, cycle: int,
                       read: Callable[[OperandRef], int | str]) -> list[ExpectationFailure]:
    """Compare the `expect` entries of `cycle` with the executor's values (B/W/D modulo 2^width)."""
    failures: list[ExpectationFailure] = []
    for index, expectation in enumerate(scenario.expect):
        if expectation.cycle != cycle:
            continue
        for name, expected in expectation.values.items():
            ref = scenario.ref(name) or parse_operand(name)
            if ref is None:
                raise KeyError(f"scenario name {name!r} is not bound; load the scenario or call bind() first")
            actual = read(ref)
            if not values_equal(ref.kind, expected, actual):
                failures.append(ExpectationFailure(cycle, name, expected, actual,
                                                   scenario.span_of("expect", index, "values", name)))
    return failures


# ---------------------------------------------------------------------------------------------
# Observed operands


def _operand_order(ref: OperandRef) -> tuple[int, int]:
    return KIND_ORDER.index(ref.kind), ref.addr


def observed_operands(scenario: Scenario, names: NameTable, written: Iterable[OperandRef],
                      outputs: Iterable[OperandRef],
                      diagnostics: Diagnostics | None = None) -> list[tuple[str, OperandRef]]:
    """Trace columns: `observe` expanded in the order given, else every written operand plus all outputs."""
    if scenario.observe is None:
        refs = sorted(set(written) | set(outputs), key=_operand_order)
        return [(names.display_name(ref), ref) for ref in refs]
    columns: list[tuple[str, OperandRef]] = []
    seen: set[OperandRef] = set()
    for i, pattern in enumerate(scenario.observe):
        matched = names.match(pattern) if is_glob(pattern) else [pattern]
        refs = [r for r in (_resolve_quiet(names, n) for n in matched) if r is not None]
        if not refs and diagnostics is not None:
            diagnostics.report("E-SCENARIO-UNUSED", scenario.span_of("observe", i),
                                f"observe pattern '{pattern}' matches no operand of the project")
        for ref in refs:
            if ref not in seen:
                seen.add(ref)
                columns.append((names.display_name(ref), ref))
    return columns


# ---------------------------------------------------------------------------------------------
# Writing a scenario back


def _mp_number(value: Decimal) -> int | float | str:
    if value == value.to_integral_value():
        return int(value)
    as_float = float(value)
    # a float that does not read back as the same decimal is written as text, which the loader accepts
    return as_float if Decimal(repr(as_float)) == value else str(value)


def _scenario_data(scenario: Scenario, base_dir: Path | None) -> dict[str, Any]:
    data: dict[str, Any] = {"name": scenario.name, "cycles": scenario.cycles,
                            "cycle_time_ms": scenario.cycle_time_ms, "profile": scenario.profile}
    if scenario.machine_parameters is not None:
        path = scenario.machine_parameters
        data["machine_parameters"] = os.path.relpath(path, base_dir) if base_dir is not None else str(path.resolve())
    if scenario.mp:
        data["mp"] = {mp_key_text(k): _mp_number(v) for k, v in scenario.mp.items()}
    if scenario.mp_data:
        data["mp_data"] = dict(scenario.mp_data)
    if scenario.initial:
        data["initial"] = dict(scenario.initial)
    if scenario.events:
        data["events"] = [_event_data(e) for e in scenario.events]
    if scenario.random is not None:
        data["random"] = scenario.random.model_dump()
    if scenario.observe is not None:
        data["observe"] = list(scenario.observe)
    if scenario.expect:
        data["expect"] = [{"cycle": x.cycle, "values": dict(x.values)} for x in scenario.expect]
    if scenario.semantics:
        data["semantics"] = dict(scenario.semantics)
    if scenario.module_results:
        data["module_results"] = {k: list(v) for k, v in scenario.module_results.items()}
    if scenario.machine is not None:
        data["machine"] = scenario.machine.as_dict()
    return data


def _event_data(event: Event) -> dict[str, Any]:
    data: dict[str, Any] = {"cycle": event.cycle}
    if event.set:
        data["set"] = dict(event.set)
    if event.nc is not None:
        data["nc"] = event.nc.as_dict()
    if event.machine is not None:
        data["machine"] = event.machine.as_dict()
    return data


def scenario_to_yaml(scenario: Scenario, base_dir: Path | None = None) -> str:
    """The scenario as YAML that load_scenario reads back to an equal Scenario.

    `machine_parameters` is written relative to `base_dir` (the folder the YAML will be saved
    in) when given, else as an absolute path.
    """
    return yaml.safe_dump(_scenario_data(scenario, base_dir), sort_keys=False, default_flow_style=None,
                          allow_unicode=True, width=100)
