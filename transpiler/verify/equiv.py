"""Equivalence: co-simulates the original and the translated program under scenarios and random stimulus,
shrinks divergent stimuli, and gives the verdict with coverage (instructions, branches, CASE entries, MC/DC and
boundary values) and JSON/JUnit reports."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence
from xml.sax.saxutils import escape, quoteattr

from transpiler.backends.iec_model import IecProject
from transpiler.backends.report.iomap import IoMap
from transpiler.diagnostics import CompileFailed, Diagnostic, Span
from transpiler.exec.interp import CompiledProgram, compile_program
from transpiler.ir import Program
from transpiler.exec.interp.machine import Coverage
from transpiler.verify.rundata import UNREPRESENTABLE
from transpiler.verify.cosim import CosimResult, StSide, builtin_side_factory, comparison_for, cosimulate
from transpiler.verify.mcdc import DecisionCoverage, decision_coverage, driven_operands, power_on_operands
from transpiler.verify.simulate import program_operands
from transpiler.verify.source_coverage import TWO_WAY, OpCoverage, SourceCoverage, op_coverage, source_coverage
from transpiler.verify.scenario import Event, NameTable, RandomStimulus, Scenario, bind
from transpiler.verify.screens import Screen, render_text
from transpiler.verify.shard import decode_coverage, encode_coverage
from transpiler.verify.stimulus import materialize_random, scenario_to_yaml
from transpiler.verify.traces import TraceRecorder, write_vcd_scopes

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
           first: CosimResult, compiled: CompiledProgram | None = None,
           base_mp: Mapping | None = None) -> tuple[Scenario, int]:
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
        res = cosimulate(program, make_side, iomap, make(events, cycles), names, compiled=compiled, base_mp=base_mp)
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
        if cosimulate(program, make_side, iomap, trial, names, compiled=compiled, base_mp=base_mp).divergence is not None:
            shrunk = trial
    return shrunk, runs


@dataclasses.dataclass(frozen=True)
class BackendChoice:
    """The ST executor chosen for a co-simulation; `factory` is None when none can run (then `note` says why)."""

    name: str
    factory: Callable[[], StSide] | None
    note: str = ""
    diagnostics: tuple[Diagnostic, ...] = ()


def choose_backend(choice: str, st_text: str, st_name: str, project: IecProject) -> BackendChoice:
    """`auto` takes matiec where iec2c is found and falls back to the built-in ST executor."""
    name, factory, note, problems = _backend(choice, st_text, st_name, project)
    return BackendChoice(name, factory, note, tuple(problems))


def _backend(choice: str, st_text: str, st_name: str, project: IecProject
             ) -> tuple[str, Callable[[], StSide] | None, str, list[Diagnostic]]:
    from transpiler.backends.st.check import find_iec2c
    if choice in ("auto", "matiec"):
        iec2c = find_iec2c()
        if iec2c is not None:
            try:
                from transpiler.exec.compiled.matiec_side import matiec_side_factory
                return "matiec", matiec_side_factory(st_text, project, iec2c), "", []
            except ImportError:
                if choice == "matiec":
                    return "matiec", None, "the matiec backend is not available in this build", []
            except Exception as exc:  # noqa: BLE001 - compile failures are reported, not raised
                if choice == "matiec":
                    return "matiec", None, f"matiec could not build the translated program: {exc}", []
                note = f"matiec failed ({exc}); using the built-in ST executor"
                factory, problems = _builtin(st_text, st_name)
                return "builtin", factory, note, problems
        elif choice == "matiec":
            return "matiec", None, "iec2c not found ($MATIEC_HOME/iec2c or PATH)", []
    factory, problems = _builtin(st_text, st_name)
    return ("builtin", factory, "" if factory is not None else f"the built-in ST executor cannot load {st_name}",
            problems)


def _builtin(st_text: str, st_name: str) -> tuple[Callable[[], StSide] | None, list[Diagnostic]]:
    try:
        return builtin_side_factory(st_text, st_name), []
    except CompileFailed as exc:
        return None, list(exc.diagnostics)


def _untaken(op: Any, seen: set) -> str:
    """The outcome of a conditional jump, call or module end that no run took, in the words of the source.
    The interpreter records 1 when the jump/call/end happens (an IFT is a JPF over its body), else 0."""
    if not seen:
        return "never reached"
    if op.mnemonic == "IFT":
        return "body never skipped" if 1 not in seen else "body never run"
    action = {"JPT": "jumps", "JPF": "jumps", "CALLT": "calls", "CALLF": "calls"}.get(op.code, "ends the module")
    return f"never {action}" if 1 not in seen else f"always {action}"


def coverage_summary(program: Program, sets: list) -> dict[str, Any]:
    """Instructions executed, conditional branches taken both ways and CASE entries taken over the runs'
    coverage sets; `never_taken` lists each branch outcome and CASE entry no run took, with its source line."""
    return summarize_coverage(op_coverage(program, sets))


def summarize_coverage(ops: list[OpCoverage]) -> dict[str, Any]:
    """The summary of coverage_summary from the per-instruction figures of source_coverage.op_coverage."""
    instructions = hit = two_way = both = case_entries = case_hit = 0
    never: list[dict[str, str]] = []
    for oc in ops:
        op, seen = oc.op, oc.seen
        instructions += 1
        hit += oc.runs > 0
        if op.code in TWO_WAY:
            two_way += 1
            if seen >= {0, 1}:
                both += 1
            else:
                never.append({"at": str(op.span), "what": f"{op.mnemonic} {_untaken(op, seen)}"})
        elif op.code == "CASE":
            case_entries += len(op.case_targets)
            for entry, target in enumerate(op.case_targets):
                if entry in seen:
                    case_hit += 1
                else:
                    at = op.case_notes[entry][0] if entry < len(op.case_notes) else op.span
                    never.append({"at": str(at), "what": f"CASE entry {entry} ({target.label}) never taken"})
    return {"instructions": instructions, "instructions_executed": hit,
            "branches": two_way, "branches_both_ways": both, "case_entries": case_entries,
            "case_entries_taken": case_hit, "never_taken": never}


@dataclasses.dataclass
class EquivalenceResult:
    """Every co-simulation run of one equivalence check, the executor used and the reference's coverage."""

    outcomes: list[Outcome]
    backend: str
    coverage: dict[str, Any]
    untranslated: tuple[tuple[Span, str], ...] = ()     # code the translation left out (allowed by the user)
    source: SourceCoverage | None = None                # the same coverage per source file and line
    decisions: DecisionCoverage | None = None           # MC/DC and boundary values (verify/mcdc.py)
    driven: frozenset[tuple[str, int]] = frozenset()    # operands the runs' scenarios set (never constant)
    power_on: frozenset[tuple[str, int]] = frozenset()  # those of them set only before cycle 0 (`initial`)
    run_ids: tuple[int, ...] = ()                       # each outcome's number in the plan (1, 2, ... when empty)

    @property
    def equivalent(self) -> bool:
        """Every run compared whole and equal, every expectation met, nothing left untranslated."""
        return self.verdict == "EQUIVALENT"

    @property
    def expectation_failures(self) -> list[Outcome]:
        return [o for o in self.outcomes if o.result.expectation_failures]

    @property
    def errors(self) -> list[Outcome]:
        """Runs that could not be carried out (bad scenario, a fault of the original, a missing tool, machine data
        refused before cycle 0)."""
        return [o for o in self.outcomes if o.result.error and not _translation_fault(o.result)]

    @property
    def refused(self) -> list[Outcome]:
        """Runs that never started because the scenario's machine data cannot be written into the emitted ST."""
        return [o for o in self.outcomes if o.result.error_code == UNREPRESENTABLE]

    @property
    def started(self) -> bool:
        """Whether any run got as far as cycle 0 (else there is no coverage to speak of)."""
        return any(o.result.error_side != "machine data" for o in self.outcomes)

    @property
    def divergent(self) -> list[Outcome]:
        """Runs that compared unequal, in which the translation lacks an operand the original writes, or in which
        the translation faulted (an endless loop, a division by zero, ...) where the original ran on."""
        return [o for o in self.outcomes if o.result.divergence or o.result.missing or _translation_fault(o.result)]

    @property
    def verdict(self) -> str:
        return verdict_of([run_state(bool(o.result.divergence), bool(o.result.missing), o.result.error,
                                     o.result.error_side, bool(o.result.expectation_failures), o.result.error_code)
                           for o in self.outcomes], bool(self.untranslated))


