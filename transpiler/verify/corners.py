"""Corner values of a program: the constants it compares against, harvested from the IR, and the operands the
stimulus may drive with them (inputs, and words and markers the program reads but never writes).

A mutated comparison or constant differs from the original only at the edges of the program's own constants
(c-1, c, c+1) or outside the ranges it decodes; random values almost never land there. The guided search
(verify/guided.py) draws its values and NC jobs from a Corners."""

from __future__ import annotations

import dataclasses
import random
from typing import Any, Mapping

from transpiler.ir import Program
from transpiler.verify.nc_facts import NC_MODEL_OWNED
from transpiler.verify.scenario import NameTable, OperandRef
from transpiler.verify.simulate import indexed_operands, program_operands

# Values worth trying on any word besides the program's constants: the edges of the signed ranges and 0.
_EDGES = (0, 1, -1, 127, 128, 255, 256, 32767, -32768, 65535)
_WIDTH_BITS = {"B": 8, "W": 16, "D": 32}
_WORD_MAX = 32767        # scenario values of W-sized NC fields (tool, pocket, mode, M code) are 0..32767


@dataclasses.dataclass(frozen=True)
class Corners:
    """What the stimulus draws from: the program's constants and the operands it may drive."""

    constants: tuple[int, ...]                    # every K value and KFIELD entry of the program
    tables: tuple[int, ...]                       # KFIELD entries and numbers compared with an NC word (decoded
                                                  # numbers such as M codes)
    values: tuple[int, ...]                       # c-1, c, c+1 of every constant, plus the range edges
    inputs: tuple[str, ...]                       # display names of the inputs the program reads
    foreign_words: tuple[tuple[str, str], ...]    # (name, kind) of B/W/D read, never written, not the NC model's
    foreign_markers: tuple[str, ...]              # markers read, never written, not the NC model's
    # (name, kind) of B/W/D whose power-on value the stimulus chooses: the ones the program writes, and the ones
    # it only reads outside the NC interface (memory another module fills)
    remanent_words: tuple[tuple[str, str], ...]
    remanent_markers: tuple[str, ...]             # markers the program writes (start values)
    # (name, kind, constant) of a drivable word the program compares with a constant, directly or through copies:
    # the stimulus can put it one below, at and one above the constant (a fuzzer's compare log, found statically)
    compare_pairs: tuple[tuple[str, str, int], ...] = ()
    # the drivable words whose power-on value reaches a compare of a word with a constant (boundary_sources): the
    # search tries each boundary value a run has not shown yet from them first, before random mutations
    boundary_sources: tuple["BoundarySource", ...] = ()

    def word_value(self, rng: random.Random, kind: str) -> int:
        """A value in the range of a `kind` (B/W/D) operand: mostly near a constant, sometimes an edge, sometimes
        a random bit pattern (a status word the program unpacks into bits has no constant to be near: a random
        pattern sets any few of its bits at once with a fair chance)."""
        bits = _WIDTH_BITS.get(kind, 16)
        draw = rng.random()
        if draw < 0.7:
            value = rng.choice(self.values)
        elif draw < 0.85:
            value = rng.choice(_EDGES)
        else:
            value = rng.randint(-(1 << (bits - 1)), (1 << (bits - 1)) - 1)
        return self.clamp(value, kind)

    def pattern_value(self, rng: random.Random, kind: str) -> int:
        """A value of a `kind` (B/W/D) operand whose bytes are all non-zero and all different, the upper ones small
        (1..15, so that a word used as a loop bound stays a few thousand at most): memory at power-on that tells
        each byte from its neighbours and from 0, so that a store or read one byte off shows."""
        count = _WIDTH_BITS.get(kind, 16) // 8
        low = rng.randrange(16, 256)
        upper = rng.sample(range(1, 16), count - 1)
        value = low + sum(b << (8 * (i + 1)) for i, b in enumerate(upper))
        return _signed(value, kind)

    def power_on(self, rng: random.Random) -> dict[str, int]:
        """Remanent memory as an earlier run may have left it: every word the stimulus may start, half of them at a
        byte pattern (pattern_value), the others at a corner value (word_value), and every written marker at 0
        or 1."""
        memory = {name: self.pattern_value(rng, kind) if rng.random() < 0.5 else self.word_value(rng, kind)
                  for name, kind in self.remanent_words}
        memory.update((marker, rng.randrange(2)) for marker in self.remanent_markers)
        return memory

    @staticmethod
    def clamp(value: int, kind: str) -> int:
        """`value` limited to the signed range of a `kind` (B/W/D) operand."""
        bits = _WIDTH_BITS.get(kind, 16)
        return max(-(1 << (bits - 1)), min((1 << (bits - 1)) - 1, value))

    def nc_value(self, rng: random.Random, low: int = 0, high: int = _WORD_MAX) -> int:
        """A corner value for an NC field (M code, tool, pocket, mode, ...) within low..high."""
        candidates = [v for v in self.values if low <= v <= high] or [low]
        pick = rng.choice(candidates) if rng.random() < 0.9 else rng.randint(low, min(high, 1000))
        return pick

    def nc_action(self, rng: random.Random, kind: str | None = None) -> dict[str, Any]:
        """One NC job (of `kind`, else of a random kind) with values at the program's corners (also 0 and out of
        the decoded ranges)."""
        kind = kind or rng.choice(_NC_KINDS)
        if kind == "m_function":
            # Mostly a number of a table the program decodes (its M codes), or one next to it.
            if self.tables and rng.random() < 0.7:
                return {kind: max(0, min(_WORD_MAX, rng.choice(self.tables) + rng.choice((0, 0, 0, -1, 1))))}
            return {kind: self.nc_value(rng)}
        if kind in ("tool_call", "tool_def"):
            # a quarter of the jobs have no pocket (0 or -1: a tool without one, or the spindle tool's)
            pocket = rng.choice((-1, 0)) if rng.random() < 0.25 else self.nc_value(rng, -1)
            job = {"tool": self.nc_value(rng), "pocket": pocket}
            if kind == "tool_call" and rng.random() < 0.2:
                job["second_strobe"] = True
            return {kind: job}
        if kind == "spindle_speed":
            return {kind: self.nc_value(rng, 0, 1 << 20) if rng.random() < 0.7 else rng.choice((0, 1500, 24000))}
        if kind == "gear":
            return {kind: rng.randint(0, 4)}
        if kind == "mode":
            return {kind: self.nc_value(rng, 0, 16)}
        if kind == "fn19":
            return {kind: {"value1": self.word_value(rng, "D"), "value2": self.word_value(rng, "D")}}
        return {kind: rng.choice(("program", "machine_parameters"))}


