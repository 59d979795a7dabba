"""MC/DC of every decision and boundary values of every word compare, from the condition vectors and compare
differences the reference interpreter recorded (machine.Coverage), with the items no run can reach explained.

MC/DC: a condition is shown when two recorded evaluations of its decision have different outcomes and differ in
it alone (unique-cause MC/DC). A condition whose operand appears more than once in its chain (coupled: it cannot
change alone) is shown by masking MC/DC instead: two evaluations with different outcomes in which it differs, the
outcome depends on it in both (flipping it alone would change the outcome), and every other condition that differs
is masked in both (flipping it alone would not). Condition values are the values read, before the instruction's
negation (`AN M5` has the condition M5).

Boundaries: for a compare of a word with a constant c, whether the word took c-1, c and c+1 (a value the word
cannot hold, such as 128 for a byte, is infeasible, and so is one it cannot hold at that compare under the program's
own logic, word_values.py, or a value of X outside what index_range.py finds there); for a compare of two words,
whether their difference took -1, 0 and +1.

Infeasible, and so neither counted as missing nor dropped: a condition whose operand can hold only one value under
the program's own logic (nothing writes it but constant values, and it is no input, timer, counter, NC-interface
operand or operand a scenario sets; power-on memory is 0; a write through the index register counts for every operand
the values the register can hold there reach), a condition the outcome cannot depend on given those
constants and the coupling of its chain (masked by a constant, or redundant), a condition the code before its
chain in the same cycle ties to the others so that it never decides alone (implication.py: a reset on every path,
a marker assigned from the chain's other operands, a timer or counter start no write can have set yet in the
cycle, a compare or bit test of WA, or an error marker of x, / and MOD, that constant word operations fix, a fact of the NC model's writes where nothing else writes its operands, see nc_facts.py; subprograms called
in that code followed into), a condition a relation between two of its chain's operands rules out that holds at
every point of every cycle (implication.Invariant: 0 at power-on, only the program writes them, each write keeps
it), a condition no path of the cycle that comes to its chain lets decide alone (cycle_paths.py: the code run from
where every run of the chain begins, through its calls and CASE entries, words and markers as each path leaves them;
from the main program's start also under what holds at the start of every cycle but the first, with the first cycle
run from any memory and the first-cycle marker 1),
a string compare the straight-line code before it fixes (string_values.py), the running bit of a timer whose
preset is 0 in every run (Coverage.idle_timers) that nothing else writes, and a boundary value the word cannot hold
(word_values.py; for X, index_range's interval and congruence; for a compare of two words, the differences
word_relations.py allows, and for a word compared with a constant, the bounds its differences with X, 0 and other
words give it there). Only these reasons are claimed; a condition that is merely hard
to reach stays missing."""

from __future__ import annotations

import dataclasses
import itertools
from typing import Any, Callable, Iterable, Mapping, Sequence

from transpiler.exec.interp.decisions import Compare, Decision, DecisionTable, decision_table
from transpiler.frontend.opcodes import implicit_writes
from transpiler.ir import BIT_KINDS, BYTES, Program, sext
from transpiler.language.presets import TIMER_MP
from transpiler.verify.scenario import is_glob
from transpiler.verify.nc_facts import NC_MODEL_OWNED, NcFact, applicable_facts
from transpiler.verify.implication import CycleOrder, Invariant, Tied, consumed_start_zero, cycle_order, \
    inductive_invariants, program_entries, tied_vectors, write_sites
from transpiler.verify.cycle_paths import (Runner, Seen, StartRelation, condition_vectors, followable,
                                          kept_between_cycles, seen_vectors, start_name, start_relations)
from transpiler.verify.cycle_states import (KeyChooser, StartStates, StepBudget, arrivals, chain_bits, merged_keys,
                                           start_states)
from transpiler.verify.index_range import XValues, index_ranges, index_values
from transpiler.verify.string_values import StringCompares
from transpiler.verify.word_relations import word_bounds, word_relations
from transpiler.verify.word_values import OVERRIDDEN_MODULE, WordValues, word_values

MODE = "unique-cause; masking where a condition's operand appears more than once in its chain"
_ENUMERATE = 14             # free conditions up to which unique-cause feasibility is decided by enumeration
_INDEXED_SPAN = 4096        # values of X up to which an indexed write counts as a write of each operand it reaches
_ENUMERATE_PAIRS = 6        # free conditions up to which masking feasibility is decided by enumerating pairs


@dataclasses.dataclass(frozen=True)
class ConditionItem:
    """One condition of one decision: `status` is shown, missing or infeasible (with `reason`)."""

    decision: Decision
    number: int
    masking: bool
    status: str
    reason: str = ""

    @property
    def condition(self):
        return self.decision.conditions[self.number]

    @property
    def at(self) -> str:
        return str(self.condition.op.span)

    def what(self) -> str:
        mode = " (masking MC/DC)" if self.masking else ""
        return f"condition {self.condition.text} of {self.decision.text()}{mode}"


@dataclasses.dataclass(frozen=True)
class BoundaryItem:
    """One boundary value of one compare: `offset` -1, 0, +1 from the constant (c-1, c, c+1), or the difference of
    the two words; `status` reached, missing or infeasible."""

    compare: Compare
    offset: int
    status: str
    reason: str = ""

    @property
    def at(self) -> str:
        return str(self.compare.op.span)

    def what(self) -> str:
        cmp = self.compare
        head = f"boundary {cmp.left} {cmp.op.rel} {cmp.right}"
        if cmp.constant is None:
            return f"{head}: {cmp.left} - {cmp.right} = {self.offset:+d}"
        word = cmp.right if cmp.constant_left else cmp.left
        name = {-1: "c-1", 0: "c", 1: "c+1"}[self.offset]
        return f"{head}: {word} = {name} ({cmp.constant + self.offset})"


@dataclasses.dataclass(frozen=True)
class DecisionCoverage:
    conditions: tuple[ConditionItem, ...]
    boundaries: tuple[BoundaryItem, ...]

    def summary(self) -> dict[str, Any]:
        """The figures and lists of the JSON report (coverage.mcdc, coverage.boundaries)."""
        def count(items, status):
            return sum(1 for i in items if i.status == status)

        def listed(items, status):
            return [{"at": i.at, "what": i.what(), **({"reason": i.reason} if i.reason else {})}
                    for i in items if i.status == status]
        return {
            "mcdc": {"mode": MODE, "conditions": len(self.conditions),
                     "conditions_shown": count(self.conditions, "shown"),
                     "conditions_infeasible": count(self.conditions, "infeasible"),
                     "not_shown": listed(self.conditions, "missing"),
                     "infeasible": listed(self.conditions, "infeasible")},
            "boundaries": {"values": len(self.boundaries), "values_reached": count(self.boundaries, "reached"),
                           "values_infeasible": count(self.boundaries, "infeasible"),
                           "not_reached": listed(self.boundaries, "missing"),
                           "infeasible": listed(self.boundaries, "infeasible")},
        }


