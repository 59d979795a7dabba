"""`hh2iec equiv`: co-simulates the original and the translated program under scenarios and random stimulus; shrinks divergences."""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path
from typing import Any, Callable
from xml.sax.saxutils import escape, quoteattr

from transpiler.cli.app import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, UsageError, options_from_args
from transpiler.atomic import write_files_atomically
from transpiler.verify.cosim import CosimResult, StSide, builtin_side_factory, comparison_for, cosimulate
from transpiler.diagnostics import CompileFailed, Diagnostics, NO_SPAN
from transpiler.exec.interp import CompiledProgram, compile_program
from transpiler.backends.report.iomap import IoMap
from transpiler.ir import Program
from transpiler.frontend.pipeline import compile_project
from transpiler.verify.scenario import Event, NameTable, RandomStimulus, Scenario, ScenarioError, bind, load_scenario
from transpiler.exec.compiled.shim import ShimUnavailable
from transpiler.verify.simulate import program_operands, project_names, scenario_semantics
from transpiler.verify.stimulus import materialize_random, scenario_to_yaml
from transpiler.verify.traces import TraceRecorder
from transpiler.backends.transpile import find_mp_file, io_map_of, read_mp_file, transpile_program

SHRINK_BUDGET = 150


@dataclasses.dataclass
class Outcome:
    result: CosimResult
    shrunk: Scenario | None = None
    shrink_runs: int = 0


def random_scenario(program: Program, names: NameTable, cycles: int, seed: int,
                    machine_parameters: Path | None = None) -> Scenario:
    """N cycles in which every input the program reads may toggle (probability 0.05 per input and cycle); timers
    and counters take their presets from the project's MP file when there is one."""
    used, _, _ = program_operands(program)
    inputs = sorted({names.display_name(r) for r in used if r.kind == "I"}) or ["I0"]
    scenario = Scenario(name=f"random_seed{seed}", cycles=cycles, profile=program.semantics.profile.name,
                        machine_parameters=machine_parameters,
                        random=RandomStimulus(seed=seed, inputs=inputs, toggle_probability=0.05))
    return bind(scenario, names)


