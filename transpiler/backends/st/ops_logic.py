"""Logic ops: loads, gates, stores and conditional set/reset of bit operands through the logic accumulator."""

from __future__ import annotations

from transpiler.ir import Op
from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.st.routine import ExecutorPart

# The registers a bit store keeps symbolic while it is emitted (made once: a program stores thousands of bits).
_LA_AND_X = frozenset(["LA", "X"])
_X = frozenset(["X"])


class LogicOpsMixin(ExecutorPart):
    """op_* handlers of the logic accumulator LA."""

    def op_LD(self, op: Op) -> None:
        self.s.set("LA", self.bit(op.operand))

    def op_LDN(self, op: Op) -> None:
        self.s.set("LA", E.b_not(self.bit(op.operand)))

    def _logic(self, op: Op, combine, negate: bool) -> None:
        b = self.bit(op.operand)
        self.s.set("LA", combine(self.s.reg("LA"), E.b_not(b) if negate else b))

    def op_AND(self, op): self._logic(op, E.b_and, False)
    def op_ANDN(self, op): self._logic(op, E.b_and, True)
    def op_OR(self, op): self._logic(op, E.b_or, False)
    def op_ORN(self, op): self._logic(op, E.b_or, True)
    def op_XOR(self, op): self._logic(op, E.b_xor, False)
    def op_XORN(self, op): self._logic(op, E.b_xor, True)

    def op_NOTL(self, op: Op) -> None:
        self.s.set("LA", E.b_not(self.s.reg("LA")))

    def op_ST(self, op: Op) -> None:
        target = self.bit_store(op.operand, lambda: self.s.reg("LA"), _LA_AND_X)
        if target is not None:
            self.s.set("LA", target)

    def op_STN(self, op: Op) -> None:
        self.bit_store(op.operand, lambda: E.b_not(self.s.reg("LA")), _LA_AND_X)

    def _conditional_bit(self, op: Op, when: bool, value: bool) -> None:
        if op.operand.indexed:
            # S/R through the index: the accessor writes the old value back when LA does not act. LA is read
            # when the write is emitted: saving values in flight first may have assigned its variable.
            old = self.bit(op.operand)

            def new() -> E.Expr:
                la = self.s.reg("LA")
                cond = la if when else E.b_not(la)
                return E.b_or(cond, old) if value else E.b_and(E.b_not(cond), old)
            self.bit_store(op.operand, new, _LA_AND_X)
            return
        la = self.s.reg("LA")
        target = self.bit(op.operand)
        if la.bool_const is not None:
            if la.bool_const == when:
                self.bit_store(op.operand, lambda: E.bool_const(value), _X)
            return
        deferred = self.prepare_write(E.written_name(target), _LA_AND_X)
        target = self.bit(op.operand)
        la = self.s.reg("LA")
        cond = la if when else E.b_not(la)
        self.ctx.out.add(S.If(cond, (S.Assign(target.text, E.bool_const(value)),)))
        self.drop(deferred)

    def op_SET(self, op): self._conditional_bit(op, True, True)
    def op_RES(self, op): self._conditional_bit(op, True, False)
    def op_SETN(self, op): self._conditional_bit(op, False, True)
    def op_RESN(self, op): self._conditional_bit(op, False, False)
