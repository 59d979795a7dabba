"""Coverage-guided stimulus: scenarios generated within a cycle budget that take the program's conditional
branches both ways and enter its CASE entries, deterministic for a seed.

As a fuzzer does, the search keeps a corpus (the user's scenarios, then every generated one that raised
coverage) and mutates its members: an NC job moved to a corner value (verify/corners.py), an NC job inserted at a
random cycle, a foreign word or marker set to a corner value, an input set, remanent memory started at a corner (one
word, or all of it at byte patterns and corners), rare random toggles added, a word the program compares with a
constant put next to that constant, a word's start value moved arithmetically (doubled, halved, plus or minus one).
Before random mutations, a run that brings a word compare near its constant is tried again with a power-on word that
reaches the compare started at the value each boundary value not shown yet needs (Directed).
Each candidate runs on the reference interpreter alone (no ST side, with coverage); one that reaches a branch
outcome or CASE entry not seen before, a marker or output the program writes in a state (0 or 1) not seen before, a
word compare whose operands come out equal or one apart in a way not seen before (its boundary values: a mutated
compare or constant differs from the original only there), a condition of a logic chain shown to decide it on its
own for the first time (an MC/DC pair: an AND that became an OR differs only on such
inputs), or a bit gate or divisor value or constant table entry not seen before (the value profile), is kept, cut
just after the last cycle that brought something new, so that the co-simulation budget is spent on cycles that
matter. What is left of the budget at the end runs as corner-random stimulus: inputs toggling, NC jobs with corner
values at random cycles, from clean memory and from dirty memory (every word at a byte pattern or corner value, so
that a store one byte off shows) in turn.

Where the original faults in its first cycle from clean memory (a table index or divisor read from memory nobody
wrote), a run starts from power-on memory drawn until one gets through that cycle.

A candidate in which the original program faults (an NC handshake that cannot finish, a runtime fault) is cut
before the faulting cycle: the generated stimulus only asks what the original answers."""

from __future__ import annotations

import dataclasses
import random
from pathlib import Path
from typing import Any, Mapping

from transpiler.diagnostics import CompileFailed, Diagnostics
from transpiler.exec.compiled.shim import NcActionError
from transpiler.exec.interp import CompiledProgram, compile_program
from transpiler.exec.interp.decisions import Decision, decision_table
from transpiler.ir import Program
from transpiler.verify.corners import Corners, harvest
from transpiler.verify.mcdc import shown_masking, shown_unique
from transpiler.verify.scenario import Event, NcAction, NameTable, OperandRef, RandomStimulus, Scenario, bind
from transpiler.verify.simulate import apply_machine_data, build_machine, program_operands
from transpiler.verify.stimulus import build_stimulus

MARGIN = 5                  # cycles kept after the last one that brought new coverage (effects settle)
SEARCH_FACTOR = 40          # interpreter cycles the search may spend per cycle of the budget
SEARCH_MIN = 20_000
SEARCH_MAX = 120_000
STALE_LIMIT = 400           # candidates in a row without anything new: the search stops
FILLER_ATTEMPTS = 8
FILLER_KINDS = 4            # healthy or not, clean or dirty memory at power-on
POWER_ON_TRIES = 64         # power-on memories drawn where the original faults at once from clean memory
FILLER_MIN = 150            # shortest filler run when the rest of the budget is split
CHILD_CYCLES = 1000         # longest candidate run
VALUE_SHARE = 0.25          # share of the budget for runs kept for value-profile features alone
# Features a run may bring that rank below branches, CASE entries and marker states: the value profile, compare
# boundaries and MC/DC pairs; runs kept for these alone share VALUE_SHARE of the budget.
_VALUE_FEATURES = frozenset({"value", "bound", "mcdc"})


