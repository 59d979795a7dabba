"""The IR: resolved operands and lowered operations with explicit chain, bracket and control-flow facts; read by every backend."""

from __future__ import annotations

import dataclasses
from typing import Mapping

from transpiler.diagnostics import Span
from transpiler.language.semantics import Semantics
from transpiler.records import quick_init

BIT_KINDS = frozenset("MIOTC")
MEM_KINDS = frozenset("BWD")
WIDTH = {"B": 8, "W": 16, "D": 32, "K": 32, "KF": 32, "X": 32}
BYTES = {"B": 1, "W": 2, "D": 4}


@quick_init
@dataclasses.dataclass(frozen=True, slots=True)
class Operand:
    """A resolved operand. kind: M I O T C | B W D | K | KF | X | S (string memory) | STR (immediate text)."""

    kind: str
    addr: int = 0                       # address; constant value for K
    indexed: bool = False
    symbol: str | None = None           # the symbol name as written in the source, if any
    kfield: tuple[int, ...] = ()        # values of a KF table
    text: str = ""                      # immediate string text (STR)

    @property
    def is_bit(self) -> bool:
        return self.kind in BIT_KINDS

    @property
    def width(self) -> int:
        return WIDTH.get(self.kind, 32)

    def display(self) -> str:
        if self.symbol:
            return self.symbol + ("[X]" if self.indexed else "")
        if self.kind == "K":
            return f"K{self.addr}"
        if self.kind == "KF":
            return f"KF {self.text}[X]"
        if self.kind == "X":
            return "X"
        if self.kind == "STR":
            return f'S"{self.text}"'
        return f"{self.kind}{self.addr}" + ("[X]" if self.indexed else "")


@quick_init
@dataclasses.dataclass(frozen=True, slots=True)
class CallTarget:
    """A subprogram entry (file index and op index of its LBL) or a PLC module number."""

    file: int = -1
    index: int = -1
    label: str = ""
    module: int | None = None

    @property
    def is_module(self) -> bool:
        return self.module is not None

    @property
    def key(self) -> tuple[int, int]:
        return (self.file, self.index)


@dataclasses.dataclass(frozen=True, slots=True)
class Bracket:
    """Static facts of a bracket: operator, mode (LOGIC/WORD) and whether it is a load bracket (A-04)."""

    op: str
    mode: str
    load: bool


@quick_init
@dataclasses.dataclass(frozen=True, slots=True)
class Op:
    """One lowered operation. `code` is the semantic operation (see interp/compile.py for the list)."""

    code: str
    mnemonic: str
    span: Span
    operand: Operand | None = None
    comments: tuple[str, ...] = ()
    target: int | None = None               # jump target: op index in the same file
    call: CallTarget | None = None
    case_targets: tuple[CallTarget, ...] = ()
    case_notes: tuple[tuple[Span, tuple[str, ...]], ...] = ()   # span and comments of each CASE entry line
    bracket: Bracket | None = None
    rel: str = ""                           # comparison relation for CMP/SCMP and compare brackets
    nbits: int = 0                          # LB/LW/LD and B=/W=/D=
    label: str = ""                         # LBL name
    chain_open: bool = False                # static chain state before this op


@dataclasses.dataclass(frozen=True)
class FileCode:
    path: str
    ops: tuple[Op, ...]
    labels: Mapping[str, int]               # label name -> op index
    line_count: int


@dataclasses.dataclass(frozen=True)
class Symbol:
    name: str
    kind: str                               # M I O T C B W D S K
    addr: int                               # address, or the constant value for K
    span: Span
    comment: str = ""
    auto: bool = False
    alias_of: str | None = None
    section: str | None = None

    @property
    def operand_text(self) -> str:
        return f"K{self.addr}" if self.kind == "K" else f"{self.kind}{self.addr}"


@dataclasses.dataclass(frozen=True)
class Program:
    """The resolved program: per-file code, symbols, call graph facts; the single source of truth for backends."""

    files: tuple[FileCode, ...]             # files[0] is the main program
    symbols: Mapping[str, Symbol]           # every symbol visible anywhere (global ones and file-local ones)
    semantics: Semantics
    routines: tuple[CallTarget, ...]        # every called subprogram entry, in file/op order
    call_depth: int
    modules_used: tuple[int, ...]
    source_files: tuple[str, ...]           # every file read (src, def, cfg), display paths
    defines: Mapping[str, object]
    inactive_regions: tuple = ()
    auto_assigned: tuple[Symbol, ...] = ()
    line_count: int = 0
    config_file: str | None = None                      # the configuration read (display path), if any
    command_line_defines: tuple[tuple[str, object], ...] = ()   # the -D values, in name order

    @property
    def main(self) -> FileCode:
        return self.files[0]

    def instruction_count(self) -> int:
        return sum(1 for f in self.files for op in f.ops if op.code != "LBL")
