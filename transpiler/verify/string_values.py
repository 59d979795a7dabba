"""The outcome of a string compare that the code right before it fixes: `L S"AB"` `+ S"CD"` `= S0` ... `L S0`
`== S"ABCD"` always gives 1, so MC/DC cannot show that condition (it never changes) and says so instead of counting
it as missing.

Both sides of the compare are worked out backwards over straight-line code only: from the compare back to the load
of the string accumulator (`L S"..."`, `L S<n>`, an error or dialog text reference), with every `+` of a known text
in between, and a string operand `S<n>` back to the last `= S<n>` before it, where the accumulator is worked out
the same way. The stretch walked may hold no op that control reaches other than from the op before it (a jump or
call target, a CASE entry, a file's start) and no call, CASE, job submission or PLC module (any of them may write
string memory); a store through the index register forgets every string operand. Within such a stretch only these
ops run, in order, every time the compare runs: the NC, scenarios and jobs write between cycles or after the main
program, never inside it. Appending cuts the text at the profile's string length, as the interpreter does.
Sound, not complete: where anything is not known, nothing is claimed."""

from __future__ import annotations

import operator
from typing import Callable, Iterator, Mapping

from transpiler.ir import Op, Program

_RELATIONS: Mapping[str, Callable[[str, str], bool]] = {
    "==": operator.eq, "<>": operator.ne, "<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge}
# ops in a stretch that may write string memory in ways not followed here
_BARRIERS = frozenset({"CALL", "CALLT", "CALLF", "CASE", "SUBM", "KFIELD", "EM", "EMT", "EMF"})


def _entered(program: Program) -> set[tuple[int, int]]:
    """(file, op index) of every op control can reach other than from the op before it."""
    found = {(f, 0) for f in range(len(program.files))}
    for f, code in enumerate(program.files):
        for op in code.ops:
            if op.code in ("JP", "JPT", "JPF") and op.target is not None:
                found.add((f, op.target))
            found |= {(t.file, t.index) for t in (op.call, *op.case_targets)
                      if t is not None and not t.is_module and t.file >= 0}
    return found


class StringCompares:
    """Works out string compares of one program (`outcome`)."""

    def __init__(self, program: Program):
        self.program = program
        self.entered = _entered(program)
        self.limit = program.semantics.profile.string_len

    def outcome(self, f: int, i: int) -> tuple[bool, str, str] | None:
        """(the outcome, the accumulator's text, the operand's text) of the string compare at op i of file f, where
        the straight-line code before it fixes both; None where it does not."""
        ops = self.program.files[f].ops
        op = ops[i]
        if op.code != "SCMP" or op.operand is None or op.rel not in _RELATIONS:
            return None
        left = self._accumulator(f, i)
        right = self._operand(f, i, op)
        if left is None or right is None:
            return None
        return _RELATIONS[op.rel](left, right), left, right

    def _operand(self, f: int, i: int, op: Op) -> str | None:
        """The text `op` (at index i) reads: a constant's, or the last store of its S<n> in the stretch before."""
        o = op.operand
        if o is None:
            return None
        if o.kind == "STR":
            return o.text
        if o.kind != "S" or o.indexed:
            return None
        for j, prev in self._stretch_before(f, i):
            if prev.code == "SST" and prev.operand is not None and prev.operand.kind == "S":
                if prev.operand.indexed:
                    return None         # may have written S<n>
                if prev.operand.addr == o.addr:
                    return self._accumulator(f, j)
        return None

    def _accumulator(self, f: int, i: int) -> str | None:
        """The string accumulator's text before op i: its last load in the stretch before, with the appends since."""
        appended: list[str] = []
        for j, prev in self._stretch_before(f, i):
            if prev.code == "SCAT":
                text = self._operand(f, j, prev)
                if text is None:
                    return None
                appended.append(text)
            elif prev.code == "SLD":
                text = self._operand(f, j, prev)
                if text is None:
                    return None
                for more in reversed(appended):
                    text = (text + more)[:self.limit]
                return text
        return None

    def _stretch_before(self, f: int, i: int) -> Iterator[tuple[int, Op]]:
        """The ops before op i, nearest first, back to the start of its straight stretch: an entry (a jump, call or
        CASE target), the file's start, or an op that may write strings unseen (a call, CASE, SUBM, module)."""
        ops = self.program.files[f].ops
        j = i
        while (f, j) not in self.entered and j > 0:
            j -= 1
            prev = ops[j]
            if prev.code in _BARRIERS or (prev.call is not None and prev.call.is_module):
                return
            yield j, prev
