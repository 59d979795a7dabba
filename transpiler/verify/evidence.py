"""The evidence of an equivalence check as the HTML page shows it (html_report.Evidence): runs, divergences replayed
with every cycle recorded, and the source files with their line coverage; decided here, laid out there."""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Mapping, Sequence

from transpiler.backends.report.iomap import IoMap
from transpiler.frontend.sources import decode_text
from transpiler.ir import Program
from transpiler.verify.cosim import StSide
from transpiler.verify.divergence_trace import DivergenceTrace, trace_divergence
from transpiler.verify.equiv import EquivalenceResult
from transpiler.verify.html_report import Evidence, RunRow, source_files
from transpiler.verify.mcdc import figures
from transpiler.verify.scenario import NameTable, Scenario


def _status(outcome) -> str:
    r = outcome.result
    if r.error:
        return f"FAULT ({r.error_side or 'harness'}): {r.error}"
    if r.divergence is not None:
        return f"DIVERGENCE at cycle {r.divergence.cycle}: {r.divergence.name}"
    if r.missing:
        return f"MISSING: {len(r.missing)} operands"
    if r.expectation_failures:
        return f"EXPECTATION FAILED ({len(r.expectation_failures)})"
    return "equivalent"


def divergence_traces(result: EquivalenceResult, program: Program, make_side: Callable[[], StSide], iomap: IoMap,
                      names: NameTable, scenarios: Sequence[Scenario], st_text: str,
                      base_mp: Mapping | None = None) -> list[DivergenceTrace]:
    """Each divergent run replayed with every cycle recorded (its shrunk stimulus where there is one). The outcomes
    are the runs of `scenarios`, in order (two scenario files may share a name)."""
    traces = []
    for outcome, scenario in zip(result.outcomes, scenarios):
        r = outcome.result
        if r.divergence is None:
            continue
        replay = outcome.shrunk if outcome.shrunk is not None else scenario
        trace = trace_divergence(program, make_side, iomap, names, r.scenario, replay, st_text, base_mp)
        if trace is None and replay is not scenario:
            trace = trace_divergence(program, make_side, iomap, names, r.scenario, scenario, st_text, base_mp)
        if trace is not None:
            traces.append(trace)
    return traces


def source_texts(program: Program, main_dir: Path, encoding: str | None = None) -> dict[str, str]:
    """Each .src file of the program (as its spans name it) -> its text, decoded as the front end decoded it."""
    texts = {}
    for f in program.files:
        path = main_dir / f.path
        try:
            texts[f.path] = decode_text(path.read_bytes(), encoding)
        except (OSError, UnicodeDecodeError):
            texts[f.path] = ""
    return texts


def equivalence_evidence(result: EquivalenceResult, program: Program, main_dir: Path, title: str,
                         traces: Sequence[DivergenceTrace] = (), encoding: str | None = None) -> Evidence:
    c = result.coverage
    cycles = sum(o.result.cycles_run for o in result.outcomes)
    summary = [f"{len(result.outcomes)} runs, {cycles} cycles, backend {result.backend}.",
               f"Coverage of the original: instructions {c['instructions_executed']}/{c['instructions']}, "
               f"conditional branches both ways {c['branches_both_ways']}/{c['branches']}, CASE entries "
               f"{c['case_entries_taken']}/{c['case_entries']}" + (f", {figures(c)}." if "mcdc" in c else ".")]
    summary += [f"Not translated: {span}: {text}" for span, text in result.untranslated]
    coverage: dict[str, dict[int, tuple[int, int, int]]] = {}
    if result.source is not None:
        for f in result.source.files:
            coverage[f.path] = {line.number: (line.hits, line.branches_covered, line.branches_valid)
                                for line in f.lines}
    notes: dict[tuple[str, int], list[str]] = {}
    for trace in traces:
        for where in trace.source_lines:
            file, line = _file_line(where)
            if file is not None:
                notes.setdefault((file, line), []).append(f"divergence: writes {trace.name} ({trace.run})")
    runs = [RunRow(o.result.scenario, _status(o), o.result.cycles_run, o.result.compared, o.result.seconds)
            for o in result.outcomes]
    return Evidence(title, result.verdict, result.equivalent, summary, runs, tuple(traces),
                    source_files(source_texts(program, main_dir, encoding), coverage, notes))


def _file_line(where: str) -> tuple[str | None, int]:
    """`file:line:col` -> (file, line)."""
    parts = where.rsplit(":", 2)
    if len(parts) == 3 and parts[1].isdigit():
        return parts[0], int(parts[1])
    return None, 0


def mutation_evidence(result, st_text: str, program: Program, main_dir: Path, title: str,
                      min_score: float, encoding: str | None = None) -> Evidence:
    """The page of a mutation run: the score against `min_score`, the surviving mutants, each beside the source line
    its statement was translated from (the traceability tag above it in the ST)."""
    from transpiler.verify.mutate import EQUIVALENT, ERROR, INVALID, KILLED, SURVIVED, survivor_location
    met = result.meets(min_score)
    summary = [f"{result.sites} mutation sites; {len(result.verdicts)} mutants judged on the {result.backend} "
               f"backend under {len(result.scenarios)} scenarios in {result.seconds:.0f} s.",
               f"{result.count(KILLED)} killed of {result.denominator} non-equivalent mutants; "
               f"{result.count(SURVIVED)} survived, {result.count(EQUIVALENT)} judged equivalent, "
               f"{result.count(ERROR)} errors, {result.count(INVALID)} invalid; minimum {100 * min_score:.1f}%."]
    survivors = []
    notes: dict[tuple[str, int], list[str]] = {}
    for v in result.verdicts:
        if v.outcome != SURVIVED:
            continue
        where = survivor_location(st_text, v.mutant)
        if " from " in where:               # the statement's own tag: the source line it was translated from
            source = where.rsplit(" from ", 1)[1]
            file, line = _file_line(source + ":1")
            note = f"mutant survived: {v.mutant.description}"
        else:                               # no tag of its own: the lines its POU was translated from
            ranges = result.pou_sources.get(v.mutant.pou, ())
            source = ranges[0].tag() if ranges else ""
            file, line = (ranges[0].file, ranges[0].first_line) if ranges else (None, 0)
            note = f"mutant survived (in {source}): {v.mutant.description}: {v.mutant.original}"
        survivors.append((source, where.split(", from ")[0], f"{v.mutant.description}: {v.mutant.original}"))
        if file is not None:
            notes.setdefault((file, line), []).append(note)
    return Evidence(title, f"score {100 * result.score:.1f}%", met, summary, survivors=survivors,
                    sources=source_files(source_texts(program, main_dir, encoding), {}, notes))