def shown_unique(vectors: Iterable[int], n: int, c: int) -> bool:
    """A pair of recorded vectors (condition bits, outcome at bit n) that differ in condition c alone and in the
    outcome."""
    recorded = set(vectors)
    bit = 1 << c
    out = 1 << n
    return any(v & bit == 0 and (v ^ bit ^ out) in recorded for v in recorded)


def shown_masking(vectors: Iterable[int], n: int, c: int, function) -> bool:
    """A masking MC/DC pair for condition c among the recorded vectors (see the module docstring)."""
    if shown_unique(vectors, n, c):
        return True             # a pair that differs in c alone is a masking pair too (nothing else differs)
    mask = (1 << n) - 1
    rows = sorted({(v & mask, v >> n) for v in vectors})
    bit = 1 << c
    return any(_masking_pair(a, b, bit, n, function) for (a, oa), (b, ob) in itertools.combinations(rows, 2)
               if oa != ob and (a ^ b) & bit)


def _masking_pair(a: int, b: int, bit: int, n: int, function) -> bool:
    for v in (a, b):
        out = function(v)
        if function(v ^ bit) == out:
            return False
        others = (a ^ b) & ~bit
        for d in range(n):
            if others >> d & 1 and function(v ^ (1 << d)) != out:
                return False
    return True


# ----------------------------------------------------------------------------------------------------- constants

def driven_operands(scenarios: Sequence, names) -> set[tuple[str, int]]:
    """(kind, address) of every operand one of `scenarios` sets (initial values, events, random inputs: a glob's
    every match), and (word_values.OVERRIDDEN_MODULE, number) of every module whose results one replaces
    (`module_results`)."""
    driven: set[tuple[str, int]] = set()
    for scenario in scenarios:
        driven.update((OVERRIDDEN_MODULE, int(number)) for number in scenario.module_results)
        written = list(scenario.initial)
        for event in scenario.events:
            written += list(event.set)
        driven |= _resolved(names, written)
        driven |= _random_inputs(scenario, names)
    return driven


def power_on_operands(scenarios: Sequence, names) -> set[tuple[str, int]]:
    """(kind, address) of every operand `scenarios` set before cycle 0 (`initial`) and never later (events, random
    inputs): a power-on value the program may overwrite before anything reads it."""
    first = _resolved(names, [name for scenario in scenarios for name in scenario.initial])
    later = _resolved(names, [name for scenario in scenarios for event in scenario.events for name in event.set])
    for scenario in scenarios:
        later |= _random_inputs(scenario, names)
    return first - later


def _resolved(names, written: Iterable[str]) -> set[tuple[str, int]]:
    found = set()
    for name in written:
        try:
            ref = names.resolve(name)
        except ValueError:
            continue
        found.add((ref.kind, ref.addr))
    return found


def _random_inputs(scenario, names) -> set[tuple[str, int]]:
    """The bit operands a scenario's random stimulus may toggle in any cycle: a glob stands for every name it matches
    (a glob such as `M5*` toggles markers, not only inputs)."""
    patterns = list(scenario.random.inputs) if scenario.random is not None else []
    matched = [n for p in patterns for n in (names.match(p) if is_glob(p) else [p])]
    return {k for k in _resolved(names, matched) if k[0] in BIT_KINDS}


@dataclasses.dataclass
class _Values:
    """The values each bit operand can hold under the program's own logic, with why (see constant_bits)."""

    values: dict[tuple[str, int], set[int]]
    writers: dict[tuple[str, int], list[str]]
    free_kinds: set[str]                            # kinds written through an index: any address, any value
    start: Callable[[str, int], set[int]]           # the values an operand has without a write of the program
    prefix: set[tuple[str, int]]                    # assigned first thing in every cycle (_written_first)

    def of(self, kind: str, addr: int) -> set[int]:
        if kind in self.free_kinds:
            return {0, 1}
        found = self.values.get((kind, addr))
        return found if found is not None else self.start(kind, addr)


def constant_bits(program: Program, table: DecisionTable, driven: set[tuple[str, int]]) -> _Values:
    """A fixpoint over the program's writes: every bit operand starts at its power-on value 0 (inputs, timers,
    counters, NC-interface operands and `driven` ones at anything), a store adds the values its chain can give, S
    adds 1 and R adds 0 (where their chain can be 1), any other write both values. A write through the index
    register writes each operand base + X can reach for the values X can hold there (index_range); where those are
    not known, every operand of its kind can hold both values. An operand the main program assigns first thing in
    every cycle, before anything reads it, has no start value a read can see."""
    profile = program.semantics.profile
    values: dict[tuple[str, int], set[int]] = {}
    writers: dict[tuple[str, int], list[str]] = {}
    free_kinds: set[str] = set()
    first = int(program.semantics["first_cycle_marker"] or -1)
    by_consumer = {d.key: d for d in table.decisions}
    outside = {"I", "T", "C"}

    prefix = _written_first(program)
    ranges = index_ranges(program)

    def start(kind: str, addr: int) -> set[int]:
        if kind in outside or (kind, addr) in NC_MODEL_OWNED or addr == first and kind == "M" \
                or profile.is_interface(kind, addr):
            return {0, 1}
        if (kind, addr) in prefix:
            return set()            # no read sees the value it had before the cycle
        return {0, 1} if (kind, addr) in driven else {0}

    stores: list[tuple[tuple[str, int], object, str]] = []      # (operand, op, span text)
    flag = program.semantics["add_overflow"] == "flag"
    for f, code in enumerate(program.files):
        for i, op in enumerate(code.ops):
            for kind, addr in implicit_writes(op, profile.interface, flag):
                stores.append(((kind, addr), None, str(op.span)))
            o = op.operand
            if o is None or op.code not in ("ST", "STN", "SET", "RES", "SETN", "RESN", "POP", "INC", "DEC",
                                            "STBITS"):
                continue
            if not o.is_bit:
                continue
            width = op.nbits if op.code == "STBITS" else 1
            if o.indexed:
                # base + X for every value X can hold there; a write outside the operand range faults instead
                x = ranges.get((f, i))
                if x is None or x[1] - x[0] > _INDEXED_SPAN:
                    free_kinds.add(o.kind)
                    continue
                targets = range(o.addr + x[0], o.addr + x[1] + width)
            else:
                targets = range(o.addr, o.addr + width)
            what = None if op.code == "STBITS" else (op, by_consumer.get((f, i)))
            for a in targets:
                if a >= 0:
                    stores.append(((o.kind, a), what, str(op.span)))
    for key, _, span in stores:
        values.setdefault(key, start(*key))
        writers.setdefault(key, []).append(span)
    state = _Values(values, writers, free_kinds, start, prefix)
    changed = True
    while changed:
        changed = False
        for key, what, _ in stores:
            if what is None:
                new = {0, 1}
            else:
                op, decision = what
                outcomes = _outcomes(decision, state) if decision is not None else {0, 1}
                code = op.code
                if code == "ST":
                    new = outcomes
                elif code == "STN":
                    new = {1 - v for v in outcomes}
                elif code in ("SET", "RES"):
                    new = ({1 if code == "SET" else 0} if 1 in outcomes else set())
                elif code in ("SETN", "RESN"):
                    new = ({1 if code == "SETN" else 0} if 0 in outcomes else set())
                else:
                    new = {0, 1}
            if not new <= values[key]:
                values[key] |= new
                changed = True
    return state