DIVERGENT, FAILED_RUN, REFUSED, UNMET, AGREED = "divergent", "error", "refused", "expectation failed", "agreed"


def run_state(divergence: bool, missing: bool, error: str | None, error_side: str | None, unmet: bool,
              error_code: str | None = None) -> str:
    """What one run counts as for the verdict: DIVERGENT (compared unequal, an operand missing, or a fault of the
    translation), REFUSED (never started: the scenario's machine data cannot be written into the emitted ST),
    FAILED_RUN (could not be carried out otherwise), UNMET (the original missed an expectation), else AGREED."""
    if divergence or missing or (error is not None and error_side == "translated"):
        return DIVERGENT
    if error is not None:
        return REFUSED if error_code == UNREPRESENTABLE else FAILED_RUN
    return UNMET if unmet else AGREED


def verdict_of(states: list[str], untranslated: bool) -> str:
    """NOT EQUIVALENT (a divergence, an operand missing, a run that failed, a translation shipped with other machine
    parameters than the project's, or no run at all), NO VERDICT (nothing else wrong, but a run's machine data
    could not be written into the ST, so that run compared nothing), EXPECTATION FAILED (the original does not meet
    the scenario), NOT PROVEN (code was left untranslated), else EQUIVALENT: the verdict of the runs' states, one
    process's or the merged shards'."""
    if not states or DIVERGENT in states or FAILED_RUN in states:
        return "NOT EQUIVALENT"
    if REFUSED in states:
        return "NO VERDICT"
    if UNMET in states:
        return "EXPECTATION FAILED"
    if untranslated:
        return "NOT PROVEN"
    return "EQUIVALENT"


