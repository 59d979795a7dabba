"""Mutation analysis of the evidence: how much can the scenarios (and the generated stimulus) catch?

Mutants of the emitted ST, each one place in the body of one translated POU changed (the emitted HH_* library is
left alone): an assignment or call that loses its effect, AND<->OR, a negation dropped, TRUE<->FALSE, an
integer constant +-1 (except the width 32 of a word gate, which cannot matter), a comparison operator replaced,
two neighbouring CASE branches swapped. Each mutant is judged by the same co-simulation as `equiv`, shortest
scenario first: it is KILLED by a divergence, an operand
missing in the translation, or a fault of the translated side (what `equiv` calls NOT EQUIVALENT); ST the
executor rejects makes it INVALID (excluded); a mutant whose runs end only in harness exceptions is an ERROR
(never a kill); else it SURVIVED. A file of judged-equivalent mutants (each with its reason) takes those out of
the denominator: score = killed / (killed + survived + error - judged equivalent).

Judging saves work without changing a verdict (prepare, Judging): each scenario's reference run is recorded once
(recording.py); where the backend builds mutant schemata, all mutants are built at once and a probing run of the
original per scenario tells which mutants it infects; a mutant then runs only under the runs that infect it (a
run that does not is the original's run, which agrees with the reference), and one no run infects survives
without a run. judge_all judges any list of mutants this way, so a subset (a shard) gets the verdicts it would
get among all."""

from __future__ import annotations

import dataclasses
import functools
import json
import multiprocessing
import multiprocessing.connection
import random
import re
import signal
import time
from pathlib import Path
from types import MappingProxyType
from typing import Any, Callable, Iterable, Iterator, Mapping, Protocol, Sequence
from xml.sax.saxutils import quoteattr

import yaml

from transpiler.backends.iec_model import SourceRange
from transpiler.backends.report.iomap import IoMap
from transpiler.diagnostics import CompileFailed, Diagnostic, Span
from transpiler.exec.interp import CompiledProgram
from transpiler.exec.st_lines import st_origin
from transpiler.ir import Program
from transpiler.verify.cosim import Comparison, StSide, comparison_for, cosimulate, record_reference
from transpiler.verify.recording import Recording
from transpiler.verify.rundata import SHIPPED
from transpiler.verify.scenario import NameTable, Scenario

KILLED, SURVIVED, INVALID, ERROR, EQUIVALENT = "killed", "survived", "invalid", "error", "equivalent"
OUTCOMES = (KILLED, SURVIVED, EQUIVALENT, ERROR, INVALID)
OPERATORS = ("drop_statement", "and_or", "negation", "constant", "comparison", "swap_case")

POU_START = re.compile(r"^(FUNCTION_BLOCK|PROGRAM|FUNCTION)\s+(\w+)")
POU_END = re.compile(r"^END_(FUNCTION_BLOCK|PROGRAM|FUNCTION)\b")
COMMENT = re.compile(r"\(\*.*?\*\)")
ASSIGNMENT = re.compile(r"^(\s*)([\w.\[\] +-]+?)\s*:=.*;\s*$")
CALL = re.compile(r"^\s*\w+\(\);\s*$")
CASE_LABEL = re.compile(r"^(\s*)(\d+)(\s*:)")
INTEGER = re.compile(r"(?<![\w#.])\d+(?![\w#.])")
COMPARISONS = MappingProxyType({"<>": "=", "<=": "<", ">=": ">", "=": "<>", "<": "<=", ">": ">="})
COMPARISON = re.compile(r"<>|<=|>=|(?<![:<>])=|<(?![>=])|>(?!=)")


@dataclasses.dataclass(frozen=True)
class Mutant:
    """One mutation: the changed lines (0-based index -> new text, None = deleted) of the ST text."""

    operator: str
    line: int                                   # 1-based line of the ST text
    pou: str
    description: str
    original: str                               # the code of the mutated line before the change (stripped)
    changes: tuple[tuple[int, str | None], ...]
    occurrence: int = 1                         # n-th mutant of the POU with the same operator, mutation and code

    def apply(self, st_text: str) -> str:
        lines = st_text.splitlines()
        for index, text in self.changes:
            lines[index] = text
        return "\n".join(line for line in lines if line is not None) + "\n"

    @property
    def key(self) -> tuple[str, str, str, str, int]:
        """What a judged-equivalent entry matches: stable when the ST moves by some lines. The occurrence tells
        apart the same statement written several times in one POU: one copy may be equivalent, another not."""
        return (self.pou.upper(), self.operator, self.description, self.original, self.occurrence)