_PREFIX_END = frozenset({"LBL", "JP", "JPT", "JPF", "CALL", "CALLT", "CALLF", "CASE", "EM", "EMT", "EMF", "SUBM",
                         "RPLY", "CAN"})


def _written_first(program: Program) -> set[tuple[str, int]]:
    """Bit operands the main program assigns (= or =N) in its first straight-line stretch, which runs first in every
    cycle, before any instruction reads them there (every other read comes later in the cycle)."""
    read: set[tuple[str, int]] = set()
    first: set[tuple[str, int]] = set()
    indexed_read: set[str] = set()
    for op in program.main.ops:
        if op.code in _PREFIX_END:
            break
        o = op.operand
        if o is None or not o.is_bit:
            continue
        if o.indexed:
            indexed_read.add(o.kind)
            continue
        key = (o.kind, o.addr)
        if op.code in ("ST", "STN"):
            if key not in read and o.kind not in indexed_read:
                first.add(key)
        elif op.code not in ("SET", "RES", "SETN", "RESN"):
            read.add(key)
    return first


def _fixed(decision: Decision, state: _Values) -> tuple[dict[int, int], list[list[int]]]:
    """The constant conditions of `decision` (number -> value) and the groups of conditions that move together
    (one group per distinct operand not constant, coupled conditions in one group)."""
    fixed: dict[int, int] = {}
    groups: dict[object, list[int]] = {}
    for n, cond in enumerate(decision.conditions):
        o = cond.operand
        if o is not None and not o.indexed:
            held = state.of(o.kind, o.addr)
            if len(held) == 1:
                fixed[n] = next(iter(held))
                continue
        groups.setdefault(cond.key if cond.key is not None else ("alone", n), []).append(n)
    return fixed, list(groups.values())


def _assignments(decision: Decision, fixed: dict[int, int], groups: list[list[int]]) -> Iterable[int]:
    base = sum(1 << n for n, v in fixed.items() if v)
    for bits in itertools.product((0, 1), repeat=len(groups)):
        v = base
        for value, group in zip(bits, groups):
            if value:
                for n in group:
                    v |= 1 << n
        yield v


def _outcomes(decision: Decision, state: _Values) -> set[int]:
    fixed, groups = _fixed(decision, state)
    if len(groups) > _ENUMERATE:
        return {0, 1}
    function = decision.function()
    found: set[int] = set()
    for v in _assignments(decision, fixed, groups):
        found.add(function(v))
        if len(found) == 2:
            break
    return found


def _infeasible_reason(decision: Decision, number: int, masking: bool, state: _Values) -> str:
    """Why condition `number` can never be shown, or "" where it may be (or where that is not decided)."""
    cond = decision.conditions[number]
    fixed, groups = _fixed(decision, state)
    o = cond.operand
    if number in fixed:
        written = state.writers.get((o.kind, o.addr))
        why = (f"the program writes only {fixed[number]} to it ({', '.join(written[:3])})" if written else
               "nothing in the program writes it")
        if (o.kind, o.addr) in state.prefix:
            return (f"{o.display()} is always {fixed[number]}: {why}, first thing in every cycle, before anything "
                    "reads it")
        return (f"{o.display()} is always {fixed[number]}: {why}, and it is no input, timer, counter, NC-interface "
                "operand or operand a scenario sets")
    function = decision.function()
    constants = ", ".join(f"{decision.conditions[n].text} = {v}" for n, v in sorted(fixed.items()))
    because = f"masked by the constant {constants}" if constants else "the chain's outcome never depends on it"
    if not masking:
        if len(groups) > _ENUMERATE:
            return ""
        bit = 1 << number
        if any(function(v) != function(v ^ bit) for v in _assignments(decision, fixed, groups)):
            return ""
        return because
    if len(groups) > _ENUMERATE_PAIRS:
        return ""
    every = list(_assignments(decision, fixed, groups))
    bit = 1 << number
    n = len(decision.conditions)
    for a, b in itertools.combinations(every, 2):
        if (a ^ b) & bit and function(a) != function(b) and _masking_pair(a, b, bit, n, function):
            return ""
    return (f"{because}; it is coupled with the other reads of {cond.text} in the chain" if constants else
            f"no two evaluations can show it: it is coupled with the other reads of {cond.text} in the chain")


def _showable(decision: Decision, number: int, masking: bool, vectors: frozenset[int]) -> bool:
    """Whether two of `vectors` (the vectors the chain can see) would show condition `number`."""
    function = decision.function()
    n = len(decision.conditions)
    with_outcome = [v | function(v) << n for v in vectors]
    if masking:
        return shown_masking(with_outcome, n, number, function)
    return shown_unique(with_outcome, n, number)


