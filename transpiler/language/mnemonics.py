"""The instruction set as data: every mnemonic of the language with its operand form and allowed operand kinds."""

from __future__ import annotations

import dataclasses

BIT = frozenset("MIOTC")
VAL = frozenset("BWDK")          # plus KF and X where stated
STR = frozenset(["S", "SREF", "SIMM"])
MEMVAL = frozenset("BWD")


@dataclasses.dataclass(frozen=True)
class Mnemonic:
    name: str
    form: str                     # 'none' | 'operand' | 'label' | 'call' (label or module number)
    kinds: frozenset[str] = frozenset()   # allowed operand kinds for 'operand'
    extended: bool = False        # A-23 optional instruction
    group: str = ""


def _m(name, form, kinds=frozenset(), extended=False, group=""):
    return Mnemonic(name, form, frozenset(kinds), extended, group)


_LOGIC_GATES = ("A", "AN", "O", "ON", "XO", "XON")
_ARITH = ("+", "-", "x", "/", "MOD")
_COMPARE = ("==", "<", ">", "<=", ">=", "<>")
BRACKET_OPS = _LOGIC_GATES + _ARITH + _COMPARE

MNEMONICS: dict[str, Mnemonic] = {m.name: m for m in (
    # 6.1 loads
    _m("L", "operand", BIT | VAL | STR | {"KF", "X"}, group="load"),
    _m("LN", "operand", BIT | VAL | {"KF", "X"}, group="load"),
    _m("L-", "operand", VAL | {"KF", "X"}, group="load"),
    _m("LB", "operand", BIT, group="load"),
    _m("LW", "operand", BIT, group="load"),
    _m("LD", "operand", BIT, group="load"),
    # 6.2 assignments
    _m("=", "operand", BIT | MEMVAL | {"X", "S"}, group="assign"),
    _m("=N", "operand", BIT, group="assign"),
    _m("B=", "operand", BIT, group="assign"),
    _m("W=", "operand", BIT, group="assign"),
    _m("D=", "operand", BIT, group="assign"),
    _m("S", "operand", BIT, group="assign"),
    _m("R", "operand", BIT, group="assign"),
    _m("SN", "operand", BIT, group="assign"),
    _m("RN", "operand", BIT, group="assign"),
    # 6.3 / 6.4 gating (bit or word), 6.5 arithmetic, 6.6 compare, 6.16 strings
    *(_m(g, "operand", BIT | VAL | {"KF", "X"}, group="gate") for g in _LOGIC_GATES),
    _m("+", "operand", VAL | STR | {"KF", "X"}, group="arith"),
    *(_m(a, "operand", VAL | {"KF", "X"}, group="arith") for a in ("-", "x", "/", "MOD")),
    *(_m(c, "operand", VAL | STR | {"KF", "X"}, group="compare") for c in _COMPARE),
    # 6.7 shifts, 6.8 bit commands
    _m("<<", "operand", VAL | {"KF", "X"}, group="shift"),
    _m(">>", "operand", VAL | {"KF", "X"}, group="shift"),
    _m("BS", "operand", VAL | {"KF", "X"}, group="bit"),
    _m("BC", "operand", VAL | {"KF", "X"}, group="bit"),
    _m("BT", "operand", VAL | {"KF", "X"}, group="bit"),
    # 6.9 brackets
    *(_m(op + "[", "none", group="bracket") for op in BRACKET_OPS),
    _m("]", "none", group="bracket"),
    # 6.10 stack
    _m("PS", "operand", BIT | VAL | {"KF", "X"}, group="stack"),
    _m("PL", "operand", BIT | MEMVAL, group="stack"),
    *(_m(s, "none", group="stack") for s in ("PSW", "PLW", "PSL", "PLL", "PSX", "PLX")),
    # 6.11 jumps, 6.12 calls
    *(_m(j, "label", group="jump") for j in ("JP", "JPT", "JPF")),
    *(_m(c, "call", group="call") for c in ("CM", "CMT", "CMF")),
    *(_m(e, "none", group="end") for e in ("EM", "EMT", "EMF")),
    # 6.14 extended
    _m("INC", "operand", BIT | MEMVAL, extended=True, group="extended"),
    _m("DEC", "operand", BIT | MEMVAL, extended=True, group="extended"),
    *(_m(e, "none", extended=True, group="extended") for e in ("INCW", "DECW", "INCX", "DECX", "NOTL", "NOTW", "TWOC")),
    # 6.15 structured statements
    *(_m(s, "none", group="struct") for s in ("IFT", "IFF", "ELSE", "ENDI", "WHILET", "WHILEF", "ENDW", "REPEAT", "UNTILT", "UNTILF")),
    _m("CASE", "operand", MEMVAL | {"K"}, group="case"),
    _m("ENDC", "none", group="case"),
    # 15 submit jobs
    _m("SUBM", "label", group="submit"),
    _m("RPLY", "operand", MEMVAL | {"K"}, group="submit"),
    _m("CAN", "operand", MEMVAL | {"K"}, group="submit"),
)}


def canonical(raw: str) -> str:
    """The table key of a mnemonic as written: upper case, no blank before '[', 'x' for multiply."""
    text = "".join(raw.split())
    if text in ("x", "X"):
        return "x"
    if text in ("x[", "X["):
        return "x["
    return text.upper()