def _code_part(line: str) -> tuple[str, str]:
    """The line without its trailing comments (mutations never touch comments) and the rest."""
    m = COMMENT.search(line)
    return (line, "") if m is None else (line[:m.start()], line[m.start():])


def _masked(code: str) -> str:
    """The code with string literals blanked out, so that sites are only found outside them (positions kept)."""
    return re.sub(r"'[^']*'", lambda m: " " * len(m.group(0)), code)


def body_lines(st_text: str) -> Iterator[tuple[int, str, str]]:
    """(index, POU name, line) of every code line in the bodies of translated POUs."""
    pou, in_body = None, False
    for index, line in enumerate(st_text.splitlines()):
        start = POU_START.match(line)
        if start:
            pou, in_body = start.group(2), False
            continue
        if POU_END.match(line):
            pou = None
            continue
        if pou is None or pou.upper().startswith("HH_"):
            continue
        if line.strip() == "END_VAR":
            in_body = True
            continue
        if in_body and line.strip() and not re.match(r"\s*VAR", line) and _code_part(line)[0].strip():
            yield index, pou, line


def _replace_at(line: str, start: int, end: int, new: str) -> str:
    return line[:start] + new + line[end:]


# The word gates of the emitted library take the operand width last and treat every width but 8 and 16 as 32
# bits, so 31 and 33 in place of 32 cannot change anything: equivalent by construction, never generated.
_GATES = frozenset({"HH_WAND", "HH_WOR", "HH_WXOR"})


def _width_of_a_gate(code: str, start: int, end: int, value: int) -> bool:
    """Whether the literal code[start:end] is a width 32 given to a word gate (its last argument)."""
    if value != 32 or not code[end:].lstrip().startswith(")") or not code[:start].rstrip().endswith(","):
        return False
    depth = 0
    for i in range(start - 1, -1, -1):
        depth += {")": 1, "(": -1}.get(code[i], 0)
        if depth < 0:
            callee = re.search(r"([A-Za-z_][A-Za-z0-9_]*)\s*$", code[:i])
            return callee is not None and callee.group(1).upper() in _GATES
    return False


def mutation_sites(st_text: str) -> list[Mutant]:
    """Every single-place mutation of the translated bodies, in file order."""
    lines = st_text.splitlines()
    out: list[Mutant] = []

    def add(operator: str, index: int, pou: str, description: str, new_line: str | None,
            extra: tuple[tuple[int, str], ...] = ()) -> None:
        out.append(Mutant(operator, index + 1, pou, description, _code_part(lines[index])[0].strip(),
                          ((index, new_line), *extra)))

    bodies = list(body_lines(st_text))
    for index, pou, line in bodies:
        code, rest = _code_part(line)
        plain = _masked(code)
        assignment = ASSIGNMENT.match(code)
        gap = code[len(code.rstrip()):]          # the blank before a trailing comment stays: only the code changes
        if assignment:
            # `x := x;` rather than deleting the line: a statement list may not be empty
            target = assignment.group(2)
            add("drop_statement", index, pou, "assignment loses its effect",
                f"{assignment.group(1)}{target} := {target};" + gap + rest)
        elif CALL.match(code):
            # kept as a statement that never runs: deleting the line could leave an IF or a loop with no statement
            indent = code[:len(code) - len(code.lstrip())]
            add("drop_statement", index, pou, "call dropped",
                f"{indent}IF FALSE THEN {code.strip()} END_IF;" + gap + rest)
        for m in re.finditer(r"\b(AND|OR)\b", plain):
            new = "OR" if m.group(1) == "AND" else "AND"
            add("and_or", index, pou, f"{m.group(1)} -> {new} at column {m.start() + 1}",
                _replace_at(code, m.start(), m.end(), new) + rest)
        for m in re.finditer(r"\bNOT\s+", plain):
            add("negation", index, pou, f"NOT dropped at column {m.start() + 1}",
                _replace_at(code, m.start(), m.end(), "") + rest)
        for m in re.finditer(r"\b(TRUE|FALSE)\b", plain):
            new = "FALSE" if m.group(1) == "TRUE" else "TRUE"
            add("negation", index, pou, f"{m.group(1)} -> {new} at column {m.start() + 1}",
                _replace_at(code, m.start(), m.end(), new) + rest)
        if not CASE_LABEL.match(code):
            for m in INTEGER.finditer(plain):
                value = int(m.group(0))
                if _width_of_a_gate(plain, m.start(), m.end(), value):
                    continue
                for delta in (1, -1):
                    if value + delta >= 0:
                        add("constant", index, pou, f"{value} -> {value + delta} at column {m.start() + 1}",
                            _replace_at(code, m.start(), m.end(), str(value + delta)) + rest)
        for m in COMPARISON.finditer(plain):
            new = COMPARISONS[m.group(0)]
            add("comparison", index, pou, f"'{m.group(0)}' -> '{new}' at column {m.start() + 1}",
                _replace_at(code, m.start(), m.end(), new) + rest)
    # Two neighbouring branches of one CASE exchange their labels, so each body runs for the other's value.
    labels = [(index, pou, CASE_LABEL.match(_code_part(line)[0])) for index, pou, line in bodies]
    labels = [(index, pou, m) for index, pou, m in labels if m]
    for (i1, pou1, m1), (i2, pou2, m2) in zip(labels, labels[1:]):
        if pou1 != pou2 or m1.group(1) != m2.group(1):
            continue
        first = lines[i1][:m1.start(2)] + m2.group(2) + lines[i1][m1.end(2):]
        second = lines[i2][:m2.start(2)] + m1.group(2) + lines[i2][m2.end(2):]
        add("swap_case", i1, pou1, f"CASE branches {m1.group(2)} and {m2.group(2)} swapped", first, ((i2, second),))
    seen: dict[tuple, int] = {}
    for i, m in enumerate(out):
        count = seen[m.key] = seen.get(m.key, 0) + 1
        if count > 1:
            out[i] = dataclasses.replace(m, occurrence=count)
    return out


