"""Brackets: an opening bracket saves the accumulator, the closing one combines it with the bracket's value."""

from __future__ import annotations

from transpiler.ir import Op
from transpiler.backends.st import exprs as E
from transpiler.backends.st.routine import ExecutorPart, Frame


class BracketOpsMixin(ExecutorPart):
    """op_BOPEN / op_BCLOSE over the symbolic bracket frames."""

    def op_BOPEN(self, op: Op) -> None:
        b = op.bracket
        saved = self.s.reg("LA") if b.mode == "LOGIC" and b.op in ("A", "AN", "O", "ON", "XO", "XON") else self.s.reg("WA")
        self.s.frames.append(Frame(op, saved))

    def op_BCLOSE(self, op: Op) -> None:
        frame = self.s.frames.pop()
        b = frame.op.bracket
        saved = frame.saved
        if b.op in ("A", "AN", "O", "ON", "XO", "XON") and b.mode == "LOGIC":
            inner = self.s.reg("LA")
            negate = b.op in ("AN", "ON", "XON")
            if b.load:
                self.s.set("LA", E.b_not(inner) if negate else inner)
                return
            rhs = E.b_not(inner) if negate else inner
            combine = {"A": E.b_and, "AN": E.b_and, "O": E.b_or, "ON": E.b_or, "XO": E.b_xor, "XON": E.b_xor}[b.op]
            self.s.set("LA", combine(saved, rhs))
            return
        wa = self.s.reg("WA")
        if b.op in ("A", "AN", "O", "ON", "XO", "XON"):
            rhs = self._not_word(wa) if b.op in ("AN", "ON", "XON") else wa
            self.s.set("WA", self._gate(b.op[0] if b.op[0] != "X" else "X", saved, rhs, 32))
        elif b.op == "+":
            self.s.set("WA", self._add(saved, wa))
        elif b.op == "-":
            self.s.set("WA", self._add(saved, wa, sub=True))
        elif b.op == "x":
            self.s.set("WA", self._mul(saved, wa))
        elif b.op in ("/", "MOD"):
            self.s.set("WA", self._divmod(saved, wa, b.op == "MOD"))
        else:
            self.s.set("LA", self._compare(b.op, saved, wa, 32))
