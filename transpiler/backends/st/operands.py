"""Operand access: reading and writing bit, word and string operands through the layout, with the index register."""

from __future__ import annotations

from typing import Callable

from transpiler.ir import BYTES, Operand
from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.st.exprs import Expr
from transpiler.backends.st.routine import ExecutorPart, Unsupported


# (what a word store keeps in flight while it is emitted: every register)
_ALL_REGISTERS = frozenset(["WA", "X", "LA", "SA"])


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
        if x.const is None and x.deps - {E.base_name(self.ctx.register("X"))}:
            self.s.set("X", self._temp_copy(x))

    def bit(self, o: Operand, offset: int = 0) -> Expr:
        """Read a bit operand: a variable, or for an indexed one the output Q of the accessor FB called now.

        Q keeps the value read until its instance is called again, so the value is `<instance>.Q` itself (its
        deps name the instance). The instance is one that no value still needed reads: none in flight that is
        live here (a dead register reading it is dropped) and none this op read before (its handler may hold
        that value outside the symbolic state). So the call changes nothing that is still needed."""
        if not o.indexed:
            return self.ctx.layout.bit_lvalue(o, offset)
        xi = self._xi(o)
        index = self.ctx.layout.bit_index(o, xi, offset)
        held = self._held_reads()
        key = _access_key(index, xi, o.addr + offset)
        inst = self.ctx.out.held_access(o.kind, key)
        if inst is None:
            live = self.ctx.live_after(self.index - 1)          # live before this op: what it reads included
            inst = self.ctx.bit_accessor(o.kind, lambda name: name not in held and self.saves_nothing(name.upper(), live),
                                         self.ctx.out.access_rank(o.kind, key))
            self.drop([kind_key[1] for kind_key in self._dependents(inst.upper()) if kind_key[0] == "reg"])
            self.ctx.out.add_access(S.Call(inst, (("IDX", index), ("WRITE", E.bool_const(False)))),
                                    o.kind, key, index.deps, write=False)
        held.add(inst)
        return E.Expr(f"{inst}.Q", "BOOL", frozenset([inst.upper()]), 0, 1)

    def _held_reads(self) -> set[str]:
        """Accessor instances the op being executed has read so far."""
        if self.s.held[0] != self.index:
            self.s.held = (self.index, set())
        return self.s.held[1]

    def bit_store(self, o: Operand, value: Callable[[], Expr], keep: frozenset[str], offset: int = 0) -> Expr | None:
        """Write a bit operand; returns the target variable (None for an indexed write).

        An indexed write goes through an accessor instance whose call needs no value in flight saved (at worst
        a new one): its inputs, the value among them, are evaluated before the call, so the value may read the
        instance's own Q."""
        if not o.indexed:
            return self.store(lambda: self.ctx.layout.bit_lvalue(o, offset), value, keep)
        keep = keep | {"X"}
        # Any operand of this space may change: values in flight that read one of them are saved first.
        deferred = self.prepare_write(f"#{o.kind}", keep)
        xi = self._xi(o)
        index = self.ctx.layout.bit_index(o, xi, offset)
        key = _access_key(index, xi, o.addr + offset)
        live = self.ctx.live_after(self.index)
        inst = self.ctx.bit_accessor(o.kind, lambda name: self.saves_nothing(name.upper(), live),
                                     self.ctx.out.access_rank(o.kind, key))
        deferred += self.prepare_write(inst.upper(), keep)
        self.ctx.out.add_access(S.Call(inst, (("IDX", index), ("WRITE", E.bool_const(True)), ("VALUE", value()))),
                                o.kind, key, index.deps, write=True)
        self.drop(deferred)
        return None

    def value(self, o: Operand) -> Expr:
        """A value operand as DINT-compatible typed expression (SINT/INT/DINT)."""
        if o.kind == "K":
            return self.ctx.layout.constant(o.addr)
        if o.kind == "X":
            return self.s.reg("X")
        if o.kind == "KF":
            name = self.ctx.kfield(o)
            x = self._x()
            return E.Expr(f"{name}[{x.text}]", "DINT", frozenset([E.base_name(name)]) | x.deps, min(o.kfield),
                          max(o.kfield))
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
        written = value()
        first = layout.write_value(o, self._xi(o), written)
        count = len(first)
        if count > 1:
            self.pin_index(o)
        if count > 1 and not value().simple:
            # The value is needed once per byte: compute it once.
            v = self._stable(value())
            value = lambda v=v: v
        for k in range(count):
            if o.indexed:
                lv = lambda k=k: E.var(layout.write_value(o, self._xi(o), value())[k][0], "BYTE")
            else:
                # (the places written of an operand without index are fixed: neither the value nor X moves them)
                lv = lambda place=layout.place(first[k][0]): place
            self.store(lv, lambda k=k: self._written(o, value, written, first, k), _ALL_REGISTERS)

    def _written(self, o: Operand, value: Callable[[], Expr], written: Expr, first: list[tuple[str, Expr]],
                 k: int) -> Expr:
        """The value of place k of `o`, worked out again when saving values in flight changed the value or the
        index (`first`: the places for the value `written` before)."""
        v = value()
        if v is written and not o.indexed:
            return first[k][1]
        return self.ctx.layout.write_value(o, self._xi(o), v)[k][1]


def _access_key(index: Expr, x: Expr | None, base: int) -> tuple[int, str]:
    """The address of an indexed bit operand as the accessor cache compares it (routine.AccessKey)."""
    if index.const is not None:
        return (index.const, "")
    return (base, x.text)
