"""What the NC model writes to the PLC (runtime_shim/hh_nc.c: the one executable model the reference machine and the
compiled side both run): the operands it owns, and facts that hold of those operands at every instant of every PLC
cycle. The NC writes only in the cycle's first phase, so a fact true after that phase stays true through the cycle
as long as nothing else writes its operands: not the program (named, through the index register, a data table),
not a scenario, and no operand the stimulus may drive overlaps them (`applicable_facts`).

The MC/DC analysis takes the facts as constraints on the condition values a chain can see (implication.py);
tests/test_nc_facts.py drives the NC model with random jobs and checks every fact after every phase, so the table
and the C model cannot drift apart unnoticed."""

from __future__ import annotations

import dataclasses
from typing import Callable, Mapping

from transpiler.ir import Program
from transpiler.language.module_table import writes_anywhere
from transpiler.verify.index_range import index_ranges
from transpiler.verify.scenario import NC_VALUE_RANGES
from transpiler.verify.simulate import indexed_operands, operand_writers, program_operands

Key = tuple[str, int]

# Operands the NC model itself writes for `nc:` actions (iTNC and TNC 407 numbers): the stimulus never sets them
# directly, or a strobe or mode word would change behind the model's back.
NC_MODEL_OWNED = frozenset({
    ("W", 256), ("W", 260), ("W", 262), ("W", 264), ("W", 272), ("D", 280), ("D", 284), ("D", 356),
    *(("M", m) for m in (4070, 4071, 4072, 4073, 4074, 4075, 4172, 4173, 4174, 4520, 4521, 4522, 4523, 2045)),
})

# TOOL CALL (hh_nc.c write_codes): tool number, pocket and exactly one of the three markers, written together with
# the strobe; TOOL DEF writes the two words only.
TOOL_CALL_STROBE: Key = ("M", 4073)
TOOL_T0: Key = ("M", 4521)
TOOL_WITH_POCKET: Key = ("M", 4522)
TOOL_NO_POCKET: Key = ("M", 4523)
TOOL_NUMBER: Key = ("W", 264)
TOOL_POCKET: Key = ("W", 262)
_FLAGS = (TOOL_T0, TOOL_WITH_POCKET, TOOL_NO_POCKET)
_WIDTH = {"B": 1, "W": 2, "D": 4}
_BYTE_KINDS = frozenset(_WIDTH)
_WRITE_CODES = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN", "STBITS", "WST", "POP", "INC", "DEC"})


@dataclasses.dataclass(frozen=True)
class NcFact:
    """A relation between operands the NC model owns that holds whenever the PLC program runs. `holds` takes the
    operands' values (bits 0/1, words signed in their width); `edges` are the word values around which its truth
    may change (it is the same for every value between two neighbouring edges): a word is tried at each edge, one
    below and one above, and at its limits. `plc_owned`: operands of the fact the program writes (a handshake's
    acknowledgement): the NC reads them in its phase, so the fact holds when the program starts and stays true at
    a point of the cycle only while no write before that point can break it (mcdc.py checks the cycle order)."""

    operands: tuple[Key, ...]
    holds: Callable[[Mapping[Key, int]], bool]
    edges: tuple[int, ...]
    text: str
    plc_owned: tuple[Key, ...] = ()

    @property
    def words(self) -> tuple[Key, ...]:
        return tuple(k for k in self.operands if k[0] in _BYTE_KINDS)

    @property
    def bits(self) -> tuple[Key, ...]:
        return tuple(k for k in self.operands if k[0] not in _BYTE_KINDS)


def _one_flag_at_most(v: Mapping[Key, int]) -> bool:
    return sum(v[k] for k in _FLAGS) <= 1


def _flags_describe_the_call(v: Mapping[Key, int]) -> bool:
    if not v[TOOL_CALL_STROBE]:
        return True
    which = TOOL_T0 if v[TOOL_NUMBER] == 0 else TOOL_WITH_POCKET if v[TOOL_POCKET] >= 1 else TOOL_NO_POCKET
    return all(v[k] == (k == which) for k in _FLAGS)


def _handshake(strobe: int, ack: int) -> NcFact:
    """hh_nc.c step(): the NC raises a strobe only when it reads the acknowledgement as 0 in that phase, and drops
    it in the phase it reads the acknowledgement as 1. The scenario's writes come before the NC phase of their
    cycle, so the NC reads them too."""
    s, a = ("M", strobe), ("M", ack)
    return NcFact((s, a), lambda v: not (v[s] and v[a]), (),
                  f"the NC raises the strobe M{strobe} only while it reads the acknowledgement M{ack} as 0 and "
                  f"drops it in the phase it reads 1, so when the cycle's program starts M{strobe} = 1 only with "
                  f"M{ack} = 0; no write before this chain in the cycle can set M{ack} (NC model)", (a,))


# The strobe/acknowledgement pairs of hh_nc.c (ITNC_KINDS, the TOOL CALL's second strobe M4520 with M4093, the TNC
# 407's M-function pair).
_HANDSHAKES = ((4070, 4090), (4071, 4091), (4072, 4092), (4073, 4093), (4520, 4093), (4074, 4094), (4075, 4095),
               (2045, 2482))

