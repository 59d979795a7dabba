"""Screen masks: each reference of a mask bound to the operand it shows, checked against its format."""

from __future__ import annotations

import dataclasses
import difflib
import re

from transpiler.diagnostics import Diagnostics
from transpiler.frontend.addresses import check_range
from transpiler.frontend.symbols import SymTables, folded_key
from transpiler.ir import Mask, MaskField, MaskRef, Symbol
from transpiler.language.semantics import Semantics

_OPERAND = re.compile(r"([MIOTCBWDS])([0-9]{1,6})", re.IGNORECASE)

def resolve_masks(masks: tuple[Mask, ...], symbols: SymTables, semantics: Semantics, diags: Diagnostics
                  ) -> tuple[Mask, ...]:
    """Each reference bound to its operand; unknown names (with the nearest ones), operands out of range and
    formats that do not suit their operand are errors."""
    if not masks:
        return ()
    table = symbols.all_symbols()
    fold = semantics["symbol_case"] == "insensitive"
    resolved = []
    for mask in masks:
        statements = []
        for stmt in mask.statements:
            pieces = tuple(_bind(p, table, fold, symbols, semantics, diags) if isinstance(p, MaskField) else p
                           for p in stmt.pieces)
            statements.append(dataclasses.replace(stmt, pieces=pieces))
        resolved.append(dataclasses.replace(mask, statements=tuple(statements)))
    return tuple(resolved)


def _bind(field: MaskField, table: dict[str, Symbol], fold: bool, symbols: SymTables, semantics: Semantics,
          diags: Diagnostics) -> MaskField:
    ref = field.ref
    if ref.symbol is not None:
        sym = table.get(ref.symbol)
        if sym is None and fold:
            key = folded_key(table, ref.symbol)
            sym = table[key] if key is not None else None
        if sym is None:
            if not symbols.already_reported("", ref.symbol):
                near = difflib.get_close_matches(ref.symbol, sorted(table), n=3, cutoff=0.6)
                hint = f"; nearest names: {', '.join(near)}" if near else ""
                diags.report("E-MASK-UNDEF", ref.span, f"unknown symbol {ref.text} in mask{hint}")
            return field
        if sym.kind == "K":
            diags.report("E-MASK-FORMAT", ref.span, f"{ref.text} is a constant ({sym.name} K {sym.addr}): a mask shows "
                         "operands")
            return field
        kind, addr = sym.kind, sym.addr
    else:
        m = _OPERAND.fullmatch(ref.text)
        if m is None:
            known = ref.text in table or (fold and folded_key(table, ref.text) is not None)
            hint = f": write the symbol between dollar signs, ${ref.text}$" if known else \
                " (a reference is $SYMBOL$ or an operand such as S1 or W230)"
            diags.report("E-MASK-UNDEF", ref.span, f"'{ref.text}' is not a reference{hint}")
            return field
        kind, addr = m.group(1).upper(), int(m.group(2))
        if not check_range(kind, addr, semantics, ref.span, diags, ref.text):
            return field
    if not _format_suits(field, kind, ref, diags):
        return field
    return dataclasses.replace(field, ref=dataclasses.replace(ref, kind=kind, addr=addr))


def _format_suits(field: MaskField, kind: str, ref: MaskRef, diags: Diagnostics) -> bool:
    name = {"S": "a string", "M": "a marker", "I": "an input", "O": "an output", "T": "a timer operand",
            "C": "a counter operand", "B": "a byte", "W": "a word", "D": "a double word"}[kind]
    if field.conversion == "s" and kind != "S":
        diags.report("E-MASK-FORMAT", ref.span, f"{field.spec} shows a string, but {ref.text} is {name} "
                     "(use %d, %D or %F)")
        return False
    if field.conversion != "s" and kind == "S":
        diags.report("E-MASK-FORMAT", ref.span, f"{field.spec} shows a number, but {ref.text} is a string (use %s)")
        return False
    if ref.decimals and field.conversion != "F":
        diags.report("E-MASK-FORMAT", ref.span, f"/n={ref.decimals} places a decimal point: it needs an F format, "
                     f"not {field.spec}")
        return False
    return True
