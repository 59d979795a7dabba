"""Resolver: symbols and auto-assignment, operand checks, labels and calls, structure matching, chain state; builds the IR program."""

from __future__ import annotations

import dataclasses
import re
from typing import Iterable

from transpiler.frontend import ast
from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend.load import ParsedProject
from transpiler.ir import BIT_KINDS, BYTES, MEM_KINDS, Bracket, CallTarget, FileCode, Op, Operand, Program, Symbol
from transpiler.language.mnemonics import MNEMONICS
from transpiler.language.modules import MODULES
from transpiler.language.semantics import Semantics

_RESERVED = re.compile(r"^(?:[MIOTCBWDS][0-9]+|K[0-9]+|X|KF|S#[ED][0-9]+)$", re.IGNORECASE)
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


# --------------------------------------------------------------------------------------------
# symbols


@dataclasses.dataclass
class _SymTables:
    global_: dict[str, Symbol]
    local: dict[str, dict[str, Symbol]]
    # Names whose definition was rejected with an error, and the files whose definitions are incomplete
    # because a definition file could not be read ("*": the global ones): their unknown names are not
    # reported again (one root error per fault).
    broken: set[str] = dataclasses.field(default_factory=set)
    incomplete: frozenset[str] = frozenset()

    def already_reported(self, file: str, name: str) -> bool:
        return name in self.broken or "*" in self.incomplete or file in self.incomplete

    def lookup(self, file: str, name: str, fold_case: bool = False) -> Symbol | None:
        local = self.local.get(file)
        if local and name in local:
            return local[name]
        found = self.global_.get(name)
        if found is None and fold_case:        # symbol_case = insensitive
            found = _folded(local or {}, name) or _folded(self.global_, name)
        return found

    def all_symbols(self) -> dict[str, Symbol]:
        merged = dict(self.global_)
        for table in self.local.values():
            for name, sym in table.items():
                merged.setdefault(name, sym)
        return merged


class _Allocator:
    """Deterministic auto-assignment (A-49): lowest free address per kind, aligned, never overlapping."""

    def __init__(self, semantics: Semantics, used_bits: dict[str, set[int]], used_bytes: set[int]):
        self.ranges = semantics.profile.ranges
        self.profile = semantics.profile
        self.used_bits = used_bits
        self.used_bytes = used_bytes
        # Addresses are only ever added to the used sets, so the lowest free address of a kind never goes
        # down: each search resumes where the previous one stopped (linear instead of quadratic time).
        self.resume: dict[str, int] = {}

    def allocate(self, kind: str) -> int | None:
        resume = self.resume.get(kind, 0)
        if kind in BIT_KINDS or kind == "S":
            used = self.used_bits.setdefault(kind, set())
            for lo, hi in getattr(self.ranges, kind):
                for addr in range(max(lo, resume), hi + 1):
                    if addr not in used and not self.profile.is_interface(kind, addr):
                        used.add(addr)
                        self.resume[kind] = addr + 1
                        return addr
            return None
        size = BYTES[kind]
        for lo, hi in self.ranges.B:
            start = (max(lo, resume) + size - 1) // size * size
            for addr in range(start, hi - size + 2, size):
                span = range(addr, addr + size)
                if any(a in self.used_bytes for a in span) or any(self.profile.is_interface("B", a) for a in span):
                    continue
                self.used_bytes.update(span)
                self.resume[kind] = addr + size
                return addr
        return None


def _explicit_addresses(project: ParsedProject) -> tuple[dict[str, set[int]], set[int]]:
    bits: dict[str, set[int]] = {}
    mem: set[int] = set()
    for src in project.src_files:
        for stmt in src.statements:
            if isinstance(stmt, ast.Instr) and stmt.operand is not None:
                op = stmt.operand
                if op.kind in BIT_KINDS or op.kind == "S":
                    count = BIT_GROUPS.get(stmt.mnemonic, 1)
                    bits.setdefault(op.kind, set()).update(range(int(op.value), int(op.value) + count))
                elif op.kind in MEM_KINDS:
                    mem.update(range(int(op.value), int(op.value) + BYTES[op.kind]))
    for defs in list(project.global_defs) + [d for ds in project.local_defs.values() for d in ds]:
        for s in defs.symbols:
            if s.address is not None:
                if s.kind in MEM_KINDS:
                    mem.update(range(s.address, s.address + BYTES[s.kind]))
                else:
                    bits.setdefault(s.kind, set()).add(s.address)
    return bits, mem