class _Implications:
    """The implication analysis of one coverage computation (implication.py): where control enters the program,
    worked out once, and what the code before each decision lets it see, worked out once per decision, whichever of
    its conditions asks. `zero`: consumed_start_zero; `facts`: the NC model's facts that hold in this program
    (nc_facts.applicable_facts)."""

    def __init__(self, program: Program, state: _Values, zero: Callable[[str, int, int, int], bool],
                 facts: Sequence[NcFact] = (), table: DecisionTable | None = None):
        self.program, self.state, self.zero, self.facts = program, state, zero, tuple(facts)
        self.entries = program_entries(program)
        self._first: dict[tuple[int, int], tuple[Tied | None, frozenset[str]]] = {}
        self._held: dict[tuple[int, int], tuple[NcFact, ...]] = {}
        self._order: CycleOrder | None | bool = False         # False: not worked out yet
        self._writes: dict[tuple[str, int], list[tuple[int, int, set[int]]]] | None = None
        self._table = table

    def facts_at(self, file: int, start: int) -> tuple[NcFact, ...]:
        """The facts that hold at a region start: all of self.facts but those with an operand the program owns
        (NcFact.plc_owned) that a write able to break the fact may change before that op in the cycle."""
        if (file, start) not in self._held:
            self._held[(file, start)] = tuple(f for f in self.facts if self._kept(f, file, start))
        return self._held[(file, start)]

    def _kept(self, fact: NcFact, file: int, start: int) -> bool:
        if not fact.plc_owned:
            return True
        if self._order is False:
            self._order = cycle_order(self.program)
        order = self._order
        if order is None or (file, start) in order.in_jobs or (file, start) not in order.positions:
            return False
        writes = self._bit_writes()
        for key in fact.plc_owned:
            for f, i, values in writes.get(key, ()):
                if order.may_precede((f, i), (file, start)) and any(not _keeps(fact, key, v) for v in values):
                    return False
        return True

    def _bit_writes(self) -> dict[tuple[str, int], list[tuple[int, int, set[int]]]]:
        """Each named write of a bit operand: (file, op index, the values it can write)."""
        if self._writes is None:
            table = self._table or decision_table(self.program)
            by_consumer = {d.key: d for d in table.decisions}
            writes: dict[tuple[str, int], list[tuple[int, int, set[int]]]] = {}
            sem = self.program.semantics
            for f, code in enumerate(self.program.files):
                for i, op in enumerate(code.ops):
                    for key in implicit_writes(op, sem.profile.interface, sem["add_overflow"] == "flag"):
                        writes.setdefault(key, []).append((f, i, {0, 1}))
                    o = op.operand
                    if o is None or not o.is_bit or o.indexed or op.code not in _BIT_STORES:
                        continue
                    decision = by_consumer.get((f, _first_consumer(code.ops, f, i, by_consumer, self.entries)))
                    outcomes = _outcomes(decision, self.state) if decision is not None else {0, 1}
                    values = {"ST": outcomes, "STN": {1 - v for v in outcomes}, "SET": {1}, "SETN": {1},
                              "RES": {0}, "RESN": {0}}.get(op.code, {0, 1})
                    for n in range(op.nbits if op.code == "STBITS" else 1):
                        writes.setdefault((o.kind, o.addr + n), []).append((f, i, values))
            self._writes = writes
        return self._writes

    def entry(self, consumed: set[str]) -> Callable[[str, int, int, int], int | None]:
        """An operand's value at a region start where the program fixes it there; a consumed timer or counter start
        taken as 0 is added to `consumed`."""
        def value(kind: str, addr: int, file: int, index: int) -> int | None:
            held = self.state.of(kind, addr)
            if len(held) == 1:
                return next(iter(held))
            if self.zero(kind, addr, file, index):
                consumed.add(f"{kind}{addr}")
                return 0
            return None
        return value

    def first(self, decision: Decision) -> tuple[Tied | None, frozenset[str]]:
        """What the longest region before `decision` lets it see, and the starts taken as 0 there."""
        if decision.key not in self._first:
            consumed: set[str] = set()
            tied = tied_vectors(self.program, decision, self.entry(consumed), entries=self.entries,
                                facts=self.facts_at)
            self._first[decision.key] = (tied, frozenset(consumed))
        return self._first[decision.key]

    def invariants(self, missing: Sequence[ConditionItem]) -> list[Invariant]:
        """The relations across cycles that would explain some of the `missing` conditions (a pair of values of two
        of its chain's operands that, never occurring, leaves the condition unshowable) and that hold
        (implication.inductive_invariants). Only markers and outputs with power-on value 0 that no scenario, NC or
        index write of unknown reach touches are candidates."""
        candidates: dict[tuple, Invariant] = {}
        for item in missing:
            decision = item.decision
            tied, _ = self.first(decision)
            if tied is None or not tied.vectors:
                continue
            conds = decision.conditions
            keys = [(c.operand.kind, c.operand.addr) if c.operand is not None and c.operand.is_bit
                    and not c.operand.indexed else None for c in conds]
            for i, j in itertools.combinations(range(len(conds)), 2):
                a, b = keys[i], keys[j]
                if a is None or b is None or a == b or not all(self._eligible(k) for k in (a, b)):
                    continue
                for x, y in ((1, 1), (1, 0), (0, 1)):
                    rest = frozenset(v for v in tied.vectors if not (v >> i & 1 == x and v >> j & 1 == y))
                    if rest and not _showable(decision, item.number, item.masking, rest):
                        candidates.setdefault((a, b, x, y), Invariant((a, b), (x, y), (conds[i].text, conds[j].text)))
        if not candidates:
            return []
        return inductive_invariants(self.program, list(candidates.values()), self.entry(set()), self.entries)

    def _eligible(self, key: tuple[str, int]) -> bool:
        return key[0] in ("M", "O") and key[0] not in self.state.free_kinds and self.state.start(*key) == {0}


def _tied_reason(analysis: _Implications, decision: Decision, number: int, masking: bool,
                 invariants: Sequence[Invariant] = ()) -> str:
    """Why the code before the chain in the same cycle keeps condition `number` from being shown (implication.py),
    naming the writes the claim rests on, and the `invariants` (proved across cycles) it needs; "" where it does
    not."""
    program = analysis.program
    if invariants:
        consumed: set[str] = set()
        tied = tied_vectors(program, decision, analysis.entry(consumed), entries=analysis.entries,
                            facts=analysis.facts_at, invariants=invariants)
    else:
        tied, first_consumed = analysis.first(decision)
        consumed = set(first_consumed)
    if tied is None or not tied.vectors or _showable(decision, number, masking, tied.vectors):
        return ""
    entry = analysis.entry(consumed)
    # the writes the claim rests on: drop each one the claim holds without
    def holds(skip: frozenset[int], facts: Sequence[NcFact], assumed: Sequence[Invariant]) -> bool:
        trial = tied_vectors(program, decision, entry, skip, tied.start, analysis.entries, facts, assumed)
        return trial is not None and bool(trial.vectors) and not _showable(decision, number, masking, trial.vectors)

    held = analysis.facts_at(decision.file, tied.start)
    absent: set[int] = set()
    for w in tied.writes:
        if holds(frozenset(absent | {w}), held, invariants):
            absent.add(w)
    # the NC model's facts it rests on, likewise (the narrower ones, later in the table, dropped first)
    resting = list(held)
    for fact in reversed(held):
        if holds(frozenset(absent), [f for f in resting if f is not fact], invariants):
            resting.remove(fact)
    used = list(invariants)
    for inv in invariants:
        if holds(frozenset(absent), resting, [i for i in used if i is not inv]):
            used.remove(inv)
    ops = program.files[decision.file].ops
    needed = [f"{ops[w].span} {ops[w].mnemonic} "
              + (ops[w].call.label if ops[w].operand is None and ops[w].call is not None else ops[w].operand.display())
              for w in tied.writes if w not in absent]
    # where an NC fact ties three conditions, the pairs alone seldom say it: name a triple that never occurs too
    facts = _ties(decision, number, tied, triples=bool(resting))
    cond = decision.conditions[number].text
    where = [f"set by {', '.join(needed[:4])} before this chain on every path to it"] if needed else []
    names = {f"{c.operand.kind}{c.operand.addr}": c.text for c in decision.conditions if c.operand is not None}
    starts = sorted({names[k] for k in consumed if k in names})
    if starts:
        where.append(f"{', '.join(starts)}: a timer or counter start the service clears after every cycle, and no "
                     "write of it runs before this chain in the cycle")
    ops_cond = decision.conditions[number]
    if ops_cond.operand is None and ops_cond.op.code in ("CMP", "BT", "BCLOSE") and not any(
            (v >> number & 1) != (next(iter(tied.vectors)) >> number & 1) for v in tied.vectors):
        where.append("WA holds one value there: the constants it is loaded from and computed with before it")
    where += [fact.text for fact in resting]
    where += [f"{inv.text()} at every point of every cycle: both are 0 at power-on, nothing but the program "
              f"writes them, and each write keeps it ({', '.join(inv.writes[:6])}"
              + (", ..." if len(inv.writes) > 6 else "") + ")" for inv in used]
    return (f"{cond} cannot change the outcome on its own here: {'; '.join(facts) or 'its conditions are tied'}"
            + (f" ({'; '.join(where)})" if where else ""))