def choose(mutants: list[Mutant], count: int, seed: int) -> list[Mutant]:
    """A seeded sample spread evenly over the operators (all of an operator when it has fewer sites)."""
    if count <= 0 or count >= len(mutants):
        return list(mutants)
    rng = random.Random(seed)
    by_op = {op: [m for m in mutants if m.operator == op] for op in OPERATORS}
    chosen: list[Mutant] = []
    remaining = count
    for n, op in enumerate(sorted(by_op, key=lambda o: len(by_op[o]))):
        share = remaining // (len(OPERATORS) - n)
        picked = rng.sample(by_op[op], min(share, len(by_op[op])))
        chosen += picked
        remaining -= len(picked)
    return sorted(chosen, key=lambda m: (m.line, m.operator, m.description))


# ---------------------------------------------------------------------------------------------
# Judged-equivalent mutants


@dataclasses.dataclass(frozen=True)
class JudgedEquivalent:
    pou: str
    operator: str
    mutation: str
    st: str
    reason: str
    span: Span
    occurrence: int = 1

    @property
    def key(self) -> tuple[str, str, str, str, int]:
        return (self.pou.upper(), self.operator, self.mutation, self.st, self.occurrence)


def load_equivalents(path: Path) -> list[JudgedEquivalent]:
    """The checked-in list of mutants judged equivalent: a YAML list of {pou, operator, mutation, st, reason};
    raises CompileFailed (E-USAGE at the entry) on a malformed file."""
    def fail(line: int, message: str) -> CompileFailed:
        return CompileFailed([Diagnostic.of("E-USAGE", Span(str(path), line, 1), message)])
    try:
        text = path.read_text(encoding="utf-8")
        nodes = yaml.compose(text)
    except (OSError, UnicodeDecodeError) as exc:
        raise fail(1, f"cannot read the equivalent-mutants file: {exc}") from None
    except yaml.YAMLError as exc:
        line = exc.problem_mark.line + 1 if getattr(exc, "problem_mark", None) else 1
        raise fail(line, f"the equivalent-mutants file is not valid YAML: {getattr(exc, 'problem', exc)}") from None
    data = yaml.safe_load(text) if nodes is not None else []
    if not isinstance(data, list):
        raise fail(1, "the equivalent-mutants file must be a list of {pou, operator, mutation, st, reason}")
    out = []
    for i, entry in enumerate(data):
        line = nodes.value[i].start_mark.line + 1
        fields = ("pou", "operator", "mutation", "st", "reason")
        if not isinstance(entry, dict) or set(entry) - {"occurrence"} != set(fields) or not all(
                isinstance(entry[f], str) and entry[f].strip() for f in fields):
            raise fail(line, "each entry needs exactly pou, operator, mutation, st and reason, all non-empty text "
                             "(and occurrence, a number, where the POU has the same statement more than once)")
        occurrence = entry.get("occurrence", 1)
        if type(occurrence) is not int or occurrence < 1:
            raise fail(line, "occurrence is the number (1, 2, ...) of the statement among equal ones of its POU")
        if entry["operator"] not in OPERATORS:
            raise fail(line, f"unknown operator '{entry['operator']}' (one of {', '.join(OPERATORS)})")
        out.append(JudgedEquivalent(entry["pou"], entry["operator"], entry["mutation"], entry["st"].strip(),
                                    entry["reason"].strip(), Span(str(path), line, 1), occurrence))
    return out


