"""Mutation self-check of the co-simulation: systematic mutations of the sample's emitted ST must be detected.

Usage: python -m tests.mutants [--count 150] [--seed 1] [--backend auto|builtin|matiec] [--jobs N] [--all]

Each mutant changes one place in the body of one translated POU (the emitted HH_* library is left alone):
AND<->OR, a negation dropped or TRUE<->FALSE, an integer constant +-1, a comparison operator replaced, a
statement dropped, two CASE branches swapped. Every mutant is co-simulated against the reference interpreter,
shortest scenario first, until a divergence shows it (only a divergence kills a mutant): the sample's
scenarios, 2 000 random cycles, and scenarios aimed at boundaries (the hand-written ones from dirty memory, a short
power-on per boundary value of the program's constants, the hand-written ones with one NC job moved to an edge of
its range, long runs of random NC jobs on a healthy and on a toggling machine). The output lists how many were
killed per operator and every mutant that was not, so that each can be judged (a survivor is either a gap in the scenarios
or a mutation that cannot change behaviour). A mutant whose ST the executor rejects is "invalid" (excluded from
the rate); one that only ever ends in an exception (executor fault, handshake timeout, loop watchdog, harness
crash) is an "error": both are listed with their message and never counted as killed.
Exit 0 when at least 90 % of the valid mutants (killed + survived + error) are killed, 1 otherwise, 2 on a usage or
setup problem.
"""

from __future__ import annotations

import argparse
import dataclasses
import multiprocessing
import os
import random
import re
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable, Iterator

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from transpiler.verify.cosim import builtin_side_factory, cosimulate  # noqa: E402
from transpiler.diagnostics import CompileFailed, Diagnostics  # noqa: E402
from transpiler.verify.equiv import random_scenario  # noqa: E402
from transpiler.frontend.load import ProjectOptions  # noqa: E402
from transpiler.exec.interp import compile_program  # noqa: E402
from transpiler.frontend.pipeline import compile_project  # noqa: E402
from transpiler.verify.scenario import Event, NcAction, RandomStimulus, Scenario, bind, load_scenario  # noqa: E402
from transpiler.language.semantics import make_semantics  # noqa: E402
from transpiler.verify.simulate import program_operands, project_names  # noqa: E402
from transpiler.backends.st.check import find_iec2c  # noqa: E402
from transpiler.backends.report.report import io_map_of  # noqa: E402
from transpiler.frontend.mpfile import read_mp_file  # noqa: E402
from transpiler.backends.transpile import transpile_program  # noqa: E402

SAMPLE = ROOT / "samples" / "basic_program"
TARGET = 0.90
RANDOM_CYCLES = 2000
PERTURBED_TOGGLE = 0.01          # every input of the program may toggle on top of a hand-written scenario
NC_RUN_CYCLES = 3000
POWER_ON_CYCLES = 30
M_CODES = (3, 4, 5, 7, 8, 9, 10, 11, 19, 30, 50, 51, 99)
POCKET_EDGES = (-1, 0, 1, 2, 23, 24, 25)
# Interface words the NC model itself writes for nc actions (scenario format): never set at random.
NC_MODEL_WORDS = {("W", 256), ("W", 260), ("W", 262), ("W", 264), ("W", 272), ("D", 280), ("D", 284), ("D", 356)}
WORD_VALUES = (0, 1, 2, 3, 4, 7, 8, 15, 16, 255, 256, -1, 32767, -32768)
OPERATORS = ("and_or", "negation", "constant", "comparison", "drop_statement", "swap_case")

POU_START = re.compile(r"^(FUNCTION_BLOCK|PROGRAM|FUNCTION)\s+(\w+)")
POU_END = re.compile(r"^END_(FUNCTION_BLOCK|PROGRAM|FUNCTION)\b")
COMMENT = re.compile(r"\(\*.*?\*\)")
STATEMENT = re.compile(r"^\s*[\w.\[\] +-]+\s*:=.*;\s*$|^\s*\w+\(\);\s*$")
CASE_LABEL = re.compile(r"^(\s*)(\d+)(\s*:)")
INTEGER = re.compile(r"(?<![\w#.])\d+(?![\w#.])")
COMPARISONS = {"<>": "=", "<=": "<", ">=": ">", "=": "<>", "<": "<=", ">": ">="}
COMPARISON = re.compile(r"<>|<=|>=|(?<![:<>])=|<(?![>=])|>(?!=)")