def build_symbols(project: ParsedProject, semantics: Semantics, diags: Diagnostics) -> tuple[_SymTables, list[Symbol]]:
    used_bits, used_bytes = _explicit_addresses(project)
    allocator = _Allocator(semantics, used_bits, used_bytes)
    auto: list[Symbol] = []
    tables = _SymTables({}, {}, incomplete=project.symbols_incomplete)
    addr_owner: dict[tuple[str, int], ast.SymbolDef] = {}
    auto_by_definition: dict[Span, Symbol] = {}

    def fill(table: dict[str, Symbol], defs: Iterable[ast.DefFile]) -> None:
        entries = [s for d in defs for s in d.symbols]
        for d in defs:
            tables.broken.update(d.broken)
        for s in entries:
            if _RESERVED.match(s.name):
                diags.report("E-SYM-RESERVED", s.span, f"symbol name '{s.name}' is literal operand syntax")
                continue
            if s.address is not None and not _check_def_address(s, semantics, diags):
                tables.broken.add(s.name)
                continue
            if s.alias is not None:
                continue
            if s.kind == "K":
                sym = Symbol(s.name, "K", int(s.constant), s.span, " ".join(s.comments), section=s.section)
            elif s.address is not None:
                sym = Symbol(s.name, s.kind, s.address, s.span, " ".join(s.comments), section=s.section)
                key = (s.kind if s.kind not in MEM_KINDS else "BYTE", s.address)
                # (the same name again is an identical redefinition or the same file read for two owners)
                if key in addr_owner and not s.cflag and addr_owner[key].kind == s.kind and addr_owner[key].name != s.name:
                    other = addr_owner[key]
                    diags.report("E-DEF-DUP-ADDR", s.span, f"{s.name} names {s.kind}{s.address} like {other.name} "
                                  f"({other.span}); mark an intended second use with /c")
                addr_owner.setdefault(key, s)
            elif s.span in auto_by_definition:
                # A local .def file named by several modules: one definition line is one operand.
                sym = auto_by_definition[s.span]
            else:
                addr = allocator.allocate(s.kind)
                if addr is None:
                    diags.report("E-DEF-POOL", s.span, f"no free {s.kind} operand left for {s.name}")
                    tables.broken.add(s.name)
                    continue
                sym = Symbol(s.name, s.kind, addr, s.span, " ".join(s.comments), auto=True, section=s.section)
                auto.append(sym)
                auto_by_definition[s.span] = sym
            _add(table, sym, diags)
        pending = [s for s in entries if s.alias is not None]
        for _ in range(len(pending) + 1):
            progressed = False
            rest = []
            for s in pending:
                target = table.get(s.alias) or tables.global_.get(s.alias)
                if target is None:
                    rest.append(s)
                    continue
                if target.kind != s.kind:
                    diags.report("E-DEF-ALIAS", s.span, f"{s.name} is of kind {s.kind} but its alias target "
                                f"{s.alias} is of kind {target.kind}")
                    tables.broken.add(s.name)
                else:
                    _add(table, Symbol(s.name, s.kind, target.addr, s.span, " ".join(s.comments),
                                       alias_of=s.alias, section=s.section), diags)
                progressed = True
            pending = rest
            if not progressed:
                break
        for s in pending:
            if s.alias not in tables.broken and "*" not in tables.incomplete:   # else reported already
                diags.report("E-DEF-ALIAS", s.span, f"alias target &{s.alias} of {s.name} is not defined")
            tables.broken.add(s.name)

    fill(tables.global_, project.global_defs)
    for owner, defs in project.local_defs.items():
        table: dict[str, Symbol] = {}
        fill(table, defs)
        tables.local[owner] = table
    _check_case_clashes(tables.all_symbols().values(), diags)
    return tables, auto


def _add(table: dict[str, Symbol], sym: Symbol, diags: Diagnostics) -> None:
    old = table.get(sym.name)
    if old is not None:
        if (old.kind, old.addr) != (sym.kind, sym.addr) or old.auto or sym.auto:
            if not (old.auto and sym.auto and old.span == sym.span):
                diags.report("E-SYM-DUP", sym.span, f"symbol {sym.name} is already defined at {old.span}")
        return
    table[sym.name] = sym


def _folded_key(table: dict, name: str) -> str | None:
    """The key that equals name ignoring case (the first in sorted order, for determinism)."""
    lower = name.lower()
    return next((key for key in sorted(table) if key.lower() == lower), None)


def _folded(table: dict, name: str):
    """The entry whose key equals name ignoring case."""
    key = _folded_key(table, name)
    return None if key is None else table[key]


def _check_case_clashes(symbols: Iterable[Symbol], diags: Diagnostics) -> None:
    by_lower: dict[str, Symbol] = {}
    for sym in sorted(symbols, key=lambda s: (s.span.file, s.span.line, s.name)):
        other = by_lower.get(sym.name.lower())
        if other is not None and other.name != sym.name:
            diags.report("E-SYM-CASE", sym.span, f"{sym.name} differs from {other.name} ({other.span}) only in case")
        by_lower.setdefault(sym.name.lower(), sym)


def _check_def_address(s: ast.SymbolDef, semantics: Semantics, diags: Diagnostics) -> bool:
    return _check_range(s.kind, s.address, semantics, s.span, diags, s.name)


def _check_range(kind: str, addr: int, semantics: Semantics, span: Span, diags: Diagnostics, what: str,
                 count: int = 1) -> bool:
    profile = semantics.profile
    prefix = "" if what == f"{kind}{addr}" else f"{what}: "     # name the symbol when one was written
    if kind in MEM_KINDS:
        size = BYTES[kind]
        if addr % size:
            diags.report("E-ADDR-ALIGN", span, f"{prefix}{kind}{addr} is not aligned to {size} bytes")
            return False
        ok = (_inside_one_interval(profile.ranges.B, addr, addr + size - 1)
              or all(profile.ranges.contains("B", a) for a in range(addr, addr + size))
              or profile.is_interface(kind, addr, size))
    elif kind in BIT_KINDS or kind == "S":
        # The fast test (whole span inside one interval) decides almost every operand; the per-address
        # test is only needed for spans that cross an interval border or touch interface operands.
        ok = (_inside_one_interval(getattr(profile.ranges, kind), addr, addr + count - 1)
              or all(profile.ranges.contains(kind, a) or profile.is_interface(kind, a) for a in range(addr, addr + count)))
    else:
        return True
    if not ok:
        extra = f" (and the following {count - 1})" if count > 1 else ""
        diags.report("E-ADDR-RANGE", span, f"{prefix}{kind}{addr}{extra} is outside the {profile.name} range")
    return ok