# ---------------------------------------------------------------------------------------------
# Judging


@dataclasses.dataclass(frozen=True)
class Verdict:
    mutant: Mutant
    outcome: str
    by: str                      # the killing scenario and how, a message, or the reason of a judged equivalent
    seconds: float
    runs: int = 0                # scenarios run on it, shortest first: a killed mutant's killer is the last of them
    ran: tuple[int, ...] | None = None     # which scenarios (by index) those were; None: the first `runs` of them

    @property
    def scenarios_run(self) -> tuple[int, ...]:
        return self.ran if self.ran is not None else tuple(range(self.runs))


class MutantSides(Protocol):
    """Many mutants of the ST text built once (a mutant schema): `factory(number)` makes ST sides of the mutant
    numbered `number` in the judged list (1, 2, ...; 0 the original, PROBE the original recording in each side's
    `infected` the mutants a run infects); `unswitched` are the numbers it does not hold."""

    unswitched: frozenset

    def factory(self, number: int) -> Callable[[], StSide]: ...


PROBE = -1                    # the mutant number of a probing run (stexec.PROBE)


@dataclasses.dataclass
class Judge:
    """Everything a worker needs to judge a mutant: the program, its scenarios (validated on the unmutated ST)
    and how to build an ST executor from a text (`side_factory(text)`; raises on a text it cannot build) or, where
    the backend can, all mutants at once (`schema_factory(text, [TextMutation, ...])`, a MutantSides)."""

    program: Program
    iomap: IoMap
    names: NameTable
    scenarios: list[Scenario]
    st_text: str
    side_factory: Callable[[str], Callable[[], StSide]]
    compiled: CompiledProgram | None = None
    base_mp: Mapping | None = None
    schema_factory: Callable[[str, list], MutantSides] | None = None
    # per scenario, its reference run recorded once (see prepare; LazyRecordings records it on first use): mutants
    # then run only their own half
    recordings: "Sequence[Recording] | None" = None
    comparison: Comparison | None = None        # what every run compares (comparison_for, made once by prepare)
    # the translated side is compiled code, which can crash the process running it: every run goes to a forked
    # process, and a crash is that mutant's error (or, probing, the unmutated translation's problem)
    isolate: bool = False

    def __call__(self, mutant: Mutant) -> Verdict:
        """The mutant's text built on its own and run under every scenario (against the recordings if any)."""
        start = time.perf_counter()
        try:
            factory = self.side_factory(mutant.apply(self.st_text))
        except CompileFailed as exc:
            return Verdict(mutant, INVALID, f"rejected by the ST executor's compiler: {_message(exc)}",
                           time.perf_counter() - start)
        except Exception as exc:  # noqa: BLE001 - a mutant that cannot be built is invalid, with its message
            return Verdict(mutant, INVALID, f"rejected: {_message(exc)}", time.perf_counter() - start)
        return self.run(mutant, factory, range(len(self.scenarios)), start)

    def run(self, mutant: Mutant, factory: Callable[[], StSide], runs: Iterable[int], start: float) -> Verdict:
        """Judge the built mutant under the scenarios numbered `runs` (in that order) until one kills it."""
        first_error = None
        done: list[int] = []
        for index in runs:
            scenario = self.scenarios[index]
            recording = self.recordings[index] if self.recordings is not None else None
            done.append(index)
            try:
                result = cosimulate(self.program, factory, self.iomap, scenario, self.names, compiled=self.compiled,
                                    base_mp=self.base_mp, recording=recording, comparison=self.comparison)
            except Exception as exc:  # noqa: BLE001 - a crash is an error of this mutant, never a kill
                first_error = first_error or f"{scenario.name}: {_message(exc)}"
                continue
            how = None
            if result.divergence is not None:
                how = f"{result.divergence.name} differs at cycle {result.divergence.cycle}"
            elif result.missing:
                how = f"{len(result.missing)} operands missing in the translation"
            elif result.error is not None and result.error_side == "translated":
                how = f"fault of the translation: {result.error}"
            elif result.error_code == SHIPPED:
                how = "its machine-parameter values differ from the project's"
            if how is not None:
                return Verdict(mutant, KILLED, f"{scenario.name}: {how}", time.perf_counter() - start, len(done),
                               tuple(done))
            if result.error is not None:
                first_error = first_error or f"{scenario.name}: {result.error}"
        if first_error is not None:
            return Verdict(mutant, ERROR, first_error, time.perf_counter() - start, len(done), tuple(done))
        return Verdict(mutant, SURVIVED, "" if done else NEVER_INFECTED, time.perf_counter() - start, len(done),
                       tuple(done))