def boundary_values(program) -> tuple[int, ...]:  # noqa: ANN001 - ir.Program
    """Word values worth trying: the usual edges plus every constant of the program and its neighbours (a mutated
    comparison or constant differs from the original only at such a boundary)."""
    constants = {op.operand.addr for f in program.files for op in f.ops
                 if op.operand is not None and op.operand.kind == "K"}
    near = {c + d for c in constants for d in (-1, 0, 1)}
    return tuple(sorted(set(WORD_VALUES) | {v for v in near if -(1 << 15) <= v < (1 << 15)}))


@dataclasses.dataclass(frozen=True)
class Mutant:
    operator: str
    line: int                   # 1-based line of project.st
    pou: str
    description: str
    text: str                   # the whole mutated ST text


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
            pou = start.group(2)
            in_body = False
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


def mutation_sites(st_text: str) -> list[Mutant]:
    """Every single-place mutation of the translated bodies, in file order."""
    lines = st_text.splitlines()
    out: list[Mutant] = []

    def add(operator: str, index: int, pou: str, description: str, new_line: str | None,
            extra: dict[int, str] | None = None) -> None:
        changed = list(lines)
        if new_line is None:
            del changed[index]
        else:
            changed[index] = new_line
        for i, text in (extra or {}).items():
            changed[i] = text
        out.append(Mutant(operator, index + 1, pou, description, "\n".join(changed) + "\n"))

    bodies = list(body_lines(st_text))
    for index, pou, line in bodies:
        code, rest = _code_part(line)
        plain = _masked(code)
        for m in re.finditer(r"\b(AND|OR)\b", plain):
            new = "OR" if m.group(1) == "AND" else "AND"
            add("and_or", index, pou, f"{m.group(1)} -> {new}", _replace_at(code, m.start(), m.end(), new) + rest)
        for m in re.finditer(r"\bNOT\s+", plain):
            add("negation", index, pou, "NOT dropped", _replace_at(code, m.start(), m.end(), "") + rest)
        for m in re.finditer(r"\b(TRUE|FALSE)\b", plain):
            new = "FALSE" if m.group(1) == "TRUE" else "TRUE"
            add("negation", index, pou, f"{m.group(1)} -> {new}", _replace_at(code, m.start(), m.end(), new) + rest)
        if not CASE_LABEL.match(code):
            for m in INTEGER.finditer(plain):
                value = int(m.group(0))
                for delta in (1, -1):
                    if value + delta < 0:
                        continue
                    add("constant", index, pou, f"{value} -> {value + delta}",
                        _replace_at(code, m.start(), m.end(), str(value + delta)) + rest)
        for m in COMPARISON.finditer(plain):
            new = COMPARISONS[m.group(0)]
            add("comparison", index, pou, f"'{m.group(0)}' -> '{new}'",
                _replace_at(code, m.start(), m.end(), new) + rest)
        if STATEMENT.match(code):
            add("drop_statement", index, pou, f"dropped: {code.strip()}", None)
    # Two neighbouring branches of one CASE exchange their labels, so each body runs for the other's value.
    labels = [(index, pou, CASE_LABEL.match(_code_part(line)[0])) for index, pou, line in bodies]
    labels = [(index, pou, m) for index, pou, m in labels if m]
    for (i1, pou1, m1), (i2, pou2, m2) in zip(labels, labels[1:]):
        if pou1 != pou2 or m1.group(1) != m2.group(1):
            continue
        first = lines[i1][:m1.start(2)] + m2.group(2) + lines[i1][m1.end(2):]
        second = lines[i2][:m2.start(2)] + m1.group(2) + lines[i2][m2.end(2):]
        add("swap_case", i1, pou1, f"CASE branches {m1.group(2)} and {m2.group(2)} swapped", first, {i2: second})
    return out


def choose(mutants: list[Mutant], count: int, seed: int) -> list[Mutant]:
    """A seeded sample spread evenly over the operators (all of an operator when it has fewer sites)."""
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


KILLED, SURVIVED, INVALID, ERROR = "killed", "survived", "invalid", "error"
OUTCOMES = (KILLED, SURVIVED, INVALID, ERROR)