_BIT_STORES = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN", "POP", "INC", "DEC", "STBITS"})
_LA_STORES = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN"})


def _first_consumer(ops, f: int, i: int, by_consumer, entries) -> int:
    """The op whose decision the store at ops[i] consumes: the first of the stores in a row before it (`= M1`
    `= M2` store one LA), where control comes to none of the later ones from elsewhere."""
    j = i
    while (f, j) not in by_consumer and j > 0 and ops[j - 1].code in _LA_STORES and ops[j].code in _LA_STORES \
            and not entries.jumps[f].get(j) and (f, j) not in entries.called:
        j -= 1
    return j


def _keeps(fact: NcFact, key: tuple[str, int], value: int) -> bool:
    """Whether writing `value` to the fact's bit operand `key` leaves the fact true in every state it holds in."""
    others = [k for k in fact.operands if k != key]
    if any(k[0] in ("B", "W", "D") for k in others):
        return False                    # not needed by the facts there are: words stay the NC's alone
    for bits in itertools.product((0, 1), repeat=len(others)):
        state = dict(zip(others, bits))
        if any(fact.holds({**state, key: v}) for v in (0, 1)) and not fact.holds({**state, key: value}):
            return False
    return True


def _ties(decision: Decision, number: int, tied: Tied, triples: bool = False) -> list[str]:
    """What the chain can see, in words: conditions that are constant there, and pairs of values that never occur
    together (those with condition `number` first); triples of values too where no pair names condition `number`,
    or where `triples` asks for them."""
    conds = decision.conditions
    n = len(conds)
    facts: list[str] = []
    seen = {(i, b): any(v >> i & 1 == b for v in tied.vectors) for i in range(n) for b in (0, 1)}
    for i in range(n):
        for b in (0, 1):
            if not seen[(i, 1 - b)] and seen[(i, b)] and f"{conds[i].text} is always {b}" not in facts:
                facts.append(f"{conds[i].text} is always {b}")
    pairs: list[tuple[int, str]] = []
    for i in range(n):
        for j in range(i + 1, n):
            if conds[i].text == conds[j].text:
                continue
            for a in (0, 1):
                for b in (0, 1):
                    if seen[(i, a)] and seen[(j, b)] and not any(v >> i & 1 == a and v >> j & 1 == b
                                                                 for v in tied.vectors):
                        text = f"{conds[i].text} = {a} only with {conds[j].text} = {1 - b}"
                        if all(text != t for _, t in pairs):
                            pairs.append((0 if number in (i, j) else 1, text))
    facts += [t for _, t in sorted(pairs, key=lambda p: p[0])][:3]
    if triples or not any(rank == 0 for rank, _ in pairs):
        facts += _never_together(decision, number, tied)[:2]
    return facts


def _never_together(decision: Decision, number: int, tied: Tied) -> list[str]:
    """Three values, one of condition `number`, that never occur together though each two of them do."""
    conds = decision.conditions
    others = [i for i in range(len(conds)) if conds[i].text != conds[number].text]
    found = []
    for i, j in itertools.combinations(others, 2):
        if conds[i].text == conds[j].text:
            continue
        for a, b, c in itertools.product((0, 1), repeat=3):
            def occurs(*fixed: tuple[int, int]) -> bool:
                return any(all(v >> k & 1 == x for k, x in fixed) for v in tied.vectors)
            trio = ((number, a), (i, b), (j, c))
            if not occurs(*trio) and all(occurs(*pair) for pair in itertools.combinations(trio, 2)):
                found.append("never " + ", ".join(f"{conds[k].text} = {x}" for k, x in trio) + " together")
    return found


# ----------------------------------------------------------------------------------------------------- figures