def _inside_one_interval(intervals: tuple[tuple[int, int], ...], first: int, last: int) -> bool:
    for lo, hi in intervals:
        if lo <= first and last <= hi:
            return True
    return False


# --------------------------------------------------------------------------------------------
# per-file lowering


@dataclasses.dataclass
class _Frame:
    op: str
    mode: str
    load: bool
    index: int
    span: Span
    # E-BRACKET-SPAN faults inside this bracket; reported when it closes. A bracket that is never closed
    # reports only E-BRACKET-BALANCE: the missing ']' is the root fault, not the EM after it.
    span_faults: list[tuple[Span, str]] = dataclasses.field(default_factory=list)


class _FileLowering:
    """Turns one parsed file into ops: operands resolved, structures matched, chain/bracket state computed."""

    def __init__(self, file_index: int, src: ast.SourceFile, symbols: _SymTables, semantics: Semantics,
                 diags: Diagnostics):
        self.file_index = file_index
        self.src = src
        self.symbols = symbols
        self.semantics = semantics
        self.diags = diags
        self.ops: list[Op] = []
        self.labels: dict[str, int] = {}
        self.kfields: dict[str, tuple[int, ...]] = {}
        self.globals: list[ast.Global] = []
        self.externs: dict[str, ast.Extern] = {}
        self.pending_calls: list[tuple[int, str, Span]] = []     # op index, label, span (CM/SUBM targets)
        self.pending_case: list[tuple[int, int, str, Span]] = []  # op index, entry, label, span
        self.case_entries: dict[int, list[tuple[Span, tuple[str, ...]]]] = {}   # CASE op index -> entry notes
        self.pending_jumps: list[tuple[int, str, Span]] = []

    def run(self) -> None:
        stmts = self.src.statements
        kfield_lines: dict[str, int] = {}
        for stmt in stmts:
            if isinstance(stmt, ast.KField):
                if stmt.name in self.kfields:
                    self.diags.report("E-SYM-DUP-LABEL", stmt.span, f"KFIELD {stmt.name} is defined twice")
                self.kfields[stmt.name] = stmt.values
                kfield_lines.setdefault(stmt.name, stmt.span.line)
        chain_open = False
        last_acc = "NONE"
        brackets: list[_Frame] = []
        structs: list[list] = []     # [keyword, op index, else index]
        case_open: tuple[int | None, Span] | None = None
        # E-CASE-BODY faults inside the open table, reported at its ENDC: a table that is never closed reports
        # only "CASE without ENDC" (the missing ENDC is the root fault, not every line after it).
        case_faults: list[tuple[Span, str]] = []
        for stmt in stmts:
            if isinstance(stmt, ast.Global):
                self.globals.append(stmt)
                continue
            if isinstance(stmt, ast.Extern):
                self.externs.setdefault(stmt.name, stmt)
                continue
            if isinstance(stmt, (ast.Uses, ast.DefineFile)):
                continue
            index = len(self.ops)
            if isinstance(stmt, ast.Label):
                if case_open:
                    case_faults.append((stmt.span, "only 'CM label' lines may stand inside CASE ... ENDC"))
                if brackets and self.semantics["bracket_span"] == "forbidden":
                    brackets[-1].span_faults.append((stmt.span, "LBL inside an open bracket"))
                if stmt.name in self.labels:
                    self.diags.report("E-SYM-DUP-LABEL", stmt.span, f"label {stmt.name} is defined twice in this file")
                else:
                    self.labels[stmt.name] = index
                    # KFIELD names live in the label name space of the file (spec 6.17): the later one is the fault
                    if kfield_lines.get(stmt.name, stmt.span.line) < stmt.span.line:
                        self.diags.report("E-SYM-DUP-LABEL", stmt.span, f"label {stmt.name} has the name of the "
                                         f"KFIELD at line {kfield_lines[stmt.name]}")
                self.ops.append(Op("LBL", "LBL", stmt.span, comments=stmt.comments, label=stmt.name, chain_open=chain_open))
                chain_open, last_acc = False, "NONE"
                continue
            if isinstance(stmt, ast.KField):
                if stmt.name in self.labels:
                    self.diags.report("E-SYM-DUP-LABEL", stmt.span, f"KFIELD {stmt.name} has the name of a label "
                                     "defined above it")
                prev = next((o for o in reversed(self.ops) if o.code not in ("KFIELD",)), None)
                if prev is None or prev.mnemonic not in ("EM", "JP"):
                    self.diags.report("E-KF-PLACEMENT", stmt.span,
                                     f"KFIELD {stmt.name} must follow an unconditional EM or JP")
                self.ops.append(Op("KFIELD", "KFIELD", stmt.span, comments=stmt.comments, label=stmt.name))
                chain_open, last_acc = False, "NONE"
                continue
            instr: ast.Instr = stmt
            m = instr.mnemonic
            info = MNEMONICS[m]
            if info.extended and not self.semantics["extended_instructions"]:
                self.diags.report("E-UNSUPPORTED", instr.span, f"{m} is an extended instruction (A-23), "
                                 f"not enabled for profile {self.semantics.profile.name}")
                continue
            if m == "=N" and not self.semantics["allow_assign_not"]:
                self.diags.report("E-UNSUPPORTED", instr.span, "=N is not part of the language (enable allow_assign_not, A-16)")
                continue
            if case_open is not None and m not in ("CM", "ENDC"):
                case_faults.append((instr.span, f"only 'CM label' lines may stand inside CASE ... ENDC, not {m}"))
                continue
            if (brackets and m in CONTROL and case_open is None      # (a table's CM and ENDC go with its CASE)
                    and self.semantics["bracket_span"] == "forbidden"):
                brackets[-1].span_faults.append(
                    (instr.span, f"{m} inside an open bracket (opened at line {brackets[-1].span.line})"))
                # CASE/ENDC and structured keywords still take part in structure matching, so that their
                # partners outside the bracket do not report a second error.
                if m not in STRUCT_ALL and m not in ("CASE", "ENDC"):
                    continue
            if case_open is not None and m == "CM":
                case_index = case_open[0]
                op = instr.operand
                if op.kind == "NUM":
                    case_faults.append((instr.span, "a PLC module cannot be a CASE entry"))
                    continue
                if case_index is None:       # the CASE line itself was rejected
                    continue
                notes = self.case_entries.setdefault(case_index, [])
                self.pending_case.append((case_index, len(notes), _label_text(op), instr.span))
                notes.append((instr.span, instr.comments))
                continue
            operand = None
            if instr.operand is not None and info.form == "operand":
                operand = self._operand(instr)
                if operand is None or not self._kind_ok(instr, operand):
                    if m == "CASE":
                        # Keep the table open (without an op) so that its entries and ENDC cause no more errors.
                        case_open, case_faults = (None, instr.span), []
                    continue
            op, chain_open, last_acc = self._lower(instr, operand, index, chain_open, last_acc, brackets, structs)
            if op is None:
                continue
            if m == "CASE":
                case_open, case_faults = (index, instr.span), []
            elif m == "ENDC":
                if case_open is None:
                    self.diags.report("E-CASE-BODY", instr.span, "ENDC without CASE")
                for fault_span, message in case_faults:
                    self.diags.report("E-CASE-BODY", fault_span, message)
                case_open, case_faults = None, []
            self.ops.append(op)
        for case_index, notes in self.case_entries.items():
            self.ops[case_index] = dataclasses.replace(self.ops[case_index], case_notes=tuple(notes))
        for frame in brackets:
            self.diags.report("E-BRACKET-BALANCE", frame.span, f"bracket {frame.op}[ is never closed")
        for frame in structs:
            self.diags.report("E-STRUCT-NEST", self.ops[frame[1]].span, f"{frame[0]} is never closed")
        if case_open is not None:
            self.diags.report("E-CASE-BODY", case_open[1], "CASE without ENDC")

    # ---- operands

    def _operand(self, instr: ast.Instr) -> Operand | None:
        syn = instr.operand
        span = instr.span
        kind, value = syn.kind, syn.value
        symbol = None
        if kind == "SYM":
            sym = self.symbols.lookup(self.src.path, str(value), self.semantics["symbol_case"] == "insensitive")
            if sym is None:
                if str(value) in self.kfields:
                    self.diags.report("E-OPERAND-KIND", span, f"constant field {value} is read as 'KF {value}[X]'")
                elif not self.symbols.already_reported(self.src.path, str(value)):
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
        if not syn.indexed and not _check_range(kind, addr, self.semantics, span, self.diags, symbol or f"{kind}{addr}", count):
            return None
        return Operand(kind, addr, indexed=syn.indexed, symbol=symbol)

    def _kind_ok(self, instr: ast.Instr, operand: Operand) -> bool:
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

    # ---- lowering

    def _lower(self, instr: ast.Instr, operand: Operand | None, index: int, chain_open: bool, last_acc: str,
               brackets: list[_Frame], structs: list[list]) -> tuple[Op | None, bool, str]:
        m = instr.mnemonic
        span = instr.span
        base = dict(mnemonic=m, span=span, operand=operand, comments=instr.comments, chain_open=chain_open)
        is_bit = operand is not None and operand.is_bit
        is_str = operand is not None and operand.kind in ("S", "STR")
        if m in ("L", "LN"):
            if is_bit:
                return Op("LD" if m == "L" else "LDN", **base), True, "LOGIC"
            if is_str:
                return Op("SLD", **base), chain_open, "STRING"
            return Op("WLD" if m == "L" else "WLDN", **base), chain_open, "WORD"
        if m == "L-":
            return Op("WNEG", **base), chain_open, "WORD"
        if m in ("LB", "LW", "LD"):
            return Op("LDBITS", nbits=BIT_GROUPS[m], **base), chain_open, "WORD"
        if m in ("=", "=N", "S", "R", "SN", "RN"):
            if is_bit:
                code = {"=": "ST", "=N": "STN", "S": "SET", "R": "RES", "SN": "SETN", "RN": "RESN"}[m]
                return Op(code, **base), False, "LOGIC"
            if operand.kind == "S":
                return Op("SST", **base), False, "STRING"
            return Op("WST", **base), False, "WORD"
        if m in ("B=", "W=", "D="):
            return Op("STBITS", nbits=BIT_GROUPS[m], **base), False, "WORD"
        if m in LOGIC_GATES:
            if is_bit:
                if chain_open or self.semantics["chain_model"] == "dynamic":
                    return Op(LOGIC_GATES[m], **base), True, "LOGIC"
                return Op(GATE_AS_LOAD[m], **base), True, "LOGIC"
            if not chain_open and self.semantics["word_gate_at_chain_start"] == "load":
                return Op("WLD" if GATE_AS_LOAD[m] == "LD" else "WLDN", **base), chain_open, "WORD"
            return Op(WORD_GATES[m], **base), chain_open, "WORD"
        if m in ARITH:
            if is_str and m == "+":
                return Op("SCAT", **base), chain_open, "STRING"
            return Op(ARITH[m], **base), chain_open, "WORD"
        if m in COMPARES:
            return Op("SCMP" if is_str else "CMP", rel=m, **base), True, "LOGIC"
        if m in ("<<", ">>"):
            return Op("SHL" if m == "<<" else "SHR", **base), chain_open, "WORD"
        if m in ("BS", "BC"):
            return Op(m, **base), chain_open, "WORD"
        if m == "BT":
            return Op("BT", **base), True, "LOGIC"
        if m.endswith("[") and m != "[":
            return self._open_bracket(m[:-1], base, index, chain_open, last_acc, brackets)
        if m == "]":
            if not brackets:
                self.diags.report("E-BRACKET-BALANCE", span, "']' without an opening bracket")
                return None, chain_open, last_acc
            frame = brackets.pop()
            for fault_span, message in frame.span_faults:
                self.diags.report("E-BRACKET-SPAN", fault_span, message)
            bracket = Bracket(frame.op, frame.mode, frame.load)
            logic_result = (frame.op in LOGIC_GATES and frame.mode == "LOGIC") or frame.op in COMPARES
            return (Op("BCLOSE", bracket=bracket, rel=frame.op if frame.op in COMPARES else "", **base),
                    True if logic_result else chain_open, "LOGIC" if logic_result else "WORD")
        if m == "PS":
            return Op("PUSH", **base), chain_open, "NONE"
        if m == "PL":
            return Op("POP", **base), chain_open, "NONE"
        if m in ("PSW", "PLW", "PSX", "PLX"):
            return Op(m, **base), chain_open, "WORD"
        if m == "PSL":
            return Op("PSL", **base), chain_open, "LOGIC"
        if m == "PLL":
            return Op("PLL", **base), True, "LOGIC"
        if m in ("JP", "JPT", "JPF"):
            self.pending_jumps.append((index, _label_text(instr.operand), span))
            return Op(m, **base), False, "NONE"
        if m in ("CM", "CMT", "CMF"):
            code = {"CM": "CALL", "CMT": "CALLT", "CMF": "CALLF"}[m]
            if instr.operand.kind == "NUM":
                number = int(instr.operand.value)
                if not 9000 <= number <= 9999:
                    self.diags.report("E-SYNTAX", span, f"PLC module numbers are 9000-9999, not {number}")
                    return None, chain_open, last_acc
                if number not in MODULES:
                    self.diags.report("E-MODULE-UNKNOWN", span, f"PLC module {number} has no model; "
                                       "it runs as a stub without parameters or results (A-46)")
                return Op(code, call=CallTarget(module=number), **base), False, "NONE"
            self.pending_calls.append((index, _label_text(instr.operand), span))
            return Op(code, **base), False, "NONE"
        if m == "SUBM":
            self.pending_calls.append((index, _label_text(instr.operand), span))
            return Op("SUBM", **base), False, "WORD"
        if m in ("RPLY", "CAN"):
            return Op(m, **base), chain_open, "WORD" if m == "RPLY" else "NONE"
        if m in ("EM", "EMT", "EMF"):
            return Op(m, **base), False, "NONE"
        if m == "CASE":
            return Op("CASE", **base), False, "NONE"
        if m == "ENDC":
            return Op("NOP", **base), False, "NONE"
        if m in STRUCT_ALL:
            return self._structured(m, base, index, structs), False, "NONE"
        if m in ("INC", "DEC"):
            return Op(m, **base), chain_open, "LOGIC" if is_bit else "NONE"
        if m == "NOTL":
            return Op("NOTL", **base), True, "LOGIC"
        if m in ("INCW", "DECW", "INCX", "DECX", "NOTW", "TWOC"):
            return Op(m, **base), chain_open, "WORD"
        self.diags.report("E-UNSUPPORTED", span, f"{m} is not supported")
        return None, chain_open, last_acc

    def _open_bracket(self, op: str, base: dict, index: int, chain_open: bool, last_acc: str,
                      brackets: list[_Frame]) -> tuple[Op | None, bool, str]:
        span = base["span"]
        if len(brackets) >= MAX_NESTING:
            if len(brackets) == MAX_NESTING:     # once per too-deep nest, not for every deeper level
                self.diags.report("E-BRACKET-DEPTH", span, f"brackets nested deeper than {MAX_NESTING}")
            # Keep a frame so that the matching ']' does not cascade into a second error.
            brackets.append(_Frame(op, "LOGIC" if op in LOGIC_GATES else "WORD", False, index, span))
            return None, chain_open, last_acc
        mode = last_acc
        if mode == "STRING":
            self.diags.report("E-BRACKET-MODE", span, f"{op}[ after a string instruction")
            brackets.append(_Frame(op, "WORD", False, index, span))   # the matching ']' must not cascade
            return None, chain_open, last_acc
        if mode == "NONE":
            mode = "LOGIC" if op in LOGIC_GATES else "WORD"
        if (op in ARITH or op in COMPARES) and mode != "WORD":
            self.diags.report("E-BRACKET-MODE", span, f"{op}[ needs a word value before it (the previous instruction "
                             "addressed the logic accumulator)")
            brackets.append(_Frame(op, "WORD", False, index, span))   # the matching ']' must not cascade
            return None, chain_open, last_acc
        load = (mode == "LOGIC" and op in LOGIC_GATES and not chain_open
                and self.semantics["bracket_at_chain_start"] == "load")
        brackets.append(_Frame(op, mode, load, index, span))
        new_chain = False if (mode == "LOGIC" or op in COMPARES) else chain_open
        return Op("BOPEN", bracket=Bracket(op, mode, load), rel=op if op in COMPARES else "", **base), new_chain, mode

    def _structured(self, m: str, base: dict, index: int, structs: list[list]) -> Op | None:
        span = base["span"]
        if m in STRUCT_OPEN:
            if len(structs) == MAX_NESTING:      # once per too-deep nest, not for every deeper level
                self.diags.report("E-STRUCT-NEST", span, f"structured statements nested deeper than {MAX_NESTING}")
            structs.append([m, index, None])
            code = {"IFT": "JPF", "IFF": "JPT", "WHILET": "JPF", "WHILEF": "JPT", "REPEAT": "NOP"}[m]
            return Op(code, **base)
        expected = {"ELSE": ("IFT", "IFF"), "ENDI": ("IFT", "IFF"), "ENDW": ("WHILET", "WHILEF"),
                    "UNTILT": ("REPEAT",), "UNTILF": ("REPEAT",)}[m]
        if not structs or structs[-1][0] not in expected or (m == "ELSE" and structs[-1][2] is not None):
            opener = structs[-1][0] if structs else "nothing"
            self.diags.report("E-STRUCT-NEST", span, f"{m} does not match the open structure ({opener})")
            # Interleaved structures (IFT WHILET ENDI ENDW): forget the opener this keyword was meant for, so
            # that the inner one still closes normally and the overlap is one error, not three.
            if m != "ELSE":
                for k in range(len(structs) - 1, -1, -1):
                    if structs[k][0] in expected:
                        del structs[k]
                        break
            return Op("NOP", **base)
        frame = structs[-1]
        if m == "ELSE":
            frame[2] = index
            self._patch(frame[1], index + 1)
            return Op("JP", **base)          # target patched at ENDI
        structs.pop()
        opener_index = frame[1]
        if m == "ENDI":
            if frame[2] is not None:
                self._patch(frame[2], index)
            else:
                self._patch(opener_index, index)
            return Op("NOP", **base)
        if m == "ENDW":
            self._patch(opener_index, index + 1)
            back = opener_index
            if self.semantics["while_retest"] == "chain":
                back = self._chain_start(opener_index)
            return Op("JP", target=back, **base)
        return Op("JPF" if m == "UNTILT" else "JPT", target=opener_index, **base)

    def _chain_start(self, index: int) -> int:
        """The first instruction of the logic chain before ops[index] (while_retest = chain)."""
        start = index
        for j in range(index - 1, -1, -1):
            o = self.ops[j]
            if o.code in ("LBL", "KFIELD") or o.mnemonic in CONTROL or o.code in (
                    "ST", "STN", "SET", "RES", "SETN", "RESN", "WST", "SST", "STBITS"):
                break
            start = j
        return start

    def _patch(self, index: int, target: int) -> None:
        self.ops[index] = dataclasses.replace(self.ops[index], target=target)


