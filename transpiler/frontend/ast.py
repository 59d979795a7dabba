"""The typed syntax tree of HEIDENHAIN project files: every node carries its original span and comments."""

from __future__ import annotations

import dataclasses
from typing import NamedTuple, Union

from transpiler.diagnostics import Span
from transpiler.records import builder, quick_init


class OperandSyntax(NamedTuple):
    """An operand as written. kind: M I O T C B W D K S SREF SIMM KF X NUM SYM.

    A typed named tuple rather than a frozen dataclass: the lowering looks each line's operand up in its caches,
    and a tuple is hashed and compared in C (the dataclass's hash was a Python call per lookup)."""

    kind: str
    value: Union[int, str]
    indexed: bool
    text: str


@quick_init
@dataclasses.dataclass(frozen=True, slots=True)
class Instr:
    mnemonic: str                 # canonical spelling: upper case, 'x' for multiply, brackets without blanks
    operand: OperandSyntax | None
    span: Span
    comments: tuple[str, ...] = ()


new_instr = builder(Instr)      # Instr(...) for the parser's loop over the lines


@quick_init
@dataclasses.dataclass(frozen=True, slots=True)
class Label:
    name: str
    span: Span
    comments: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True, slots=True)
class KField:
    name: str
    values: tuple[int, ...]
    span: Span
    comments: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True, slots=True)
class Uses:
    file: str
    span: Span
    comments: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True, slots=True)
class Global:
    name: str
    span: Span
    comments: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True, slots=True)
class Extern:
    name: str
    span: Span
    comments: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True, slots=True)
class DefineFile:
    file: str
    is_global: bool
    span: Span
    comments: tuple[str, ...] = ()


Statement = Union[Instr, Label, KField, Uses, Global, Extern, DefineFile]


@dataclasses.dataclass(frozen=True, slots=True)
class SymbolDef:
    """A .def entry: fixed operand, constant, auto-assigned operand, or alias of another symbol."""

    name: str
    kind: str                     # M I O T C B W D S K
    address: int | None           # fixed address (None for auto and alias)
    constant: int | None          # value of a K entry
    alias: str | None             # target of '&name'
    cflag: bool                   # '/c' prefix
    span: Span
    comments: tuple[str, ...] = ()
    section: str | None = None    # text of the preceding #type marker


@dataclasses.dataclass(frozen=True, slots=True)
class SourceFile:
    path: str                     # display path
    statements: tuple[Statement, ...]
    trailing_comments: tuple[str, ...]
    line_count: int
    broken_labels: tuple[str, ...] = ()   # names of LBL/KFIELD lines rejected with an error (not reported again)


@dataclasses.dataclass(frozen=True, slots=True)
class DefFile:
    path: str
    symbols: tuple[SymbolDef, ...]
    includes: tuple[DefineFile, ...]
    line_count: int
    broken: tuple[str, ...] = ()  # names of definitions rejected with an error (their uses are not reported again)