def _translation_fault(result: CosimResult) -> bool:
    return result.error is not None and result.error_side == "translated"


def run_equivalence(program: Program, make_side: Callable[[], StSide], iomap: IoMap, scenarios: list[Scenario],
                    names: NameTable, backend: str, *, shrink_divergences: bool = True, vcd_dir: Path | None = None,
                    progress: Callable[[str, int, int], Callable[[int, int], None]] | None = None,
                    base_mp: Mapping | None = None,
                    untranslated: tuple[tuple[Span, str], ...] = (), pipelined: bool = False,
                    explain_missing: bool = True) -> EquivalenceResult:
    """Co-simulate every scenario; shrink each divergent stimulus. Raises CompileFailed on bad scenario input.
    `base_mp` are the machine parameters the translation was made with, `pipelined` runs the reference in a process
    of its own where it can (see cosim.cosimulate). `progress(run name, cycles of the runs before, cycles of all
    runs)` gives the cycle counter of one run. Without `explain_missing` (a shard's share of the runs, whose
    coverage the merge computes again over all of them), a condition no run showed is not analysed for a reason
    it cannot be shown: it is only missing here."""
    outcomes: list[Outcome] = []
    coverage_sets: list = []
    reference = compile_program(program, coverage=True, exact=False)      # fast code, exact coverage
    total_cycles = sum(s.cycles for s in scenarios)
    cycles_before = 0
    for scenario in scenarios:
        traces: list = []
        record = (lambda c, a, b: traces.append((c, a, b))) if vcd_dir else None
        res = cosimulate(program, make_side, iomap, scenario, names, coverage=True,
                         progress=progress(scenario.name, cycles_before, total_cycles) if progress else None,
                         record=record, compiled=reference, base_mp=base_mp, pipelined=pipelined)
        cycles_before += scenario.cycles
        outcome = Outcome(res)
        if res.divergence is not None and shrink_divergences:
            outcome.shrunk, outcome.shrink_runs = shrink(program, make_side, iomap, scenario, names, res,
                                                         compile_program(program), base_mp)
        outcomes.append(outcome)
        if res.coverage is not None:
            coverage_sets.append(res.coverage)
        if vcd_dir:
            write_vcd(vcd_dir, scenario, res, traces, program, names, iomap)
    driven = driven_operands(scenarios, names)
    power_on = power_on_operands(scenarios, names)
    summary, source, decisions = coverage_of(program, coverage_sets, driven, explain_missing, power_on)
    return EquivalenceResult(outcomes, backend, summary, tuple(untranslated), source, decisions,
                             driven=frozenset(driven), power_on=frozenset(power_on))


