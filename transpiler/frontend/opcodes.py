"""Mnemonic groups and limits the resolver stages share (gates, arithmetic, compares, structured and control keywords)."""

from __future__ import annotations

LOGIC_GATES = {"A": "AND", "AN": "ANDN", "O": "OR", "ON": "ORN", "XO": "XOR", "XON": "XORN"}
WORD_GATES = {"A": "WAND", "AN": "WANDN", "O": "WOR", "ON": "WORN", "XO": "WXOR", "XON": "WXORN"}
GATE_AS_LOAD = {"A": "LD", "AN": "LDN", "O": "LD", "ON": "LDN", "XO": "LD", "XON": "LDN"}
ARITH = {"+": "ADD", "-": "SUB", "x": "MUL", "/": "DIV", "MOD": "MOD"}
COMPARES = ("==", "<", ">", "<=", ">=", "<>")
STRUCT_OPEN = {"IFT", "IFF", "WHILET", "WHILEF", "REPEAT"}
STRUCT_ALL = STRUCT_OPEN | {"ELSE", "ENDI", "ENDW", "UNTILT", "UNTILF"}
# the statements that decide where control goes (a file's flow can be checked only when none of them was rejected)
FLOW = frozenset({"EM", "EMT", "EMF", "JP", "JPT", "JPF", "CASE", "ENDC"}) | STRUCT_ALL
CONTROL = {"JP", "JPT", "JPF", "CM", "CMT", "CMF", "EM", "EMT", "EMF", "CASE", "ENDC", "SUBM"} | STRUCT_ALL
BIT_GROUPS = {"LB": 8, "LW": 16, "LD": 32, "B=": 8, "W=": 16, "D=": 32}   # bits read/written from the operand on
MAX_NESTING = 16

_BRACKET_ARITH = {"x": "MUL", "/": "DIV", "MOD": "MOD", "+": "ADD", "-": "SUB"}


def implicit_writes(op, interface, add_overflow_flag: bool = False) -> tuple[tuple[str, int], ...]:
    """The operands `op` (an ir.Op) writes without naming them, as (kind, address): the error marker of x, / and
    MOD (also closing an arithmetic bracket; of + and - too where an overflow sets it, `add_overflow_flag`), and
    for a PLC module call the module error marker and the error-code word of the profile's `interface`."""
    code = op.code
    if code == "BCLOSE" and op.bracket is not None:
        code = _BRACKET_ARITH.get(op.bracket.op, "")
    if code == "MUL" or add_overflow_flag and code in ("ADD", "SUB"):
        return (("M", interface.mul_err),)
    if code in ("DIV", "MOD"):
        return (("M", interface.div_err if code == "DIV" else interface.mod_err),)
    if op.code in ("CALL", "CALLT", "CALLF") and op.call is not None and op.call.is_module:
        word = interface.module_err_code_word
        return (("M", interface.module_err),) + ((("W", word),) if word is not None else ())
    return ()
