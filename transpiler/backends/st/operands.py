"""Operand access: reading and writing bit, word and string operands through the layout, with the index register."""

from __future__ import annotations

from typing import Callable

from transpiler.ir import BYTES, Operand
from transpiler.backends.st import exprs as E
from transpiler.backends.st.exprs import Expr
from transpiler.backends.st.routine import ExecutorPart, Unsupported


class OperandMixin(ExecutorPart):
    """Reads and writes operands: named variables, the byte array, indexed bits through their accessor FB."""

    def _x(self) -> Expr:
        return self.s.reg("X")

    def _xi(self, o: Operand) -> Expr | None:
        """The index register for an indexed operand; a constant index that would be out of range is kept in
        its variable (matiec rejects constant out-of-range subscripts; the original faults at run time)."""
        if not o.indexed:
            return None
        x = self.s.reg("X")
        if x.const is not None:
            ranges = self.ctx.semantics.profile.ranges
            size = ranges.size("B" if o.kind in BYTES else o.kind)
            width = BYTES.get(o.kind, 1)
            scale = width if self.ctx.semantics["index_scaling"] == "elements" else 1
            addr = o.addr + x.const * scale
            if not 0 <= addr <= size - width:
                self.materialize("X")
                x = self.s.reg("X")
        return x

    def pin_index(self, o: Operand) -> None:
        """Before one op writes an indexed operand in several statements: the index register as a value that
        those statements cannot change (the first may overwrite memory the index expression reads)."""
        if not o.indexed:
            return
        x = self.s.reg("X")
        # Only X's own variable is safe to read: saving another register variable before a store may drop X.
        if x.const is None and x.deps - {self.ctx.register("X").upper()}:
            self.s.set("X", self._temp_copy(x))

    def bit(self, o: Operand, offset: int = 0) -> Expr:
        """Read a bit operand: a variable, or for an indexed one the value read now through the accessor FB."""
        if not o.indexed:
            return self.ctx.layout.bit_lvalue(o, offset)
        inst = self.ctx.bit_accessor(o.kind)
        index = self.ctx.layout.bit_index(o, self._xi(o), offset)
        self.ctx.out.line(f"{inst}(IDX := {index.text}, WRITE := FALSE);")
        name = self.ctx.temp("BOOL")
        self.ctx.out.line(f"{name} := {inst}.Q;")
        return E.var(name, "BOOL")

    def bit_store(self, o: Operand, value: Callable[[], Expr], keep: frozenset[str], offset: int = 0) -> Expr | None:
        """Write a bit operand; returns the target variable (None for an indexed write)."""
        if not o.indexed:
            return self.store(lambda: self.ctx.layout.bit_lvalue(o, offset), value, keep)
        inst = self.ctx.bit_accessor(o.kind)
        # Any operand of this space may change: values in flight that read one of them are saved first.
        deferred = self.prepare_write(f"#{o.kind}", keep | {"X"})
        index = self.ctx.layout.bit_index(o, self._xi(o), offset)
        self.ctx.out.line(f"{inst}(IDX := {index.text}, WRITE := TRUE, VALUE := {value().text});")
        self.drop(deferred)
        return None

    def value(self, o: Operand) -> Expr:
        """A value operand as DINT-compatible typed expression (SINT/INT/DINT)."""
        if o.kind == "K":
            return E.int_const(o.addr)
        if o.kind == "X":
            return self.s.reg("X")
        if o.kind == "KF":
            name = self.ctx.kfield(o)
            x = self._x()
            return E.Expr(f"{name}[{x.text}]", "DINT", frozenset([name.upper()]) | x.deps, min(o.kfield), max(o.kfield))
        if o.kind in "BWD":
            return self.ctx.layout.read_value(o, self._xi(o))
        raise Unsupported(f"{o.display()} as a word operand")

    def string(self, o: Operand) -> Expr:
        if o.kind == "STR":
            text = o.text.replace("$", "$$").replace("'", "$'")
            return E.Expr(f"'{text}'", "STRING")
        return self.ctx.layout.string_lvalue(o, self._xi(o))

    def _store_value(self, o: Operand, value: Callable[[], Expr]) -> None:
        """Store a DINT value into a B/W/D operand (one assignment, or one per byte in the byte array)."""
        layout = self.ctx.layout
        count = len(layout.write_value(o, self._xi(o), value()))
        if count > 1:
            self.pin_index(o)
        if count > 1 and not value().simple:
            # The value is needed once per byte: compute it once.
            v = self._stable(value())
            value = lambda v=v: v
        for k in range(count):
            lv = lambda k=k: E.var(layout.write_value(o, self._xi(o), value())[k][0], "BYTE")
            rv = lambda k=k: layout.write_value(o, self._xi(o), value())[k][1]
            self.store(lv, rv, frozenset(["WA", "X", "LA", "SA"]))