def decision_coverage(program: Program, sets: Sequence, driven: set[tuple[str, int]] = frozenset(),
                      table: DecisionTable | None = None, explain_missing: bool = True,
                      power_on: set[tuple[str, int]] = frozenset()) -> DecisionCoverage:
    """MC/DC and boundaries over the runs' coverage sets (machine.Coverage); `driven`: operands the scenarios set,
    `power_on`: those of them set only before cycle 0 (a boundary value they hold may never be read).
    Without `explain_missing`, a condition no run showed is missing without the search for why it cannot be."""
    table = table or decision_table(program)
    vectors: dict[tuple[int, int], set[int]] = {}
    bounds: dict[tuple[int, int], set[int]] = {}
    for cov in sets:
        for key, found in cov.vectors.items():
            vectors.setdefault(key, set()).update(found)
        for key, found in cov.bounds.items():
            bounds.setdefault(key, set()).update(found)
    state: _Values | None = None
    implications: _Implications | None = None
    strings: StringCompares | None = None
    idle: dict[tuple[str, int], str] = {}
    conditions: list[ConditionItem] = []
    for decision in table.decisions:
        recorded = vectors.get(decision.key, set())
        n = len(decision.conditions)
        function = decision.function()
        for number, coupled in enumerate(decision.coupled):
            shown = (shown_masking(recorded, n, number, function) if coupled else
                     shown_unique(recorded, n, number))
            if shown:
                conditions.append(ConditionItem(decision, number, coupled, "shown"))
                continue
            if not explain_missing:
                conditions.append(ConditionItem(decision, number, coupled, "missing"))
                continue
            if state is None:
                state = constant_bits(program, table, set(driven))
                implications = _Implications(program, state, consumed_start_zero(program, set(driven)),
                                             applicable_facts(program, set(driven)), table)
            if strings is None:
                strings = StringCompares(program)
                idle = _idle_timers(program, sets, driven)
            reason = (_infeasible_reason(decision, number, coupled, state)
                      or _tied_reason(implications, decision, number, coupled)
                      or _constant_string_reason(strings, decision, number)
                      or _idle_timer_reason(decision, number, idle))
            conditions.append(ConditionItem(decision, number, coupled, "infeasible" if reason else "missing", reason))
    # what is still missing may be explained by a relation that holds across cycles (implication.Invariant)
    missing = [k for k, item in enumerate(conditions) if item.status == "missing"]
    if missing and implications is not None:
        invariants = implications.invariants([conditions[k] for k in missing])
        for k in missing if invariants else ():
            item = conditions[k]
            reason = _tied_reason(implications, item.decision, item.number, item.masking, invariants)
            if reason:
                conditions[k] = dataclasses.replace(item, status="infeasible", reason=reason)
    # what is still missing may be ruled out by the paths that come to its chain (cycle_paths)
    if explain_missing:
        _explain_by_paths(program, conditions)
        # and by what holds at the start of every cycle but the first (operands set after power-on break it)
        if any(item.status == "missing" for item in conditions):
            at_start = start_relations(program, set(driven) - set(power_on))
            if at_start:
                _explain_by_paths(program, conditions, at_start)
    boundaries = _boundary_coverage(program, table, bounds, set(driven), set(power_on), explain_missing)
    if explain_missing:
        # last, as it runs whole cycles: what holds at the start of every cycle but the first, item by item
        _explain_by_states(program, table, conditions, boundaries, set(driven), set(power_on))
    return DecisionCoverage(tuple(conditions), tuple(boundaries))


def _boundary_coverage(program: Program, table: DecisionTable, bounds: Mapping[tuple[int, int], set[int]],
                       driven: set[tuple[str, int]], power_on: set[tuple[str, int]],
                       explain_missing: bool) -> list[BoundaryItem]:
    """The boundary items of every compare: reached by a run, or missing unless an analysis (word_values, X's
    values, the NC ranges, word_relations) shows the value cannot be there."""
    boundaries: list[BoundaryItem] = []
    held: WordValues | None = None
    xs: dict[tuple[int, int], XValues] | None = None
    ranges: dict[tuple[str, int], NcFact] = {}
    relations: dict[tuple[int, int], tuple[int | None, int | None]] | None = None
    word_range: dict[tuple[int, int], tuple[int, int]] | None = None
    for cmp in table.compares:
        items = _boundary_items(cmp, bounds.get(cmp.key, set()))
        if explain_missing and any(i.status == "missing" for i in items):
            if held is None:
                held = word_values(program, table.compares, set(driven), set(power_on))
                xs = index_values(program)
                ranges = {f.operands[0]: f for f in applicable_facts(program, set(driven)) if len(f.operands) == 1}
            items = [_explained(program, cmp, item, held, xs, ranges) if item.status == "missing" else item
                     for item in items]
            if cmp.constant is None:
                relations = word_relations(program) if relations is None else relations
                items = [_related(cmp, item, relations) if item.status == "missing" else item for item in items]
            elif any(i.status == "missing" for i in items):
                word_range = word_bounds(program) if word_range is None else word_range
                items = [_bounded(cmp, item, word_range) if item.status == "missing" else item for item in items]
        boundaries += items
    return boundaries


def _explain_by_paths(program: Program, conditions: list[ConditionItem],
                      relations: Sequence[StartRelation] = ()) -> None:
    """Marks the missing conditions the paths that come to their chain never show (cycle_paths) as infeasible; with
    `relations` (cycle_paths.start_relations), runs from the main program's start assume them in every cycle but
    the first, and the reason names those the claim rests on."""
    runner: Runner | None = None
    found: dict[tuple[int, int], Seen | None] = {}
    for k, item in enumerate(conditions):
        if item.status != "missing":
            continue
        decision = item.decision
        if decision.key not in found:
            runner = runner or Runner(program, relations)
            found[decision.key] = seen_vectors(runner, decision)
        seen = found[decision.key]
        if seen is None or not seen.vectors or _showable(decision, item.number, item.masking, seen.vectors):
            continue
        used = list(relations) if seen.start == (0, 0) else []
        for rel in list(used):
            trial = Runner(program, [r for r in used if r is not rel])
            again = trial.seen(decision, seen.start)
            if again is not None and again and not _showable(decision, item.number, item.masking, again):
                used.remove(rel)
        ties = _ties(decision, item.number, Tied(seen.vectors, seen.start[1], ()))
        marker = runner.first_cycle_marker() if used and runner is not None else None
        assumed = "".join(f"; {rel.text()}" for rel in used) + (
            "; the first cycle followed from any memory" + (f" with the first-cycle marker M{marker[1]} = 1"
                                                            if marker is not None else "") if used else "")
        reason = (f"{item.condition.text} cannot change the outcome on its own here: "
                  f"{'; '.join(ties) or 'its conditions are tied'} (on every path of the cycle to this chain, "
                  f"followed from {start_name(program, seen.start)} through the calls and CASE entries on the way, "
                  f"with the values the compares, jumps and stores on each path leave its markers and words{assumed})")
        conditions[k] = dataclasses.replace(item, status="infeasible", reason=reason)


# The searches for start states (cycle_states) run whole cycles: one report runs them only where few items are left
# (the last ones of a project whose runs cover the rest), within one budget of ops followed.
_MAX_ITEMS_FOR_STATES = 32
_STATES_BUDGET = 8_000_000


