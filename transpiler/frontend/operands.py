"""Operand checks: a written operand becomes an ir.Operand (symbol, constant, constant field, string) and must suit its mnemonic."""

from __future__ import annotations

from transpiler.diagnostics import Diagnostics
from transpiler.frontend import ast
from transpiler.frontend.addresses import check_range
from transpiler.frontend.opcodes import BIT_GROUPS, COMPARES
from transpiler.frontend.symbols import SymTables
from transpiler.ir import Operand
from transpiler.language.mnemonics import MNEMONICS
from transpiler.language.semantics import Semantics


class OperandResolver:
    """Resolves and checks the operands of one file; `kfields` is the file's KFIELD table (filled before use)."""

    def __init__(self, path: str, symbols: SymTables, kfields: dict[str, tuple[int, ...]], semantics: Semantics,
                 diags: Diagnostics):
        self.path = path
        self.symbols = symbols
        self.kfields = kfields
        self.semantics = semantics
        self.diags = diags
        self.case_insensitive = semantics["symbol_case"] == "insensitive"

    def resolve(self, instr: ast.Instr) -> Operand | None:
        syn = instr.operand
        span = instr.span
        kind, value = syn.kind, syn.value
        symbol = None
        if kind == "SYM":
            sym = self.symbols.lookup(self.path, str(value), self.case_insensitive)
            if sym is None:
                if str(value) in self.kfields:
                    self.diags.report("E-OPERAND-KIND", span, f"constant field {value} is read as 'KF {value}[X]'")
                elif not self.symbols.already_reported(self.path, str(value)):
                    self.diags.report("E-SYM-UNDEF", span, f"unknown symbol '{value}'")
                return None
            symbol = sym.name
            kind, value = sym.kind, sym.addr
            if kind == "K":
                if syn.indexed:
                    self.diags.report("E-OPERAND-KIND", span, f"constant {symbol} cannot be indexed")
                    return None
                return Operand("K", value, symbol=symbol)
        if kind == "K":
            return Operand("K", int(value))
        if kind == "X":
            return Operand("X")
        if kind == "SREF":
            text = str(value)
            letter, number = text[0], int(text[1:])
            limit = 999 if letter == "E" else 4095
            if number > limit:
                self.diags.report("E-ADDR-RANGE", span, f"S#{letter}{number}: line number above {limit}")
                return None
            return Operand("STR", text=f"{letter}{number:04d}")
        if kind == "SIMM":
            return Operand("STR", text=str(value))
        if kind == "KF":
            values = self.kfields.get(str(value))
            if values is None:
                self.diags.report("E-SYM-UNDEF", span, f"unknown constant field '{value}'")
                return None
            if not syn.indexed:
                self.diags.report("E-SYNTAX", span, f"constant field access is written 'KF {value}[X]'")
                return None
            return Operand("KF", indexed=True, kfield=values, text=str(value))
        if kind == "NUM":
            self.diags.report("E-SYNTAX", span, f"'{value}' is not an operand")
            return None
        addr = int(value)
        count = BIT_GROUPS.get(instr.mnemonic, 1)
        # (an indexed operand's effective address, alignment included, is checked at run time)
        if not syn.indexed and not check_range(kind, addr, self.semantics, span, self.diags, symbol or f"{kind}{addr}", count):
            return None
        return Operand(kind, addr, indexed=syn.indexed, symbol=symbol)

    def kind_ok(self, instr: ast.Instr, operand: Operand) -> bool:
        info = MNEMONICS[instr.mnemonic]
        kind = operand.kind
        if kind == "STR":
            kind = "SIMM"
        if kind == "S" and instr.mnemonic in ("L", "+") + COMPARES:
            return True
        if kind not in info.kinds:
            self.diags.report("E-OPERAND-KIND", instr.span, f"{instr.mnemonic} does not accept {operand.display()} "
                             f"({_kind_name(operand.kind)})")
            return False
        return True


def label_text(syn: ast.OperandSyntax) -> str:
    return str(syn.value) if syn.kind == "SYM" else syn.text


def _kind_name(kind: str) -> str:
    return {"M": "marker", "I": "input", "O": "output", "T": "timer", "C": "counter", "B": "byte", "W": "word",
            "D": "double word", "K": "constant", "KF": "constant field", "X": "index register",
            "S": "string", "STR": "string literal"}.get(kind, kind)

