"""Decisions and conditions of a program, found statically over the IR: every logic chain that ends in an assignment
(`=`, `=N`, `S`, `R`, `SN`, `RN`) or a conditional jump, call or module end, as a boolean function of its conditions,
and every word compare with the values one below, at and one above its other side.

A condition is one read that feeds the chain: a bit operand loaded or gated (A, AN, O, ON, XO, XON, also inside
brackets), a word or string compare, a bit test, a logic value pulled from the stack. Its value is the value read,
before any negation of the instruction (`AN M5` has the condition M5, and the chain's function negates it). The
decision's outcome is LA when the chain's first consumer runs; later consumers of the same LA (repeated
assignments) are the same decision. The interpreter records, with coverage, each distinct vector of condition values
and outcome of a decision (compile.py), and the verify side finds the MC/DC pairs in them (verify/mcdc.py).

A chain is followed in op order within a block only: a jump target, a label, a call, a CASE or an unconditional
jump forgets it (LA may come from elsewhere there), and so does a word instruction when LA is bit 7 of WA (A-05
shared_bit7)."""

from __future__ import annotations

import dataclasses
from typing import Callable

from transpiler.ir import Op, Operand, Program

# The expression of a decision is a tuple: ("c", i) is condition i, ("not", e), and (op, a, b) with op "and", "or"
# or "xor".

CONSUMERS = frozenset({"ST", "STN", "SET", "RES", "SETN", "RESN", "JPT", "JPF", "CALLT", "CALLF", "EMT", "EMF"})
GATES = {"AND": "and", "ANDN": "and", "OR": "or", "ORN": "or", "XOR": "xor", "XORN": "xor"}
BRACKET_GATES = {"A": "and", "AN": "and", "O": "or", "ON": "or", "XO": "xor", "XON": "xor"}
_FORGET = frozenset({"LBL", "CALL", "CASE", "JP", "EM", "SUBM", "KFIELD"})   # LA unknown after these
# Ops that leave LA as it is (with LA apart from WA); anything not listed here and not handled forgets the chain.
KEEPS_LA = frozenset({"WLD", "WLDN", "WNEG", "LDBITS", "WST", "STBITS", "WAND", "WANDN", "WOR", "WORN", "WXOR",
                      "WXORN", "ADD", "SUB", "MUL", "DIV", "MOD", "SHL", "SHR", "BS", "BC", "INCW", "DECW", "TWOC",
                      "NOTW", "INC", "DEC", "INCX", "DECX", "PUSH", "POP", "PSW", "PLW", "PSL", "PSX", "PLX", "SLD",
                      "SCAT", "SST", "RPLY", "CAN", "NOP"})
WORD_WRITERS = frozenset({"WLD", "WLDN", "WNEG", "LDBITS", "WAND", "WANDN", "WOR", "WORN", "WXOR", "WXORN", "ADD",
                          "SUB", "MUL", "DIV", "MOD", "SHL", "SHR", "BS", "BC", "INCW", "DECW", "TWOC", "NOTW", "PLW",
                          "SUBM", "RPLY"})
_SYMBOL = {"and": "AND", "or": "OR", "xor": "XOR"}


@dataclasses.dataclass(frozen=True)
class Condition:
    """One read feeding a decision: the op that reads it (file, op index), what it reads, and `key`, the same for
    two conditions that read the same thing (coupled conditions: a bit operand named twice in one chain)."""

    file: int
    index: int
    op: Op
    text: str                       # the operand or compare as the source writes it
    key: tuple | None               # None: never coupled (indexed reads, stack values)
    operand: Operand | None = None  # the bit operand read (None for compares, bit tests, pulled values)
    negated: bool = False           # the instruction uses the complement (AN, ON, XON, LN, ...)


@dataclasses.dataclass(frozen=True)
class Decision:
    """One logic chain and its first consumer (file, op index): its conditions in op order and its function."""

    file: int
    index: int
    op: Op
    conditions: tuple[Condition, ...]
    expr: tuple

    @property
    def key(self) -> tuple[int, int]:
        return (self.file, self.index)

    def text(self) -> str:
        """The chain as a formula over its conditions, with its consumer: `(I1 AND NOT M2) = O3`."""
        formula = render(self.expr, [c.text for c in self.conditions])
        if self.op.operand is not None:
            return f"{formula} {self.op.mnemonic} {self.op.operand.display()}"
        return f"{formula} ({self.op.mnemonic})"

    def function(self) -> Callable[[int], int]:
        """The outcome (0/1) for a vector of condition values (bit i = condition i)."""
        return evaluator(self.expr)

    @property
    def coupled(self) -> tuple[bool, ...]:
        """Per condition: another condition of the chain reads the same thing."""
        keys = [c.key for c in self.conditions]
        return tuple(k is not None and keys.count(k) > 1 for k in keys)


