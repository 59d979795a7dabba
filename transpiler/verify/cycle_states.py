"""States one of which holds at the start of every cycle but the first: an inductive invariant of the whole cycle,
found by running it path by path (cycle_paths.Runner) with the paths kept apart by the values of a few key operands.

A step chain keeps its state across cycles: a tool change evaluates in one cycle what its idle step took over from
the NC in the one before (`ML_new_auto` and `WG_new_pocket` together), a decoder sets at most one pending marker
per strobe and clears them all when the strobe goes. No analysis of a single cycle can see that; this one runs
whole cycles and keeps, for each value of the key operands (a CASE step word, the markers a missing MC/DC pair
reads and the markers their writers read), what the other kept operands can be at the cycle's end.

Base: the first cycle run from any memory, the first-cycle marker 1 where the program never writes it. Step: a
cycle run from each state found ends in states found (a state that grows more than a few times forgets the words
whose values grew, so the search ends). Every run starts with what the NC model guarantees when the program starts
(nc_facts.applicable_facts: the one-of-three tool flags with their pocket word, a strobe only with its
acknowledgement 0, the NC words in their ranges), split where a fact's bits are operands the run forks on. Paths
are joined where they meet with the same key values and LA; a loop is run again from a state that forgets what it
writes (as Runner.summarize). Between cycles only what nothing but the program's cycle writes is kept
(kept_between_cycles): markers and outputs that are no interface operand, and words that are no NC, interface,
data-table or scenario-set operand; what a submitted job may write is forgotten. The search gives up (no claim)
where a run gives up or the states keep growing past the limits.

tests/test_cycle_states.py checks the claim where it matters: from random memory and from the sample's scenarios,
every state a cycle starts in after the first is one of those found."""

from __future__ import annotations

import dataclasses
import itertools
from typing import Callable, Sequence

from transpiler.exec.interp.decisions import Decision, DecisionTable
from transpiler.ir import Program
from transpiler.verify.cycle_paths import (_DEPTH, _RETURN, Runner, Word, _full, _GiveUp, _join, _Path, followable,
                                           kept_between_cycles)
from transpiler.verify.nc_facts import NC_FACTS, NC_MODEL_OWNED, NcFact, applicable_facts

Key = tuple[str, int]

_MAX_PARTS = 512            # key values a cycle's paths are kept apart by at one point, at most
_WIDEN_AFTER = 2            # times the state of one key value grows before the words that grew are forgotten
_MAX_CYCLES = 400           # whole cycles run for one set of keys, at most
_MAX_TOTAL_STEPS = 6_000_000    # ops run over all those cycles, at most (about half a minute)


@dataclasses.dataclass
class StepBudget:
    """Ops the whole-cycle runs may still follow (shared by the searches one report runs)."""

    left: int = _MAX_TOTAL_STEPS

    def spend(self, runner: Runner) -> None:
        self.left -= runner.steps


_WORDS = ("B", "W", "D")
# ops where paths may part or meet: a run goes straight on over any other op
_CONTROL = frozenset({"JP", "JPT", "JPF", "EM", "EMT", "EMF", "CALL", "CALLT", "CALLF", "CASE", "LBL"})


@dataclasses.dataclass(frozen=True)
class StartStates:
    """States one of which holds at the start of every cycle but the first (start_states), and what they were kept
    apart by: `keys` (with their names)."""

    keys: tuple[Key, ...]
    names: tuple[str, ...]
    states: tuple[_Path, ...]
    split: frozenset[Key] = frozenset()         # the bits the runs forked on (the facts' bits too)
    facts: tuple[NcFact, ...] = ()              # what the NC guarantees when the program starts

    def text(self) -> str:
        return (f"at the start of every cycle but the first, one of {len(self.states)} states holds, kept apart by "
                f"{', '.join(self.names)}: whole cycles followed path by path from any memory in the first cycle and "
                "then from each state found until none grows, with what the NC guarantees when the program starts, "
                "and only what nothing but the program writes kept between cycles")


def step_words(program: Program, outside: set[Key]) -> list[Key]:
    """The words CASE dispatches on (not through the index register) that keep their value between cycles, in
    program order."""
    found: list[Key] = []
    kept = kept_between_cycles(program, outside)
    for code in program.files:
        for op in code.ops:
            o = op.operand
            if op.code == "CASE" and o is not None and not o.indexed and o.kind in _WORDS:
                key = (o.kind, o.addr)
                if key not in found and kept(key):
                    found.append(key)
    return found


