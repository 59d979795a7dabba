"""Control-flow checks of each file: static successors, subprogram bodies, paths that run off the end, unreachable module code."""

from __future__ import annotations

from typing import Mapping

from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend import ast
from transpiler.frontend.lowering import FileLowering
from transpiler.frontend.opcodes import STRUCT_ALL
from transpiler.ir import CallTarget, FileCode, Op, Program

LOST_LINE_CODES = frozenset({"E-SYNTAX", "E-UNSUPPORTED", "E-LIT-RANGE", "E-PP-NEST", "E-PP-SYNTAX",
                             "E-FILE-NOT-FOUND", "E-FILE-ESCAPE", "E-FILE-READ", "E-FILE-INCLUDE-CYCLE"})
_FLOW_MNEMONICS = frozenset({"EM", "EMT", "EMF", "JP", "JPT", "JPF", "CASE", "ENDC"}) | STRUCT_ALL


def flow_is_complete(low: FileLowering, lost_lines: set[str]) -> bool:
    """False when an earlier error removed a line (in one of `lost_lines`' files) or a control statement of the
    file: a path that then seems to run off the end is a consequence of that error, not a second fault."""
    statements = low.src.statements
    if lost_lines and (low.src.path in lost_lines or any(stmt.span.file in lost_lines for stmt in statements)):
        return False
    # (an op has the mnemonic of the statement it was lowered from: only the control statements' spans are
    # looked up, instead of hashing the span of every op)
    lowered = {op.span for op in low.ops if op.mnemonic in _FLOW_MNEMONICS}
    return all(stmt.span in lowered for stmt in statements
               if type(stmt) is ast.Instr and stmt.mnemonic in _FLOW_MNEMONICS)


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


def check_flow(file_index: int, f: FileCode, diags: Diagnostics) -> None:
    ops = f.ops
    entries = [0] if file_index == 0 else []
    entries += list(f.labels.values())
    seen: set[int] = set()
    n = len(ops)
    stack = [e for e in entries if e < n]
    falls_off = file_index == 0 and not ops
    while stack:
        i = stack.pop()
        if i in seen:
            continue
        seen.add(i)
        # successors(ops, i), inlined: this walk visits every op of the program
        op = ops[i]
        code = op.code
        if code == "KFIELD" or code == "EM":      # (EM: no successor)
            continue
        if code == "JP" or code == "JPT" or code == "JPF":
            if op.target is not None:
                if op.target >= n:
                    falls_off = True
                elif op.target not in seen:
                    stack.append(op.target)
            if code == "JP":
                continue
        if i + 1 >= n:
            falls_off = True
        elif i + 1 not in seen:
            stack.append(i + 1)
    if falls_off:
        diags.report("E-FALL-OFF-END", Span(f.path, max(1, f.line_count), 1),
                    "a path reaches the end of the file without EM")


def routines_entered(op: Op) -> list[CallTarget]:
    """The subprograms `op` calls: the target of a CM/CMT/CMF of a label, every entry of a CASE table (PLC
    modules and unresolved targets are no subprogram of the project)."""
    if op.code in ("CALL", "CALLT", "CALLF") and op.call is not None and not op.call.is_module and op.call.file >= 0:
        return [op.call]
    if op.code == "CASE":
        return [t for t in op.case_targets if t is not None and t.file >= 0]
    return []


def routine_body(files: tuple[FileCode, ...], entry: CallTarget) -> list[int]:
    """Op indices reachable from an entry until EM (the body of a subprogram)."""
    ops = files[entry.file].ops
    n = len(ops)
    seen: set[int] = set()
    stack = [entry.index]
    while stack:
        i = stack.pop()
        if i in seen or i >= n:
            continue
        seen.add(i)
        # successors(ops, i), inlined: this walk runs for every routine in several stages
        op = ops[i]
        code = op.code
        if code == "EM":
            continue
        if code == "JP" or code == "JPT" or code == "JPF":
            if op.target is not None and op.target not in seen:
                stack.append(op.target)
            if code == "JP":
                continue
        stack.append(i + 1)
    return sorted(seen)


class RoutineBodies:
    """routine_body of each entry of one program's files, worked out once: the call graph and the back end's analyses
    (liveness, the stack interfaces, the job plan, the translation itself) each walk every routine's body.
    `known` are bodies of these files worked out before (Program.routine_bodies)."""

    def __init__(self, files: tuple[FileCode, ...], known: Mapping[tuple[int, int], tuple[int, ...]] | None = None):
        self.files = files
        self._bodies: dict[tuple[int, int], tuple[int, ...]] = dict(known or {})

    @classmethod
    def of(cls, program: Program) -> RoutineBodies:
        """The bodies of `program`'s files, starting from those its front end worked out."""
        return cls(program.files, program.routine_bodies)

    def worked_out(self) -> dict[tuple[int, int], tuple[int, ...]]:
        """A copy of the bodies asked for so far, by entry key."""
        return dict(self._bodies)

    def __call__(self, entry: CallTarget) -> tuple[int, ...]:
        key = (entry.file, entry.index)
        body = self._bodies.get(key)
        if body is None:
            body = self._bodies[key] = tuple(routine_body(self.files, entry))
        return body


def check_module_starts(files: tuple[FileCode, ...], lowerings: list[FileLowering], diags: Diagnostics) -> None:
    """A module file runs from its labels only: a statement before its first LBL is never executed."""
    for i, low in enumerate(lowerings[1:], start=1):
        if low.src.broken_labels:            # the first LBL may be the line that was rejected
            continue
        for op in files[i].ops:
            if op.code == "LBL":
                break
            if op.code not in ("KFIELD",):
                diags.report("E-MOD-UNREACHABLE", op.span, "statement in a module file before its first LBL is never executed")
                break
