"""Control-flow checks of each file: static successors, subprogram bodies, paths that run off the end, unreachable module code."""

from __future__ import annotations

from bisect import bisect_left
from itertools import chain
from typing import Iterator, Mapping

from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend.lowering import FileLowering
from transpiler.ir import CallTarget, FileCode, Op, Program

LOST_LINE_CODES = frozenset({"E-SYNTAX", "E-UNSUPPORTED", "E-LIT-RANGE", "E-PP-NEST", "E-PP-SYNTAX",
                             "E-FILE-NOT-FOUND", "E-FILE-ESCAPE", "E-FILE-READ", "E-FILE-INCLUDE-CYCLE"})
_BLOCK_ENDS = frozenset({"EM", "JP", "JPT", "JPF", "KFIELD"})


def flow_is_complete(low: FileLowering, lost_lines: set[str]) -> bool:
    """False when an earlier error removed a line (in one of `lost_lines`' files) or a control statement of the
    file: a path that then seems to run off the end is a consequence of that error, not a second fault."""
    statements = low.src.statements
    if lost_lines and (low.src.path in lost_lines or any(stmt.span.file in lost_lines for stmt in statements)):
        return False
    return not low.flow_rejected


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


def block_ends(ops: tuple[Op, ...]) -> list[int]:
    """The indices, in order, of the ops after which control does not simply go on with the next op (EM, jumps,
    KFIELD): the walks below go over the ops in between a block at a time, most ops being none of these."""
    return [i for i, op in enumerate(ops) if op.code in _BLOCK_ENDS]


def check_flow(file_index: int, f: FileCode, diags: Diagnostics, ends: list[int] | None = None) -> None:
    """E-FALL-OFF-END when a path from the file's entries reaches its end without EM; `ends` are the file's
    block_ends when the caller has them."""
    ops = f.ops
    n = len(ops)
    ends = block_ends(ops) if ends is None else ends
    starts = [0] if file_index == 0 else []
    starts += [e for e in f.labels.values() if e < n]
    followed: set[int] = set()          # the block ends whose successors are taken
    falls_off = file_index == 0 and not ops
    while starts:
        k = bisect_left(ends, starts.pop())
        if k == len(ends):              # no EM, jump or table after it: straight on past the last op
            falls_off = True
            continue
        last = ends[k]
        if last in followed:
            continue
        followed.add(last)
        op = ops[last]
        code = op.code
        if code == "KFIELD" or code == "EM":      # (EM: no successor)
            continue
        if op.target is not None:
            if op.target >= n:
                falls_off = True
            else:
                starts.append(op.target)
        if code != "JP":                # JPT, JPF: the next op when the jump is not taken
            if last + 1 >= n:
                falls_off = True
            else:
                starts.append(last + 1)
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


def routine_body(files: tuple[FileCode, ...], entry: CallTarget, ends: list[int] | None = None) -> list[int]:
    """Op indices reachable from an entry until EM (the body of a subprogram), in order; `ends` are the file's
    block_ends when the caller has them."""
    return list(_expanded(_body_blocks(files[entry.file].ops, entry.index,
                                       block_ends(files[entry.file].ops) if ends is None else ends)))


def _body_blocks(ops: tuple[Op, ...], entry: int, ends: list[int]) -> dict[int, int]:
    """The body from `entry` as blocks of consecutive ops: the last op of each block -> its first op."""
    n = len(ops)
    first: dict[int, int] = {}
    starts = [entry]
    while starts:
        start = starts.pop()
        if start >= n:
            continue
        k = bisect_left(ends, start)
        last = ends[k] if k < len(ends) else n - 1
        if last in first:               # the block was reached before: only its start may move up
            first[last] = min(first[last], start)
            continue
        first[last] = start
        if k == len(ends):              # runs off the end of the file
            continue
        op = ops[last]
        code = op.code
        if code == "EM":
            continue
        if code != "KFIELD" and op.target is not None:
            starts.append(op.target)
        if code != "JP":
            starts.append(last + 1)
    return first


def _expanded(blocks: dict[int, int]) -> Iterator[int]:
    """The op indices of blocks (last op -> first op), in order."""
    return chain.from_iterable(range(first, last + 1) for last, first in sorted(blocks.items()))


class RoutineBodies:
    """routine_body of each entry of one program's files, worked out once: the call graph and the back end's analyses
    (liveness, the stack interfaces, the job plan, the translation itself) each walk every routine's body.
    `known` are bodies of these files worked out before (Program.routine_bodies)."""

    def __init__(self, files: tuple[FileCode, ...], known: Mapping[tuple[int, int], tuple[int, ...]] | None = None):
        self.files = files
        self._bodies: dict[tuple[int, int], tuple[int, ...]] = dict(known or {})
        self._ends: dict[int, list[int]] = {}          # file index -> its block_ends

    @classmethod
    def of(cls, program: Program) -> RoutineBodies:
        """The bodies of `program`'s files, starting from those its front end worked out."""
        return cls(program.files, program.routine_bodies)

    def worked_out(self) -> dict[tuple[int, int], tuple[int, ...]]:
        """A copy of the bodies asked for so far, by entry key."""
        return dict(self._bodies)

    def ends(self, file_index: int) -> list[int]:
        """block_ends of one file's ops."""
        ends = self._ends.get(file_index)
        if ends is None:
            ends = self._ends[file_index] = block_ends(self.files[file_index].ops)
        return ends

    def __call__(self, entry: CallTarget) -> tuple[int, ...]:
        key = (entry.file, entry.index)
        body = self._bodies.get(key)
        if body is None:
            blocks = _body_blocks(self.files[entry.file].ops, entry.index, self.ends(entry.file))
            body = self._bodies[key] = tuple(_expanded(blocks))
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
