"""Data stack and string instructions in the generated code (6.10, 6.16)."""

from __future__ import annotations

import re

from transpiler.exec.interp.gen_exprs import REL, norm
from transpiler.ir import Op

# A value expression that can neither fault nor change anything: a register, a constant-address read, a literal,
# a register-only bit expression (then it may be evaluated after the capacity check)
_SIDE_EFFECT_FREE = re.compile(r"(\(\(WA >> 7\) & 1\)|[A-Za-z_]\w*(\[\d+\])?|\(?-?\d+\)?)( << 7| & 65535)?")


class StackStringCode:
    """Mixin of the code generator: PUSH POP PSW PLW PSL PLL PSX PLX and SLD SCAT SST SCMP; uses `out`, `sem`
    and the operand access of AccessCode."""

    # data stack (6.10, A-19, A-20): pushes and pulls are inline list operations, the faults are helpers. A value is
    # read before the capacity check, as the helpers did, so a fault of the operand read comes first. Every word
    # on the stack is 0..65535: a 16-bit push is of a bit << 7 or of X & 65535, 32-bit pushes are masked.

    def _push16(self, ind: int, expr: str, opid: int) -> None:
        if not _SIDE_EFFECT_FREE.fullmatch(expr):
            self.out(ind, f"_v = {expr}", opid)
            expr = "_v"
        self.out(ind, f"stk.append({expr}) if len(stk) < {int(self.sem['data_stack_words'])} else _overflow()", opid)

    def _push32(self, ind: int, expr: str, opid: int) -> None:
        if not _SIDE_EFFECT_FREE.fullmatch(expr):
            self.out(ind, f"_v = {expr}", opid)
            expr = "_v"
        self.out(ind, f"if len(stk) > {int(self.sem['data_stack_words']) - 2}: _overflow()", opid)
        self.out(ind, f"stk.append({expr} & 65535); stk.append(({expr} >> 16) & 65535)", opid)

    def _pushed_words(self, op: Op) -> list[str] | None:
        """The words a push op puts on the stack (low word first), if computing them can neither fault nor change
        anything; None for any other op."""
        c = op.code
        if c == "PUSH" and op.operand.is_bit:
            value = f"{self.bit(op.operand)} << 7"
            return [value] if _SIDE_EFFECT_FREE.fullmatch(value) else None
        if c == "PUSH":
            value = self.value(op.operand)
        elif c == "PSL":
            return [f"{self.la()} << 7"]
        elif c == "PSW":
            value = "WA"
        elif c == "PSX":
            if int(self.sem["psx_width"]) == 16:
                return ["X & 65535"]
            value = "X"
        else:
            return None
        if not _SIDE_EFFECT_FREE.fullmatch(value):
            return None
        return [f"{value} & 65535", f"({value} >> 16) & 65535"]

    def _push_run(self, ops: tuple[Op, ...], start: int) -> tuple[int, list[str]] | None:
        """A run of two or more such pushes from `start` on: (its number of ops, the words it pushes in order)."""
        words: list[str] = []
        count = 0
        for op in ops[start:]:
            pushed = self._pushed_words(op)
            if pushed is None:
                break
            words += pushed
            count += 1
        return (count, words) if count >= 2 else None

    @staticmethod
    def _pull16() -> str:
        return "(stk.pop() if stk else _underflow(1))"

    @staticmethod
    def _pull32() -> str:
        # the high word is on top; evaluated left to right, the first pop() is the high word
        return f"({norm('stk.pop() << 16 | stk.pop()')} if len(stk) > 1 else _underflow(2))"

    def _op_PUSH(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if o.is_bit:
            self._push16(ind, f"{self.bit(o)} << 7", opid)
        else:
            self._push32(ind, self.value(o), opid)

    def _op_POP(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if o.is_bit:
            self.bit_store(ind, o, f"({self._pull16()} >> 7) & 1", opid)
        else:
            self.store(ind, o, self._pull32(), opid)

    def _op_PSW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self._push32(ind, "WA", opid)

    def _op_PLW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {self._pull32()}", opid)

    def _op_PSL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self._push16(ind, f"{self.la()} << 7", opid)

    def _op_PLL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.set_la(ind, f"({self._pull16()} >> 7) & 1", opid)

    def _op_PSX(self, op: Op, opid: int, ind: int, *_: object) -> None:
        if int(self.sem["psx_width"]) == 16:
            self._push16(ind, "X & 65535", opid)
        else:
            self._push32(ind, "X", opid)

    def _op_PLX(self, op: Op, opid: int, ind: int, *_: object) -> None:
        if int(self.sem["psx_width"]) == 16:
            self.out(ind, self.x_store(self._pull16()), opid)
        else:
            self.out(ind, self.x_store(self._pull32()), opid)

    # strings (6.16, A-50)

    def _op_SLD(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"SA = {self.string(op.operand)}", opid)

    def _op_SCAT(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"SA = _scat(SA + {self.string(op.operand)}, {opid})", opid)

    def _op_SST(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"{self.string(op.operand, write=True)} = SA", opid)

    def _op_SCMP(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.set_la(ind, f"SA {REL[op.rel]} {self.string(op.operand)}", opid)