@dataclasses.dataclass(frozen=True)
class Probe:
    """One candidate run on the reference interpreter."""

    cycles_ok: int                 # cycles that ran without a fault of the original
    vectors: tuple = ()            # (cycle, decision, vector) of the condition vectors the run recorded first
    # the features not seen before this run, each with the cycle it first appeared in: (op id, outcome),
    # ("bit", ...), ("value", ...), ("bound", op id, difference), ("mcdc", decision, condition)
    firsts: Mapping = dataclasses.field(default_factory=dict)
    # op id of each word compare the run drove to a boundary value (seen before or not) -> the first such cycle
    compares_at: Mapping = dataclasses.field(default_factory=dict)

    @property
    def new(self) -> frozenset:
        return frozenset(self.firsts)

    @property
    def last_new(self) -> int:
        """The cycle in which the last new feature first appeared (-1: none)."""
        return max(self.firsts.values(), default=-1)

    @property
    def last_before_mcdc(self) -> int:
        """The cycle of the last new feature other than an MC/DC pair (-1: none). MC/DC pairs keep turning up
        late in a run (there are many more of them than branches): a run kept for other features is cut after
        those, and the pairs it found later stay to be found again, rather than lengthening every kept run."""
        return max((cycle for feature, cycle in self.firsts.items() if feature[0] != "mcdc"), default=-1)


@dataclasses.dataclass
class Search:
    """The state of one search: the program compiled with coverage once, the features seen so far."""

    program: Program
    names: NameTable
    corners: Corners
    compiled: CompiledProgram
    base_mp: Mapping | None
    seen: set = dataclasses.field(default_factory=set)
    interpreter_cycles: int = 0
    # Bit operands the program writes, whose 0 and 1 count as features too (toggle coverage): straight-line logic
    # (a clamp that closes only after a delay, an output that needs several inputs at once) has no branch, and
    # without this the search would never ask for the states that make it act.
    toggled: tuple[OperandRef, ...] = ()
    # MC/DC: the decisions (decisions.decision_table order) and the condition vectors of the kept runs per decision
    decisions: tuple[Decision, ...] = ()
    vectors: dict = dataclasses.field(default_factory=dict)

    def shown(self, number: int, extra: set[int]) -> set[tuple[str, int, int]]:
        """The MC/DC features of decision `number` given the kept runs' vectors and `extra` ones."""
        decision = self.decisions[number]
        recorded = self.vectors.get(number, set()) | extra
        n = len(decision.conditions)
        function = decision.function()
        return {("mcdc", number, c) for c, coupled in enumerate(decision.coupled)
                if ("mcdc", number, c) not in self.seen
                and (shown_masking(recorded, n, c, function) if coupled else shown_unique(recorded, n, c))}

    def probe(self, scenario: Scenario) -> Probe | None:
        """Run `scenario` on the reference interpreter; None when the scenario is unusable (bad NC job)."""
        try:
            stimulus = build_stimulus(scenario, self.names)
            machine = build_machine(self.program, scenario, Diagnostics(), coverage=True, compiled=self.compiled,
                                    base_mp=self.base_mp)
        except (CompileFailed, ValueError):
            return None
        local: set = set()
        count, value_count, bound_count, vector_count, ok = 0, 0, 0, 0, 0
        vectors: list[tuple[int, int, int]] = []
        run_vectors: dict[int, set[int]] = {}
        firsts: dict = {}
        compares_at: dict = {}
        read_toggled = machine.reader([(ref.kind, ref.addr) for ref in self.toggled])
        # The values not seen yet (in this run or kept runs), per watched bit: these lists shrink fast, so the
        # per-cycle check costs little once the common states were seen.
        unseen = [(i, v) for i, ref in enumerate(self.toggled) for v in (0, 1) if ("bit", str(ref), v) not in self.seen]
        for cycle in range(stimulus.cycles):
            for data in stimulus.machine_updates(cycle):
                apply_machine_data(machine.sys, data)
            try:
                report = machine.run_cycle(cycle, stimulus.writes(cycle), stimulus.nc_actions(cycle))
            except NcActionError:
                return None
            self.interpreter_cycles += 1
            if report.faults:
                break
            ok = cycle + 1
            # The counts only grow; the outcomes are fetched only in the rare cycles in which one did.
            fresh: set = set()
            if machine.branch_outcome_count != count:
                count = machine.branch_outcome_count
                fresh = machine.branch_outcomes() - local
            if machine.value_outcome_count != value_count:
                value_count = machine.value_outcome_count
                fresh |= {("value", *pair) for pair in machine.value_outcomes()} - local
            if machine.boundary_outcome_count != bound_count:
                bound_count = machine.boundary_outcome_count
                fresh |= {("bound", *pair) for pair in machine.boundary_outcomes()} - local
            if machine.vector_count != vector_count:
                # new condition vectors: the conditions they show together with the kept runs' vectors
                arrived = machine.decision_vectors_since(vector_count)
                vector_count = machine.vector_count
                changed = set()
                for number, vector in arrived:
                    if vector not in self.vectors.get(number, ()):
                        run_vectors.setdefault(number, set()).add(vector)
                        vectors.append((cycle, number, vector))
                        changed.add(number)
                for number in changed:
                    fresh |= self.shown(number, run_vectors[number]) - local
            if fresh:
                local |= fresh
                for feature in fresh:
                    if feature[0] == "bound":
                        compares_at.setdefault(feature[1], cycle)
                fresh -= self.seen
                if fresh:
                    firsts.update(dict.fromkeys(fresh, cycle))
            if unseen:
                values = read_toggled()
                reached = [(i, v) for i, v in unseen if values[i] == v]
                if reached:
                    firsts.update(dict.fromkeys((("bit", str(self.toggled[i]), v) for i, v in reached), cycle))
                    unseen = [pair for pair in unseen if pair not in reached]
        return Probe(ok, tuple(vectors), firsts, compares_at)

    def keep(self, probe: Probe, cycles: int | None = None) -> None:
        """Take the run's features and condition vectors of its first `cycles` cycles (all: None) as seen."""
        self.seen |= probe.new if cycles is None else {f for f, cycle in probe.firsts.items() if cycle < cycles}
        for cycle, number, vector in probe.vectors:
            if cycles is None or cycle < cycles:
                self.vectors.setdefault(number, set()).add(vector)