def _label_text(syn: ast.OperandSyntax) -> str:
    return str(syn.value) if syn.kind == "SYM" else syn.text


def _kind_name(kind: str) -> str:
    return {"M": "marker", "I": "input", "O": "output", "T": "timer", "C": "counter", "B": "byte", "W": "word",
            "D": "double word", "K": "constant", "KF": "constant field", "X": "index register",
            "S": "string", "STR": "string literal"}.get(kind, kind)


# --------------------------------------------------------------------------------------------
# program


def resolve(project: ParsedProject, semantics: Semantics, diags: Diagnostics) -> Program:
    symbols, auto = build_symbols(project, semantics, diags)
    lowerings = [_FileLowering(i, src, symbols, semantics, diags) for i, src in enumerate(project.src_files)]
    for low in lowerings:
        low.run()
    exports = _exports(lowerings, diags)
    for low in lowerings:
        _link(low, lowerings, exports, diags, project.labels_incomplete)
    files = tuple(FileCode(low.src.path, tuple(low.ops), dict(low.labels), low.src.line_count) for low in lowerings)
    lost_lines = {d.span.file for d in diags.errors if d.code in _LOST_LINE_CODES}
    for i, (f, low) in enumerate(zip(files, lowerings)):
        if _flow_is_complete(low, lost_lines):
            _check_flow(i, f, diags)
    for i, low in enumerate(lowerings[1:], start=1):
        if low.src.broken_labels:            # the first LBL may be the line that was rejected
            continue
        for op in files[i].ops:
            if op.code == "LBL":
                break
            if op.code not in ("KFIELD",):
                diags.report("E-MOD-UNREACHABLE", op.span, "statement in a module file before its first LBL is never executed")
                break
    routines, depth = _call_graph(files, semantics, diags)
    modules = sorted({op.call.module for f in files for op in f.ops if op.call is not None and op.call.is_module})
    return Program(files, symbols.all_symbols(), semantics, routines, depth, tuple(modules), project.files_read,
                   dict(project.defines), project.inactive, tuple(auto), project.line_count)


