"""Word ops: loads, stores, gates, arithmetic, comparisons, shifts and increments through the word accumulator."""

from __future__ import annotations

from transpiler.ir import Op, Operand
from transpiler.backends.st import exprs as E
from transpiler.backends.st.arith import shift_value
from transpiler.backends.st.exprs import Expr
from transpiler.backends.st.routine import ExecutorPart


class WordOpsMixin(ExecutorPart):
    """op_* handlers of the word accumulator WA and the index register X."""

    def op_WLD(self, op: Op) -> None:
        self.s.set("WA", E.to_dint(self.value(op.operand)))

    def op_WLDN(self, op: Op) -> None:
        self.s.set("WA", self._not_word(self.value(op.operand)))

    def op_WNEG(self, op: Op) -> None:
        self.s.set("WA", self._neg(self.value(op.operand)))

    def op_LDBITS(self, op: Op) -> None:
        bits = [self.bit(op.operand, k) for k in range(op.nbits)]
        lo, hi = -(2 ** (op.nbits - 1)), 2 ** (op.nbits - 1) - 1
        self.s.set("WA", self._fn(f"HH_PACK{op.nbits}", bits, "DINT", lo, hi))

    def op_WST(self, op: Op) -> None:
        o = op.operand
        if o.kind == "X":
            self.s.set("X", self.s.reg("WA"))
            return
        self._store_value(o, lambda: self.s.reg("WA"))
        if o.kind == "D" and not o.indexed and self.ctx.layout.mem_array is None:
            self.s.set("WA", self.ctx.layout.read_value(o, None))

    def op_STBITS(self, op: Op) -> None:
        wa = self._stable(E.to_dint(self.s.reg("WA")))
        self.s.set("WA", wa)
        self.pin_index(op.operand)

        def bit(k: int) -> E.Expr:
            word = self.s.reg("WA")
            if word.const is not None:      # a constant word: each bit is TRUE or FALSE already
                return E.bool_const(bool((word.const >> k) & 1))
            return self._bit_of(word, k)

        for k in range(op.nbits):
            self.bit_store(op.operand, lambda k=k: bit(k), frozenset(["WA", "X"]), offset=k)

    def _word_gate(self, op: Op, kind: str, negate: bool) -> None:
        v = self.value(op.operand)
        width = op.operand.width
        if negate:
            v = self._not_word(v)
        self.s.set("WA", self._gate(kind, self.s.reg("WA"), v, width))

    def op_WAND(self, op): self._word_gate(op, "A", False)
    def op_WANDN(self, op): self._word_gate(op, "A", True)
    def op_WOR(self, op): self._word_gate(op, "O", False)
    def op_WORN(self, op): self._word_gate(op, "O", True)
    def op_WXOR(self, op): self._word_gate(op, "X", False)
    def op_WXORN(self, op): self._word_gate(op, "X", True)

    def op_ADD(self, op): self.s.set("WA", self._add(self.s.reg("WA"), self.value(op.operand)))
    def op_SUB(self, op): self.s.set("WA", self._add(self.s.reg("WA"), self.value(op.operand), sub=True))
    def op_MUL(self, op): self.s.set("WA", self._mul(self.s.reg("WA"), self.value(op.operand)))
    def op_DIV(self, op): self.s.set("WA", self._divmod(self.s.reg("WA"), self.value(op.operand), False))
    def op_MOD(self, op): self.s.set("WA", self._divmod(self.s.reg("WA"), self.value(op.operand), True))

    def op_CMP(self, op: Op) -> None:
        self.s.set("LA", self._compare(op.rel, self.s.reg("WA"), self.value(op.operand), op.operand.width))

    def _shift_count(self, o: Operand) -> Expr:
        v = self.value(o)
        if v.const is not None:
            return E.int_const(v.const % 32)
        return E.to_dint(v)

    def _shift(self, op: Op, fn: str) -> None:
        """WA shifted, or one bit of it set or cleared, by the helper `fn`; folded where both are constants."""
        wa, count = E.to_dint(self.s.reg("WA")), self._shift_count(op.operand)
        if wa.const is not None and count.const is not None:
            self.s.set("WA", E.int_const(shift_value(fn, wa.const, count.const)))
        else:
            self.s.set("WA", self._fn(fn, [wa, count]))

    def op_SHL(self, op): self._shift(op, "HH_SHL")
    def op_SHR(self, op): self._shift(op, "HH_SHR")
    def op_BS(self, op): self._shift(op, "HH_BSET")
    def op_BC(self, op): self._shift(op, "HH_BCLR")

    def op_BT(self, op: Op) -> None:
        wa, count = E.to_dint(self.s.reg("WA")), self._shift_count(op.operand)
        if wa.const is not None and count.const is not None:
            self.s.set("LA", E.bool_const(bool(wa.const >> (count.const % 32) & 1)))
        else:
            self.s.set("LA", self._fn("HH_BTEST", [wa, count], "BOOL", 0, 1))

    def op_INCW(self, op): self.s.set("WA", self._add(self.s.reg("WA"), E.int_const(1)))
    def op_DECW(self, op): self.s.set("WA", self._add(self.s.reg("WA"), E.int_const(1), sub=True))
    def op_INCX(self, op): self.s.set("X", self._add(self.s.reg("X"), E.int_const(1)))
    def op_DECX(self, op): self.s.set("X", self._add(self.s.reg("X"), E.int_const(1), sub=True))
    def op_NOTW(self, op): self.s.set("WA", self._not_word(self.s.reg("WA")))
    def op_TWOC(self, op): self.s.set("WA", self._neg(self.s.reg("WA")))

    def _incdec(self, op: Op, delta: int) -> None:
        o = op.operand
        if o.is_bit:
            old = self.bit(o)
            self.bit_store(o, lambda: E.b_not(old), frozenset(["X"]))
            return
        self._store_value(o, lambda: self._add(self.value(o), E.int_const(abs(delta)), sub=delta < 0))

    def op_INC(self, op): self._incdec(op, 1)
    def op_DEC(self, op): self._incdec(op, -1)