NEVER_INFECTED = "no run reaches the mutated code with a value the mutation changes"


def _message(exc: BaseException) -> str:
    """An exception as one short line: its type and the first line of its message."""
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0][:200]}" if text else type(exc).__name__


@dataclasses.dataclass
class Judging:
    """A list of mutants ready to be judged (prepare): the scenarios' reference runs recorded, the mutants built
    once where the backend has schemata, and per scenario the mutants its run of the original infects. A mutant
    is then judged (`judging(index)`) only under the runs that infect it, shortest first, until one kills it: a
    run that does not infect it runs as the original's, which agrees with the reference; never infected, it
    survives without a run. Mutants outside the schema are built from their text and run under every scenario."""

    judge: Judge
    mutants: list[Mutant]
    sides: MutantSides | None = None
    infected: tuple[frozenset[int], ...] | None = None      # per scenario: numbers (index + 1) its run infects
    # runs of the unmutated translation that do not agree with the reference: mutation results would mean nothing
    problems: tuple[str, ...] = ()

    def __call__(self, index: int) -> Verdict:
        mutant, number = self.mutants[index], index + 1
        if self.sides is None or number in self.sides.unswitched:
            return self.judge(mutant)
        start = time.perf_counter()
        runs = range(len(self.judge.scenarios))
        if self.infected is not None:
            runs = [i for i in runs if number in self.infected[i]]
        return self.judge.run(mutant, self.sides.factory(number), runs, start)


class LazyRecordings:
    """The scenarios' reference runs, each recorded the first time a mutant needs it: a shard that was given the
    infection map by its plan file records only the runs its own mutants go through."""

    def __init__(self, judge: Judge):
        self._judge = judge
        self._made: dict[int, Recording] = {}

    def __len__(self) -> int:
        return len(self._judge.scenarios)

    def __getitem__(self, index: int) -> Recording:
        if index not in self._made:
            judge = self._judge
            self._made[index] = record_reference(judge.program, judge.iomap, judge.scenarios[index], judge.names,
                                                 compiled=judge.compiled, base_mp=judge.base_mp,
                                                 comparison=judge.comparison)
        return self._made[index]


def prepare(judge: Judge, mutants: list[Mutant], jobs: int = 1,
            infected: "tuple[frozenset[int], ...] | None" = None) -> Judging:
    """Record every scenario's reference run, build the mutant schema (where the backend has one) and probe each
    scenario with it; the scenarios are shared out over `jobs` forked processes. `infected` (per scenario, the
    mutants' numbers its run infects, as a plan file carries them from the job that probed every scenario) skips
    the probing: the reference runs are then recorded as the mutants need them."""
    judge = dataclasses.replace(judge, comparison=judge.comparison or comparison_for(judge.program, judge.names,
                                                                                    judge.iomap))
    sides = None
    if judge.schema_factory is not None:
        from transpiler.exec.stexec import TextMutation
        sides = judge.schema_factory(judge.st_text, [TextMutation(i + 1, m.changes) for i, m in enumerate(mutants)])
    if infected is not None and sides is not None:
        if len(infected) != len(judge.scenarios):
            raise ValueError("the infection map does not have one entry per scenario")
        lazy = dataclasses.replace(judge)
        lazy.recordings = LazyRecordings(lazy)
        return Judging(lazy, mutants, sides, tuple(infected))
    original = judge.side_factory(judge.st_text) if sides is None else None
    task = functools.partial(_prepare_scenario, judge, sides, original)
    found = dict(_each(task, range(len(judge.scenarios)), jobs, _probe_crashed(judge) if judge.isolate else None))
    ordered = [found[i] for i in range(len(judge.scenarios))]
    problems = tuple(problem for _, _, problem in ordered if problem is not None)
    infected = None
    if sides is not None and not problems:
        infected = tuple(runs for _, runs, _ in ordered)
    return Judging(dataclasses.replace(judge, recordings=tuple(recording for recording, _, _ in ordered)), mutants,
                   sides, infected, problems)


def _prepare_scenario(judge: Judge, sides: MutantSides | None, original: Callable[[], StSide] | None, index: int
                      ) -> tuple[Recording, frozenset | None, str | None]:
    """One scenario's reference run recorded, the unmutated translation run against it (with a schema, its
    probing run, which also finds the mutants the run infects) and what is wrong if that run does not agree."""
    scenario = judge.scenarios[index]
    recording = record_reference(judge.program, judge.iomap, scenario, judge.names, compiled=judge.compiled,
                                 base_mp=judge.base_mp, comparison=judge.comparison)
    made: list = []
    factory = sides.factory(PROBE) if sides is not None else original

    def side():
        made.append(factory())
        return made[-1]
    r = cosimulate(judge.program, side, judge.iomap, scenario, judge.names, compiled=judge.compiled,
                   base_mp=judge.base_mp, recording=recording, comparison=judge.comparison)
    if not r.equivalent:
        return recording, None, f"{scenario.name}: {r.divergence or r.error or 'operands missing in the translation'}"
    return recording, frozenset(made[0].infected) if sides is not None else None, None