def _exports(lowerings: list[_FileLowering], diags: Diagnostics) -> dict[str, CallTarget]:
    exports: dict[str, CallTarget] = {}
    where: dict[str, Span] = {}
    for low in lowerings:
        for g in low.globals:
            if g.name not in low.labels:
                if g.name not in low.src.broken_labels:
                    diags.report("E-SYM-GLOBAL-UNDEF", g.span, f"GLOBAL {g.name}: no such label in this file")
                continue
            if g.name in exports and exports[g.name].file != low.file_index:
                diags.report("E-SYM-DUP-GLOBAL", g.span, f"label {g.name} is also exported at {where[g.name]}")
                continue
            exports[g.name] = CallTarget(low.file_index, low.labels[g.name], g.name)
            where[g.name] = g.span
    return exports


def _link(low: _FileLowering, lowerings: list[_FileLowering], exports: dict[str, CallTarget], diags: Diagnostics,
          labels_incomplete: bool = False) -> None:
    if low.semantics["symbol_case"] == "insensitive":       # labels are looked up ignoring case too
        def spelled(name: str, table: dict) -> str:
            return name if name in table else _folded_key(table, name) or name
    else:
        def spelled(name: str, table: dict) -> str:
            return name

    def target(name: str, span: Span) -> CallTarget | None:
        name = spelled(name, low.labels)
        if name not in low.labels:
            name = spelled(name, low.externs)
        if name in low.externs:
            name = spelled(name, exports)
        if name in low.labels:
            return CallTarget(low.file_index, low.labels[name], name)
        if name in low.externs:
            found = exports.get(name)
            if found is not None:
                return found
            # (not again when the module that would export it is unreadable, or its LBL line was rejected)
            if not labels_incomplete and not any(name in o.src.broken_labels for o in lowerings):
                diags.report("E-SYM-UNRESOLVED", span, f"EXTERN {name} is not exported with GLOBAL by any used module")
            return None
        if name in low.src.broken_labels:   # its LBL line was rejected already
            return None
        elsewhere = [o.src.path for o in lowerings if name in o.labels]
        hint = f" (it is defined in {elsewhere[0]}: add GLOBAL there and EXTERN here)" if elsewhere else ""
        diags.report("E-SYM-UNRESOLVED", span, f"label {name} is not defined in this file{hint}")
        return None

    for index, name, span in low.pending_calls:
        t = target(name, span)
        if t is not None:
            low.ops[index] = dataclasses.replace(low.ops[index], call=t)
    case_targets: dict[int, list[CallTarget]] = {}
    for index, entry, name, span in low.pending_case:          # entries arrive in table order
        t = target(name, span)
        case_targets.setdefault(index, []).append(t if t is not None else CallTarget(label=name))
    for index, targets in case_targets.items():
        low.ops[index] = dataclasses.replace(low.ops[index], case_targets=tuple(targets))
    for index, name, span in low.pending_jumps:
        name = spelled(name, low.labels)
        if name in low.labels:
            low.ops[index] = dataclasses.replace(low.ops[index], target=low.labels[name])
        elif name not in low.src.broken_labels:
            elsewhere = [o.src.path for o in lowerings if name in o.labels]
            where = f"; it is in {elsewhere[0]} (jumps stay inside a file, A-31)" if elsewhere else ""
            diags.report("E-JUMP-SCOPE", span, f"jump target {name} is not a label of this file{where}")