def _explain_by_states(program: Program, table: DecisionTable, conditions: list[ConditionItem],
                       boundaries: list[BoundaryItem], driven: set[tuple[str, int]],
                       power_on: set[tuple[str, int]]) -> None:
    """Marks the missing items that no path of a cycle shows from the states one of which holds at the start of
    every cycle but the first (cycle_states: kept apart by the keys the item needs) as infeasible; the first cycle
    is followed from any memory. Only items every run of which starts at the main program's start, and only where
    few items are left; the searches with the fewest keys run first, within one budget."""
    todo = [(conditions, k) for k, item in enumerate(conditions) if item.status == "missing"]
    todo += [(boundaries, k) for k, item in enumerate(boundaries) if item.status == "missing"
             and item.compare.constant is not None and not item.compare.constant_left and item.compare.index > 0
             and program.files[item.compare.file].ops[item.compare.index - 1].code == "WLD"]
    if not todo or len(todo) > _MAX_ITEMS_FOR_STATES or not followable(program):
        return
    outside = driven - power_on
    base = Runner(program)
    chooser = KeyChooser.of(base, table, kept_between_cycles(program, outside))
    candidates: list[tuple[list, list, int]] = []       # (the key sets to try in turn, items, index)
    for items, k in todo:
        item = items[k]
        if isinstance(item, ConditionItem):
            decision = item.decision
            target, bits = (decision.file, min(c.index for c in decision.conditions)), chain_bits(decision)
            if any(c.file != decision.file for c in decision.conditions) or \
                    base.starts(*target) != base.starts(decision.file, decision.index):
                continue
        else:
            target, bits = item.compare.key, []
        if base.starts(*target)[:1] == [(0, 0)]:
            candidates.append((chooser.keys(target, bits), items, k))
    budget = StepBudget(_STATES_BUDGET)
    for turn in range(max((len(c[0]) for c in candidates), default=0)):
        # the items still missing try their next key set (the narrow one first, then a wider one)
        needs = [(keys[turn], items, k) for keys, items, k in candidates
                 if turn < len(keys) and items[k].status == "missing"]
        needs = [(merged, items, k) for merged, (_, items, k) in zip(merged_keys([n[0] for n in needs]), needs)]
        searches: dict[tuple, list[tuple[list, int]]] = {}
        for need, items, k in sorted(needs, key=lambda n: len(n[0][0]) + len(n[0][1])):
            searches.setdefault(need, []).append((items, k))
        for (keys, split), judged in searches.items():
            states = start_states(program, keys, set(split), outside, driven, _key_names(program, keys), budget) \
                if budget.left > 0 else None
            if states is not None:
                _judge_from_states(program, states, judged, budget)


def _judge_from_states(program: Program, states: StartStates, judged: list[tuple[list, int]],
                       budget: StepBudget) -> None:
    """Judges the items `judged` ((list, index) of each) from `states`: one cycle run per file of theirs finds
    what each sees (the values paths read are kept by op index, so the chains of one run are in one file)."""
    by_file: dict[int, list[tuple[list, int]]] = {}
    for items, k in judged:
        item = items[k]
        by_file.setdefault(item.decision.file if isinstance(item, ConditionItem) else item.compare.file,
                           []).append((items, k))
    for here in by_file.values():
        points = [items[k].decision.key if isinstance(items[k], ConditionItem) else items[k].compare.key
                  for items, k in here]
        decisions = [items[k].decision for items, k in here if isinstance(items[k], ConditionItem)]
        came = arrivals(program, states, points, [(c.file, c.index) for d in decisions for c in d.conditions],
                        {b for d in decisions for b in chain_bits(d)}, budget)
        for (items, k), point in zip(here, points):
            if came is not None and came[point]:
                items[k] = (_judged_by_states(items[k], states, came[point]) if isinstance(items[k], ConditionItem)
                            else _bounded_by_states(items[k], states, came[point]))


def _judged_by_states(item: ConditionItem, states: StartStates, came: list) -> ConditionItem:
    """`item` (missing) as infeasible where no path of a cycle from `states` (those that `came` to its chain)
    shows it."""
    decision = item.decision
    vectors = condition_vectors(tuple(p.reads.get(c.index) for c in decision.conditions) for p in came)
    if not vectors or _showable(decision, item.number, item.masking, vectors):
        return item
    ties = _ties(decision, item.number, Tied(vectors, 0, ()))
    return dataclasses.replace(item, status="infeasible", reason=(
        f"{item.condition.text} cannot change the outcome on its own here: "
        f"{'; '.join(ties) or 'its conditions are tied'} (on every path of the cycle to this chain from the "
        f"start of the main program; {states.text()})"))


def _bounded_by_states(item: BoundaryItem, states: StartStates, came: list) -> BoundaryItem:
    """`item` (missing, of a word loaded right before its compare) as infeasible where no path of a cycle from
    `states` (those that `came` to the compare) holds the word at its value."""
    if any(p.wa is None for p in came):
        return item
    held = came[0].wa
    for path in came[1:]:
        held = held.join(path.wa)
    cmp = item.compare
    value = cmp.constant + item.offset
    if held.holds(value):
        return item
    shown = f"{held.lo}..{held.hi}" if held.some is None else ", ".join(map(str, sorted(held.some)))
    return dataclasses.replace(item, status="infeasible", reason=(
        f"{cmp.left} holds only {shown} here, never {value} (on every path of the cycle to this compare from the "
        f"start of the main program; {states.text()})"))


def _key_names(program: Program, keys: Sequence[tuple[str, int]]) -> tuple[str, ...]:
    """The operands' names as the source writes them (the first op that names each)."""
    names = {}
    for code in program.files:
        for op in code.ops:
            o = op.operand
            if o is not None and not o.indexed and (o.kind, o.addr) in keys:
                names.setdefault((o.kind, o.addr), o.display())
    return tuple(names.get(k, f"{k[0]}{k[1]}") for k in keys)


def _constant_string_reason(strings: StringCompares, decision: Decision, number: int) -> str:
    """Why condition `number`, a string compare the code right before it fixes (string_values.py), can never be
    shown: it never changes; "" where it is no such compare."""
    cond = decision.conditions[number]
    found = strings.outcome(cond.file, cond.index)
    if found is None:
        return ""
    outcome, left, right = found
    return (f"{cond.text} is always {int(outcome)}: SA holds \"{left}\" and the operand \"{right}\" there, set by the "
            "string loads, appends and stores right before it on the only way to it")


def _idle_timers(program: Program, sets: Sequence, driven: set[tuple[str, int]]) -> dict[tuple[str, int], str]:
    """The timer running bits no run can see at 1, with the machine parameter that says why: the timer's preset is 0
    in every run (Coverage.idle_timers), so the timer service never sets the bit, and nothing else writes it (no write
    of the program, named, implicit or through the index register, and no scenario)."""
    if not sets:
        return {}
    idle = frozenset.intersection(*(frozenset(getattr(cov, "idle_timers", ())) for cov in sets))
    if not idle:
        return {}
    profile = program.semantics.profile
    sites, other, indexed = write_sites(program)
    if "T" in indexed:
        return {}
    out: dict[tuple[str, int], str] = {}
    for addr in sorted(idle):
        key = ("T", addr)
        if key in driven or key in sites or key in other:
            continue
        number = profile.timer_start[0] + addr - profile.timer_running[0]
        out[key] = f"MP{TIMER_MP}.{number}"
    return out