def start_states(program: Program, keys: Sequence[Key], split: set[Key], outside: set[Key], driven: set[Key],
                 names: Sequence[str] = (), budget: StepBudget | None = None) -> StartStates | None:
    """The states one of which holds at the start of every cycle but the first (see the module's docstring), kept
    apart by `keys`; runs fork on the bits of `split` where they are not known. `outside`: operands a scenario sets
    after power-on; `driven`: all a scenario sets; `budget`: the ops the runs may follow (spent as they run). None
    where a run gives up, the budget runs out or the states grow past the limits."""
    budget = budget or StepBudget()
    if not followable(program) or any(op.code == "SUBM" and (op.call is None or op.call.is_module or op.call.file < 0)
                                      for code in program.files for op in code.ops):
        return None
    keys = tuple(keys)
    split = set(split) | {k for k in keys if k[0] not in _WORDS}
    kept = kept_between_cycles(program, outside)
    facts = [f for f in applicable_facts(program, driven) if not f.bits or set(f.bits) & split]
    # (a fact's bits are forked on at the start: runs keep them apart, or what the fact narrowed is lost at a join)
    runner, apart = _keyed_runner(program, keys, split | {k for f in facts for k in f.bits})
    jobs = [op.call.key for code in program.files for op in code.ops
            if op.code == "SUBM" and op.call is not None and not op.call.is_module]
    marker = runner.first_cycle_marker()
    key_of = _key_reader(keys)
    parts: dict[tuple, _Path] = {}
    grown: dict[tuple, int] = {}
    # the states still to run a cycle from, by key value (a state that grows again before its run is run once)
    todo: dict[tuple | None, _Path] = {None: _Path({marker: 1} if marker is not None else {}, {})}
    cycles = 0
    stop = max(0, budget.left - _MAX_TOTAL_STEPS)          # (the budget left when this search gives up)
    try:
        while todo:
            cycles += 1
            if cycles > _MAX_CYCLES:
                return None
            runner.max_steps = budget.left - stop
            try:
                ends = _cycle_ends(runner, _nc_cases([todo.pop(next(iter(todo)))], facts), apart)
            finally:
                budget.spend(runner)
            for end in ends:
                for job in jobs:
                    runner.forget(end, runner.writes(job))
                end = _Path({k: v for k, v in end.bits.items() if kept(k)},
                            {k: v for k, v in end.words.items() if kept(k)})
                value = key_of(end)
                old = parts.get(value)
                new = end if old is None else _join(old, end)
                new = _Path(new.bits, new.words)
                if new == old:
                    continue
                if old is not None:
                    grown[value] = grown.get(value, 0) + 1
                    if grown[value] > _WIDEN_AFTER:
                        new = _widened(old, new)
                        if new == old:
                            continue
                parts[value] = new
                todo[value] = new.copy()
                if len(parts) > _MAX_PARTS:
                    return None
    except _GiveUp:
        return None
    states = tuple(state for part in parts.values() for state in _nc_cases([part.copy()], facts))
    return StartStates(keys, tuple(names) or tuple(f"{k[0]}{k[1]}" for k in keys), states,
                       frozenset(runner.split), tuple(facts))


def arrivals(program: Program, found: StartStates, points: Sequence[tuple[int, int]], reads: Sequence[tuple[int, int]]
             = (), split: set[Key] = frozenset(), budget: StepBudget | None = None
             ) -> dict[tuple[int, int], list[_Path]] | None:
    """The states in which each op of `points` (file, op index) runs in a cycle, on every path: from each of
    `found`'s states and, for the first cycle, from any memory with the first-cycle marker 1, with what the NC
    guarantees; the paths kept apart as `found`'s were, and by the bits of `split` too; the ops of `reads` record
    the values they read (path.reads, by op index). None where a run gives up or `budget` runs out."""
    budget = budget or StepBudget()
    runner, apart = _keyed_runner(program, found.keys, set(found.split) | set(split))
    runner.max_steps = budget.left
    marker = runner.first_cycle_marker()
    starts = [s.copy() for s in found.states] + _nc_cases([_Path({} if marker is None else {marker: 1}, {})],
                                                           found.facts)
    watch = _Watch({point: [] for point in points}, {})
    for f, i in reads:
        watch.reads[f] = watch.reads.get(f, frozenset()) | {i}
    try:
        _cycle_ends(runner, starts, apart, watch)
    except _GiveUp:
        return None
    finally:
        budget.spend(runner)
    return watch.found