_LOST_LINE_CODES = frozenset({"E-SYNTAX", "E-UNSUPPORTED", "E-LIT-RANGE", "E-PP-NEST", "E-PP-SYNTAX",
                              "E-FILE-NOT-FOUND", "E-FILE-ESCAPE", "E-FILE-READ", "E-FILE-INCLUDE-CYCLE"})
_FLOW_MNEMONICS = frozenset({"EM", "EMT", "EMF", "JP", "JPT", "JPF", "CASE", "ENDC"}) | STRUCT_ALL


def _flow_is_complete(low: _FileLowering, lost_lines: set[str]) -> bool:
    """False when an earlier error removed a line (in one of `lost_lines`' files) or a control statement of the
    file: a path that then seems to run off the end is a consequence of that error, not a second fault."""
    files = {low.src.path} | {stmt.span.file for stmt in low.src.statements}
    if not lost_lines.isdisjoint(files):
        return False
    lowered = {op.span for op in low.ops}
    return all(stmt.span in lowered for stmt in low.src.statements
               if isinstance(stmt, ast.Instr) and stmt.mnemonic in _FLOW_MNEMONICS)


def successors(ops: tuple[Op, ...], i: int) -> list[int]:
    """Static successors of op i inside its file (calls return to i+1)."""
    op = ops[i]
    if op.code == "EM":
        return []
    if op.code == "JP":
        return [op.target] if op.target is not None else []
    if op.code in ("JPT", "JPF"):
        return [i + 1] + ([op.target] if op.target is not None else [])
    return [i + 1]


