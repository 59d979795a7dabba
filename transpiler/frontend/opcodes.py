"""Mnemonic groups and limits the resolver stages share (gates, arithmetic, compares, structured and control keywords)."""

from __future__ import annotations

LOGIC_GATES = {"A": "AND", "AN": "ANDN", "O": "OR", "ON": "ORN", "XO": "XOR", "XON": "XORN"}
WORD_GATES = {"A": "WAND", "AN": "WANDN", "O": "WOR", "ON": "WORN", "XO": "WXOR", "XON": "WXORN"}
GATE_AS_LOAD = {"A": "LD", "AN": "LDN", "O": "LD", "ON": "LDN", "XO": "LD", "XON": "LDN"}
ARITH = {"+": "ADD", "-": "SUB", "x": "MUL", "/": "DIV", "MOD": "MOD"}
COMPARES = ("==", "<", ">", "<=", ">=", "<>")
STRUCT_OPEN = {"IFT", "IFF", "WHILET", "WHILEF", "REPEAT"}
STRUCT_ALL = STRUCT_OPEN | {"ELSE", "ENDI", "ENDW", "UNTILT", "UNTILF"}
CONTROL = {"JP", "JPT", "JPF", "CM", "CMT", "CMF", "EM", "EMT", "EMF", "CASE", "ENDC", "SUBM"} | STRUCT_ALL
BIT_GROUPS = {"LB": 8, "LW": 16, "LD": 32, "B=": 8, "W=": 16, "D=": 32}   # bits read/written from the operand on
MAX_NESTING = 16
