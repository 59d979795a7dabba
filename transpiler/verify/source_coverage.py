"""Coverage of the original source, per instruction and per file and line, from the reference interpreter's coverage
sets of the runs: the one place those sets are combined (equiv's summary and the CI coverage files both read it)."""

from __future__ import annotations

import collections
import dataclasses
from typing import Iterable, Mapping, Sequence

from transpiler.ir import Op, Program

NOT_COUNTED = ("LBL", "KFIELD", "NOP")
"""Op codes that are no instruction of their own (labels, constant tables, placeholders): never counted."""

TWO_WAY = ("JPT", "JPF", "CALLT", "CALLF", "EMT", "EMF")
"""Conditional jumps, calls and module ends (an IFT is a JPF over its body): outcome 1 when the jump, call or end
happens, 0 when execution falls through."""


@dataclasses.dataclass(frozen=True)
class OpCoverage:
    """One counted instruction: in how many runs it executed and how many runs took each outcome it has."""

    file: int
    index: int
    op: Op
    runs: int                            # runs that executed it
    taken: Mapping[int, int]             # outcome -> runs that took it (two-way: 0/1; CASE: entry, -1 = none)

    @property
    def outcomes(self) -> tuple[int, ...]:
        """The outcomes that count as branches: fall through and jump for a two-way op, each entry of a CASE."""
        if self.op.code in TWO_WAY:
            return (0, 1)
        if self.op.code == "CASE":
            return tuple(range(len(self.op.case_targets)))
        return ()

    @property
    def seen(self) -> set[int]:
        return {outcome for outcome, runs in self.taken.items() if runs}


def op_coverage(program: Program, sets: Sequence) -> list[OpCoverage]:
    """Every counted instruction of `program` (in file and op order) with its figures over the runs' coverage sets
    (machine.Coverage: executed ops and the outcomes seen at each branching op, each a set per run)."""
    executed: collections.Counter = collections.Counter()
    taken: dict[tuple[int, int], collections.Counter] = {}
    for cov in sets:
        executed.update(cov.executed)
        for key, values in cov.branches.items():
            taken.setdefault(key, collections.Counter()).update(values)
    empty: Mapping[int, int] = {}
    return [OpCoverage(fi, i, op, executed[(fi, i)], taken.get((fi, i), empty))
            for fi, f in enumerate(program.files) for i, op in enumerate(f.ops) if op.code not in NOT_COUNTED]


@dataclasses.dataclass(frozen=True)
class BranchPoint:
    """The outcomes of one branching instruction: `jump` (a conditional jump, call or module end: outcome 0 falls
    through, 1 jumps) or `switch` (a CASE: one outcome per entry); `taken` counts the runs that took each."""

    kind: str
    runs: int                            # runs that executed the instruction
    taken: tuple[int, ...]

    @property
    def covered(self) -> int:
        return sum(1 for runs in self.taken if runs)


@dataclasses.dataclass(frozen=True)
class LineCoverage:
    """A source line holding instructions: `hits` counts the runs that executed it."""

    number: int
    hits: int
    branches: tuple[BranchPoint, ...] = ()

    lines_valid = 1

    @property
    def lines_covered(self) -> int:
        return 1 if self.hits else 0

    @property
    def branches_valid(self) -> int:
        return sum(len(b.taken) for b in self.branches)

    @property
    def branches_covered(self) -> int:
        return sum(b.covered for b in self.branches)


class _Totals:
    """The line and branch figures summed over `parts` (lines, or files)."""

    parts: tuple

    @property
    def lines_valid(self) -> int:
        return sum(p.lines_valid for p in self.parts)

    @property
    def lines_covered(self) -> int:
        return sum(p.lines_covered for p in self.parts)

    @property
    def branches_valid(self) -> int:
        return sum(p.branches_valid for p in self.parts)

    @property
    def branches_covered(self) -> int:
        return sum(p.branches_covered for p in self.parts)


@dataclasses.dataclass(frozen=True)
class FileCoverage(_Totals):
    """The lines with instructions of one source file, by line number; `path` as the program's spans name it."""

    path: str
    lines: tuple[LineCoverage, ...]

    @property
    def parts(self) -> tuple[LineCoverage, ...]:
        return self.lines


@dataclasses.dataclass(frozen=True)
class SourceCoverage(_Totals):
    """Line and branch coverage of source files (every one of the program, or a folder's) over `runs` runs."""

    runs: int
    files: tuple[FileCoverage, ...]

    @property
    def parts(self) -> tuple[FileCoverage, ...]:
        return self.files


def source_coverage(program: Program, ops: Iterable[OpCoverage], runs: int) -> SourceCoverage:
    """Per file and line: the instructions of a line are counted together (a line holds one instruction in
    practice; where it holds more, they run together, so its hits are the most runs any of them executed in).
    Every file of the program is listed, in program order, also one without instructions (all inside inactive
    `#if` regions); lines without instructions (comments, labels, inactive code) are left out."""
    by_line: dict[str, dict[int, list[OpCoverage]]] = {f.path: {} for f in program.files}
    for oc in ops:
        by_line.setdefault(oc.op.span.file, {}).setdefault(oc.op.span.line, []).append(oc)
    files = []
    for path, lines in by_line.items():
        files.append(FileCoverage(path, tuple(_line(number, lines[number]) for number in sorted(lines))))
    return SourceCoverage(runs, tuple(files))


def _line(number: int, ops: list[OpCoverage]) -> LineCoverage:
    branches = tuple(BranchPoint("switch" if oc.op.code == "CASE" else "jump", oc.runs,
                                 tuple(oc.taken.get(outcome, 0) for outcome in oc.outcomes))
                     for oc in ops if oc.outcomes)
    return LineCoverage(number, max(oc.runs for oc in ops), branches)
