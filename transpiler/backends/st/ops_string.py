"""String ops: load, concatenate, store and compare through the string accumulator SA."""

from __future__ import annotations

from transpiler.ir import Op
from transpiler.backends.st import exprs as E
from transpiler.backends.st.arith import REL
from transpiler.backends.st.routine import ExecutorPart


class StringOpsMixin(ExecutorPart):
    """op_* handlers of the string accumulator SA."""

    def op_SLD(self, op): self.s.set("SA", self.string(op.operand))

    def op_SCAT(self, op: Op) -> None:
        self.s.set("SA", E.call("CONCAT", [self.s.reg("SA"), self.string(op.operand)], "STRING"))

    def op_SST(self, op: Op) -> None:
        self.store(lambda: self.string(op.operand), lambda: self.s.reg("SA"), frozenset(["SA", "X"]))

    def op_SCMP(self, op: Op) -> None:
        prec = E.PREC_EQ if op.rel in ("==", "<>") else E.PREC_CMP
        self.s.set("LA", E.binop(REL[op.rel], self.s.reg("SA"), self.string(op.operand), "BOOL", prec, 0, 1))