def shrink(program: Program, make_side: Callable[[], StSide], iomap: IoMap, scenario: Scenario, names: NameTable,
           first: CosimResult, compiled: CompiledProgram | None = None) -> tuple[Scenario, int]:
    """The shortest stimulus found that still diverges: fewer cycles, then fewer events (ddmin over single writes)."""
    base = materialize_random(scenario, names)
    cycle = first.divergence.cycle
    singles: list[Event] = []
    for e in base.events:
        if e.cycle > cycle:
            continue
        if e.nc is not None:
            singles.append(Event(cycle=e.cycle, nc=e.nc))
        for name, value in e.set.items():
            singles.append(Event(cycle=e.cycle, set={name: value}))
    runs = 0

    def make(events: list[Event], cycles: int) -> Scenario:
        return bind(base.model_copy(update={"events": events, "cycles": cycles, "expect": [],
                                            "name": f"{scenario.name}_shrunk"}), names)

    def diverges(events: list[Event], cycles: int) -> CosimResult | None:
        nonlocal runs
        runs += 1
        res = cosimulate(program, make_side, iomap, make(events, cycles), names, compiled=compiled)
        return res if res.divergence is not None else None

    best_cycles = cycle + 1
    events = singles
    chunk = max(1, len(events) // 2)
    while chunk >= 1 and runs < SHRINK_BUDGET and events:
        i = 0
        removed = False
        while i < len(events) and runs < SHRINK_BUDGET:
            trial = events[:i] + events[i + chunk:]
            res = diverges(trial, best_cycles)
            if res is not None:
                events = trial
                best_cycles = res.divergence.cycle + 1
                events = [e for e in events if e.cycle < best_cycles]
                removed = True
            else:
                i += chunk
        if not removed:
            chunk //= 2
    # Initial values are part of the stimulus too.
    shrunk = make(events, best_cycles)
    for name in list(shrunk.initial):
        if runs >= SHRINK_BUDGET:
            break
        trial_initial = {k: v for k, v in shrunk.initial.items() if k != name}
        trial = bind(shrunk.model_copy(update={"initial": trial_initial}), names)
        runs += 1
        if cosimulate(program, make_side, iomap, trial, names, compiled=compiled).divergence is not None:
            shrunk = trial
    return shrunk, runs


def _progress_printer(label: str) -> Callable[[int, int], None]:
    start = time.perf_counter()
    state = {"last": start}

    def show(done: int, total: int) -> None:
        now = time.perf_counter()
        if now - start > 3 and now - state["last"] > 1 and sys.stderr.isatty():
            state["last"] = now
            print(f"\r{label}: cycle {done}/{total} ({done / (now - start):.0f} cycles/s)", end="", file=sys.stderr)
        if done == total and now - start > 3 and sys.stderr.isatty():
            print(file=sys.stderr)
    return show


def register(sub: argparse._SubParsersAction, common: Callable[[argparse.ArgumentParser], None]) -> None:
    p = sub.add_parser("equiv", help="co-simulate the original and the translated program and compare every cycle")
    common(p)
    p.add_argument("--scenario", type=Path, action="append", default=[], help="scenario file (repeatable)")
    p.add_argument("--backend", choices=("auto", "matiec", "builtin"), default="auto")
    p.add_argument("--st", type=Path, help="use this ST file instead of transpiling afresh")
    p.add_argument("--io-map", type=Path, help="io_map.csv of the --st file (default: io_map.csv beside it, "
                   "else the map of a fresh transpilation)")
    p.add_argument("--random-cycles", type=int, default=0, metavar="N", help="also run N cycles of random stimulus")
    p.add_argument("--seed", type=int, default=1, metavar="S", help="seed of the random stimulus")
    p.add_argument("--report", type=Path, metavar="OUT.json")
    p.add_argument("--junit", type=Path, metavar="OUT.xml")
    p.add_argument("--vcd", type=Path, metavar="DIR", help="write both traces of each run as value-change dumps")
    p.add_argument("--mp", type=Path, help="machine-parameter file used for the transpilation's preset defaults")
    p.add_argument("--no-shrink", action="store_true", help="do not shrink a divergent stimulus")
    p.set_defaults(handler=cmd_equiv)


def cmd_equiv(args: argparse.Namespace) -> int:
    if not args.scenario and args.random_cycles <= 0:
        raise UsageError("equiv needs at least one --scenario or --random-cycles N")
    for path in args.scenario:
        if not path.is_file():
            raise UsageError(f"scenario file '{path}' does not exist")
    if args.st is not None and not args.st.is_file():
        raise UsageError(f"ST file '{args.st}' does not exist")
    semantics = scenario_semantics(args, args.scenario[0] if args.scenario else None)
    if semantics is None:
        return EXIT_BAD_INPUT
    compiled = compile_project(options_from_args(args), semantics)
    for d in compiled.diagnostics.items:
        print(d.render(), file=sys.stderr)
    if not compiled.ok:
        return EXIT_BAD_INPUT
    program = compiled.program
    diags = Diagnostics()
    mp_path = args.mp or find_mp_file(args.main)
    mp = read_mp_file(mp_path, diags) if mp_path else {}
    transpiled = transpile_program(program, diags, mp, {"st"})
    st_text, st_name = transpiled.st_text, "project.st"
    iomap = io_map_of(transpiled.result)
    if args.st is not None:
        st_text, st_name = args.st.read_text(encoding="utf-8", errors="replace"), str(args.st)
        map_path = args.io_map or args.st.parent / "io_map.csv"
        if map_path.is_file():
            try:
                iomap = IoMap.from_csv(map_path.read_text(encoding="utf-8"))
            except ValueError as exc:
                print(f"{map_path}:1:1: error[E-USAGE]: {exc}", file=sys.stderr)
                return EXIT_BAD_INPUT
    backend, factory, note = _backend(args.backend, st_text, st_name, transpiled)
    if factory is None:
        print(f"{NO_SPAN}: error[E-TOOL]: {note}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if note:
        print(f"note: {note}", file=sys.stderr)
    names = project_names(program)
    scenarios: list[Scenario] = []
    try:
        for path in args.scenario:
            scenarios.append(load_scenario(path, names))
        if args.random_cycles > 0:
            scenarios.append(random_scenario(program, names, args.random_cycles, args.seed, mp_path))
    except ScenarioError as exc:
        for d in exc.diagnostics:
            print(d.render(), file=sys.stderr)
        return EXIT_BAD_INPUT
    outcomes: list[Outcome] = []
    coverage_sets: list = []
    reference = compile_program(program, coverage=True)
    try:
        for scenario in scenarios:
            traces: list = []
            record = (lambda c, a, b: traces.append((c, a, b))) if args.vcd else None
            res = cosimulate(program, factory, iomap, scenario, names, coverage=True,
                             progress=_progress_printer(scenario.name), record=record, compiled=reference)
            outcome = Outcome(res)
            if res.divergence is not None and not args.no_shrink:
                outcome.shrunk, outcome.shrink_runs = shrink(program, factory, iomap, scenario, names, res,
                                                             compile_program(program))
            outcomes.append(outcome)
            if res.machine is not None and res.machine.coverage_enabled:
                coverage_sets.append(res.machine.coverage)
            if args.vcd:
                _write_vcd(args.vcd, scenario, res, traces, program, names, iomap)
    except CompileFailed as exc:
        for d in exc.diagnostics:
            print(d.render(), file=sys.stderr)
        return EXIT_BAD_INPUT
    except ShimUnavailable as exc:
        print(f"{NO_SPAN}: error[E-TOOL]: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    coverage = _coverage_summary(program, coverage_sets)
    _print_outcomes(outcomes, backend, coverage)
    if args.report:
        _write_json(args.report, outcomes, backend, coverage)
    if args.junit:
        _write_junit(args.junit, outcomes, backend)
    if any(o.result.error for o in outcomes):
        return EXIT_BAD_INPUT
    return EXIT_FAILED if any(o.result.divergence for o in outcomes) else EXIT_OK


def _backend(choice: str, st_text: str, st_name: str, transpiled) -> tuple[str, Callable[[], StSide] | None, str]:
    from transpiler.backends.st.check import find_iec2c
    if choice in ("auto", "matiec"):
        iec2c = find_iec2c()
        if iec2c is not None:
            try:
                from transpiler.exec.compiled.matiec_side import matiec_side_factory
                return "matiec", matiec_side_factory(st_text, transpiled.result.project, iec2c), ""
            except ImportError:
                if choice == "matiec":
                    return "matiec", None, "the matiec backend is not available in this build"
            except Exception as exc:  # noqa: BLE001 - compile failures are reported, not raised
                if choice == "matiec":
                    return "matiec", None, f"matiec could not build the translated program: {exc}"
                note = f"matiec failed ({exc}); using the built-in ST executor"
                return "builtin", _builtin(st_text, st_name), note
        elif choice == "matiec":
            return "matiec", None, "iec2c not found ($MATIEC_HOME/iec2c or PATH)"
    factory = _builtin(st_text, st_name)
    return "builtin", factory, "" if factory is not None else f"the built-in ST executor cannot load {st_name}"


def _builtin(st_text: str, st_name: str):
    try:
        return builtin_side_factory(st_text, st_name)
    except CompileFailed as exc:
        for d in exc.diagnostics:
            print(d.render(), file=sys.stderr)
        return None


def _coverage_summary(program: Program, sets: list) -> dict[str, Any]:
    total_ops = [(fi, i) for fi, f in enumerate(program.files) for i, op in enumerate(f.ops)
                 if op.code not in ("LBL", "KFIELD", "NOP")]
    branch_ops = [(fi, i) for fi, f in enumerate(program.files) for i, op in enumerate(f.ops)
                  if op.code in ("JPT", "JPF", "CALLT", "CALLF", "EMT", "EMF", "CASE")]
    executed: set = set()
    outcomes: dict = {}
    for cov in sets:
        executed |= set(cov.executed)
        for key, values in cov.branches.items():
            outcomes.setdefault(key, set()).update(values)
    op_hit = len([k for k in total_ops if k in executed])
    two_way = 0
    both = 0
    for fi, i in branch_ops:
        op = program.files[fi].ops[i]
        if op.code == "CASE":
            continue
        two_way += 1
        if outcomes.get((fi, i), set()) >= {0, 1}:
            both += 1
    case_entries = sum(len(program.files[fi].ops[i].case_targets) for fi, i in branch_ops if program.files[fi].ops[i].code == "CASE")
    case_hit = sum(len([v for v in outcomes.get((fi, i), set()) if v >= 0]) for fi, i in branch_ops
                   if program.files[fi].ops[i].code == "CASE")
    return {"instructions": len(total_ops), "instructions_executed": op_hit,
            "branches": two_way, "branches_both_ways": both, "case_entries": case_entries, "case_entries_taken": case_hit}


def _pct(a: int, b: int) -> str:
    return f"{100.0 * a / b:.1f}%" if b else "n/a"


def _compared_text(r: CosimResult) -> str:
    """The operands compared per cycle; addresses the program stored to through the index register are counted
    apart because they join the comparison only from their first indexed store on (see cosim.cosimulate)."""
    text = f"{r.compared} operands compared per cycle"
    if r.compared_indexed:
        text += f" + {r.compared_indexed} indexed addresses from their first indexed store"
    return text


def _print_outcomes(outcomes: list[Outcome], backend: str, coverage: dict[str, Any]) -> None:
    for o in outcomes:
        r = o.result
        if r.error:
            print(f"{NO_SPAN}: error[E-TOOL]: {r.scenario}: {r.error}", file=sys.stderr)
        elif r.divergence:
            d = r.divergence
            print(f"DIVERGENCE in {r.scenario} at cycle {d.cycle}: {d.name} ({d.operand}): original {d.original!r}, "
                  f"translated {d.translated!r}")
            if o.shrunk is not None:
                print(f"shortest input trace found ({o.shrunk.cycles} cycles, {len(o.shrunk.events)} events, "
                      f"{o.shrink_runs} runs); rerun it with --scenario:")
                print(scenario_to_yaml(o.shrunk))
        else:
            print(f"equivalent: {r.scenario}: {r.cycles_run} cycles, {_compared_text(r)} ({r.seconds:.2f} s)")
    c = coverage
    print(f"coverage: instructions {c['instructions_executed']}/{c['instructions']} ({_pct(c['instructions_executed'], c['instructions'])}), "
          f"conditional branches both ways {c['branches_both_ways']}/{c['branches']} "
          f"({_pct(c['branches_both_ways'], c['branches'])}), CASE entries {c['case_entries_taken']}/{c['case_entries']}")
    verdict = "EQUIVALENT" if all(o.result.equivalent for o in outcomes) else "NOT EQUIVALENT"
    print(f"hh2iec equiv: {verdict} ({len(outcomes)} runs, backend {backend})")


def _write_json(path: Path, outcomes: list[Outcome], backend: str, coverage: dict[str, Any]) -> None:
    runs = []
    for o in outcomes:
        r = o.result
        runs.append({"scenario": r.scenario, "cycles": r.cycles_run, "compared_operands": r.compared,
                     "compared_indexed_addresses": r.compared_indexed,
                     "equivalent": r.equivalent, "error": r.error, "seconds": round(r.seconds, 3),
                     "divergence": dataclasses.asdict(r.divergence) if r.divergence else None,
                     "shrunk_scenario": scenario_to_yaml(o.shrunk) if o.shrunk else None})
    data = {"backend": backend, "equivalent": all(o.result.equivalent for o in outcomes), "runs": runs,
            "coverage": coverage}
    write_files_atomically({path: json.dumps(data, indent=2) + "\n"})


def _write_junit(path: Path, outcomes: list[Outcome], backend: str) -> None:
    failures = sum(1 for o in outcomes if o.result.divergence)
    errors = sum(1 for o in outcomes if o.result.error)
    total = sum(o.result.seconds for o in outcomes)
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<testsuite name={quoteattr("hh2iec equiv (" + backend + ")")} tests="{len(outcomes)}" '
             f'failures="{failures}" errors="{errors}" time="{total:.3f}">']
    for o in outcomes:
        r = o.result
        lines.append(f'  <testcase classname="hh2iec.equiv" name={quoteattr(r.scenario)} time="{r.seconds:.3f}">')
        if r.divergence:
            d = r.divergence
            msg = f"cycle {d.cycle}: {d.name} ({d.operand}): original {d.original!r}, translated {d.translated!r}"
            body = scenario_to_yaml(o.shrunk) if o.shrunk else ""
            lines.append(f"    <failure message={quoteattr(msg)}>{escape(body)}</failure>")
        elif r.error:
            lines.append(f"    <error message={quoteattr(r.error)}/>")
        lines.append("  </testcase>")
    lines.append("</testsuite>")
    write_files_atomically({path: "\n".join(lines) + "\n"})


def _write_vcd(folder: Path, scenario: Scenario, res: CosimResult, traces: list, program: Program,
               names: NameTable, iomap: IoMap) -> None:
    columns = list(comparison_for(program, names, iomap).columns)
    folder.mkdir(parents=True, exist_ok=True)
    for side, pick in (("original", 1), ("translated", 2)):
        rec = TraceRecorder(columns)
        for row in traces:
            rec.record(row[0], list(row[pick]))
        rec.write_vcd(folder / f"{scenario.name}.{side}.vcd", res.machine.cycle_time_ms if res.machine else 20)