def _each(task: Callable[[int], Any], items: Iterable[int], jobs: int, crashed: Callable[[int, int], Any] | None = None
          ) -> Iterator[tuple[int, Any]]:
    """(item, task(item)) for every item, in `jobs` forked processes when jobs > 1 (results are pickled). With
    `crashed`, the items always run in forked processes (one at least): compiled code can crash the process that
    runs it, and an item whose process died gives crashed(item, exit code) while a new process takes the rest.
    Without it, a process that dies is an error (RuntimeError), never a wait for results that cannot come."""
    items = list(items)
    if crashed is None and (jobs <= 1 or len(items) <= 1):
        for item in items:
            yield item, task(item)
        return
    context = multiprocessing.get_context("fork")
    tasks = context.Queue()
    for item in items:
        tasks.put(item)
    workers: dict[int, tuple[Any, Any]] = {}        # slot -> (process, the read end of its pipe)
    running: dict[int, int] = {}                    # slot -> the item its process started and has not answered

    def start(slot: int) -> None:
        tasks.put(None)                             # its end marker, after every item
        reader, writer = context.Pipe(duplex=False)
        process = context.Process(target=_worker, args=(task, tasks, writer), daemon=True)
        process.start()
        writer.close()
        workers[slot] = (process, reader)

    for slot in range(max(1, min(jobs, len(items)))):
        start(slot)
    done = 0
    try:
        while done < len(items) and workers:
            multiprocessing.connection.wait([w for pair in workers.values() for w in (pair[0].sentinel, pair[1])])
            for slot, (process, reader) in list(workers.items()):
                exited = process.exitcode is not None     # before reading: all it sent is in the pipe then
                for kind, item, value in _received(reader):
                    if kind == "start":
                        running[slot] = item
                    else:
                        running.pop(slot, None)
                        done += 1
                        yield item, value
                if not exited:
                    continue
                del workers[slot]
                if slot in running or process.exitcode != 0:
                    if crashed is None or slot not in running:
                        raise RuntimeError(f"a worker process ended with exit code {process.exitcode}")
                    item = running.pop(slot)
                    done += 1
                    yield item, crashed(item, process.exitcode)
                    start(slot)
    finally:
        for process, reader in workers.values():
            if process.is_alive():
                process.terminate()
            process.join()
            reader.close()


def _received(reader) -> Iterator[tuple]:
    """The messages waiting in a worker's pipe (none once it is closed)."""
    try:
        while reader.poll():
            yield reader.recv()
    except (EOFError, OSError):
        return


def _worker(task: Callable[[int], Any], tasks, pipe) -> None:
    """A forked process: runs the task on items until it takes the end marker, saying first which item it starts
    (a pipe's send is written before it returns, so the parent knows the item if the process dies in it)."""
    while (item := tasks.get()) is not None:
        pipe.send(("start", item, None))
        pipe.send(("done", item, task(item)))


def judge_all(judge: Judge, mutants: list[Mutant], jobs: int, judging: Judging | None = None,
              indexes: Iterable[int] | None = None) -> Iterator[Verdict]:
    """Verdicts of the given mutants as they come in (prepare, unless `judging` is that of these mutants, then judge
    each, or those at `indexes`; with jobs > 1 in forked workers, which share what was prepared and send back only
    verdicts). Any list of mutants can be given: a subset judges exactly as it would among all."""
    judging = judging or prepare(judge, mutants, jobs)
    chosen = range(len(mutants)) if indexes is None else list(indexes)
    crashed = (lambda index, code: (ERROR, f"the compiled mutant crashed the process running it ({_exit(code)})",
                                    0.0, 0, ())) if judge.isolate else None
    for index, verdict in _each(functools.partial(_verdict_fields, judging), chosen, jobs, crashed):
        yield Verdict(mutants[index], *verdict)


def _probe_crashed(judge: Judge) -> Callable[[int, int], tuple]:
    def crashed(index: int, code: int) -> tuple:
        return None, None, (f"{judge.scenarios[index].name}: the unmutated translation crashed the process running "
                            f"it ({_exit(code)})")
    return crashed