def _keyed_runner(program: Program, keys: tuple[Key, ...], split: set[Key]) -> tuple[Runner, tuple[Key, ...]]:
    """A runner whose joined runs fork on `split`, and what its paths are kept apart by: the keys, then the forked
    bits."""
    runner = Runner(program)
    runner.fork_joined = True
    runner.split = split
    return runner, keys + tuple(sorted(split - set(keys)))


@dataclasses.dataclass(frozen=True)
class _Watch:
    """Where a keyed cycle run records the paths that come to an op (`found`: op -> paths), and the ops whose
    reads it records (`reads`: file -> op indices)."""

    found: dict[tuple[int, int], list[_Path]]
    reads: dict[int, frozenset[int]]


def _key_reader(keys: tuple[Key, ...]) -> Callable[[_Path], tuple]:
    """The values a path gives `keys` (None: not known; bits first, then words), as a function: the cycle runs call
    it for every path at every point where paths may meet."""
    bits = [k for k in keys if k[0] not in _WORDS]
    words = [k for k in keys if k[0] in _WORDS]
    return lambda path: (*map(path.bits.get, bits), *map(path.words.get, words))


def _widened(old: _Path, new: _Path) -> _Path:
    """`new` (a join with `old`) without the words whose values grew: any value of their width (a word that keeps
    growing, such as a counter, makes the search end so)."""
    return _Path(new.bits, {k: w for k, w in new.words.items() if old.words.get(k) == w})


# ------------------------------------------------------------------------------------------ what the NC guarantees

def _nc_cases(paths: list[_Path], facts: Sequence[NcFact]) -> list[_Path]:
    """`paths` split by what `facts` allow when the program starts: one path per value of a fact's bits that some
    value of its words lets hold, the words narrowed to the values that do (joined over those)."""
    for fact in facts:
        paths = [case for path in paths for case in _fact_cases(path, fact)]
    return paths


def _fact_cases(path: _Path, fact: NcFact) -> list[_Path]:
    bits, words = fact.bits, fact.words
    bit_values = [(path.bits[k],) if k in path.bits else (0, 1) for k in bits]
    word_parts = [_parts(path.words.get(k, _full(k[0])), fact.edges) for k in words]
    allowed: dict[tuple[int, ...], list[Word]] = {}
    for bv in itertools.product(*bit_values):
        for wv in itertools.product(*word_parts):
            values = dict(zip(bits, bv))
            values.update((k, w.lo) for k, w in zip(words, wv))
            if fact.holds(values):
                old = allowed.get(bv)
                allowed[bv] = list(wv) if old is None else [a.join(b) for a, b in zip(old, wv)]
    # values of the bits that leave the words alike are one case (what the bits are is then not known): a fact
    # that only ties its bits, or a strobe at 0 that frees the words, forks nothing
    cases: dict[tuple[Word, ...], list[tuple[int, ...]]] = {}
    for bv, wv in allowed.items():
        cases.setdefault(tuple(wv), []).append(bv)
    out = []
    for wv, group in cases.items():
        p = path.copy()
        p.bits.update((k, v) for n, (k, v) in enumerate(zip(bits, group[0])) if all(g[n] == v for g in group))
        p.words.update(zip(words, wv))
        out.append(p)
    return out


def _parts(word: Word, edges: tuple[int, ...]) -> list[Word]:
    """`word`'s values cut at a fact's edges (each edge, one below and one above, alone): a fact's truth is the same
    for every value of one part."""
    points = sorted({p for e in edges for p in (e - 1, e, e + 1)})
    cuts = [(p, p) for p in points]
    bounds = [-(1 << 40), *points, 1 << 40]
    cuts += [(a + 1, b - 1) for a, b in zip(bounds, bounds[1:]) if a + 1 <= b - 1]
    return [part for lo, hi in cuts for part in (word.meet(lo, hi),) if part is not None]


# ------------------------------------------------------------------------------------------ one cycle, keyed