@dataclasses.dataclass(frozen=True)
class Compare:
    """A word compare (CMP) and what its boundary values are about: `left` and `right` as written (the left one
    is the word loaded into WA just before, if any), `constant` the constant side (None: two words), and the range
    of values the non-constant side can hold (for c-1 and c+1 at its limits)."""

    file: int
    index: int
    op: Op
    left: str
    right: str
    constant: int | None
    constant_left: bool             # the constant is the left side (`L K5` `< W10`): the word is on the right
    low: int
    high: int
    constants_only: bool = False    # both sides are constants

    @property
    def key(self) -> tuple[int, int]:
        return (self.file, self.index)


def render(expr: tuple, names: list[str], parent: str = "") -> str:
    kind = expr[0]
    if kind == "c":
        return names[expr[1]]
    if kind == "not":
        return "NOT " + render(expr[1], names, "not")
    text = f"{render(expr[1], names, kind)} {_SYMBOL[kind]} {render(expr[2], names, kind)}"
    return f"({text})" if parent and parent != kind else text


def evaluator(expr: tuple) -> Callable[[int], int]:
    """A function of the condition vector, built once (the MC/DC analysis calls it many times)."""
    kind = expr[0]
    if kind == "c":
        bit = expr[1]
        return lambda v: (v >> bit) & 1
    if kind == "not":
        inner = evaluator(expr[1])
        return lambda v: inner(v) ^ 1
    a, b = evaluator(expr[1]), evaluator(expr[2])
    if kind == "and":
        return lambda v: a(v) & b(v)
    if kind == "or":
        return lambda v: a(v) | b(v)
    return lambda v: a(v) ^ b(v)


def _leaves(expr: tuple, out: list[int]) -> list[int]:
    if expr[0] == "c":
        out.append(expr[1])
    else:
        for sub in expr[1:]:
            _leaves(sub, out)
    return out


def _renumber(expr: tuple, mapping: dict[int, int]) -> tuple:
    if expr[0] == "c":
        return ("c", mapping[expr[1]])
    return (expr[0], *(_renumber(sub, mapping) for sub in expr[1:]))


@dataclasses.dataclass(frozen=True)
class DecisionTable:
    """Every decision and compare of a program, and for the code generator: which op reads which condition slot of
    its chain (`reads`: (file, op index) -> slot) and which slots each decision records (`records`)."""

    decisions: tuple[Decision, ...]
    compares: tuple[Compare, ...]
    reads: dict[tuple[int, int], int]
    records: dict[tuple[int, int], tuple[int, tuple[int, ...]]]    # consumer -> (decision number, slots in order)


def decision_table(program: Program) -> DecisionTable:
    walk = _ChainWalk(program.semantics["accumulator_model"] == "shared_bit7")
    entered = _entered(program)
    for f, code in enumerate(program.files):
        walk.file(f)
        for i, op in enumerate(code.ops):
            if (f, i) in entered:
                walk.la = None          # reached from elsewhere too (a structured loop jumps back to its test)
            if op.code == "CMP":
                walk.compares.append(_compare(program, code.ops, f, i))
            walk.step(i, op)
    return DecisionTable(tuple(walk.decisions), tuple(walk.compares), walk.reads, walk.records)


def _entered(program: Program) -> set[tuple[int, int]]:
    """(file, op index) of every op that a jump, call, CASE entry or submitted job may enter by."""
    entered = set()
    for f, code in enumerate(program.files):
        for op in code.ops:
            if op.code in ("JP", "JPT", "JPF") and op.target is not None:
                entered.add((f, op.target))
            for target in (op.call, *op.case_targets):
                if target is not None and not target.is_module and target.file >= 0:
                    entered.add((target.file, target.index))
    return entered


