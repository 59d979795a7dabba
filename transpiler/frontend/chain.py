"""Chain state: lowers one instruction to its op, tracking the open logic chain, the last accumulator used and the brackets."""

from __future__ import annotations

import dataclasses
from typing import Callable, NamedTuple

from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend import ast
from transpiler.frontend.opcodes import (ARITH, BIT_GROUPS, COMPARES, GATE_AS_LOAD, LOGIC_GATES, MAX_NESTING, STRUCT_ALL,
                                         WORD_GATES)
from transpiler.frontend.operands import label_text
from transpiler.frontend.structure import StructureMatcher
from transpiler.ir import Bracket, CallTarget, Op, Operand, new_op
from transpiler.language.modules import MODULES, nearest
from transpiler.language.semantics import Semantics

Lowered = tuple[Op | None, bool, str]        # the op (None: rejected), then chain_open and last_acc after it


@dataclasses.dataclass
class BracketFrame:
    op: str
    mode: str
    load: bool
    index: int
    span: Span
    # E-BRACKET-SPAN faults inside this bracket; reported when it closes. A bracket that is never closed
    # reports only E-BRACKET-BALANCE: the missing ']' is the root fault, not the EM after it.
    span_faults: list[tuple[Span, str]] = dataclasses.field(default_factory=list)


class _Step(NamedTuple):
    """One instruction being lowered, with the chain state before it."""

    m: str
    instr: ast.Instr
    operand: Operand | None
    base: dict
    index: int
    chain_open: bool
    last_acc: str
    is_bit: bool
    is_str: bool


class _Shape(NamedTuple):
    """What a pure instruction group made of one (mnemonic, operand kind, chain state): the op's code and
    fields besides the instruction's own, and the chain state after it."""

    code: str
    rel: str
    nbits: int
    chain_open: bool
    last_acc: str