def _cycle_ends(runner: Runner, starts: list[_Path], keys: tuple[Key, ...], watch: _Watch | None = None
                ) -> list[_Path]:
    """The states a cycle run from each of `starts` on every path ends in (joined where the values of `keys`
    agree); `watch`: where to record the paths that come to an op."""
    runner.target = (-1, -1)
    runner.leading = set()
    runner._leads = {}
    runner.steps = 0
    runner.joining += 1
    try:
        return _run_parted(runner, 0, 0, [p.copy() for p in starts], keys, 0, watch)
    finally:
        runner.joining -= 1


def _run_parted(runner: Runner, f: int, entry: int, paths: list[_Path], keys: tuple[Key, ...],
                depth: int, watch: _Watch | None = None) -> list[_Path]:
    """Runs the subprogram entered at (f, entry) from each of `paths` and those it calls likewise, the paths joined
    where they meet with the same key values and LA: the states it returns with (as Runner.summarize, whose loop
    rule it follows, keeping the key values apart)."""
    if depth > _DEPTH:
        raise _GiveUp
    ops = runner.program.files[f].ops
    heads = {op.target for op in ops if op.code in ("JPT", "JPF", "JP") and op.target is not None}
    pending: dict[int, dict] = {}
    returned: dict = {}
    key_of = _key_reader(keys)
    reads = watch.reads.get(f, frozenset()) if watch is not None else frozenset()
    watched = {i for g, i in watch.found if g == f} if watch is not None else set()

    def add(into: dict, q: _Path) -> None:
        # (paths with different LA kept apart too: a compare's two outcomes meet at the jump that decides on them)
        value = (key_of(q), q.la)
        into[value] = q if value not in into else _join(into[value], q)
        if len(into) > _MAX_PARTS:
            raise _GiveUp

    def run(i: int, path: _Path) -> tuple[int, list]:
        # straight on from op i where nothing else can meet the path (no jump target, no control op next): the
        # op it stopped after and what that op gave
        while True:
            runner.count()
            if i in watched:
                watch.found[f, i].append(path.copy())
            outs = runner.step(f, i, ops[i], path, runner.split, reads)
            if len(outs) != 1 or ops[i].code in _CONTROL:
                return i, outs
            g, j, q = outs[0]
            if g != f or j != i + 1 or j >= len(ops) or j in heads or ops[j].code in _CONTROL or len(q.calls) > 1:
                return i, outs
            i, path = j, q

    for p in paths:
        p.calls = (_RETURN,)
        add(pending.setdefault(entry, {}), p)
    entered: dict[int, list[_Path]] = {}
    widened: set[int] = set()
    while pending:
        first = min(pending)
        here = pending.pop(first)
        if not 0 <= first < len(ops):
            raise _GiveUp
        if first in heads:
            entered[first] = [p.copy() for p in here.values()]
        for path in here.values():
            i, outs = run(first, path)
            for g, j, q in outs:
                if (g, j) == _RETURN:
                    add(returned, q)
                    continue
                if len(q.calls) > 1:            # a call entered: its returns go on after it
                    back, q.calls = q.calls[-1], (_RETURN,)
                    if back[0] != f or back[1] <= i:
                        raise _GiveUp
                    for r in _run_parted(runner, g, j, [q], keys, depth + 1, watch):
                        r.calls = (_RETURN,)
                        add(pending.setdefault(back[1], {}), r)
                    continue
                if g != f or j <= i and j not in entered:
                    raise _GiveUp
                if j <= i:
                    if j in widened:
                        continue
                    widened = {a for a in widened if a < j} | {j}
                    for again in runner.pass_start(entered[j], f, entry, j, i):
                        add(pending.setdefault(j, {}), again)
                    continue
                add(pending.setdefault(j, {}), q)
    return list(returned.values())


# ------------------------------------------------------------------------------------------ which keys an item needs

_MAX_KEYS = 8               # bits an item's states are kept apart by, at most (more: no search, it would not end)
_THROUGH = 3                # bits recomputed every cycle followed back to what they are computed from, at most
_MAX_FORKS = 2              # NC operands and inputs an item's runs fork on, at most
_BIT_WRITES = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN"})
_DECIDES = frozenset({"JPT", "JPF", "EMT", "EMF", "CALLT", "CALLF"})