class _ChainWalk:
    """Follows LA through one file's ops as an expression over the conditions read since its chain began."""

    def __init__(self, shared: bool):
        self.shared = shared
        self.decisions: list[Decision] = []
        self.compares: list[Compare] = []
        self.reads: dict[tuple[int, int], int] = {}
        self.records: dict[tuple[int, int], tuple[int, tuple[int, ...]]] = {}
        self.f = 0

    def file(self, f: int) -> None:
        self.f = f
        self.la: tuple | None = None
        self.slots: list[Condition] = []        # the conditions read since the chain began, by slot
        self.frames: list[tuple | None] = []    # saved LA of each open logic bracket (None: a word bracket)
        self.decided: tuple | None = None       # the LA expression the last decision recorded

    def read(self, i: int, op: Op, text: str, key: tuple | None, operand: Operand | None = None,
             negated: bool = False) -> tuple:
        self.reads[(self.f, i)] = len(self.slots)
        self.slots.append(Condition(self.f, i, op, text, key, operand, negated))
        return ("c", len(self.slots) - 1)

    def consume(self, i: int, op: Op) -> None:
        la = self.la
        if la is not None and la is not self.decided and len(self.slots) < 64:
            used = sorted(set(_leaves(la, [])))
            mapping = {slot: n for n, slot in enumerate(used)}
            self.records[(self.f, i)] = (len(self.decisions), tuple(used))
            self.decisions.append(Decision(self.f, i, op, tuple(self.slots[s] for s in used), _renumber(la, mapping)))
            self.decided = la
        if op.code in ("CALLT", "CALLF"):
            self.la = None              # the subprogram leaves LA as it pleases

    def step(self, i: int, op: Op) -> None:
        c = op.code
        o = op.operand
        if c in CONSUMERS:
            self.consume(i, op)
            return
        if not self.frames and c in ("LD", "LDN", "CMP", "SCMP", "BT", "PLL"):
            self.slots = []             # a load outside brackets begins a new chain
        if c in ("LD", "LDN"):
            cond = self.read(i, op, o.display(), _bit_key(o), o, c == "LDN")
            self.la = ("not", cond) if c == "LDN" else cond
        elif c in GATES:
            cond = self.read(i, op, o.display(), _bit_key(o), o, c.endswith("N"))
            cond = ("not", cond) if c.endswith("N") else cond
            self.la = None if self.la is None else (GATES[c], self.la, cond)
        elif c == "CMP":
            cmp = self.compares[-1]
            plain = "[" not in cmp.left + cmp.right and cmp.left != "WA"
            self.la = self.read(i, op, f"{cmp.left} {op.rel} {cmp.right}",
                                ("cmp", cmp.left, op.rel, cmp.right) if plain else None)
        elif c == "SCMP":
            self.la = self.read(i, op, f"SA {op.rel} {o.display()}", None)
        elif c == "BT":
            self.la = self.read(i, op, f"bit {o.display()} of WA", None)
        elif c == "PLL":
            self.la = self.read(i, op, "PLL (logic value pulled from the stack)", None)
        elif c == "NOTL":
            self.la = None if self.la is None else ("not", self.la)
        elif c == "BOPEN":
            self.open_bracket(op)
        elif c == "BCLOSE":
            self.close_bracket(i, op)
        elif c in _FORGET:
            self.la = None
            if c == "LBL":
                self.frames = []
        elif c not in KEEPS_LA or (self.shared and c in WORD_WRITERS):
            self.la = None

    def open_bracket(self, op: Op) -> None:
        if op.bracket.mode == "LOGIC" and op.bracket.op in BRACKET_GATES:
            self.frames.append(self.la if not op.bracket.load else ("load",))
            self.la = None
        else:
            self.frames.append(None)

    def close_bracket(self, i: int, op: Op) -> None:
        saved = self.frames.pop() if self.frames else None
        br = op.bracket
        if br.mode == "LOGIC" and br.op in BRACKET_GATES:
            inner = self.la
            if inner is not None and br.op in ("AN", "ON", "XON"):
                inner = ("not", inner)
            if inner is None or saved is None:
                self.la = None
            elif saved == ("load",):
                self.la = inner
            else:
                self.la = (BRACKET_GATES[br.op], saved, inner)
        elif op.rel:
            self.la = self.read(i, op, f"bracket {op.rel}", None)
        elif self.shared:
            self.la = None


def _bit_key(o: Operand) -> tuple | None:
    return None if o.indexed else ("bit", o.kind, o.addr)


_RANGE = {"B": 8, "W": 16}


def _compare(program: Program, ops: tuple[Op, ...], f: int, i: int) -> Compare:
    """The compare at ops[i] with its sides and the range of its word side (see Compare)."""
    op = ops[i]
    sem = program.semantics
    right = op.operand
    width = {"B": 8, "W": 16}.get(right.kind, 16 if right.kind == "X" and int(sem["index_register_width"]) == 16
                                  else 32)
    unsigned = sem["compare_signedness"] == "unsigned"
    prev = ops[i - 1] if i > 0 else None
    left = prev.operand if prev is not None and prev.code == "WLD" and prev.operand is not None else None
    constant: int | None = None
    constant_left = False
    word = None
    if right.kind == "K" and (left is None or left.kind != "K"):
        constant, word = right.addr, left
    elif left is not None and left.kind == "K" and right.kind != "K":
        constant, constant_left, word = left.addr, True, right
    elif left is not None and left.kind == "K" and right.kind == "K":
        constant = right.addr
    # The values the word side can take: the compare's width, narrower where the word is a byte or word loaded
    # (sign- or zero-extended, A-06) or read as the compare's operand.
    bits = width
    zero = unsigned
    if word is not None and word.kind in _RANGE:
        bits = min(bits, _RANGE[word.kind])
        if word is left and sem["load_extension"] == "zero":
            zero = True
    if constant is not None and constant_left is False and unsigned:
        constant &= (1 << width) - 1
    low, high = (0, (1 << bits) - 1) if zero else (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)
    return Compare(f, i, op, left.display() if left is not None else "WA", right.display(), constant, constant_left,
                   low, high, left is not None and left.kind == "K" and right.kind == "K")