@dataclasses.dataclass(frozen=True)
class Verdict:
    mutant: Mutant
    outcome: str                 # KILLED (a scenario diverged), SURVIVED, INVALID (ST rejected), ERROR (exceptions only)
    by: str                      # the diverging scenario, or the message of the rejection or first exception
    seconds: float

    @property
    def detected(self) -> bool:
        """Only a reported divergence kills a mutant."""
        return self.outcome == KILLED


def _message(exc: BaseException) -> str:
    """An exception as one short line: its type and the first line of its message."""
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0][:200]}" if text else type(exc).__name__


class Harness:
    """The sample compiled once; each mutant gets its own ST executor and runs the scenarios until one diverges."""

    def __init__(self, backend: str):
        semantics = make_semantics("itnc530", {})
        self.program = compile_project(ProjectOptions(main=SAMPLE / "Main_PGM.src"), semantics).program
        diags = Diagnostics()
        self.out = transpile_program(self.program, diags, read_mp_file(SAMPLE / "MP_data.mp", diags), {"st"})
        self.iomap = io_map_of(self.out.result)
        self.names = project_names(self.program)
        self.compiled = compile_program(self.program)      # the reference side, compiled once for every run
        self.word_values = boundary_values(self.program)
        written = [load_scenario(p, self.names) for p in sorted((SAMPLE / "scenarios").glob("*.yaml"))]
        random_run = random_scenario(self.program, self.names, RANDOM_CYCLES, seed=1,
                                     machine_parameters=SAMPLE / "MP_data.mp")
        inputs = random_run.random.inputs
        generated = [self._perturbed(s, inputs, seed) for seed, s in enumerate(written, 1) if s.cycles <= 1000]
        healthy = next(s for s in written if s.name == "random_keys_automatic_mode")
        generated += [self._power_on(healthy, value) for value in self.word_values]
        generated += self._value_variants(written)
        # NC jobs on a machine whose inputs also toggle at random, and on a healthy one (no toggles) where
        # sequences such as tool changes run to their end.
        generated += [self._nc_run(healthy, inputs, seed, PERTURBED_TOGGLE) for seed in (1, 2, 3)]
        generated += [self._nc_run(healthy, inputs, seed, 0.0) for seed in (4, 5, 6)]
        self.generated = {s.name for s in generated}        # may be cut short by keep_equivalent_scenarios
        candidates = written + [random_run] + generated
        self.backend = backend
        self.iec2c = find_iec2c() if backend == "matiec" else None
        self.scenarios = sorted(candidates, key=lambda s: s.cycles)

    def _dirty(self, rng: random.Random, uniform: int | None = None) -> dict[str, int]:
        """Start values for every marker and word the program writes, as after a restart with remanent memory:
        markers at random; words at random, near a constant of the program, or all `uniform`."""
        _, written, _ = program_operands(self.program)
        dirty = {}
        for ref in sorted(written, key=lambda r: (r.kind, r.addr)):
            if ref.kind == "M":
                dirty[self.names.display_name(ref)] = rng.randrange(2)
            elif ref.kind in "BWD":
                # Double words are mostly bit sets (packed markers): a boundary value leaves most bits alike.
                bits = {"B": 8, "W": 16, "D": 32}[ref.kind]
                value = (uniform if uniform is not None
                         else rng.choice(self.word_values) if rng.random() < (0.2 if bits == 32 else 0.5)
                         else rng.randrange(-(1 << (bits - 1)), 1 << (bits - 1)))
                dirty[self.names.display_name(ref)] = max(-(1 << (bits - 1)), min((1 << (bits - 1)) - 1, value))
        return dirty

    def _perturbed(self, scenario: Scenario, inputs: list[str], seed: int) -> Scenario:
        """A hand-written scenario from dirty memory with rare random toggles of every input: the states next to
        the intended path, and initialisations that would otherwise only ever write the value already there."""
        initial = {**self._dirty(random.Random(seed)), **scenario.initial}
        return bind(scenario.model_copy(update={
            "name": f"{scenario.name}_perturbed", "expect": [], "initial": initial,
            "random": RandomStimulus(seed=seed, inputs=inputs, toggle_probability=PERTURBED_TOGGLE)}), self.names)

    def _power_on(self, base: Scenario, value: int) -> Scenario:
        """The first cycles of a machine with healthy inputs, every written word at `value` (one run per boundary
        value) and the markers at random: the checks of the first cycle see each edge of the program's ranges."""
        initial = {**self._dirty(random.Random(value), uniform=value), **base.initial}
        return bind(base.model_copy(update={
            "name": f"power_on_{value}", "cycles": POWER_ON_CYCLES, "expect": [], "initial": initial,
            "events": [e for e in base.events if e.cycle < POWER_ON_CYCLES], "random": None}), self.names)

    def _value_variants(self, written: list[Scenario]) -> list[Scenario]:
        """Each hand-written scenario again with the value of one NC job changed to an edge of its range: the
        scenario's own input events then drive the sequence the other value starts (M19 instead of M3, pocket 24,
        mode 3, ...)."""
        edges = {
            "m_function": lambda v: [{"m_function": m} for m in M_CODES if m != v],
            "tool_call": lambda v: [{"tool_call": {**v, "pocket": p}} for p in POCKET_EDGES if p != v["pocket"]],
            "tool_def": lambda v: [{"tool_def": {**v, "pocket": p}} for p in POCKET_EDGES if p != v["pocket"]],
            "spindle_speed": lambda v: [{"spindle_speed": w} for w in self.word_values if w >= 0 and w != v],
            "gear": lambda v: [{"gear": g} for g in (0, 1, 2, 3) if g != v],
            "mode": lambda v: [{"mode": m} for m in range(7) if m != v],
        }
        variants = []
        for scenario in written:
            if scenario.cycles > 1000:
                continue
            for k, event in enumerate(scenario.events):
                if event.nc is None or event.nc.kind not in edges:
                    continue
                plain = event.nc.as_dict()
                for n, action in enumerate(edges[event.nc.kind](plain[event.nc.kind])):
                    events = list(scenario.events)
                    events[k] = Event(cycle=event.cycle, nc=NcAction(**action))
                    variants.append(bind(scenario.model_copy(update={
                        "name": f"{scenario.name}_event{k}_{n}", "events": events, "expect": []}), self.names))
        return variants

    def _nc_run(self, base: Scenario, inputs: list[str], seed: int, toggle: float) -> Scenario:
        """A machine switched on (the first cycles of `base`) fed random NC jobs, every input toggling with
        probability `toggle` per cycle."""
        rng = random.Random(seed)
        events = [e for e in base.events if e.cycle < 20]
        # Status words the NC owns and the program only reads (axes in position, ...) get random values too.
        used, written, _ = program_operands(self.program)
        profile = self.program.semantics.profile
        words = sorted(self.names.display_name(r) for r in set(used) - set(written)
                       if r.kind in "WD" and (r.kind, r.addr) not in NC_MODEL_WORDS
                       and profile.is_interface(r.kind, r.addr, 2 if r.kind == "W" else 4))

        def pocket() -> int:
            """Half of the pockets at the ends of the magazine's range (1 and 24) or just outside it (-1, 0, 25)."""
            return rng.choice(POCKET_EDGES) if rng.random() < 0.5 else rng.randrange(0, 25)

        cycle = 40
        while cycle < NC_RUN_CYCLES - 50:
            kind = rng.choice(("m_function", "m_function", "tool_call", "spindle_speed", "mode", "tool_def", "gear",
                               "restart"))
            value = {"m_function": lambda: rng.choice(M_CODES),
                     "tool_call": lambda: {"tool": rng.randrange(0, 30), "pocket": pocket()},
                     "tool_def": lambda: {"tool": rng.randrange(0, 30), "pocket": pocket()},
                     "spindle_speed": lambda: rng.choice((0, 59, 60, 61, 1500, 4000, 12000)),
                     "mode": lambda: rng.randrange(0, 7),
                     "gear": lambda: rng.randrange(1, 3),
                     "restart": lambda: rng.choice(("program", "machine_parameters"))}[kind]()
            events.append(Event(cycle=cycle, nc=NcAction(**{kind: value})))
            if words:
                operand = rng.choice(words)
                events.append(Event(cycle=cycle + 1, set={operand: rng.choice(self.word_values)}))
            cycle += rng.randrange(30, 200)
        return bind(base.model_copy(update={
            "name": f"nc_jobs_{seed}", "cycles": NC_RUN_CYCLES, "events": events, "expect": [],
            "random": RandomStimulus(seed=seed, inputs=inputs, toggle_probability=toggle)}), self.names)

    def keep_equivalent_scenarios(self) -> list[str]:
        """Generated scenarios end where the unmutated run stops being defined (a random NC job the machine cannot
        finish times out on both sides); a hand-written scenario that fails is returned for the caller to report."""
        factory = self.side_factory(self.out.st_text)
        kept, failing = [], []
        for scenario in self.scenarios:
            result = cosimulate(self.program, factory, self.iomap, scenario, self.names, compiled=self.compiled)
            generated = scenario.name in self.generated
            if result.equivalent:
                kept.append(scenario)
            elif generated and result.divergence is None and result.cycles_run > 0:
                events = [e for e in scenario.events if e.cycle < result.cycles_run]
                kept.append(bind(scenario.model_copy(update={"cycles": result.cycles_run, "events": events}),
                                 self.names))
            elif not generated:
                failing.append(f"{scenario.name}: {result.divergence or result.error}")
        self.scenarios = sorted(kept, key=lambda s: s.cycles)
        return failing

    def side_factory(self, st_text: str) -> Callable:
        if self.backend == "matiec":
            from transpiler.exec.compiled.matiec_side import matiec_side_factory
            return matiec_side_factory(st_text, self.out.result.project, self.iec2c)
        return builtin_side_factory(st_text)

    def judge(self, mutant: Mutant) -> Verdict:
        """KILLED by the first scenario that diverges; a scenario that ends in an exception (a fault of the
        translated side, or one raised by the co-simulation) shows nothing, so the next one runs; ERROR when
        exceptions were all there was, INVALID when the mutated ST is not a program the executor accepts."""
        start = time.perf_counter()
        try:
            factory = self.side_factory(mutant.text)
        except CompileFailed as exc:
            return Verdict(mutant, INVALID, f"rejected by the ST executor's compiler: {_message(exc)}",
                           time.perf_counter() - start)
        except Exception as exc:  # noqa: BLE001 - a mutant that cannot be built is invalid, with its message
            return Verdict(mutant, INVALID, f"rejected: {_message(exc)}", time.perf_counter() - start)
        first_error = None
        for scenario in self.scenarios:
            try:
                result = cosimulate(self.program, factory, self.iomap, scenario, self.names, compiled=self.compiled)
            except Exception as exc:  # noqa: BLE001 - a crash is an error of this mutant, never a kill
                first_error = first_error or f"{scenario.name}: {_message(exc)}"
                continue
            if result.divergence is not None:
                how = f"{result.divergence.name} at cycle {result.divergence.cycle}"
                return Verdict(mutant, KILLED, f"{scenario.name}: {how}", time.perf_counter() - start)
            if result.error is not None:
                first_error = first_error or f"{scenario.name}: {result.error}"
        if first_error is not None:
            return Verdict(mutant, ERROR, first_error, time.perf_counter() - start)
        return Verdict(mutant, SURVIVED, "", time.perf_counter() - start)