def coverage_of(program: Program, sets: list, driven: set[tuple[str, int]], explain_missing: bool = True,
                power_on: set[tuple[str, int]] = frozenset()) -> tuple[dict[str, Any], SourceCoverage, DecisionCoverage]:
    """The coverage summary, the per-file coverage and MC/DC with boundary values over the runs' coverage sets
    (`driven`: the operands the runs' scenarios set, never constant; `power_on`: those set only before cycle 0): one
    process's runs, or the runs of every shard (merge_reports), computed alike."""
    ops = op_coverage(program, sets)
    decisions = decision_coverage(program, sets, driven, explain_missing=explain_missing, power_on=power_on)
    return ({**summarize_coverage(ops), **decisions.summary()}, source_coverage(program, ops, len(sets)),
            decisions)


def screen_json(screen: Screen) -> dict[str, Any]:
    """One screen of `--show-mask` as report data: which mask after which cycle of which scenario, both drawings
    (None where a side drew nothing), whether they differ, and why nothing was drawn."""
    return {"scenario": screen.scenario, "mask": screen.mask, "cycle": screen.cycle,
            "drawn": screen.original is not None, "differs": screen.differs,
            "original": list(screen.original) if screen.original is not None else None,
            "translated": list(screen.translated) if screen.translated is not None else None,
            "note": screen.note}


def _screen_of(data: Mapping[str, Any]) -> Screen:
    return Screen(data["scenario"], data["mask"], data["cycle"],
                  tuple(data["original"]) if data["original"] is not None else None,
                  tuple(data["translated"]) if data["translated"] is not None else None, data["note"])


def report_data(result: EquivalenceResult, reproduce: Callable[[int], str] | None = None,
                shard: Mapping[str, Any] | None = None, screens: Sequence[Screen] = ()) -> dict[str, Any]:
    """The machine-readable report (`--report`) as data: every run with its number in the plan, verdict, divergence
    and shrunk stimulus; `reproduce(run)` gives the command line that runs one failing run alone; the screens
    `--show-mask` drew (`screens`: empty without it, and in shards, which draw none). A shard's report carries
    `shard` (see verify/shard.py) with each run's coverage sets, from which merge_reports recomputes the coverage of
    all runs."""
    ids = result.run_ids or tuple(range(1, len(result.outcomes) + 1))
    runs = []
    for run_id, o in zip(ids, result.outcomes):
        r = o.result
        entry = {"run": run_id, "scenario": r.scenario, "cycles": r.cycles_run, "compared_operands": r.compared,
                 "compared_indexed_addresses": r.compared_indexed,
                 "compared_after_last_cycle": r.swept,
                 "equivalent": r.equivalent, "error": r.error, "error_side": r.error_side, "error_code": r.error_code,
                 "seconds": round(r.seconds, 3),
                 "divergence": dataclasses.asdict(r.divergence) if r.divergence else None,
                 "compared": list(r.compared_operands),
                 "excluded": [{"operand": operand, "reason": reason} for operand, reason in r.excluded],
                 "missing_in_translation": [{"operand": m.operand, "name": m.name,
                                             "written_at": [str(s) for s in m.written_at], "text": m.render()}
                                            for m in r.missing],
                 "expectation_failures": [{"cycle": f.cycle, "name": f.name, "expected": f.expected,
                                           "actual": f.actual, "at": str(f.span) if f.span else None,
                                           "message": f.message()}
                                          for f in r.expectation_failures],
                 "shrunk_scenario": scenario_to_yaml(o.shrunk) if o.shrunk else None}
        if reproduce is not None and _state_of(entry) != AGREED:
            entry["reproduce"] = reproduce(run_id)
        runs.append(entry)
    data = _report(result.backend, runs, [{"at": str(span), "what": text} for span, text in result.untranslated],
                   result.coverage, result.source)
    data["screens"] = [screen_json(screen) for screen in screens]
    if shard is not None:
        # each run's sets as one compact JSON text: thousands of items per run, one line each in the indented report
        data["shard"] = {**shard, "driven": sorted([kind, addr] for kind, addr in result.driven),
                         "power_on": sorted([kind, addr] for kind, addr in result.power_on),
                         "coverage": [[run_id, json.dumps(encode_coverage(o.result.coverage), separators=(",", ":"))]
                                      for run_id, o in zip(ids, result.outcomes) if o.result.coverage is not None]}
    return data