def _idle_timer_reason(decision: Decision, number: int, idle: Mapping[tuple[str, int], str]) -> str:
    """Why condition `number`, a running bit of a timer whose preset is 0 in every run, can never be shown: it is
    always 0; "" where it is no such bit."""
    o = decision.conditions[number].operand
    if o is None or o.indexed or (o.kind, o.addr) not in idle:
        return ""
    return (f"{o.display()} is always 0: its timer's preset ({idle[(o.kind, o.addr)]}) is 0 in every run, so the "
            "timer service never sets it, and neither the program nor a scenario writes it")


def _related(cmp: Compare, item: BoundaryItem,
             relations: Mapping[tuple[int, int], tuple[int | None, int | None]]) -> BoundaryItem:
    """`item` (missing, of a compare of two words) as infeasible where the difference the words can have there
    (word_relations) leaves its offset out."""
    low, high = relations.get(cmp.key, (None, None))
    offset = item.offset
    if high is not None and offset > high:
        bound = f"{cmp.left} - {cmp.right} is at most {high}"
    elif low is not None and offset < low:
        bound = f"{cmp.left} - {cmp.right} is at least {low}"
    else:
        return item
    return dataclasses.replace(item, status="infeasible", reason=(
        f"{bound} here, never {offset:+d}: the compares of the two words the jumps before it went on, and the steps "
        "of one of them by a constant since, on every path to it, keep the difference there"))


def _bounded(cmp: Compare, item: BoundaryItem, bounds: Mapping[tuple[int, int], tuple[int, int]]) -> BoundaryItem:
    """`item` (missing, of a compare of a word loaded right before it with a constant) as infeasible where the
    bounds its differences with X, 0 and other words give it there (word_relations.word_bounds) leave its value
    out."""
    found = bounds.get(cmp.key)
    if found is None or cmp.constant_left:
        return item
    value = cmp.constant + item.offset
    if found[0] <= value <= found[1]:
        return item
    return dataclasses.replace(item, status="infeasible", reason=(
        f"{cmp.left} holds only {found[0]}..{found[1]} here, not {value}: its differences with X, 0 and the other "
        "words it is compared with or copied from, set by its stores, moved by its steps (INC, DEC, + and - of a "
        "constant, each shown not to wrap) and by X's, and narrowed by the compares the jumps before it went on (also "
        "through a marker assigned from a compare, and through a bound of another word where every way into a join "
        "either sets this word's bound or denies that one), on every path to it, with X's interval there, keep it in "
        "that range"))


def _boundary_items(cmp: Compare, seen: set[int]) -> list[BoundaryItem]:
    items = []
    for offset in (-1, 0, 1):
        if cmp.constant is None:
            status = "reached" if offset in seen else "missing"
            items.append(BoundaryItem(cmp, offset, status))
            continue
        difference = -offset if cmp.constant_left else offset
        value = cmp.constant + offset
        if difference in seen:
            items.append(BoundaryItem(cmp, offset, "reached"))
        elif cmp.constants_only:
            items.append(BoundaryItem(cmp, offset, "infeasible", "both sides are constants"))
        elif not cmp.low <= value <= cmp.high:
            word = cmp.right if cmp.constant_left else cmp.left
            items.append(BoundaryItem(cmp, offset, "infeasible",
                                      f"{word} holds {cmp.low}..{cmp.high} in this compare, not {value}"))
        else:
            items.append(BoundaryItem(cmp, offset, "missing"))
    return items


def _explained(program: Program, cmp: Compare, item: BoundaryItem, held: WordValues,
               xs: Mapping[tuple[int, int], XValues], ranges: Mapping[tuple[str, int], NcFact]
               ) -> BoundaryItem:
    """`item` (missing) as infeasible where the values the word can hold at the compare (word_values), the values
    the index register can hold there (index_range) or the values the NC model writes to a word only it writes
    (`ranges`: single-word facts of nc_facts that apply) leave its value out."""
    if cmp.constant is None:
        return item
    value = cmp.constant + item.offset
    found = held.at(cmp)
    if found is not None and value not in found.values:
        return dataclasses.replace(item, status="infeasible", reason=found.reason(value))
    x = xs.get(cmp.key)
    ops = program.files[cmp.file].ops
    # The word compared: the compare's operand, or the one loaded just before it (decisions.Compare's rule); where WA
    # was computed (`L K100` `- W260` `== K-5`) the operand before the compare is no side of it.
    load = ops[cmp.index - 1] if cmp.index > 0 else None
    word = ops[cmp.index].operand if cmp.constant_left else \
        load.operand if load is not None and load.code == "WLD" else None
    fact = ranges.get((word.kind, word.addr)) if word is not None and not word.indexed else None
    # (the fact is about the word's signed content; a compare that reads it zero-extended sees 65535 for -1)
    if fact is not None and not fact.holds({fact.operands[0]: sext(value, 8 * BYTES[word.kind])}):
        shown = cmp.right if cmp.constant_left else cmp.left
        return dataclasses.replace(item, status="infeasible", reason=f"{shown} never holds {value}: {fact.text}")
    if x is None or word is None or word.kind != "X" or x[0] < 0 or program.semantics["compare_signedness"] == \
            "unsigned":
        return item
    if not x[0] <= value <= x[1]:
        return dataclasses.replace(item, status="infeasible",
                                   reason=f"X holds only {x[0]}..{x[1]} here, not {value}: the index register's "
                                          "loads, steps and compares before this one on every path keep it there")
    residue = _index_residue_reason(x, value)
    return dataclasses.replace(item, status="infeasible", reason=residue) if residue else item


def _index_residue_reason(x: XValues, value: int) -> str:
    """Why X cannot hold `value`, inside its interval, where its loads and steps keep it to one residue (a loop
    stepping X by 2 from 0 never gives it an odd value); "" where it can."""
    if x.modulus == 1 or x.holds(value):
        return ""
    if x.modulus == 0:
        return (f"X holds only {x.residue} here, not {value}: the index register's loads and steps before this one on "
                "every path give it no other value")
    return (f"X holds only values {x.residue} modulo {x.modulus} here ({x.lo}..{x.hi}), not {value}: the index "
            f"register's loads and steps before this one on every path keep it at {x.residue} modulo {x.modulus}")


def figures(cov: Mapping[str, Any]) -> str:
    """`MC/DC 412/430 conditions (3 infeasible), boundaries 80/95 (2 infeasible)` from a coverage summary."""
    m, b = cov.get("mcdc"), cov.get("boundaries")
    if m is None or b is None:
        return ""

    def part(shown: int, total: int, infeasible: int, unit: str) -> str:
        return f"{shown}/{total - infeasible}{unit}" + (f" ({infeasible} infeasible)" if infeasible else "")
    return (f"MC/DC {part(m['conditions_shown'], m['conditions'], m['conditions_infeasible'], ' conditions')}, "
            f"boundaries {part(b['values_reached'], b['values'], b['values_infeasible'], '')}")