def _worker(harness: Harness, mutants: list[Mutant], tasks, results) -> None:
    """A forked process: judges mutants by index until it takes the end marker."""
    while (index := tasks.get()) is not None:
        verdict = harness.judge(mutants[index])
        results.put((index, verdict.outcome, verdict.by, verdict.seconds))


def judge_all(harness: Harness, mutants: list[Mutant], jobs: int) -> Iterator[Verdict]:
    """Verdicts as they come in; with jobs > 1 the harness is shared with forked workers (nothing is pickled but results)."""
    if jobs <= 1:
        for mutant in mutants:
            yield harness.judge(mutant)
        return
    context = multiprocessing.get_context("fork")
    tasks, results = context.Queue(), context.Queue()
    for index in range(len(mutants)):
        tasks.put(index)
    for _ in range(jobs):
        tasks.put(None)
    workers = [context.Process(target=_worker, args=(harness, mutants, tasks, results), daemon=True)
               for _ in range(jobs)]
    for w in workers:
        w.start()
    for _ in mutants:
        index, outcome, by, seconds = results.get()
        yield Verdict(mutants[index], outcome, by, seconds)
    for w in workers:
        w.join()


def pick_backend(choice: str) -> str:
    if choice == "builtin":
        return "builtin"
    if find_iec2c() is not None:
        return "matiec"
    if choice == "matiec":
        raise SystemExit("mutants: --backend matiec needs iec2c ($MATIEC_HOME/iec2c or PATH)")
    return "builtin"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=100, help="mutants to run, spread over the operators")
    parser.add_argument("--all", action="store_true", help="run every mutation site (slow)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--backend", choices=("auto", "builtin", "matiec"), default="auto")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args(argv)
    backend = pick_backend(args.backend)
    if backend == "matiec":
        # Mutant libraries are throw-away: keep them out of the user's build cache.
        os.environ["HH2IEC_CACHE"] = tempfile.mkdtemp(prefix="hh2iec-mutants-")
    harness = Harness(backend)
    failing = harness.keep_equivalent_scenarios()
    if failing:
        print("mutants: the unmutated translation is not equivalent, mutation results would mean nothing:\n  "
              + "\n  ".join(failing), file=sys.stderr)
        return 2
    sites = mutation_sites(harness.out.st_text)
    chosen = sites if args.all else choose(sites, args.count, args.seed)
    counts = {op: sum(1 for m in sites if m.operator == op) for op in OPERATORS}
    print(f"mutants: {len(sites)} mutation sites in the translated sample "
          f"({', '.join(f'{op} {n}' for op, n in counts.items())}); running {len(chosen)} on the {backend} backend, "
          f"{len(harness.scenarios)} scenarios each until one diverges")
    start = time.perf_counter()
    verdicts: list[Verdict] = []
    for verdict in judge_all(harness, chosen, args.jobs):
        verdicts.append(verdict)
        _progress(len(verdicts), len(chosen), start)
    if sys.stderr.isatty():
        print(file=sys.stderr)
    return report(verdicts, time.perf_counter() - start)