def _word_range(word: Key, field: str, what: str) -> NcFact:
    """A word only the NC writes holds what the scenario format lets an NC action carry (NC_VALUE_RANGES: the NC
    model writes the action's value as given) or its power-on value 0 (W272: the mode, 1 until a scenario sets
    one)."""
    low, high = NC_VALUE_RANGES[field]
    assert low <= 0 <= high and low <= 1 <= high      # the power-on value and the default mode lie inside
    return NcFact((word,), lambda v: low <= v[word] <= high, (low, high),
                  f"the NC writes only {low}..{high} to {word[0]}{word[1]} ({what}) and nothing else writes it (NC "
                  "model)")


# The interface words each NC action writes (hh_nc.c write_codes; W272 also in every phase, from the last mode).
_WORD_RANGES = (
    (("W", 256), "gear", "the gear range of the spindle job"), (("W", 260), "m_function", "the M code"),
    (TOOL_POCKET, "pocket", "the pocket of TOOL CALL and TOOL DEF"),
    (TOOL_NUMBER, "tool", "the tool of TOOL CALL and TOOL DEF"), (("W", 272), "mode", "the operating mode"),
    (("D", 356), "spindle_speed", "the spindle speed"),
)

NC_FACTS: tuple[NcFact, ...] = (
    NcFact(_FLAGS, _one_flag_at_most, (),
           "M4521, M4522 and M4523 are never 1 two at a time: the NC sets exactly one of them with each TOOL CALL "
           "and none before the first (NC model)"),
    NcFact((TOOL_CALL_STROBE, *_FLAGS, TOOL_NUMBER, TOOL_POCKET), _flags_describe_the_call, (0, 1),
           "while the TOOL CALL strobe M4073 is 1, exactly one of M4521 (W264 = 0), M4522 (W262 >= 1) and M4523 "
           "(W262 <= 0) is 1, the one that fits W264 and W262: the NC writes all of them with the strobe and writes "
           "none of them again (no TOOL DEF either) before that handshake ends (NC model)"),
    *(_handshake(strobe, ack) for strobe, ack in _HANDSHAKES),
    *(_word_range(word, field, what) for word, field, what in _WORD_RANGES),
)


def _span(kind: str, addr: int, width: int = 1) -> tuple[str, int, int]:
    """The cells an operand occupies: B/W/D share one byte memory, bits are one cell of their own kind."""
    if kind in _BYTE_KINDS:
        return ("mem", addr, addr + _WIDTH[kind] * width)
    return (kind, addr, addr + width)


def _overlaps(a: tuple[str, int, int], b: tuple[str, int, int]) -> bool:
    return a[0] == b[0] and a[1] < b[2] and b[1] < a[2]


def applicable_facts(program: Program, driven: set[tuple[str, int]]) -> tuple[NcFact, ...]:
    """The facts of NC_FACTS nothing but the NC can break in this program: none of their operands is written by the
    program (by name, through the index register where it can reach them, by a data table), set by a scenario
    (`driven`), or overlapped by another byte, word or double word the program names (which the generated
    stimulus may set). A fact's `plc_owned` operands may be written by name and by a scenario (see NcFact); not
    through the index register or by a data table (which loads after the NC phase). A PLC module that writes to
    an address it is given, or one the module table does not know, may write anywhere: then no fact applies."""
    if any(_writes_anywhere(op) for code in program.files for op in code.ops):
        return ()
    _, written, _ = program_operands(program)
    named_cells = [_span(r.kind, r.addr) for r in written] + [_span(k, a) for k, a in driven]
    written_cells = [_span(r.kind, r.addr) for r in program.data_rows]
    named_read, _ = indexed_operands(program)
    used, _, _ = program_operands(program)
    ranges = index_ranges(program)
    for f, code in enumerate(program.files):
        for i, op in enumerate(code.ops):
            o = op.operand
            if o is None or not o.indexed or op.code not in _WRITE_CODES:
                continue
            x = ranges.get((f, i))
            width = op.nbits if op.code == "STBITS" else 1
            if x is None:
                written_cells.append(_span(o.kind, 0, 1 << 20) if o.kind not in _BYTE_KINDS else ("mem", 0, 1 << 30))
                continue
            size = _WIDTH.get(o.kind, 1)
            # the index counts bytes, or elements where the dialect scales it: both reaches are covered
            low = o.addr + min(x[0], x[0] * size)
            high = o.addr + max(x[1], x[1] * size) + size * width
            written_cells.append(((o.kind if o.kind not in _BYTE_KINDS else "mem"), low, high))
    others = [_span(r.kind, r.addr) + ((r.kind, r.addr),) for r in used | named_read if r.kind in _BYTE_KINDS]
    found = []
    for fact in NC_FACTS:
        cells = [_span(*k) for k in fact.operands]
        if any(_overlaps(c, w) for c in cells for w in written_cells):
            continue
        if any(_overlaps(_span(*k), w) for k in fact.operands if k not in fact.plc_owned for w in named_cells):
            continue
        if any(_overlaps(_span(*k), o[:3]) and o[3] != k for k in fact.words for o in others):
            continue
        found.append(fact)
    return tuple(found)


def _writes_anywhere(op) -> bool:
    return op.call is not None and op.call.is_module and writes_anywhere(op.call.module)