def _state_of(run: Mapping[str, Any]) -> str:
    return run_state(bool(run["divergence"]), bool(run["missing_in_translation"]), run["error"],
                     run.get("error_side"), bool(run["expectation_failures"]), run.get("error_code"))


def _report(backend: str, runs: list[dict[str, Any]], untranslated: list[dict[str, str]], coverage: dict[str, Any],
            source: SourceCoverage | None) -> dict[str, Any]:
    verdict = verdict_of([_state_of(run) for run in runs], bool(untranslated))
    data = {"backend": backend, "verdict": verdict, "equivalent": verdict == "EQUIVALENT", "runs": runs,
            "not_translated": untranslated, "coverage": coverage, "screens": []}
    if source is not None:
        data["coverage"] = {**coverage, "files": [
            {"file": f.path, "lines": f.lines_valid, "lines_executed": f.lines_covered,
             "branch_outcomes": f.branches_valid, "branch_outcomes_taken": f.branches_covered}
            for f in source.files]}
    return data


def report_json(result: EquivalenceResult, reproduce: Callable[[int], str] | None = None,
                shard: Mapping[str, Any] | None = None, screens: Sequence[Screen] = ()) -> str:
    """The machine-readable report (`--report`): report_data as JSON."""
    return data_json(report_data(result, reproduce, shard, screens))


def data_json(data: Mapping[str, Any]) -> str:
    return json.dumps(data, indent=2) + "\n"


def report_junit(result: EquivalenceResult, screens: Sequence[Screen] = ()) -> str:
    """One JUnit test case per run (`--junit`): a divergence is a failure, a harness or runtime error an error; and
    one per screen of `--show-mask` (see junit_of)."""
    return junit_of(report_data(result, screens=screens))