def _exit(code: int) -> str:
    """A process's exit code as words: the signal that ended it, or the code."""
    if code < 0:
        try:
            return f"signal {-code}, {signal.Signals(-code).name}"
        except ValueError:
            return f"signal {-code}"
    return f"exit code {code}"


def _verdict_fields(judging: Judging, index: int) -> tuple:
    verdict = judging(index)
    return verdict.outcome, verdict.by, verdict.seconds, verdict.runs, verdict.ran


@dataclasses.dataclass
class MutationResult:
    verdicts: list[Verdict]
    sites: int                                  # mutation sites in the translation (before --count)
    scenarios: list[str]
    backend: str
    seconds: float
    unmatched_equivalents: list[tuple[JudgedEquivalent, str]] = dataclasses.field(default_factory=list)
    listed_absent: int = 0                      # mutants the --mutants file lists that the translation has not
    scenario_files: tuple[str, ...] = ()        # the file of each of `scenarios` ("" for generated stimulus)
    # POU -> the source lines it was translated from
    pou_sources: Mapping[str, tuple[SourceRange, ...]] = dataclasses.field(default_factory=dict)

    def count(self, outcome: str) -> int:
        return sum(1 for v in self.verdicts if v.outcome == outcome)

    @property
    def denominator(self) -> int:
        """Mutants that ran and are not judged equivalent (invalid ones are no programs at all)."""
        return self.count(KILLED) + self.count(SURVIVED) + self.count(ERROR)

    @property
    def score(self) -> float:
        return self.count(KILLED) / self.denominator if self.denominator else 0.0

    def meets(self, min_score: float) -> bool:
        """The score reaches `min_score`, with at least one mutant that counts (nothing judged proves nothing)."""
        return self.denominator > 0 and self.score >= min_score


KILLED_ANYWAY = "killed"     # a judged-equivalent mutant that a scenario told apart: the judgement was wrong
NO_SUCH_MUTANT = "gone"      # the translation has no such mutant (any more): the entry is stale


def apply_equivalents(verdicts: list[Verdict], equivalents: list[JudgedEquivalent],
                      sites: Iterable[Mutant]) -> tuple[list[Verdict], list[tuple[JudgedEquivalent, str]]]:
    """Survivors named in the judged-equivalent list become EQUIVALENT (with the reason). Entries worth a look are
    returned with why: the mutant was judged and not a survivor (KILLED_ANYWAY), or it is not among `sites`, the
    translation's mutants (NO_SUCH_MUTANT); an entry whose mutant a sample (--count) left out is neither."""
    by_key = {e.key: e for e in equivalents}
    used = set()
    judged = set()
    out = []
    for v in verdicts:
        judged.add(v.mutant.key)
        entry = by_key.get(v.mutant.key)
        if entry is not None and v.outcome == SURVIVED:
            used.add(entry.key)
            v = dataclasses.replace(v, outcome=EQUIVALENT, by=entry.reason)
        out.append(v)
    existing = {m.key for m in sites}
    notes = [(e, KILLED_ANYWAY if e.key in judged else NO_SUCH_MUTANT) for e in equivalents
             if e.key not in used and (e.key in judged or e.key not in existing)]
    return out, notes


def survivor_location(st_text: str, mutant: Mutant) -> str:
    """`POU X, ST line N, from file:line` (the traceability tag above the line)."""
    return st_origin(st_text, mutant.line)


def report_data(result: MutationResult, st_text: str, unit_ids: Mapping[Mutant, int] | None = None,
                reproduce: Callable[[int], str] | None = None, shard: Mapping[str, Any] | None = None
                ) -> dict[str, Any]:
    """The report (`--report`) as data: every judged mutant (with its number in the plan, `unit`, when known), the
    counts and the score; `reproduce(unit)` gives the command line that judges one survivor or error alone. A shard's
    report carries `shard` (verify/shard.py), from which merge_reports counts the score over all shards."""
    mutants = []
    for v in result.verdicts:
        entry: dict[str, Any] = {"outcome": v.outcome, "operator": v.mutant.operator, "pou": v.mutant.pou,
                                 "st_line": v.mutant.line, "where": survivor_location(st_text, v.mutant),
                                 "st": v.mutant.original, "mutation": v.mutant.description, "by": v.by,
                                 "seconds": round(v.seconds, 3), "occurrence": v.mutant.occurrence}
        unit = (unit_ids or {}).get(v.mutant)
        if unit is not None:
            entry["unit"] = unit
            if reproduce is not None and v.outcome in (SURVIVED, ERROR):
                entry["reproduce"] = reproduce(unit)
        mutants.append(entry)
    data = _report(result.backend, result.sites, round(result.seconds, 1), result.scenarios, mutants,
                   [{"at": str(e.span), "pou": e.pou, "mutation": e.mutation, "st": e.st, "why": why,
                     "line": e.span.line} for e, why in result.unmatched_equivalents])
    if shard is not None:
        data["shard"] = dict(shard)
    return data


