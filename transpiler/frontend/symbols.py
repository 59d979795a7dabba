"""Symbol tables of the .def files: explicit addresses, auto-assignment of the rest (A-49), aliases, duplicate and case checks."""

from __future__ import annotations

import dataclasses
import re
from typing import Iterable

from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend import ast
from transpiler.frontend.addresses import check_range
from transpiler.frontend.load import ParsedProject
from transpiler.frontend.opcodes import BIT_GROUPS
from transpiler.ir import BIT_KINDS, BYTES, MEM_KINDS, Symbol
from transpiler.language.semantics import Semantics

_ADDRESSED = BIT_KINDS | MEM_KINDS | {"S"}       # the operand kinds written with an address
_RESERVED = re.compile(r"^(?:[MIOTCBWDS][0-9]+|K[0-9]+|X|KF|S#[ED][0-9]+)$", re.IGNORECASE)


@dataclasses.dataclass
class SymTables:
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
    instr_type = ast.Instr
    for src in project.src_files:
        for stmt in src.statements:
            op = stmt.operand if type(stmt) is instr_type else None
            if op is not None and op.kind in _ADDRESSED:
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


def build_symbols(project: ParsedProject, semantics: Semantics, diags: Diagnostics) -> tuple[SymTables, list[Symbol]]:
    used_bits, used_bytes = _explicit_addresses(project)
    allocator = _Allocator(semantics, used_bits, used_bytes)
    auto: list[Symbol] = []
    tables = SymTables({}, {}, incomplete=project.symbols_incomplete)
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
        _resolve_aliases([s for s in entries if s.alias is not None], table, tables, diags)

    fill(tables.global_, project.global_defs)
    for owner, defs in project.local_defs.items():
        table: dict[str, Symbol] = {}
        fill(table, defs)
        tables.local[owner] = table
    _check_case_clashes(tables.all_symbols().values(), diags)
    return tables, auto


def _resolve_aliases(pending: list[ast.SymbolDef], table: dict[str, Symbol], tables: SymTables,
                     diags: Diagnostics) -> None:
    """Aliases take their target's address; repeated passes let an alias name another alias defined later."""
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


def _add(table: dict[str, Symbol], sym: Symbol, diags: Diagnostics) -> None:
    old = table.get(sym.name)
    if old is not None:
        if (old.kind, old.addr) != (sym.kind, sym.addr) or old.auto or sym.auto:
            if not (old.auto and sym.auto and old.span == sym.span):
                # at the second definition in the file (an alias is taken after every fixed address, so the
                # table may hold the later line)
                first, second = (sym, old) if sym.span.file == old.span.file and sym.span < old.span else (old, sym)
                diags.report("E-SYM-DUP", second.span, f"symbol {sym.name} is already defined at {first.span}")
        return
    table[sym.name] = sym


def folded_key(table: dict, name: str) -> str | None:
    """The key that equals name ignoring case (the first in sorted order, for determinism)."""
    lower = name.lower()
    return next((key for key in sorted(table) if key.lower() == lower), None)


def _folded(table: dict, name: str):
    """The entry whose key equals name ignoring case."""
    key = folded_key(table, name)
    return None if key is None else table[key]


def _check_case_clashes(symbols: Iterable[Symbol], diags: Diagnostics) -> None:
    by_lower: dict[str, Symbol] = {}
    for sym in sorted(symbols, key=lambda s: (s.span.file, s.span.line, s.name)):
        other = by_lower.get(sym.name.lower())
        if other is not None and other.name != sym.name:
            diags.report("E-SYM-CASE", sym.span, f"{sym.name} differs from {other.name} ({other.span}) only in case")
        by_lower.setdefault(sym.name.lower(), sym)


def _check_def_address(s: ast.SymbolDef, semantics: Semantics, diags: Diagnostics) -> bool:
    return check_range(s.kind, s.address, semantics, s.span, diags, s.name)