def junit_of(data: Mapping[str, Any]) -> str:
    """The JUnit file of a report's data (report_data, or merged shards). Each screen is a test case too: screens
    that differ are a failure, one not drawn (the run ended before its cycle) is skipped."""
    runs, backend = data["runs"], data["backend"]
    screens = [_screen_of(screen) for screen in data.get("screens", ())]
    failures = sum(1 for r in runs if r["divergence"] or r["missing_in_translation"] or r["expectation_failures"])
    failures += sum(1 for screen in screens if screen.differs)
    errors = sum(1 for r in runs if r["error"])
    skipped = sum(1 for screen in screens if screen.original is None)
    total = sum(r["seconds"] for r in runs)
    skipped_attr = f' skipped="{skipped}"' if skipped else ""
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<testsuite name={quoteattr("hh2iec equiv (" + backend + ")")} tests="{len(runs) + len(screens)}" '
             f'failures="{failures}" errors="{errors}"{skipped_attr} time="{total:.3f}">']
    for r in runs:
        lines.append(f'  <testcase classname="hh2iec.equiv" name={quoteattr(r["scenario"])} time="{r["seconds"]:.3f}">')
        if r["divergence"]:
            d = r["divergence"]
            msg = (f"cycle {d['cycle']}: {d['name']} ({d['operand']}): original {d['original']!r}, "
                   f"translated {d['translated']!r}")
            body = r["shrunk_scenario"] or ""
            lines.append(f"    <failure message={quoteattr(msg)}>{escape(body)}</failure>")
        elif r["error"] is not None and r.get("error_side") == "translated":
            lines.append(f"    <failure message={quoteattr(r['error'])}/>")
        elif r["missing_in_translation"]:
            missing = r["missing_in_translation"]
            msg = f"{len(missing)} operands written by the original are missing in the translation"
            lines.append(f"    <failure message={quoteattr(msg)}>{escape(chr(10).join(m['text'] for m in missing))}</failure>")
        elif r["expectation_failures"]:
            msg = f"{len(r['expectation_failures'])} expectations of the scenario failed on the original"
            body = "\n".join(f["message"] for f in r["expectation_failures"])
            lines.append(f"    <failure message={quoteattr(msg)}>{escape(body)}</failure>")
        elif r["error"]:
            lines.append(f"    <error message={quoteattr(r['error'])}/>")
        lines.append("  </testcase>")
    lines += _screen_cases(screens)
    lines.append("</testsuite>")
    return "\n".join(lines) + "\n"


def _screen_cases(screens: Sequence[Screen]) -> list[str]:
    """The JUnit test cases of the screens, each with its drawing(s) as the command line prints them."""
    lines = []
    for screen in screens:
        name = f"{screen.mask} after cycle {screen.cycle} of {screen.scenario}"
        lines.append(f'  <testcase classname="hh2iec.equiv.screens" name={quoteattr(name)} time="0.000">')
        text = escape(render_text(screen))
        if screen.original is None:
            lines.append(f"    <skipped message={quoteattr('not drawn: ' + screen.note)}/>")
        elif screen.differs:
            lines.append(f"    <failure message={quoteattr('the original and the translation draw different screens')}>"
                         f"{text}</failure>")
        else:
            lines.append(f"    <system-out>{text}</system-out>")
        lines.append("  </testcase>")
    return lines


def merge_reports(shards: list[Mapping[str, Any]], program: Program) -> dict[str, Any]:
    """One report from the reports of every shard (checked with shard.check_shards first): the runs in plan order,
    the coverage recomputed from the runs' coverage sets as one process computes it, the verdict of all runs."""
    runs = sorted((run for data in shards for run in data["runs"]), key=lambda run: run["run"])
    sets = [decode_coverage(json.loads(encoded), Coverage)
            for _, encoded in sorted((item for data in shards for item in data["shard"]["coverage"]),
                                     key=lambda item: item[0])]
    driven = {(kind, addr) for data in shards for kind, addr in data["shard"].get("driven", ())}
    # set only before cycle 0 in every shard that sets it at all
    later = {(kind, addr) for data in shards for kind, addr in data["shard"].get("driven", ())
             if [kind, addr] not in data["shard"].get("power_on", ())}
    power_on = {(kind, addr) for data in shards for kind, addr in data["shard"].get("power_on", ())} - later
    summary, source, _ = coverage_of(program, sets, driven, power_on=power_on)
    backends = sorted({data["backend"] for data in shards})
    return _report("+".join(backends), runs, shards[0]["not_translated"], summary, source)


def write_vcd(folder: Path, scenario: Scenario, res: CosimResult, traces: list, program: Program,
               names: NameTable, iomap: IoMap) -> None:
    """One VCD per run: the compared operands of both executors side by side (scopes `original`, `translated`)."""
    columns = list(comparison_for(program, names, iomap).columns)
    folder.mkdir(parents=True, exist_ok=True)
    sides = {}
    for side, pick in (("original", 1), ("translated", 2)):
        rec = TraceRecorder(columns)
        for row in traces:
            rec.record(row[0], list(row[pick]))
        sides[side] = rec
    write_vcd_scopes(folder / f"{scenario.name}.vcd", sides, res.machine.cycle_time_ms if res.machine else 20)
