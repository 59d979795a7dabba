"""The IR: resolved operands and lowered operations with explicit chain, bracket and control-flow facts; read by every backend."""

from __future__ import annotations

import dataclasses
from typing import Mapping

from transpiler.diagnostics import Span
from transpiler.language.semantics import Semantics
from transpiler.records import builder, quick_init

BIT_KINDS = frozenset("MIOTC")
MEM_KINDS = frozenset("BWD")
WIDTH = {"B": 8, "W": 16, "D": 32, "K": 32, "KF": 32, "X": 32}
BYTES = {"B": 1, "W": 2, "D": 4}
# The values a byte, word or double word takes from a user (a scenario, a data table): signed or unsigned in its width.
VALUE_RANGES: Mapping[str, tuple[int, int]] = {"B": (-(1 << 7), (1 << 8) - 1), "W": (-(1 << 15), (1 << 16) - 1),
                                               "D": (-(1 << 31), (1 << 32) - 1)}


def sext(value: int, bits: int) -> int:
    """The low `bits` bits of value as a signed number."""
    mask = (1 << bits) - 1
    value &= mask
    return value - (1 << bits) if value >> (bits - 1) else value


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


@quick_init
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


new_op = builder(Op)        # Op(...) for the front end's loop over the lines


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


# ---- screen masks (.msk, .a): what the operator's PLC window shows


@dataclasses.dataclass(frozen=True)
class MaskRef:
    """What one field of a mask shows: a symbol `$NAME$`, an operand written by number (`S1`, `W230`), with its
    modifiers (`/c`, `/n=3`). `kind`/`addr` are the operand once resolved ('' before, or when it did not resolve)."""

    text: str                               # as written, without modifiers: "$WG_tc_status$", "S1"
    symbol: str | None                      # the symbol name of a $NAME$ reference
    modifiers: tuple[str, ...]              # "c", "n=3", ...
    span: Span
    kind: str = ""                          # M I O T C B W D S once resolved
    addr: int = 0

    @property
    def operand(self) -> str:
        return f"{self.kind}{self.addr}" if self.kind else ""

    @property
    def decimals(self) -> int:
        """`/n=k`: the value is a fixed-point number with k decimal places (0 without /n)."""
        for m in self.modifiers:
            if m.startswith("n="):
                return int(m[2:])
        return 0


@dataclasses.dataclass(frozen=True)
class MaskField:
    """One printf-like field of a formatted line (`%4D`, `%+5.0F`, `%s`) and the reference it shows."""

    spec: str                               # as written: "%+5.0F"
    flags: str                              # of "+-0 #"
    width: int | None
    precision: int | None
    conversion: str                         # d D s F
    ref: MaskRef


@dataclasses.dataclass(frozen=True)
class MaskStatement:
    """One statement of a mask, in file order.

    kind "text": static text (`pieces` is one string); "line": a formatted line (`pieces` alternate text and
    fields); "setting": KEY=VALUE (`key`, `value`); "errque": the error queue, `lines` lines of it."""

    kind: str
    span: Span
    pieces: tuple[str | MaskField, ...] = ()
    key: str = ""
    value: str = ""
    lines: int = 0
    modifiers: tuple[str, ...] = ()

    @property
    def fields(self) -> tuple[MaskField, ...]:
        return tuple(p for p in self.pieces if isinstance(p, MaskField))


@dataclasses.dataclass(frozen=True)
class Mask:
    """A screen mask file: its name (the file name), display path and statements."""

    name: str
    file: str
    statements: tuple[MaskStatement, ...]

    @property
    def fields(self) -> tuple[MaskField, ...]:
        return tuple(f for s in self.statements for f in s.fields)


@dataclasses.dataclass(frozen=True)
class DataRow:
    """One row of a PLC data table (MP_Data.tab, MP_Config.tab): the operand of a .def symbol and the value it holds
    from power-on and after each machine-parameter restart (M4174)."""

    table: str                              # the table's display path
    nr: int | None                          # the row's NR column, when the table has one
    symbol: str
    kind: str                               # M B W D S
    addr: int
    value: int | str                        # bits 0/1, B/W/D signed in their width, S text
    span: Span                              # of the row's value

    @property
    def operand_text(self) -> str:
        return f"{self.kind}{self.addr}"

    @property
    def key(self) -> str:
        """How the io map names the row's stored value: `MP_Data.tab:DG_TC_pos_X_manual`."""
        file = self.table.replace("\\", "/").rsplit("/", 1)[-1]
        return f"{file}:{self.symbol}"


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
    masks: tuple[Mask, ...] = ()            # the project's screen masks, references resolved
    data_rows: tuple[DataRow, ...] = ()                 # rows of the PLC data tables, in file and line order
    # The op indices of the main program's and every routine's body (flow.routine_body), keyed by CallTarget.key:
    # the call graph walks them all, and the back end's analyses walk them again. Derived from `files`: a Program
    # made from another one with other files (dataclasses.replace) must leave them out.
    routine_bodies: Mapping[tuple[int, int], tuple[int, ...]] = dataclasses.field(default_factory=dict)

    @property
    def main(self) -> FileCode:
        return self.files[0]

    def instruction_count(self) -> int:
        return sum(1 for f in self.files for op in f.ops if op.code != "LBL")
