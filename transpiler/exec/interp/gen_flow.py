"""Control flow in the generated code: jumps, calls with the call-depth check, EM, CASE tables and submit jobs."""

from __future__ import annotations

from transpiler.ir import Op


class FlowCode:
    """Mixin of the code generator: JP JPT JPF, CALL CALLT CALLF, EM EMT EMF, CASE, SUBM RPLY CAN; uses `out`,
    `sem`, `coverage`, `depth_limit`, `seg_maps`, `case_tables` and the operand access of AccessCode."""

    # control flow

    def _cover(self, ind: int, opid: int, outcome: int) -> None:
        """The coverage mark of one outcome of a conditional jump, call or module end (a slot of branch_slots)."""
        if self.coverage:
            self.out(ind, f"_bh[{self.branch_slot[opid, outcome]}] = 1", opid)

    def _falls_to(self, block: int) -> bool:
        """Whether a jump from the block being generated to `block` can fall through the remaining `if b == k`
        tests of its dispatch leaf instead of going round the dispatch loop: `block` comes later in the same leaf."""
        return self.block < block and self.leaf_of[block] == self.leaf_of[self.block]

    def _op_JP(self, op: Op, opid: int, ind: int, f: int, seg_of: dict[int, int]) -> None:
        block = seg_of[op.target]
        if self._falls_to(block):
            self.goto(ind, block, opid)
        else:
            self.out(ind, f"b = {block}", opid)
            self._go_round(ind, opid, block)

    def _op_JPT(self, op: Op, opid: int, ind: int, f: int, seg_of: dict[int, int], negate: bool = False) -> int:
        """Returns the indentation of the code after the jump: one level deeper when that code becomes the else
        branch of a jump that falls through to a later block of the leaf (nesting is capped, Python limits it)."""
        block = seg_of[op.target]
        self.out(ind, f"if {'not ' if negate else ''}{self.la()}:", opid)
        self._cover(ind + 1, opid, 1)
        if self._falls_to(block) and ind < self.max_indent:
            self.goto(ind + 1, block, opid)
            self.out(ind, "else:", opid)
            self._cover(ind + 1, opid, 0)
            return ind + 1
        self.out(ind + 1, f"b = {block}", opid)
        self._go_round(ind + 1, opid, block)
        self._cover(ind, opid, 0)
        return ind

    def _go_round(self, ind: int, opid: int, block: int) -> None:
        """To `block` through the dispatch loop; a jump back may close a loop, so the budget is checked there."""
        if block not in self.dispatched:
            self.tests_broken = True
        if block <= self.block:
            self.budget_check(ind, opid)
        self.out(ind, "continue", opid)

    def _op_JPF(self, op: Op, opid: int, ind: int, f: int, seg_of: dict[int, int]) -> int:
        return self._op_JPT(op, opid, ind, f, seg_of, negate=True)

    def _call(self, op: Op, opid: int, ind: int) -> None:
        call = op.call
        if call is None or (not call.is_module and call.file < 0):
            self.out(ind, "_falloff()", opid)       # unresolved target: the front end reported it
            return
        if call.is_module:
            self.budget_check(ind, opid)
            self.out(ind, f"_module({call.module}, {opid})", opid)
            return
        self._nested(ind, opid, f"F{call.file}({self.seg_maps[call.file][call.index]})")

    def _nested(self, ind: int, opid: int, *call: str) -> None:
        """A call one level deeper (CM and CASE), checked against call_depth (A-29)."""
        self.budget_check(ind, opid)
        self.out(ind, "d += 1", opid)
        self.out(ind, f"if d > {self.depth_limit}: _depth_fault(d)", opid)
        for line in call:
            self.out(ind, line, opid)
        self.out(ind, "d -= 1", opid)

    def _op_CALL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self._call(op, opid, ind)

    def _op_CALLT(self, op: Op, opid: int, ind: int, *_: object, negate: bool = False) -> None:
        self.out(ind, f"if {'not ' if negate else ''}{self.la()}:", opid)
        self._cover(ind + 1, opid, 1)
        self._call(op, opid, ind + 1)
        if self.coverage:
            self.out(ind, "else:", opid)
            self._cover(ind + 1, opid, 0)

    def _op_CALLF(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self._op_CALLT(op, opid, ind, negate=True)

    def _op_EM(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"_em = {opid}", opid)
        self.out(ind, "return", opid)

    def _op_EMT(self, op: Op, opid: int, ind: int, *_: object, negate: bool = False) -> None:
        self.out(ind, f"if {'not ' if negate else ''}{self.la()}:", opid)
        self._cover(ind + 1, opid, 1)
        self.out(ind + 1, f"_em = {opid}", opid)
        self.out(ind + 1, "return", opid)
        self._cover(ind, opid, 0)

    def _op_EMF(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self._op_EMT(op, opid, ind, negate=True)

    def _op_CASE(self, op: Op, opid: int, ind: int, *_: object) -> None:
        targets = []
        for t in op.case_targets:
            if t is None or t.file < 0:
                targets.append("None")
            else:
                targets.append(f"(F{t.file}, {self.seg_maps[t.file][t.index]})")
        table = f"_CT{opid}"
        self.case_tables.append(f"{table} = ({', '.join(targets)}{',' if targets else ''})")
        count = len(targets)
        self.out(ind, f"_s = {self.value(op.operand)}", opid)
        self.out(ind, f"if 0 <= _s < {count}:", opid)
        if self.coverage and count:
            # the slots of entries 0..count-1 are consecutive (branch_slots)
            self.out(ind + 1, f"_bh[_s + {self.branch_slot[opid, 0]}] = 1", opid)
        self._nested(ind + 1, opid, f"_f, _g = {table}[_s]", "_f(_g)")
        if self.coverage or self.sem["case_out_of_range"] == "fault":
            self.out(ind, "else:", opid)
            self._cover(ind + 1, opid, -1)
            if self.sem["case_out_of_range"] == "fault":
                self.out(ind + 1, f"_case_fault(_s, {count})", opid)

    # submit jobs (section 15, A-45)

    def _op_SUBM(self, op: Op, opid: int, ind: int, *_: object) -> None:
        call = op.call
        if call is None or call.file < 0:
            self.out(ind, "_falloff()", opid)
            return
        seg = self.seg_maps[call.file][call.index]
        self.out(ind, f"WA = _subm(F{call.file}, {seg}, {call.label!r})", opid)

    def _op_RPLY(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = _rply({self.value(op.operand)})", opid)

    def _op_CAN(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"_can({self.value(op.operand)})", opid)
