"""Per-file lowering: the statements of one parsed file become ops (labels, KFIELD tables, instructions, CASE tables)."""

from __future__ import annotations

from typing import NamedTuple

from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend import ast
from transpiler.frontend.chain import ChainLowering
from transpiler.frontend.opcodes import CONTROL, FLOW, STRUCT_ALL
from transpiler.frontend.operands import OperandResolver, label_text
from transpiler.frontend.structure import StructureMatcher
from transpiler.frontend.symbols import SymTables
from transpiler.ir import Op, Operand, new_op
from transpiler.language.mnemonics import MNEMONICS
from transpiler.language.semantics import Semantics
from transpiler.records import replaced


class _PlainLowered(NamedTuple):
    """How a plain instruction was lowered in one chain state: its op's fields besides span and comments, and the
    chain state after it."""

    code: str
    operand: Operand | None
    rel: str
    nbits: int
    chain_open: bool
    last_acc: str


class FileLowering:
    """Turns one parsed file into ops: operands resolved, structures matched, chain/bracket state computed."""

    def __init__(self, file_index: int, src: ast.SourceFile, symbols: SymTables, semantics: Semantics,
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
        self.operands = OperandResolver(src.path, symbols, self.kfields, semantics, diags)
        self.resolved: dict[tuple[str, ast.OperandSyntax], Operand] = {}     # (mnemonic, operand) -> accepted operand
        # (mnemonic, operand as written, chain_open, last_acc) -> how a plain instruction of a pure group was lowered
        self.plain_lowered: dict[tuple[str, ast.OperandSyntax | None, bool, str], _PlainLowered] = {}
        self.structure = StructureMatcher(self.ops, semantics, diags)
        self.chain = ChainLowering(semantics, diags, self.structure, self.pending_jumps, self.pending_calls)
        # state while lowering the statements in order
        self.kfield_lines: dict[str, int] = {}
        self.chain_open = False
        self.last_acc = "NONE"
        self.case_open: tuple[int | None, Span] | None = None
        # E-CASE-BODY faults inside the open table, reported at its ENDC: a table that is never closed reports
        # only "CASE without ENDC" (the missing ENDC is the root fault, not every line after it).
        self.case_faults: list[tuple[Span, str]] = []
        self.flow_rejected = False      # a statement of FLOW gave no op (it was rejected with an error)

    def run(self) -> None:
        self._collect_kfields()
        instr_type = ast.Instr
        plain_lowered = self.plain_lowered
        ops = self.ops
        for stmt in self.src.statements:
            if type(stmt) is instr_type:         # (nine lines in ten: tested first)
                if self.case_open is None:
                    # Most lines repeat an instruction lowered before in the same chain state: its op differs only
                    # in span and comments (no diagnostic, no queued jump, no bracket), so it is not checked and
                    # lowered again.
                    chain_open = self.chain_open
                    known = plain_lowered.get((stmt.mnemonic, stmt.operand, chain_open, self.last_acc))
                    if known is not None:
                        code, operand, rel, nbits, self.chain_open, self.last_acc = known
                        ops.append(new_op(code, stmt.mnemonic, stmt.span, operand, stmt.comments, rel=rel,
                                          nbits=nbits, chain_open=chain_open))
                        continue
                count = len(ops)
                self._instruction(stmt)
                if len(ops) == count and stmt.mnemonic in FLOW:
                    self.flow_rejected = True
            elif isinstance(stmt, ast.Global):
                self.globals.append(stmt)
            elif isinstance(stmt, ast.Extern):
                self.externs.setdefault(stmt.name, stmt)
            elif isinstance(stmt, (ast.Uses, ast.DefineFile)):
                continue
            elif isinstance(stmt, ast.Label):
                self._label(stmt)
            elif isinstance(stmt, ast.KField):
                self._kfield(stmt)
            else:
                self._instruction(stmt)
        self._finish()

    def _collect_kfields(self) -> None:
        """KFIELD tables are known to the whole file, before the statements are lowered in order."""
        kfield_type = ast.KField
        for stmt in self.src.statements:
            if type(stmt) is kfield_type:
                if stmt.name in self.kfields:
                    self.diags.report("E-SYM-DUP-LABEL", stmt.span, f"KFIELD {stmt.name} is defined twice")
                self.kfields[stmt.name] = stmt.values
                self.kfield_lines.setdefault(stmt.name, stmt.span.line)

    def _label(self, stmt: ast.Label) -> None:
        index = len(self.ops)
        brackets = self.chain.brackets
        if self.case_open:
            self.case_faults.append((stmt.span, "only 'CM label' lines may stand inside CASE ... ENDC"))
        if brackets and self.semantics["bracket_span"] == "forbidden":
            brackets[-1].span_faults.append((stmt.span, "LBL inside an open bracket"))
        if stmt.name in self.labels:
            self.diags.report("E-SYM-DUP-LABEL", stmt.span, f"label {stmt.name} is defined twice in this file")
        else:
            self.labels[stmt.name] = index
            # KFIELD names live in the label name space of the file: the later one is the fault
            if self.kfield_lines.get(stmt.name, stmt.span.line) < stmt.span.line:
                self.diags.report("E-SYM-DUP-LABEL", stmt.span, f"label {stmt.name} has the name of the "
                                 f"KFIELD at line {self.kfield_lines[stmt.name]}")
        self.ops.append(new_op("LBL", "LBL", stmt.span, comments=stmt.comments, label=stmt.name,
                               chain_open=self.chain_open))
        self.chain_open, self.last_acc = False, "NONE"

    def _kfield(self, stmt: ast.KField) -> None:
        if stmt.name in self.labels:
            self.diags.report("E-SYM-DUP-LABEL", stmt.span, f"KFIELD {stmt.name} has the name of a label "
                             "defined above it")
        prev = next((o for o in reversed(self.ops) if o.code not in ("KFIELD",)), None)
        if prev is None or prev.mnemonic not in ("EM", "JP"):
            self.diags.report("E-KF-PLACEMENT", stmt.span,
                             f"KFIELD {stmt.name} must follow an unconditional EM or JP")
        self.ops.append(new_op("KFIELD", "KFIELD", stmt.span, comments=stmt.comments, label=stmt.name))
        self.chain_open, self.last_acc = False, "NONE"

    def _instruction(self, instr: ast.Instr) -> None:
        """An instruction not lowered before in this chain state (run() takes the others from plain_lowered)."""
        m = instr.mnemonic
        index = len(self.ops)
        info = MNEMONICS[m]
        # (_admitted has nothing to say about a plain instruction outside CASE tables and brackets: most of them)
        plain = (not info.extended and m != "=N" and self.case_open is None
                 and (not self.chain.brackets or m not in CONTROL))
        if not plain and not self._admitted(instr):
            return
        if self.case_open is not None and m == "CM":
            self._case_entry(instr)
            return
        operand = None
        if instr.operand is not None and info.form == "operand":
            # An operand resolved and checked once for this mnemonic is the same operand the next time (the
            # file's symbols and KFIELD tables are fixed while it is lowered); only a rejected one is checked
            # again, so that each occurrence reports its own diagnostic.
            key = (m, instr.operand)
            operand = self.resolved.get(key)
            if operand is None:
                operand = self.operands.resolve(instr)
                if operand is None or not self.operands.kind_ok(instr, operand):
                    if m == "CASE":
                        # Keep the table open (without an op) so that its entries and ENDC cause no more errors.
                        self.case_open, self.case_faults = (None, instr.span), []
                    return
                self.resolved[key] = operand
        before = (m, instr.operand, self.chain_open, self.last_acc)
        op, self.chain_open, self.last_acc = self.chain.lower(instr, operand, index, self.chain_open, self.last_acc)
        if op is None:
            return
        if plain and self.chain.pure(m):
            self.plain_lowered[before] = _PlainLowered(op.code, operand, op.rel, op.nbits, self.chain_open,
                                                       self.last_acc)
        if m == "CASE":
            self.case_open, self.case_faults = (index, instr.span), []
        elif m == "ENDC":
            if self.case_open is None:
                self.diags.report("E-STRUCT-NEST", instr.span, "ENDC without CASE")
            for fault_span, message in self.case_faults:
                self.diags.report("E-CASE-BODY", fault_span, message)
            self.case_open, self.case_faults = None, []
        self.ops.append(op)

    def _admitted(self, instr: ast.Instr) -> bool:
        """False for an instruction the profile does not enable or that may not stand where it is."""
        m = instr.mnemonic
        brackets = self.chain.brackets
        if MNEMONICS[m].extended and not self.semantics["extended_instructions"]:
            self.diags.report("E-UNSUPPORTED", instr.span, f"{m} is an extended instruction (A-23), "
                             f"not enabled for profile {self.semantics.profile.name}")
            return False
        if m == "=N" and not self.semantics["allow_assign_not"]:
            self.diags.report("E-UNSUPPORTED", instr.span, "=N is not part of the language (enable allow_assign_not, A-16)")
            return False
        if self.case_open is not None and m not in ("CM", "ENDC"):
            self.case_faults.append((instr.span, f"only 'CM label' lines may stand inside CASE ... ENDC, not {m}"))
            return False
        if (brackets and m in CONTROL and self.case_open is None      # (a table's CM and ENDC go with its CASE)
                and self.semantics["bracket_span"] == "forbidden"):
            brackets[-1].span_faults.append(
                (instr.span, f"{m} inside an open bracket (opened at line {brackets[-1].span.line})"))
            # CASE/ENDC and structured keywords still take part in structure matching, so that their
            # partners outside the bracket do not report a second error.
            if m not in STRUCT_ALL and m not in ("CASE", "ENDC"):
                return False
        return True

    def _case_entry(self, instr: ast.Instr) -> None:
        """A 'CM label' line inside CASE ... ENDC: one entry of the table, linked later."""
        case_index = self.case_open[0]
        op = instr.operand
        if op.kind == "NUM":
            self.case_faults.append((instr.span, "a PLC module cannot be a CASE entry"))
            return
        if case_index is None:       # the CASE line itself was rejected
            return
        notes = self.case_entries.setdefault(case_index, [])
        self.pending_case.append((case_index, len(notes), label_text(op), instr.span))
        notes.append((instr.span, instr.comments))

    def _finish(self) -> None:
        """Attach the CASE entry notes; report what is still open at the end of the file."""
        for case_index, notes in self.case_entries.items():
            self.ops[case_index] = replaced(self.ops[case_index], case_notes=tuple(notes))
        self.chain.report_unclosed()
        self.structure.report_unclosed()
        if self.case_open is not None:
            self.diags.report("E-CASE-BODY", self.case_open[1], "CASE without ENDC")