def _progress(done: int, total: int, start: float) -> None:
    if sys.stderr.isatty():
        print(f"\rmutants: {done}/{total} judged ({time.perf_counter() - start:.0f} s)", end="", file=sys.stderr)


def report(verdicts: list[Verdict], seconds: float) -> int:
    """The table per operator and outcome, the kill rate over the valid mutants, then every mutant that was not
    killed by category: survivors, errors and invalid mutants (with their messages)."""
    verdicts = sorted(verdicts, key=lambda v: (v.mutant.line, v.mutant.operator, v.mutant.description))
    count = {o: sum(1 for v in verdicts if v.outcome == o) for o in OUTCOMES}
    print(f"{'operator':<16}{'mutants':>8}" + "".join(f"{o:>10}" for o in OUTCOMES))
    for op in OPERATORS:
        mine = [v for v in verdicts if v.mutant.operator == op]
        print(f"{op:<16}{len(mine):>8}" + "".join(f"{sum(1 for v in mine if v.outcome == o):>10}" for o in OUTCOMES))
    # Invalid mutants are no programs and say nothing about the scenarios; errors ran but showed no divergence.
    valid = count[KILLED] + count[SURVIVED] + count[ERROR]
    share = count[KILLED] / valid if valid else 0.0
    verdict = "met" if share >= TARGET else "MISSED"
    print(f"killed {count[KILLED]} of {valid} valid mutants = {100 * share:.1f} % in {seconds:.0f} s "
          f"(target >= {100 * TARGET:.0f} %: {verdict}); errors {count[ERROR]} (not killed), "
          f"invalid {count[INVALID]} (excluded)")
    for outcome, title in ((SURVIVED, "survivors"), (ERROR, "errors: only exceptions, no divergence"),
                           (INVALID, "invalid mutants: the mutated ST was rejected")):
        mine = [v for v in verdicts if v.outcome == outcome]
        if mine:
            print(f"{title} (project.st line, POU, mutation{'' if outcome == SURVIVED else ': message'}):")
            for v in mine:
                why = f": {v.by}" if v.by else ""
                print(f"  line {v.mutant.line} in {v.mutant.pou}: {v.mutant.operator}: {v.mutant.description}{why}")
    return 0 if share >= TARGET else 1


if __name__ == "__main__":
    sys.exit(main())