class Directed:
    """The search's directed candidates: for each run that drives a compare of a word with a constant near its
    constant (any of its boundary values), each boundary value of that compare not shown yet is tried from each
    power-on source of the word (Corners.boundary_sources): that run, up to the cycle it reached the compare, with
    the source started at the value that gives the missing difference (worked out from the run's own start values
    of the other words on the way). A missing value that only a power-on value gives (a speed of -1 the program
    takes over unchanged, a pocket count that comes out -1 from a remanent position beyond the magazine) is then
    tried at once, where random mutations would pick that word, that value and a run reaching the compare together
    only by chance. At most RUNS_PER_COMPARE runs per compare; the candidates go through the search's budget rule
    like any other."""

    RUNS_PER_COMPARE = 24

    def __init__(self, sources, names: NameTable):
        self.names = names
        self.by_op: dict[int, list] = {}
        for source in sources:
            self.by_op.setdefault(source.op, []).append(source)
        self.runs: dict[int, int] = {}          # compare op id -> runs queued for it
        self.queue: list[tuple[Scenario, int, object, int]] = []   # (run, cycles, source, difference)

    def reached(self, probe: Probe, run: Scenario) -> None:
        """Queue the candidates of the compares `run` (kept as it is) drives near their constant."""
        for op, cycle in sorted(probe.compares_at.items(), key=lambda item: item[1]):
            if op not in self.by_op or cycle >= run.cycles or self.runs.get(op, 0) >= self.RUNS_PER_COMPARE:
                continue
            self.runs[op] = self.runs.get(op, 0) + 1
            self.queue += [(run, min(run.cycles, cycle + 1 + MARGIN), source, difference)
                           for source in self.by_op[op] for difference in (-1, 0, 1)]

    def next(self, search: Search, serial: int) -> Scenario | None:
        """The next queued candidate whose boundary value no kept run has shown yet (None: none left)."""
        while self.queue:
            run, cycles, source, difference = self.queue.pop(0)
            if ("bound", source.op, difference) in search.seen:
                continue
            value = source.value(difference, run.initial)
            if value is None or run.initial.get(source.name) == value:
                continue
            child = run.model_copy(update={"name": f"{_stem(run.name)}_g{serial}", "expect": [],
                                           "initial": {**run.initial, source.name: value}})
            return _cut(child, cycles, self.names)
        return None


def _events_with(scenario: Scenario, extra: list[Event]) -> list[Event]:
    # sorted() is stable: at equal cycles the scenario's own events stay first
    return sorted([*scenario.events, *extra], key=lambda e: e.cycle)