def _report(backend: str, sites: int, seconds: float, scenarios: list[str], mutants: list[dict[str, Any]],
            unmatched: list[dict[str, Any]]) -> dict[str, Any]:
    counts = {o: sum(1 for m in mutants if m["outcome"] == o) for o in OUTCOMES}
    denominator = counts[KILLED] + counts[SURVIVED] + counts[ERROR]
    return {"backend": backend, "score": round(counts[KILLED] / denominator if denominator else 0.0, 4),
            "sites": sites, "judged": len(mutants), "seconds": seconds, "scenarios": scenarios, "counts": counts,
            "mutants": mutants, "unmatched_equivalents": unmatched}


def report_json(result: MutationResult, st_text: str, unit_ids: Mapping[Mutant, int] | None = None,
                reproduce: Callable[[int], str] | None = None, shard: Mapping[str, Any] | None = None) -> str:
    return data_json(report_data(result, st_text, unit_ids, reproduce, shard))


def data_json(data: Mapping[str, Any]) -> str:
    return json.dumps(data, indent=2) + "\n"


def report_junit(result: MutationResult, st_text: str) -> str:
    """One test case per mutant: a survivor is a failure, an error an error, invalid/equivalent skipped."""
    return junit_of(report_data(result, st_text), result.seconds)


def junit_of(data: Mapping[str, Any], seconds: float | None = None) -> str:
    """The JUnit file of a report's data (report_data, or merged shards)."""
    mutants, counts = data["mutants"], data["counts"]
    total = data["seconds"] if seconds is None else seconds
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<testsuite name={quoteattr("hh2iec mutate (" + data["backend"] + ")")} tests="{len(mutants)}" '
             f'failures="{counts[SURVIVED]}" errors="{counts[ERROR]}" '
             f'skipped="{counts[INVALID] + counts[EQUIVALENT]}" time="{total:.3f}">']
    for m in mutants:
        name = f"{m['where']}: {m['operator']}: {m['mutation']}"
        lines.append(f'  <testcase classname="hh2iec.mutate" name={quoteattr(name)} time="{m["seconds"]:.3f}">')
        if m["outcome"] == SURVIVED:
            lines.append(f"    <failure message={quoteattr('survived: ' + m['st'])}/>")
        elif m["outcome"] == ERROR:
            lines.append(f"    <error message={quoteattr(m['by'])}/>")
        elif m["outcome"] in (INVALID, EQUIVALENT):
            lines.append(f"    <skipped message={quoteattr(m['outcome'] + ': ' + m['by'])}/>")
        lines.append("  </testcase>")
    lines.append("</testsuite>")
    return "\n".join(lines) + "\n"


def merge_reports(shards: list[Mapping[str, Any]]) -> dict[str, Any]:
    """One report from the reports of every shard (checked with shard.check_shards first): the mutants in the order
    one process reports them, the counts and score over all of them, each note on the judged-equivalent list once
    (a shard notes an entry whose mutant it judged and killed, every shard one whose mutant does not exist)."""
    mutants = sorted((m for data in shards for m in data["mutants"]),
                     key=lambda m: (m["st_line"], m["operator"], m["mutation"], m.get("unit", 0)))
    notes: dict[tuple, dict[str, Any]] = {}
    for data in shards:
        for note in data["unmatched_equivalents"]:
            notes.setdefault((note["line"], note["at"], note["why"]), note)
    unmatched = [notes[key] for key in sorted(notes, key=lambda key: (key[0], key[1]))]
    first = shards[0]
    backends = sorted({data["backend"] for data in shards})
    return _report("+".join(backends), first["sites"], round(sum(data["seconds"] for data in shards), 1),
                   first["scenarios"], mutants, unmatched)


def equivalents_yaml(verdicts: list[Verdict]) -> str:
    """Survivors in the format of the judged-equivalent file, with a reason still to be written."""
    entries: list[dict[str, Any]] = []
    for v in verdicts:
        if v.outcome == SURVIVED:
            m = v.mutant
            entry: dict[str, Any] = {"pou": m.pou, "operator": m.operator, "mutation": m.description,
                                     "st": m.original}
            if m.occurrence > 1:
                entry["occurrence"] = m.occurrence
            entries.append({**entry, "reason": "TODO: why this mutation cannot change behaviour"})
    return yaml.safe_dump(entries, sort_keys=False, width=120, allow_unicode=True)