@dataclasses.dataclass(frozen=True)
class KeyChooser:
    """What choosing an item's keys needs of a program, worked out once for all its items: who writes which bit
    (_Feeds), the bits that carry a value from one cycle into the next, the words CASE dispatches on by their
    entries."""

    runner: Runner
    kept: Callable[[Key], bool]
    graph: _Feeds
    carried: frozenset[Key]
    dispatch: tuple[tuple[Key, frozenset[tuple[int, int]]], ...]      # (step word, the entries its CASEs call)

    @staticmethod
    def of(runner: Runner, table: DecisionTable, kept: Callable[[Key], bool]) -> KeyChooser:
        program = runner.program
        dispatch = tuple((word, frozenset(t.key for code in program.files for op in code.ops
                                          if op.code == "CASE" and op.operand is not None
                                          and (op.operand.kind, op.operand.addr) == word
                                          for t in op.case_targets if t is not None and not t.is_module))
                         for word in step_words(program, set()) if kept(word))
        return KeyChooser(runner, kept, _Feeds.of(runner, table), frozenset(_carried(runner, table)), dispatch)

    def keys(self, target: tuple[int, int], bits: Sequence[Key]) -> list[tuple[tuple[Key, ...], frozenset[Key]]]:
        """The key sets to try in turn, each with the bits to fork on, for the states an item at op `target`
        (file, op index) that reads `bits` is judged with. Keys: the step words whose CASE leads to it; the item's
        bits that carry a value from one cycle into the next (a subprogram reads them before writing them; a bit
        recomputed every cycle stands for those it is computed from); those the chains deciding whether their
        writes run read (jumps, module ends and conditional calls of the writing subprogram and its callers);
        then, first, the bits other entries of a CASE write where an entry writes one of the item's bits (at most
        one entry runs a cycle) that the item's writers read, and second, every carried bit those writers read.
        Forks: the NC operands and inputs the keys' writers read, at most _MAX_FORKS (an NC fact's bits first, then
        those read directly). A set of more than _MAX_KEYS bits is left out."""
        leading = self.runner._leading(target)
        words = tuple(word for word, entries in self.dispatch if entries & leading)
        graph, carried, kept = self.graph, self.carried, self.kept
        own = [b for b in self.sources(bits) if b in carried and kept(b)]
        deciding = [b for b in self.sources([c for b in own for c in graph.control.get(b, ())])
                    if b in carried and kept(b)]
        fed = [b for b in self.sources([c for b in own for c in graph.data.get(b, ())]) if b in carried and kept(b)]
        alternatives = [b for b in fed if any(b in graph.siblings.get(a, ()) for a in own)]
        tied = {k for fact in NC_FACTS for k in fact.bits}
        found: list[tuple[tuple[Key, ...], frozenset[Key]]] = []
        for chosen in (own + deciding + alternatives, own + deciding + fed):
            keys = list(dict.fromkeys(chosen))
            if len(keys) > _MAX_KEYS or any(words + tuple(keys) == f[0] for f in found):
                continue
            direct = [c for b in keys for c in graph.data.get(b, ())]
            forks = [b for b in dict.fromkeys(self.sources(direct)) if b in NC_MODEL_OWNED or b[0] == "I"]
            # (those an NC fact ties to other operands first, then those the writers read themselves)
            forks.sort(key=lambda b: (b not in tied, b not in direct))
            found.append((words + tuple(keys), frozenset(forks[:_MAX_FORKS])))
        return found

    def sources(self, start: Sequence[Key]) -> list[Key]:
        """The carried, NC and input bits `start` stands for: bits recomputed every cycle followed back to what
        they are computed from (_THROUGH writers at most)."""
        found: list[Key] = []
        level, seen = list(start), set(start)
        for _ in range(_THROUGH + 1):
            nxt: list[Key] = []
            for b in level:
                if b in self.carried or b in NC_MODEL_OWNED or b[0] == "I":
                    found.append(b)
                elif self.kept(b):
                    nxt += [c for c in (*self.graph.data.get(b, ()), *self.graph.control.get(b, ())) if c not in seen]
                    seen.update(nxt)
            level = nxt
        return found