_NC_KINDS = ("m_function", "m_function", "m_function", "tool_call", "tool_call", "tool_def", "spindle_speed", "gear",
             "mode", "mode", "fn19", "restart")


def _signed(value: int, kind: str) -> int:
    """`value` wrapped into the signed range of a `kind` (B/W/D) operand (K$FF compared with a byte is -1)."""
    bits = _WIDTH_BITS.get(kind, 16)
    value &= (1 << bits) - 1
    return value - (1 << bits) if value >> (bits - 1) else value


def harvest(program: Program, names: NameTable) -> Corners:
    """The constants of the program (compare operands, K values, KFIELD tables such as decoded M-function numbers,
    CASE limits, tool/pocket and mode values) and the operands the stimulus may drive."""
    constants: set[int] = set()
    tables: set[int] = set()
    for code in program.files:
        for op in code.ops:
            operand = op.operand
            if operand is None:
                continue
            if operand.kind == "K":
                constants.add(operand.addr)
            elif operand.kind == "KF":
                constants.update(operand.kfield)
                tables.update(operand.kfield)
    used, written, _ = program_operands(program)
    # operands reached through the index register count as named ones: a table read or filled through X
    indexed_read, indexed_written = indexed_operands(program)
    used = used | indexed_read | indexed_written
    written = written | indexed_written
    # a constant compared with a byte or word counts at that width too (K$FF against a byte is -1)
    compared, sources = _compares(program)
    constants |= {const for _, const in compared}
    # a number compared with a word of the NC interface (the M code, a tool number) is one the program decodes, as
    # the entries of a table are: NC jobs draw from these
    tables |= {const for word, const in compared if (word.kind, word.addr) in NC_MODEL_OWNED and const >= 0}
    values = {c + d for c in constants for d in (-1, 0, 1)} | set(_EDGES)
    profile = program.semantics.profile

    def name(ref: OperandRef) -> str:
        return names.display_name(ref)

    def drivable(ref: OperandRef) -> bool:
        return (ref.kind, ref.addr) not in NC_MODEL_OWNED and name(ref) not in names.non_toggle

    foreign = sorted((r for r in set(used) - set(written) if drivable(r)), key=lambda r: (r.kind, r.addr))
    # Only interface words: a B/W/D the program reads but never writes outside the NC interface is memory the
    # program expects another module to fill, and is set through `initial` like the remanent words.
    foreign_byte_memory = [r for r in foreign if r.kind in _WIDTH_BITS]
    interface = {r for r in foreign_byte_memory if profile.is_interface(r.kind, r.addr, _WIDTH_BITS[r.kind] // 8)}
    foreign_words = tuple((name(r), r.kind) for r in foreign_byte_memory if r in interface)
    foreign_markers = tuple(name(r) for r in foreign if r.kind == "M")
    filled_elsewhere = {r for r in foreign_byte_memory if r not in interface}
    remanent = sorted((r for r in set(written) | filled_elsewhere if drivable(r)), key=lambda r: (r.kind, r.addr))
    remanent_words = tuple((name(r), r.kind) for r in remanent if r.kind in _WIDTH_BITS)
    return Corners(
        compare_pairs=_compare_pairs(compared, sources, dict(foreign_words + remanent_words), name),
        boundary_sources=boundary_sources(program, dict(foreign_words + remanent_words), name),
        constants=tuple(sorted(constants)),
        tables=tuple(sorted(tables)),
        values=tuple(sorted(values)),
        inputs=tuple(sorted({name(r) for r in used if r.kind == "I" and name(r) not in names.non_toggle})),
        foreign_words=foreign_words,
        foreign_markers=foreign_markers,
        remanent_words=remanent_words,
        remanent_markers=tuple(name(r) for r in remanent if r.kind == "M"))


_COPY_DEPTH = 3             # copies followed back from a compared word (`L W32` `= W8` ... `L W8` `< K10`)


def _compares(program: Program) -> tuple[set[tuple[OperandRef, int]], dict[OperandRef, set[OperandRef]]]:
    """(each word compared with a constant by a load and a compare in a row (`L W10` `> K100`, or `L K100`
    `< W10`), with the constant at the word's width; each word's sources: the words loaded and stored into it in
    a row)."""
    compared: set[tuple[OperandRef, int]] = set()
    sources: dict[OperandRef, set[OperandRef]] = {}
    for code in program.files:
        for prev, op in zip(code.ops, code.ops[1:]):
            if prev.code != "WLD" or op.operand is None or prev.operand is None:
                continue
            if op.code == "WST" and _plain_word(prev.operand) and _plain_word(op.operand):
                sources.setdefault(_ref(op.operand), set()).add(_ref(prev.operand))
            if op.code != "CMP":
                continue
            word, const = (prev.operand, op.operand) if op.operand.kind == "K" else (op.operand, prev.operand)
            if const.kind == "K" and _plain_word(word):
                compared.add((_ref(word), _signed(const.addr, word.kind)))
    return compared, sources


def _compare_pairs(compared, sources, drivable: dict[str, str], name) -> tuple[tuple[str, str, int], ...]:
    """Each word compared with a constant, and each word it is copied from (a few copies back; `compared` and
    `sources` as _compares gives them), where the stimulus may drive that word: the program often works on a copy
    of the word the machine supplies."""
    pairs: set[tuple[str, str, int]] = set()
    for word, const in compared:
        reached, frontier = {word}, {word}
        for _ in range(_COPY_DEPTH):
            frontier = {src for w in frontier for src in sources.get(w, ())} - reached
            reached |= frontier
        for ref in reached:
            if name(ref) in drivable:
                pairs.add((name(ref), ref.kind, const))
    return tuple(sorted(pairs))


@dataclasses.dataclass(frozen=True)
class BoundarySource:
    """A word the stimulus may start at power-on whose value reaches a compare of a word with a constant: there the
    compared word is `coefficient` x the source + `offset` + the sum of the `others` (name, coefficient) at their
    start values, through copies (`L W8` `= W10`), sums and differences with constants and other words on the way
    (`L W8` `- W12` `+ K24` `MOD K24` `= W10`, the remainder taken as the value itself, as for small values), and
    parameters passed on the data stack (`PS W8` `CM Sub`, `LBL Sub` `PL W10`). A way to pick start values, not a
    claim: a run shows whether the value reached the compare."""

    op: int             # the compare's op id (every file's ops numbered in order, as the coverage numbers them)
    name: str           # display name of the source word
    kind: str
    coefficient: int    # 1 or -1
    offset: int
    others: tuple[tuple[str, int], ...]
    constant: int
    word_left: bool     # `L W10` `< K5` (the boundary difference is word - constant), not `L K5` `> W10`

    def value(self, difference: int, initial: Mapping[str, Any]) -> int | None:
        """The source's start value that gives the compare `difference` (left - right) where the other words start
        as `initial` has them (0 where it leaves them out), None where it does not fit the source's width."""
        word = self.constant + difference if self.word_left else self.constant - difference
        rest = self.offset
        for name, coefficient in self.others:
            start = initial.get(name, 0)
            if not isinstance(start, int):
                return None
            rest += coefficient * start
        value = (word - rest) * self.coefficient
        return value if Corners.clamp(value, self.kind) == value else None


def boundary_sources(program: Program, drivable: dict[str, str], name) -> tuple[BoundarySource, ...]:
    """Each compare of a plain word with a constant and each drivable word (display name -> kind) whose power-on
    value reaches it, a few steps back (_COPY_DEPTH; see BoundarySource)."""
    feeds = _linear_feeds(program)
    found: list[BoundarySource] = []
    opid = 0
    for code in program.files:
        for prev, op in zip((None, *code.ops), code.ops):
            if op.code == "CMP" and prev is not None and prev.code == "WLD" and op.operand is not None \
                    and prev.operand is not None:
                left = op.operand.kind == "K"
                word, const = (prev.operand, op.operand) if left else (op.operand, prev.operand)
                if const.kind == "K" and _plain_word(word):
                    constant = _signed(const.addr, word.kind)
                    for ref, coefficient, offset, others in _ways_back(_ref(word), feeds):
                        if name(ref) in drivable:
                            found.append(BoundarySource(opid, name(ref), ref.kind, coefficient, offset,
                                                        tuple((name(o), c) for o, c in others), constant, left))
            opid += 1
    return tuple(found)


Linear = tuple[OperandRef, int, int, tuple[tuple[OperandRef, int], ...]]   # (source, coefficient, offset, others)


def _ways_back(word: OperandRef, feeds: dict[OperandRef, list[Linear]]) -> list[Linear]:
    """The words `word` is made from, a few steps back, each as a linear function (word = coefficient x source +
    offset + others); the first way found to each source."""
    ways: dict[OperandRef, Linear] = {word: (word, 1, 0, ())}
    frontier = [ways[word]]
    for _ in range(_COPY_DEPTH):
        nxt: list[Linear] = []
        for ref, coefficient, offset, others in frontier:
            for src, a, more, extra in feeds.get(ref, ()):
                if src in ways:
                    continue
                way = (src, coefficient * a, offset + coefficient * more,
                       others + tuple((o, coefficient * c) for o, c in extra))
                ways[src] = way
                nxt.append(way)
        frontier = nxt
    return [ways[ref] for ref in sorted(ways, key=lambda r: (r.kind, r.addr))]


def _linear_feeds(program: Program) -> dict[OperandRef, list[Linear]]:
    """Word -> the ways a store makes it from other words: `L W8` [`+`/`-` a constant or a plain word]...
    [`MOD K`] `= W10` gives W10 from W8 (coefficient 1) and from each word added (1) or subtracted (-1), the rest
    as offset and others; a parameter pulled from the data stack comes from the word pushed for it."""
    feeds: dict[OperandRef, list[Linear]] = {}
    for code in program.files:
        ops = code.ops
        for i, op in enumerate(ops):
            if op.code != "WLD" or op.operand is None or not _plain_word(op.operand):
                continue
            terms: list[tuple[OperandRef, int]] = [(_ref(op.operand), 1)]
            offset, j = 0, i + 1
            while j < len(ops) and ops[j].operand is not None and (
                    ops[j].code in ("ADD", "SUB") and (ops[j].operand.kind == "K" or _plain_word(ops[j].operand))
                    or ops[j].code == "MOD" and ops[j].operand.kind == "K"):
                sign = -1 if ops[j].code == "SUB" else 1
                if ops[j].code != "MOD" and ops[j].operand.kind == "K":
                    offset += sign * _signed(ops[j].operand.addr, "D")
                elif ops[j].code != "MOD":
                    terms.append((_ref(ops[j].operand), sign))
                j += 1
            if j >= len(ops) or ops[j].code != "WST" or ops[j].operand is None or not _plain_word(ops[j].operand):
                continue
            target = _ref(ops[j].operand)
            for k, (src, a) in enumerate(terms):
                others = tuple(t for n, t in enumerate(terms) if n != k)
                # word = a x src + offset + others  ->  per source, coefficient a (1 or -1)
                feeds.setdefault(target, []).append((src, a, offset, others))
    for word, source in _stack_copies(program):
        feeds.setdefault(word, []).append((source, 1, 0, ()))
    return feeds


def _stack_copies(program: Program) -> set[tuple[OperandRef, OperandRef]]:
    """(word, source) of each parameter a subprogram takes from the data stack: the words pushed just before a call
    (`PS W8` `PS W10` `CM Sub`) and pulled first thing in the subprogram (`LBL Sub` `PL W20` `PL W22`), the last
    pushed pulled first (W20 from W10, W22 from W8): the program's usual way of passing a word on."""
    found: set[tuple[OperandRef, OperandRef]] = set()
    for code in program.files:
        for i, op in enumerate(code.ops):
            target = op.call
            if op.code != "CALL" or target is None or target.is_module or target.file < 0:
                continue
            pushed: list = []
            j = i - 1
            while j >= 0 and code.ops[j].code == "PUSH" and code.ops[j].operand is not None:
                pushed.append(code.ops[j].operand)        # last pushed first
                j -= 1
            callee = program.files[target.file].ops
            k = target.index
            while k < len(callee) and callee[k].code == "LBL":
                k += 1
            for source in pushed:
                if k >= len(callee) or callee[k].code != "POP" or callee[k].operand is None:
                    break
                word = callee[k].operand
                if _plain_word(source) and _plain_word(word) and source.kind == word.kind:
                    found.add((_ref(word), _ref(source)))
                k += 1
    return found


def _plain_word(operand) -> bool:
    return operand.kind in _WIDTH_BITS and not operand.indexed


def _ref(operand) -> OperandRef:
    return OperandRef(operand.kind, operand.addr)
