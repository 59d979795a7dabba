"""The data stack: pushes stay symbolic until a boundary, then go to the stack array as 16-bit words; pops read it back."""

from __future__ import annotations

from transpiler.ir import Op
from transpiler.backends.st import exprs as E
from transpiler.backends.st.exprs import Expr
from transpiler.backends.st.routine import ExecutorPart


class StackMixin(ExecutorPart):
    """PS/PL of bits, words and the index register over the symbolic stack and the real one."""

    def _real_push(self, kind: str, value: Expr) -> None:
        stack, sp = self.ctx.stack_names()
        out = self.ctx.out
        if kind == "bit":
            self.ctx.helper("HH_BIT")
            out.line(f"{stack}[{sp}] := BOOL_TO_INT({value.text}) * 128;")
            out.line(f"{sp} := {sp} + 1;")
            return
        v = self._stable(E.to_dint(value))
        self.ctx.helper("HH_LOWORD")
        self.ctx.helper("HH_HIWORD")
        out.line(f"{stack}[{sp}] := HH_LOWORD({v.text});")
        out.line(f"{stack}[{sp} + 1] := HH_HIWORD({v.text});")
        out.line(f"{sp} := {sp} + 2;")

    def _pop(self, kind: str) -> Expr:
        if self.s.stack and self.s.stack[-1][0] == kind:
            return self.s.stack.pop()[1]
        self.flush_stack()
        stack, sp = self.ctx.stack_names()
        out = self.ctx.out
        if kind == "bit":
            self.ctx.helper("HH_BIT")
            out.line(f"{sp} := {sp} - 1;")
            value = E.Expr(f"HH_BIT(INT_TO_DINT({stack}[{sp}]), 7)", "BOOL", frozenset([stack.upper(), sp.upper()]), 0, 1)
        else:
            self.ctx.helper("HH_FROMWORDS")
            out.line(f"{sp} := {sp} - 2;")
            value = E.Expr(f"HH_FROMWORDS({stack}[{sp} + 1], {stack}[{sp}])", "DINT", frozenset([stack.upper(), sp.upper()]))
        # The popped value must be captured now: the stack pointer moves again later.
        return self._temp_copy(value)

    def op_PUSH(self, op: Op) -> None:
        o = op.operand
        if o.is_bit:
            self.s.stack.append(("bit", self.bit(o)))
        else:
            self.s.stack.append(("val", E.to_dint(self.value(o))))

    def op_POP(self, op: Op) -> None:
        o = op.operand
        value = self._pop("bit" if o.is_bit else "val")
        if value.deps & self.ctx.layout.register_vars:
            # Saving in-flight values before the store may assign the register variable the value reads.
            value = self._temp_copy(value)
        if o.is_bit:
            self.bit_store(o, lambda: value, frozenset(["X"]))
        else:
            self._store_value(o, lambda: value)

    def op_PSW(self, op): self.s.stack.append(("val", E.to_dint(self.s.reg("WA"))))
    def op_PLW(self, op): self.s.set("WA", self._pop("val"))
    def op_PSL(self, op): self.s.stack.append(("bit", self.s.reg("LA")))
    def op_PLL(self, op): self.s.set("LA", self._pop("bit"))
    def op_PSX(self, op): self.s.stack.append(("val", self.s.reg("X")))
    def op_PLX(self, op): self.s.set("X", self._pop("val"))