def _check_flow(file_index: int, f: FileCode, diags: Diagnostics) -> None:
    ops = f.ops
    entries = [0] if file_index == 0 else []
    entries += list(f.labels.values())
    seen: set[int] = set()
    stack = [e for e in entries if e < len(ops)]
    falls_off = file_index == 0 and not ops
    while stack:
        i = stack.pop()
        if i in seen:
            continue
        seen.add(i)
        if ops[i].code == "KFIELD":
            continue
        for s in successors(ops, i):
            if s >= len(ops):
                falls_off = True
            elif s not in seen:
                stack.append(s)
    if falls_off:
        diags.report("E-FALL-OFF-END", Span(f.path, max(1, f.line_count), 1),
                    "a path reaches the end of the file without EM")


def routine_body(files: tuple[FileCode, ...], entry: CallTarget) -> list[int]:
    """Op indices reachable from an entry until EM (the body of a subprogram, spec 7.3)."""
    ops = files[entry.file].ops
    seen: set[int] = set()
    stack = [entry.index]
    while stack:
        i = stack.pop()
        if i in seen or i >= len(ops):
            continue
        seen.add(i)
        stack.extend(s for s in successors(ops, i) if s not in seen)
    return sorted(seen)


def _call_graph(files: tuple[FileCode, ...], semantics: Semantics, diags: Diagnostics) -> tuple[tuple[CallTarget, ...], int]:
    main = CallTarget(0, 0, "<main>")
    nodes: dict[tuple[int, int], CallTarget] = {}
    edges: dict[tuple[int, int], list[tuple[CallTarget, Span]]] = {}     # callee and the span of the call
    roots = [main] if files and files[0].ops else []
    todo = list(roots)
    while todo:
        node = todo.pop()
        if node.key in edges:
            continue
        out: list[tuple[CallTarget, Span]] = []
        for i in routine_body(files, node):
            op = files[node.file].ops[i]
            callees: list[tuple[CallTarget, Span]] = []
            if op.code in ("CALL", "CALLT", "CALLF") and op.call is not None and not op.call.is_module and op.call.file >= 0:
                callees.append((op.call, op.span))
            elif op.code == "CASE":
                # each entry is a call site of its own (spec 6.15.1), located at its CM line
                callees.extend((t, op.case_notes[k][0] if k < len(op.case_notes) else op.span)
                               for k, t in enumerate(op.case_targets) if t is not None and t.file >= 0)
            elif op.code == "SUBM" and op.call is not None and op.call.file >= 0:
                if op.call.key not in nodes:
                    nodes[op.call.key] = op.call
                    roots.append(op.call)
                    todo.append(op.call)
            for c, call_span in callees:
                out.append((c, call_span))
                if c.key not in nodes:
                    nodes[c.key] = c
                    todo.append(c)
        edges[node.key] = out
    # recursion: strongly connected components with a cycle
    index_of: dict[tuple[int, int], int] = {}
    low: dict[tuple[int, int], int] = {}
    on_stack: set[tuple[int, int]] = set()
    stack: list[tuple[int, int]] = []
    sccs: list[list[tuple[int, int]]] = []

    def strong(v: tuple[int, int]) -> None:
        work: list[tuple[tuple[int, int], int]] = []

        def enter(w: tuple[int, int]) -> None:
            index_of[w] = low[w] = len(index_of)      # visit order: nodes are numbered as they are entered
            stack.append(w)
            on_stack.add(w)
            work.append((w, 0))

        enter(v)
        while work:
            node, pos = work[-1]
            succ = edges.get(node, [])
            if pos < len(succ):
                work[-1] = (node, pos + 1)
                w = succ[pos][0].key
                if w not in index_of:
                    enter(w)
                elif w in on_stack:
                    low[node] = min(low[node], index_of[w])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index_of[node]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == node:
                        break
                sccs.append(comp)

    for key in list(edges):
        if key not in index_of:
            strong(key)
    recursive: set[tuple[int, int]] = set()
    for comp in sccs:
        members = set(comp)
        # 17b.11: at the call that closes the cycle, the first one in file order (program file, then line)
        calls = [(k[0], span.line, span) for k in comp for (c, span) in edges.get(k, []) if c.key in members]
        if calls:
            recursive |= members
            span = min(calls, key=lambda t: (t[0], t[1]))[2]
            names = ", ".join(sorted(nodes[k].label if k in nodes else "<main>" for k in comp))
            diags.report("E-CALL-RECURSION", span, f"recursive calls between {names} (A-29)")
    depth_limit = int(semantics["call_depth"])
    depth = _longest_paths(edges, recursive)
    max_depth = max((depth.get(r.key, 0) for r in roots), default=0)
    if max_depth > depth_limit and not recursive:
        diags.report("E-CALL-DEPTH", files[0].ops[0].span if files[0].ops else Span(files[0].path, 1, 1),
                    f"static call depth {max_depth} exceeds the limit {depth_limit} (A-29)")
    routines = tuple(sorted((n for n in nodes.values()), key=lambda t: (t.file, t.index)))
    return routines, max_depth


def _longest_paths(edges: dict[tuple[int, int], list[tuple[CallTarget, Span]]],
                   skip: set[tuple[int, int]]) -> dict[tuple[int, int], int]:
    """Longest call chain below each node of the (acyclic once `skip` is removed) call graph."""
    depth: dict[tuple[int, int], int] = {}
    for root in edges:
        if root in depth:
            continue
        stack = [(root, False)]
        while stack:
            node, expanded = stack.pop()
            if node in depth:
                continue
            callees = [c.key for c, _ in edges.get(node, []) if c.key not in skip and c.key != node]
            if expanded:
                depth[node] = max((depth.get(c, 0) + 1 for c in callees), default=0)
                continue
            stack.append((node, True))
            stack.extend((c, False) for c in callees if c not in depth)
    return depth