def mutate(parent: Scenario, rng: random.Random, corners: Corners, names: NameTable, serial: int) -> Scenario:
    """A child of `parent` with one to three mutations (see the module docstring)."""
    events = list(parent.events)
    initial = dict(parent.initial)
    stimulus = parent.random
    cycles = min(parent.cycles, CHILD_CYCLES)      # a long seed (a 15 000-cycle soak) would eat the search budget
    for _ in range(rng.randint(1, 3)):
        choice = rng.random()
        at = rng.randrange(cycles)
        numeric = [n for n, v in initial.items() if isinstance(v, int) and names.resolve(n).kind in "BWD"]
        if numeric and rng.random() < 0.1:
            # a word's start value moved arithmetically, as fuzzers do: a loop that halves or counts reaches a
            # compare's constant only from a multiple or a neighbour of it
            word = rng.choice(numeric)
            v = initial[word]
            initial[word] = corners.clamp(rng.choice((2 * v, 2 * v + 1, v // 2, v + 1, v - 1, -v)),
                                          names.resolve(word).kind)
            continue
        if corners.compare_pairs and rng.random() < 0.15:
            # a word the program compares with a constant, put next to it: at power-on or, where the machine supplies
            # it (an interface word), at a random cycle; memory the program keeps changes after power-on only by the
            # program's own stores, so a later write of it would be a state no machine reaches
            name, kind, constant = rng.choice(corners.compare_pairs)
            value = corners.clamp(constant + rng.choice((-1, 0, 1)), kind)
            if rng.random() < 0.5 or all(name != word for word, _ in corners.foreign_words):
                initial[name] = value
            else:
                events.append(Event(cycle=at, set={name: value}))
            continue
        nc_events = [i for i, e in enumerate(events) if e.nc is not None]
        if choice < 0.3 and nc_events:
            # the same kind of job with a corner value: the scenario's own inputs then drive what that value starts
            i = rng.choice(nc_events)
            events[i] = Event(cycle=events[i].cycle, nc=NcAction(**corners.nc_action(rng, events[i].nc.kind)))
        elif choice < 0.5:
            # half of the inserted jobs are M functions when the program decodes a table of them: each decoded
            # number is a CASE entry of its own, a dozen targets a uniform pick of the job kind rarely reaches
            kind = "m_function" if corners.tables and rng.random() < 0.5 else None
            events.append(Event(cycle=at, nc=NcAction(**corners.nc_action(rng, kind))))
        elif choice < 0.62 and (corners.foreign_words or corners.foreign_markers):
            if corners.foreign_words and (not corners.foreign_markers or rng.random() < 0.6):
                name, kind = rng.choice(corners.foreign_words)
                events.append(Event(cycle=at, set={name: corners.word_value(rng, kind)}))
            else:
                events.append(Event(cycle=at, set={rng.choice(corners.foreign_markers): rng.randrange(2)}))
        elif choice < 0.75 and corners.inputs:
            events.append(Event(cycle=at, set={rng.choice(corners.inputs): rng.randrange(2)}))
        elif choice < 0.85 and (corners.remanent_words or corners.remanent_markers or corners.inputs):
            # the state at power-on: remanent memory at a corner, or an input already made in the first cycle
            draw = rng.random()
            if corners.inputs and draw < 0.3:
                initial[rng.choice(corners.inputs)] = rng.randrange(2)
            elif draw >= 0.9:
                # all of it at once, as an earlier run may have left it (words at byte patterns or corners)
                initial.update(corners.power_on(rng))
            elif corners.remanent_words and draw < 0.7:
                name, kind = rng.choice(corners.remanent_words)
                initial[name] = corners.word_value(rng, kind)
            elif corners.remanent_markers:
                initial[rng.choice(corners.remanent_markers)] = rng.randrange(2)
        elif choice < 0.93 and corners.inputs:
            stimulus = RandomStimulus(seed=rng.randrange(1 << 30), inputs=list(corners.inputs),
                                      toggle_probability=rng.choice((0.005, 0.01, 0.02, 0.05)))
        elif events:
            events.pop(rng.randrange(len(events)))
    events.sort(key=lambda e: e.cycle)
    events = [e for e in events if e.cycle < cycles]
    return bind(parent.model_copy(update={"name": f"{_stem(parent.name)}_g{serial}", "events": events, "cycles": cycles,
                                          "initial": initial, "random": stimulus, "expect": []}), names)


def _stem(name: str) -> str:
    return name.split("_g", 1)[0] if "_g" in name and name.rsplit("_g", 1)[-1].isdigit() else name


def corner_random(program: Program, corners: Corners, names: NameTable, cycles: int, rng: random.Random, name: str,
                  machine_parameters: Path | None, healthy: bool, dirty: Mapping[str, int] | None = None) -> Scenario:
    """`cycles` cycles of corner-random stimulus: every input toggling (from all 1, a healthy machine with its
    normally-closed contacts made, or all 0), NC jobs with corner values every 20-200 cycles, and a foreign word or
    marker set to a corner value with each job. `dirty`: the memory the program writes starts as remanent memory
    left by an earlier run would (the markers at these values, some words at corners), so that a store that only
    ever writes the power-on value still shows whether it happens: the markers at these values, every word at a
    byte pattern or a corner value (Corners.power_on)."""
    events: list[Event] = []
    cycle = rng.randrange(2, 20)
    while cycle < cycles:
        events.append(Event(cycle=cycle, nc=NcAction(**corners.nc_action(rng))))
        if corners.foreign_words and rng.random() < 0.5:
            operand, kind = rng.choice(corners.foreign_words)
            events.append(Event(cycle=cycle, set={operand: corners.word_value(rng, kind)}))
        elif corners.foreign_markers and rng.random() < 0.3:
            events.append(Event(cycle=cycle, set={rng.choice(corners.foreign_markers): rng.randrange(2)}))
        cycle += rng.randrange(20, 200)
    initial: dict[str, Any] = {n: 1 for n in corners.inputs} if healthy else {}
    if dirty is not None:
        initial.update(corners.power_on(rng))
        initial.update(dirty)
    inputs = list(corners.inputs)
    scenario = Scenario(name=name, cycles=cycles, profile=program.semantics.profile.name,
                        machine_parameters=machine_parameters, initial=initial, events=events,
                        random=RandomStimulus(seed=rng.randrange(1 << 30), inputs=inputs,
                                              toggle_probability=0.01 if healthy else 0.05) if inputs else None)
    return bind(scenario, names)


def _fill(search: Search, runner, budget: int, kept: list[Scenario], corpus: list[Scenario], seed: int,
          rng: random.Random) -> list[Scenario]:
    """Corner-random runs (`runner`) for what is left of the budget: healthy and not, from clean and from dirty
    memory. The four kinds share `budget` (a share too short to matter goes to the one running now); clean and dirty
    alternate, so that a short rest still has runs from both. `kept` and `corpus`: the search's runs, whose power-on
    memory a filler that faults at once may start from."""
    corners = search.corners
    filled: list[Scenario] = []
    spent = 0
    attempt = 0
    # the two dirty kinds start each written marker at opposite values: one of them starts it at 1
    dirty = {marker: rng.randrange(2) for marker in corners.remanent_markers}
    while spent < budget and attempt < FILLER_ATTEMPTS:
        share = (budget - spent) // max(1, FILLER_KINDS - attempt)
        cycles = budget - spent if share < FILLER_MIN or attempt >= FILLER_KINDS - 1 else share
        make = runner(cycles, f"random_seed{seed}" + (f"_{attempt}" if attempt else ""), attempt % 4 < 2)
        memory = None if attempt % 2 == 0 else dirty if attempt % 4 == 1 else \
            {marker: 1 - value for marker, value in dirty.items()}
        filler = _starting(search, make(memory), make, [*kept, *filled, *corpus], corners, rng)
        attempt += 1
        probe = search.probe(filler)
        if probe is None or probe.cycles_ok == 0:
            continue
        search.keep(probe, probe.cycles_ok)
        filled.append(filler if probe.cycles_ok == filler.cycles else _cut(filler, probe.cycles_ok, search.names))
        spent += probe.cycles_ok
    return filled


def _starting(search: Search, scenario: Scenario, make, runs: list[Scenario], corners: Corners,
              rng: random.Random) -> Scenario:
    """`scenario`, or where the original faults in its first cycle with it (a table index or a divisor read from
    memory at power-on), `make(memory)` with memory drawn afresh (Corners.power_on), else with the power-on memory
    of one of `runs`, the first that gets through its first cycle (`scenario` when none does)."""
    if _gets_going(search, scenario):
        return scenario
    # fresh draws first (each run then starts from other memory), the memories of runs that got going after them
    for attempt in range(POWER_ON_TRIES + len(runs)):
        if attempt < POWER_ON_TRIES:
            memory = corners.power_on(rng)
        else:
            run = runs[attempt - POWER_ON_TRIES]
            memory = {name: value for name, value in run.initial.items() if name not in corners.inputs}
        candidate = make(memory)
        if _gets_going(search, candidate):
            return candidate
    return scenario


def _gets_going(search: Search, scenario: Scenario) -> bool:
    # one cycle is enough to tell (and costs one interpreter cycle)
    probe = search.probe(_cut(scenario, 1, search.names))
    return probe is not None and probe.cycles_ok > 0


def _cut(scenario: Scenario, cycles: int, names: NameTable) -> Scenario:
    return bind(scenario.model_copy(update={"cycles": cycles,
                                            "events": [e for e in scenario.events if e.cycle < cycles]}), names)


def generate(program: Program, names: NameTable, budget: int, seed: int, seeds: list[Scenario] = (), *,
             machine_parameters: Path | None = None, base_mp: Mapping | None = None,
             search_cycles: int | None = None) -> list[Scenario]:
    """Scenarios of at most `budget` cycles in all (the whole budget unless the original faults early in every
    attempt), chosen by coverage of the reference interpreter, starting from `seeds` (the user's scenarios);
    the same list for the same seed."""
    if budget <= 0:
        return []
    rng = random.Random(seed)
    corners = harvest(program, names)
    toggled = tuple(sorted((ref for ref in program_operands(program)[1] if ref.kind in "MO"),
                           key=lambda ref: (ref.kind, ref.addr)))
    search = Search(program, names, corners, compile_program(program, coverage=True, exact=False, value_profile=True),
                    base_mp, toggled=toggled, decisions=decision_table(program).decisions)
    limit = search_cycles if search_cycles is not None else min(SEARCH_MAX, max(SEARCH_MIN, SEARCH_FACTOR * budget))
    corpus: list[Scenario] = []
    directed = Directed(corners.boundary_sources, names)
    for scenario in seeds:
        probe = search.probe(scenario)
        if probe is not None:
            search.keep(probe)
            corpus.append(bind(scenario.model_copy(update={"expect": []}), names))
            directed.reached(probe, corpus[-1])
    kept: list[Scenario] = []
    spent = 0

    def runner(cycles: int, name: str, healthy: bool):
        """A corner-random run of `cycles` cycles from the power-on memory given to it."""
        return lambda memory: corner_random(program, corners, names, cycles, rng, name, machine_parameters, healthy,
                                            memory)
    # Without scenarios of the user, the corpus starts from corner-random runs (kept only where they add).
    if not corpus:
        for n, healthy in enumerate((True, False)):
            make = runner(min(budget, 400), f"corner_seed{seed}_{n}", healthy)
            corpus.append(_starting(search, make(None), make, [], corners, rng))
    search.interpreter_cycles = 0       # the seeds' own runs are not part of the search budget
    serial = 0
    stale = 0
    spent_on_values = 0
    while spent < budget and search.interpreter_cycles < limit and stale < STALE_LIMIT:
        serial += 1
        child = directed.next(search, serial)
        tried = child is not None       # a directed candidate that fails does not count as stale
        if child is None:
            # Short parents give short children, which leave more of the budget to the next find.
            parent = rng.choices(corpus, weights=[1.0 / max(50, min(s.cycles, CHILD_CYCLES)) for s in corpus])[0]
            child = mutate(parent, rng, corners, names, serial)
        probe = search.probe(child)
        if probe is None or not probe.new or probe.last_new >= budget - spent:
            stale += not tried
            continue
        last = probe.last_before_mcdc
        length = min(probe.cycles_ok, (probe.last_new if last < 0 else last) + 1 + MARGIN, budget - spent)
        value_only = all(feature[0] in _VALUE_FEATURES for feature in probe.new)
        if value_only and spent_on_values + length > VALUE_SHARE * budget:
            # the value profile has many more features than branches: it may not crowd them out of the budget
            stale += 1
            continue
        stale = 0
        child = _cut(child, length, names)
        search.keep(probe, length)
        directed.reached(probe, child)
        kept.append(child)
        corpus.append(child)
        spent += length
        spent_on_values += length if value_only else 0
    kept += _fill(search, runner, budget - spent, kept, corpus, seed, rng)
    return kept