class ChainLowering:
    """Lowers the instructions of one file; jumps and calls are queued in `pending_jumps`/`pending_calls` for linking."""

    def __init__(self, semantics: Semantics, diags: Diagnostics, structure: StructureMatcher,
                 pending_jumps: list[tuple[int, str, Span]], pending_calls: list[tuple[int, str, Span]]):
        self.semantics = semantics
        self.diags = diags
        self.structure = structure
        self.pending_jumps = pending_jumps
        self.pending_calls = pending_calls
        self.brackets: list[BracketFrame] = []
        # mnemonic -> the group that took it. (The groups are kept as functions, not bound methods: a bound method
        # kept by its own object is a reference cycle, which would keep every op of the file alive until the cyclic
        # collector runs, at the latest when the process exits, where it cost ~0.1 s on a 100 000-line project.)
        self._group_of: dict[str, Callable[[ChainLowering, _Step], Lowered | None]] = {}
        self._shapes: dict[tuple[str, str | None, bool, str], _Shape] = {}
        self.modules_called: set[int] = set()      # the PLC modules of the call ops made (each op made is kept)

    def lower(self, instr: ast.Instr, operand: Operand | None, index: int, chain_open: bool, last_acc: str) -> Lowered:
        m = instr.mnemonic
        shape_key = (m, operand.kind if operand is not None else None, chain_open, last_acc)
        shape = self._shapes.get(shape_key)
        if shape is not None:
            return (new_op(shape.code, m, instr.span, operand, instr.comments, rel=shape.rel, nbits=shape.nbits,
                           chain_open=chain_open), shape.chain_open, shape.last_acc)
        base = dict(mnemonic=m, span=instr.span, operand=operand, comments=instr.comments, chain_open=chain_open)
        is_bit = operand is not None and operand.is_bit
        is_str = operand is not None and operand.kind in ("S", "STR")
        step = _Step(m, instr, operand, base, index, chain_open, last_acc, is_bit, is_str)
        # (the groups take disjoint mnemonics; each answers None for a mnemonic that is not its own and a tuple for
        # one that is, so the group that took a mnemonic once is asked first the next time)
        known = self._group_of.get(m)
        if known is not None:
            lowered = known(self, step)
            if lowered is not None:
                return self._keep_shape(known, shape_key, lowered)
        for group in _GROUPS:
            lowered = group(self, step)
            if lowered is not None:
                self._group_of[m] = group
                return self._keep_shape(group, shape_key, lowered)
        self.diags.report("E-UNSUPPORTED", instr.span, f"{m} is not supported")
        return None, chain_open, last_acc

    def pure(self, m: str) -> bool:
        """Whether the op of mnemonic m depends only on its operand and the chain state (no diagnostics, no queued
        jumps or brackets): a pure group lowered it."""
        return self._group_of.get(m) in _PURE_GROUPS

    def _keep_shape(self, group: Callable, key: tuple, lowered: Lowered) -> Lowered:
        op, chain_open, last_acc = lowered
        if op is not None and group in _PURE_GROUPS:
            self._shapes[key] = _Shape(op.code, op.rel, op.nbits, chain_open, last_acc)
        return lowered

    def report_unclosed(self) -> None:
        for frame in self.brackets:
            self.diags.report("E-BRACKET-BALANCE", frame.span, f"bracket {frame.op}[ is never closed")

    # ---- instruction groups

    def _load_store(self, s: _Step) -> Lowered | None:
        m, base, chain_open = s.m, s.base, s.chain_open
        if m in ("L", "LN"):
            if s.is_bit:
                return new_op("LD" if m == "L" else "LDN", **base), True, "LOGIC"
            if s.is_str:
                return new_op("SLD", **base), chain_open, "STRING"
            return new_op("WLD" if m == "L" else "WLDN", **base), chain_open, "WORD"
        if m == "L-":
            return new_op("WNEG", **base), chain_open, "WORD"
        if m in ("LB", "LW", "LD"):
            return new_op("LDBITS", nbits=BIT_GROUPS[m], **base), chain_open, "WORD"
        if m in ("=", "=N", "S", "R", "SN", "RN"):
            if s.is_bit:
                code = {"=": "ST", "=N": "STN", "S": "SET", "R": "RES", "SN": "SETN", "RN": "RESN"}[m]
                return new_op(code, **base), False, "LOGIC"
            if s.operand.kind == "S":
                return new_op("SST", **base), False, "STRING"
            return new_op("WST", **base), False, "WORD"
        if m in ("B=", "W=", "D="):
            return new_op("STBITS", nbits=BIT_GROUPS[m], **base), False, "WORD"
        return None

    def _logic_word(self, s: _Step) -> Lowered | None:
        m, base, chain_open = s.m, s.base, s.chain_open
        if m in LOGIC_GATES:
            if s.is_bit:
                if chain_open or self.semantics["chain_model"] == "dynamic":
                    return new_op(LOGIC_GATES[m], **base), True, "LOGIC"
                return new_op(GATE_AS_LOAD[m], **base), True, "LOGIC"
            if not chain_open and self.semantics["word_gate_at_chain_start"] == "load":
                return new_op("WLD" if GATE_AS_LOAD[m] == "LD" else "WLDN", **base), chain_open, "WORD"
            return new_op(WORD_GATES[m], **base), chain_open, "WORD"
        if m in ARITH:
            if s.is_str and m == "+":
                return new_op("SCAT", **base), chain_open, "STRING"
            return new_op(ARITH[m], **base), chain_open, "WORD"
        if m in COMPARES:
            return new_op("SCMP" if s.is_str else "CMP", rel=m, **base), True, "LOGIC"
        if m in ("<<", ">>"):
            return new_op("SHL" if m == "<<" else "SHR", **base), chain_open, "WORD"
        if m in ("BS", "BC"):
            return new_op(m, **base), chain_open, "WORD"
        if m == "BT":
            return new_op("BT", **base), True, "LOGIC"
        return None

    def _bracket_stack(self, s: _Step) -> Lowered | None:
        m, base, chain_open = s.m, s.base, s.chain_open
        if m.endswith("[") and m != "[":
            return self._open_bracket(m[:-1], base, s.index, chain_open, s.last_acc)
        if m == "]":
            return self._close_bracket(base, chain_open, s.last_acc)
        if m == "PS":
            return new_op("PUSH", **base), chain_open, "NONE"
        if m == "PL":
            return new_op("POP", **base), chain_open, "NONE"
        if m in ("PSW", "PLW", "PSX", "PLX"):
            return new_op(m, **base), chain_open, "WORD"
        if m == "PSL":
            return new_op("PSL", **base), chain_open, "LOGIC"
        if m == "PLL":
            return new_op("PLL", **base), True, "LOGIC"
        return None

    def _control(self, s: _Step) -> Lowered | None:
        m, base, chain_open = s.m, s.base, s.chain_open
        span = base["span"]
        if m in ("JP", "JPT", "JPF"):
            self.pending_jumps.append((s.index, label_text(s.instr.operand), span))
            return new_op(m, **base), False, "NONE"
        if m in ("CM", "CMT", "CMF"):
            return self._call(s)
        if m == "SUBM":
            self.pending_calls.append((s.index, label_text(s.instr.operand), span))
            return new_op("SUBM", **base), False, "WORD"
        if m in ("RPLY", "CAN"):
            return new_op(m, **base), chain_open, "WORD" if m == "RPLY" else "NONE"
        if m in ("EM", "EMT", "EMF"):
            return new_op(m, **base), False, "NONE"
        if m == "CASE":
            return new_op("CASE", **base), False, "NONE"
        if m == "ENDC":
            return new_op("NOP", **base), False, "NONE"
        if m in STRUCT_ALL:
            return self.structure.lower(m, base, s.index), False, "NONE"
        return None

    def _call(self, s: _Step) -> Lowered:
        """CM/CMT/CMF: a PLC module by number, or a label linked later."""
        base = s.base
        span = base["span"]
        code = {"CM": "CALL", "CMT": "CALLT", "CMF": "CALLF"}[s.m]
        if s.instr.operand.kind == "NUM":
            number = int(s.instr.operand.value)
            if not 9000 <= number <= 9999:
                self.diags.report("E-SYNTAX", span, f"PLC module numbers are 9000-9999, not {number}")
                return None, s.chain_open, s.last_acc
            profile = self.semantics.profile.name
            if number not in MODULES or profile not in MODULES[number].profiles:
                known = ", ".join(map(str, nearest(number)))
                where = "in the module table" if number not in MODULES else f"a module of profile {profile}"
                self.diags.report("E-MODULE-UNKNOWN", span, f"PLC module {number} is not {where} "
                                  f"(nearest known: {known}; see docs/modules.md)")
            self.modules_called.add(number)
            return new_op(code, call=CallTarget(module=number), **base), False, "NONE"
        self.pending_calls.append((s.index, label_text(s.instr.operand), span))
        return new_op(code, **base), False, "NONE"

    def _extended(self, s: _Step) -> Lowered | None:
        m, base, chain_open = s.m, s.base, s.chain_open
        if m in ("INC", "DEC"):
            return new_op(m, **base), chain_open, "LOGIC" if s.is_bit else "NONE"
        if m == "NOTL":
            return new_op("NOTL", **base), True, "LOGIC"
        if m in ("INCW", "DECW", "INCX", "DECX", "NOTW", "TWOC"):
            return new_op(m, **base), chain_open, "WORD"
        return None

    # ---- brackets

    def _open_bracket(self, op: str, base: dict, index: int, chain_open: bool, last_acc: str) -> Lowered:
        brackets = self.brackets
        span = base["span"]
        if len(brackets) >= MAX_NESTING:
            if len(brackets) == MAX_NESTING:     # once per too-deep nest, not for every deeper level
                self.diags.report("E-BRACKET-DEPTH", span, f"brackets nested deeper than {MAX_NESTING}")
            # Keep a frame so that the matching ']' does not cascade into a second error.
            brackets.append(BracketFrame(op, "LOGIC" if op in LOGIC_GATES else "WORD", False, index, span))
            return None, chain_open, last_acc
        mode = last_acc
        if mode == "STRING":
            self.diags.report("E-BRACKET-MODE", span, f"{op}[ after a string instruction")
            brackets.append(BracketFrame(op, "WORD", False, index, span))   # the matching ']' must not cascade
            return None, chain_open, last_acc
        if mode == "NONE":
            mode = "LOGIC" if op in LOGIC_GATES else "WORD"
        if (op in ARITH or op in COMPARES) and mode != "WORD":
            self.diags.report("E-BRACKET-MODE", span, f"{op}[ needs a word value before it (the previous instruction "
                             "addressed the logic accumulator)")
            brackets.append(BracketFrame(op, "WORD", False, index, span))   # the matching ']' must not cascade
            return None, chain_open, last_acc
        load = (mode == "LOGIC" and op in LOGIC_GATES and not chain_open
                and self.semantics["bracket_at_chain_start"] == "load")
        brackets.append(BracketFrame(op, mode, load, index, span))
        new_chain = False if (mode == "LOGIC" or op in COMPARES) else chain_open
        return (new_op("BOPEN", bracket=Bracket(op, mode, load), rel=op if op in COMPARES else "", **base), new_chain,
                mode)

    def _close_bracket(self, base: dict, chain_open: bool, last_acc: str) -> Lowered:
        if not self.brackets:
            self.diags.report("E-BRACKET-BALANCE", base["span"], "']' without an opening bracket")
            return None, chain_open, last_acc
        frame = self.brackets.pop()
        for fault_span, message in frame.span_faults:
            self.diags.report("E-BRACKET-SPAN", fault_span, message)
        bracket = Bracket(frame.op, frame.mode, frame.load)
        logic_result = (frame.op in LOGIC_GATES and frame.mode == "LOGIC") or frame.op in COMPARES
        return (new_op("BCLOSE", bracket=bracket, rel=frame.op if frame.op in COMPARES else "", **base),
                True if logic_result else chain_open, "LOGIC" if logic_result else "WORD")


_GROUPS = (ChainLowering._load_store, ChainLowering._logic_word, ChainLowering._bracket_stack, ChainLowering._control,
           ChainLowering._extended)
# The groups whose answer depends only on the mnemonic, the operand's kind and the chain state (no diagnostics, no
# queued jumps or brackets): their op shape is kept per such key and reused (_Shape).
_PURE_GROUPS = (ChainLowering._load_store, ChainLowering._logic_word, ChainLowering._extended)