def merged_keys(needs: Sequence[tuple[tuple[Key, ...], frozenset[Key]]]
                ) -> list[tuple[tuple[Key, ...], frozenset[Key]]]:
    """`needs` (KeyChooser.keys of several items) with those that share their step words merged into one search (their
    bits and forks together) where the merged bits stay within _MAX_KEYS: one search then judges them all."""
    groups: dict[tuple[Key, ...], tuple[list[Key], set[Key]]] = {}
    for keys, split in needs:
        bits, forks = groups.setdefault(tuple(k for k in keys if k[0] in _WORDS), ([], set()))
        bits += [k for k in keys if k[0] not in _WORDS and k not in bits]
        forks |= split
    out = []
    for keys, split in needs:
        words = tuple(k for k in keys if k[0] in _WORDS)
        bits, forks = groups[words]
        out.append((words + tuple(bits), frozenset(forks)) if len(bits) <= _MAX_KEYS else (keys, split))
    return out


@dataclasses.dataclass(frozen=True)
class _Feeds:
    """For each bit the program writes by name: `data`, the bits the chains that write it read; `control`, the bits
    the chains deciding whether those writes run read (the jumps, module ends and conditional calls of the writing
    subprogram, and of those that call it); `siblings`, the bits the other entries of a CASE write where an entry
    writes it."""

    data: dict[Key, list[Key]]
    control: dict[Key, list[Key]]
    siblings: dict[Key, set[Key]]

    @staticmethod
    def of(runner: Runner, table: DecisionTable) -> _Feeds:
        program = runner.program
        deciding: dict[tuple[int, int], list[Key]] = {}
        for d in table.decisions:
            if d.op.code in _DECIDES:
                for entry in runner.entries:
                    if (d.file, d.index) in runner.reach(entry):
                        deciding.setdefault(entry, []).extend(chain_bits(d))
        data: dict[Key, list[Key]] = {}
        for d in table.decisions:
            o = d.op.operand
            if d.op.code in _BIT_WRITES and o is not None and o.is_bit and not o.indexed:
                data.setdefault((o.kind, o.addr), []).extend(chain_bits(d))
        control: dict[Key, list[Key]] = {}
        written_in: dict[tuple[int, int], set[Key]] = {}
        for f, code in enumerate(program.files):
            for i, op in enumerate(code.ops):
                o = op.operand
                if op.code not in (*_BIT_WRITES, "STBITS") or o is None or not o.is_bit or o.indexed:
                    continue
                inner = [e for e in runner.entries if (f, i) in runner.reach(e)]
                around = inner + [e for a in inner for c in runner.callers.get(a, ()) for e in runner.entries
                                  if c[0] >= 0 and c in runner.reach(e)]
                for n in range(op.nbits if op.code == "STBITS" else 1):
                    key = (o.kind, o.addr + n)
                    control.setdefault(key, []).extend(b for e in around for b in deciding.get(e, ()))
                    for e in inner:
                        written_in.setdefault(e, set()).add(key)
        siblings: dict[Key, set[Key]] = {}
        for code in program.files:
            for op in code.ops:
                entries = [t.key for t in op.case_targets if t is not None and not t.is_module]
                for a in entries:
                    for key in written_in.get(a, ()):
                        siblings.setdefault(key, set()).update(
                            k for b in entries if b != a for k in written_in.get(b, ()))
        return _Feeds(data, control, siblings)


def _carried(runner: Runner, table: DecisionTable) -> set[Key]:
    """Bits a subprogram reads where no write of its own before (in op order) has set them: what they hold may come
    from an earlier cycle."""
    written: dict[tuple[int, int], dict[Key, int]] = {}
    for entry in runner.entries:
        first: dict[Key, int] = {}
        for f, i in sorted(runner.reach(entry)):
            op = runner.program.files[f].ops[i]
            o = op.operand
            if op.code in (*_BIT_WRITES, "STBITS") and o is not None and o.is_bit and not o.indexed:
                for n in range(op.nbits if op.code == "STBITS" else 1):
                    first.setdefault((o.kind, o.addr + n), i)
        written[entry] = first
    found: set[Key] = set()
    for d in table.decisions:
        for c in d.conditions:
            o = c.operand
            if o is None or o.indexed or not o.is_bit:
                continue
            key = (o.kind, o.addr)
            if all(written[e].get(key, c.index) >= c.index for e in runner.entries if (c.file, c.index) in
                   runner.reach(e)):
                found.add(key)
    return found


def chain_bits(decision: Decision) -> list[Key]:
    """The bit operands a chain reads by name, in order."""
    return [(c.operand.kind, c.operand.addr) for c in decision.conditions
            if c.operand is not None and c.operand.is_bit and not c.operand.indexed]
