"""Symbolic execution of one routine's ops: accumulators, data stack and brackets become expressions; stores become ST statements."""

from __future__ import annotations

import dataclasses
from typing import Callable

from transpiler.backends.iec_model import st_comment
from transpiler.ir import BYTES, Op, Operand
from transpiler.backends.st import exprs as E
from transpiler.backends.st.exprs import Expr
from transpiler.backends.st.layout import Layout
from transpiler.backends.st.liveness import REGS

REL = {"==": "=", "<>": "<>", "<": "<", ">": ">", "<=": "<=", ">=": ">="}
WIDTH_TYPE = {8: "SINT", 16: "INT", 32: "DINT"}
REG_TYPES = {"LA": ("BOOL", "HH_LA", "logic accumulator"), "WA": ("DINT", "HH_WA", "word accumulator"),
             "SA": ("STRING", "HH_SA", "string accumulator"), "X": ("DINT", "HH_X", "index register")}


class Unsupported(Exception):
    """An op the ST backend cannot translate; the routine reports it and continues."""


@dataclasses.dataclass
class _Frame:
    op: Op
    saved: Expr


class Emitter:
    """Collects ST lines with indentation and pending source comments."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.indent = 0
        self.pending_comments: list[str] = []

    def comment(self, text: str) -> None:
        self.pending_comments.append(text)

    def flush_comments(self) -> None:
        for text in self.pending_comments:
            self.lines.append("    " * self.indent + st_comment(text))
        self.pending_comments = []

    def line(self, text: str) -> None:
        self.flush_comments()
        self.lines.append("    " * self.indent + text)


class SymbolicState:
    """Accumulators (None = the value sits in its global register variable), data stack and bracket frames."""

    def __init__(self, gen: "RoutineContext"):
        self.gen = gen
        self.regs: dict[str, Expr | None] = dict.fromkeys(REGS)
        self.stack: list[tuple[str, Expr]] = []
        self.frames: list[_Frame] = []

    def reg(self, name: str) -> Expr:
        value = self.regs[name]
        if value is not None:
            return value
        return E.var(self.gen.register(name), REG_TYPES[name][0])

    def set(self, name: str, value: Expr) -> None:
        self.regs[name] = value


class RoutineContext:
    """What the symbolic executor needs from the backend: layout, register names, helper registry, liveness."""

    def __init__(self, layout: Layout, emitter: Emitter, live_after: Callable[[int], frozenset[str]],
                 register: Callable[[str], str], helper: Callable[[str], None], temp: Callable[[str], str],
                 kfield: Callable[[Operand], str], stack_names: Callable[[], tuple[str, str]],
                 module_call: Callable[[int], str], semantics, bit_accessor: Callable[[str], str]):
        self.layout = layout
        self.out = emitter
        self.live_after = live_after
        self.register = register
        self.helper = helper
        self.temp = temp
        self.kfield = kfield
        self.stack_names = stack_names
        self.module_call = module_call
        self.semantics = semantics
        self.bit_accessor = bit_accessor
        self.flag_markers = semantics.profile.interface


class Executor:
    """Translates straight-line ops; control-flow ops are left to the structurer, which calls the hooks below."""

    def __init__(self, ctx: RoutineContext):
        self.ctx = ctx
        self.s = SymbolicState(ctx)
        self.index = 0

    # ---- state management

    def _dependents(self, base: str):
        for name, value in self.s.regs.items():
            if value is not None and base in value.deps:
                yield ("reg", name)
        for k, (_, value) in enumerate(self.s.stack):
            if base in value.deps:
                yield ("stack", k)
        for k, frame in enumerate(self.s.frames):
            if base in frame.saved.deps:
                yield ("frame", k)

    def prepare_write(self, base: str, keep: frozenset[str] = frozenset()) -> list[str]:
        """Before `base` is assigned: save every in-flight value that reads it.

        Registers still live after this op go to their variables; registers in `keep` (read by the
        pending statement itself) stay symbolic and are returned, to be dropped once it is emitted.
        """
        live = self.ctx.live_after(self.index)
        deferred: list[str] = []
        for kind, key in list(self._dependents(base)):
            if kind == "reg":
                if key in live or self.s.frames or self.s.stack:
                    self.materialize(key)
                elif key in keep:
                    deferred.append(key)
                else:
                    self.s.regs[key] = None
            elif kind == "stack":
                entry_kind, value = self.s.stack[key]
                name = self.ctx.temp(value.typ)
                self._assign_raw(name, value)
                self.s.stack[key] = (entry_kind, E.var(name, value.typ))
            else:
                frame = self.s.frames[key]
                name = self.ctx.temp(frame.saved.typ)
                self._assign_raw(name, frame.saved)
                frame.saved = E.var(name, frame.saved.typ)
        return deferred

    def drop(self, regs: list[str]) -> None:
        for r in regs:
            self.s.regs[r] = None

    def materialize(self, reg: str) -> None:
        value = self.s.regs[reg]
        if value is None:
            return
        name = self.ctx.register(reg)
        if value.var is not None and value.var.upper() == name.upper():
            self.s.regs[reg] = None
            return
        # Other in-flight values reading this register variable are saved first; the value itself
        # is evaluated before the assignment, so it may read the variable.
        self.s.regs[reg] = None
        self.prepare_write(name.upper())
        self.ctx.out.line(f"{name} := {value.text};")

    def _assign_raw(self, lvalue: str, value: Expr) -> None:
        self.ctx.out.line(f"{lvalue} := {value.text};")

    def store(self, target: Callable[[], Expr], value: Callable[[], Expr], keep: frozenset[str]) -> Expr:
        """Emit `target := value`; both are built after in-flight values that read the target were saved."""
        t = target()
        deferred = self.prepare_write(E.base_name(t.text), keep)
        t = target()
        v = value()
        self.ctx.out.line(f"{t.text} := {v.text};")
        self.drop(deferred)
        return t

    def flush(self, live: frozenset[str]) -> None:
        """At a block boundary: live registers into their variables, the data stack into the real stack."""
        self.flush_stack()
        for reg in REGS:
            if reg in live:
                self.materialize(reg)
            else:
                self.s.regs[reg] = None

    def forget(self) -> None:
        """After a call, a return or a join of paths: every register is read from its variable again."""
        self.s.regs = dict.fromkeys(REGS)

    def la_is(self, value: bool) -> Expr:
        """The condition `LA = value`: LA, or NOT LA."""
        la = self.s.reg("LA")
        return la if value else E.b_not(la)

    def snapshot(self) -> tuple[dict, list]:
        return dict(self.s.regs), list(self.s.stack)

    def restore(self, snap: tuple[dict, list]) -> None:
        self.s.regs, self.s.stack = dict(snap[0]), list(snap[1])

    def keep_live(self, live: frozenset[str]) -> None:
        """Before a branch: live registers into their variables, the rest stays symbolic for the branch."""
        self.flush_stack()
        for reg in REGS:
            if reg in live:
                self.materialize(reg)

    def flush_stack(self) -> None:
        entries, self.s.stack = self.s.stack, []
        for kind, value in entries:
            self._real_push(kind, value)

    # ---- operand access

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

    # ---- helpers

    def _fn(self, name: str, args: list[Expr], typ: str = "DINT", lo: int | None = None, hi: int | None = None) -> Expr:
        self.ctx.helper(name)
        return E.call(name, args, typ, lo, hi)

    def _add(self, a: Expr, b: Expr, sub: bool = False) -> Expr:
        a, b = E.to_dint(a), E.to_dint(b)
        lo = a.lo - b.hi if sub else a.lo + b.lo
        hi = a.hi - b.lo if sub else a.hi + b.hi
        if a.const is not None and b.const is not None:
            return E.int_const(_wrap32(a.const - b.const if sub else a.const + b.const))
        if E.INT32[0] <= lo and hi <= E.INT32[1]:
            return E.binop("-" if sub else "+", a, b, "DINT", E.PREC_ADD, lo, hi)
        return self._fn("HH_SUB" if sub else "HH_ADD", [a, b])

    def _neg(self, a: Expr) -> Expr:
        a = E.to_dint(a)
        if a.const is not None:
            return E.int_const(_wrap32(-a.const))
        if a.lo > E.INT32[0]:
            return E.Expr(f"-{a.wrap(E.PREC_UNARY + 1)}", "DINT", a.deps, -a.hi, -a.lo, E.PREC_UNARY)
        return self._fn("HH_SUB", [E.int_const(0), a])

    def _not_word(self, a: Expr) -> Expr:
        a = E.to_dint(a)
        if a.const is not None:
            return E.int_const(~a.const)
        return E.binop("-", E.int_const(-1), a, "DINT", E.PREC_ADD, -1 - a.hi, -1 - a.lo)

    def _flag(self, marker: int, value: Expr) -> None:
        self.store(lambda: self.ctx.layout.bit_lvalue(Operand("M", marker)), lambda: value, frozenset())

    def _mul(self, a: Expr, b: Expr) -> Expr:
        a, b = E.to_dint(a), E.to_dint(b)
        products = [a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi]
        flag = self.ctx.flag_markers.mul_err
        if E.INT32[0] <= min(products) and max(products) <= E.INT32[1]:
            self._flag(flag, E.bool_const(False))
            if a.const is not None and b.const is not None:
                return E.int_const(a.const * b.const)
            return E.binop("*", a, b, "DINT", E.PREC_MUL, min(products), max(products))
        a = self._stable(a)
        b = self._stable(b)
        self._flag(flag, self._fn("HH_MULOVF", [a, b], "BOOL", 0, 1))
        return self._fn("HH_MUL", [a, b])

    def _divmod(self, a: Expr, b: Expr, mod: bool) -> Expr:
        """Division or MOD with the spec's zero rule: result = a unchanged, error marker set."""
        a, b = E.to_dint(a), E.to_dint(b)
        flag = self.ctx.flag_markers.mod_err if mod else self.ctx.flag_markers.div_err
        fn = "HH_MOD" if mod else "HH_DIV"
        if b.const is not None and b.const != 0:
            self._flag(flag, E.bool_const(False))
            if b.const == -1 and a.lo == E.INT32[0]:
                return self._fn(fn, [a, b])
            if a.const is not None:
                q = abs(a.const) // abs(b.const) * (1 if (a.const >= 0) == (b.const >= 0) else -1)
                return E.int_const(a.const - b.const * q if mod else q)
            lo, hi = (min(-abs(b.const) + 1, 0) if a.lo < 0 else 0, abs(b.const) - 1) if mod else (
                min(a.lo // abs(b.const), -(a.hi // abs(b.const))), max(a.hi // abs(b.const), -(a.lo // abs(b.const))))
            return E.binop("MOD" if mod else "/", a, b, "DINT", E.PREC_MUL, lo, hi)
        if b.const == 0:
            self._flag(flag, E.bool_const(True))
            return a
        # Unknown divisor: keep WA and set the marker when it is 0 (spec 6.5, 17b.4).
        result_var = self.ctx.register("WA")
        if not b.simple or result_var.upper() in b.deps:
            b = self._temp_copy(b)
        self.s.regs["WA"] = None
        self.prepare_write(result_var.upper())
        if a.var is None or a.var.upper() != result_var.upper():
            self.ctx.out.line(f"{result_var} := {a.text};")
        a_text = result_var
        marker = self.ctx.layout.bit_lvalue(Operand("M", flag))
        self.prepare_write(E.base_name(marker.text))
        self.ctx.helper(fn)
        out = self.ctx.out
        out.line(f"IF {b.wrap(E.PREC_EQ)} <> 0 THEN")
        out.indent += 1
        out.line(f"{result_var} := {fn}({a_text}, {b.text});")
        out.line(f"{marker.text} := FALSE;")
        out.indent -= 1
        out.line("ELSE")
        out.indent += 1
        out.line(f"{marker.text} := TRUE;")
        out.indent -= 1
        out.line("END_IF;")
        return E.var(result_var, "DINT")

    def _stable(self, e: Expr) -> Expr:
        """An expression that may be evaluated twice: simple ones as they are, others through a temporary."""
        return e if e.simple else self._temp_copy(e)

    def _temp_copy(self, e: Expr) -> Expr:
        """`e` assigned to a new temporary, which then stands for it (with the same value range)."""
        name = self.ctx.temp(e.typ)
        self._assign_raw(name, e)
        return E.Expr(name, e.typ, frozenset([name.upper()]), e.lo, e.hi, var=name)

    def _sext(self, a: Expr, width: int) -> Expr:
        if width == 32:
            return a
        typ = WIDTH_TYPE[width]
        if E.fits(a, *E.RANGES[typ]):
            return a
        return self._fn(f"HH_SEXT{width}", [E.to_dint(a)], "DINT", *E.RANGES[typ])

    def _compare(self, rel: str, a: Expr, b: Expr, width: int) -> Expr:
        a = self._sext(E.to_dint(a), width)
        b = E.to_dint(b)
        # Compare the narrow values themselves where both sides allow it, so that comparisons read like the source.
        narrow_a, narrow_b = E.unwiden(a), E.unwiden(b)
        if narrow_a is not None and narrow_b is not None and narrow_a.typ == narrow_b.typ:
            a, b = narrow_a, narrow_b
        elif narrow_a is not None and b.const is not None and E.fits(b, *E.RANGES[narrow_a.typ]):
            a = narrow_a
        elif narrow_b is not None and a.const is not None and E.fits(a, *E.RANGES[narrow_b.typ]):
            b = narrow_b
        prec = E.PREC_EQ if rel in ("==", "<>") else E.PREC_CMP
        return E.binop(REL[rel], a, b, "BOOL", prec, 0, 1)

    def _gate(self, kind: str, a: Expr, b: Expr, width: int) -> Expr:
        fn = {"A": "HH_WAND", "O": "HH_WOR", "X": "HH_WXOR"}[kind]
        return self._fn(fn, [E.to_dint(a), E.to_dint(b), E.int_const(width)])

    # ---- stack

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

    # ---- the ops

    def run(self, op: Op, index: int) -> None:
        self.index = index
        for text in op.comments:
            self.ctx.out.comment(text)
        handler = getattr(self, "op_" + op.code, None)
        if handler is None:
            raise Unsupported(f"{op.mnemonic} ({op.code})")
        handler(op)

    def op_LBL(self, op: Op) -> None:
        pass

    op_NOP = op_LBL
    op_KFIELD = op_LBL

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
        target = self.bit_store(op.operand, lambda: self.s.reg("LA"), frozenset(["LA", "X"]))
        if target is not None:
            self.s.set("LA", target)

    def op_STN(self, op: Op) -> None:
        self.bit_store(op.operand, lambda: E.b_not(self.s.reg("LA")), frozenset(["LA", "X"]))

    def _conditional_bit(self, op: Op, when: bool, value: bool) -> None:
        la = self.s.reg("LA")
        if op.operand.indexed:
            # S/R through the index: the accessor writes the old value back when LA does not act.
            old = self.bit(op.operand)
            cond = la if when else E.b_not(la)
            new = E.b_or(cond, old) if value else E.b_and(E.b_not(cond), old)
            self.bit_store(op.operand, lambda: new, frozenset(["LA", "X"]))
            return
        target = self.bit(op.operand)
        if la.bool_const is not None:
            if la.bool_const == when:
                self.bit_store(op.operand, lambda: E.bool_const(value), frozenset(["X"]))
            return
        deferred = self.prepare_write(E.base_name(target.text), frozenset(["LA", "X"]))
        target = self.bit(op.operand)
        la = self.s.reg("LA")
        cond = la if when else E.b_not(la)
        out = self.ctx.out
        out.line(f"IF {cond.text} THEN")
        out.indent += 1
        out.line(f"{target.text} := {'TRUE' if value else 'FALSE'};")
        out.indent -= 1
        out.line("END_IF;")
        self.drop(deferred)

    def op_SET(self, op): self._conditional_bit(op, True, True)
    def op_RES(self, op): self._conditional_bit(op, True, False)
    def op_SETN(self, op): self._conditional_bit(op, False, True)
    def op_RESN(self, op): self._conditional_bit(op, False, False)

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

    def op_STBITS(self, op: Op) -> None:
        wa = self._stable(E.to_dint(self.s.reg("WA")))
        self.s.set("WA", wa)
        self.ctx.helper("HH_BIT")
        self.pin_index(op.operand)
        for k in range(op.nbits):
            self.bit_store(op.operand,
                           lambda k=k: E.Expr(f"HH_BIT({self.s.reg('WA').text}, {k})", "BOOL", self.s.reg("WA").deps, 0, 1),
                           frozenset(["WA", "X"]), offset=k)

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

    def op_SHL(self, op): self.s.set("WA", self._fn("HH_SHL", [E.to_dint(self.s.reg("WA")), self._shift_count(op.operand)]))
    def op_SHR(self, op): self.s.set("WA", self._fn("HH_SHR", [E.to_dint(self.s.reg("WA")), self._shift_count(op.operand)]))
    def op_BS(self, op): self.s.set("WA", self._fn("HH_BSET", [E.to_dint(self.s.reg("WA")), self._shift_count(op.operand)]))
    def op_BC(self, op): self.s.set("WA", self._fn("HH_BCLR", [E.to_dint(self.s.reg("WA")), self._shift_count(op.operand)]))

    def op_BT(self, op: Op) -> None:
        self.s.set("LA", self._fn("HH_BTEST", [E.to_dint(self.s.reg("WA")), self._shift_count(op.operand)], "BOOL", 0, 1))

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

    # brackets

    def op_BOPEN(self, op: Op) -> None:
        b = op.bracket
        saved = self.s.reg("LA") if b.mode == "LOGIC" and b.op in ("A", "AN", "O", "ON", "XO", "XON") else self.s.reg("WA")
        self.s.frames.append(_Frame(op, saved))

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

    # stack

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

    # strings

    def op_SLD(self, op): self.s.set("SA", self.string(op.operand))

    def op_SCAT(self, op: Op) -> None:
        self.s.set("SA", E.call("CONCAT", [self.s.reg("SA"), self.string(op.operand)], "STRING"))

    def op_SST(self, op: Op) -> None:
        self.store(lambda: self.string(op.operand), lambda: self.s.reg("SA"), frozenset(["SA", "X"]))

    def op_SCMP(self, op: Op) -> None:
        prec = E.PREC_EQ if op.rel in ("==", "<>") else E.PREC_CMP
        self.s.set("LA", E.binop(REL[op.rel], self.s.reg("SA"), self.string(op.operand), "BOOL", prec, 0, 1))


def _wrap32(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - 2 ** 32 if v >= 2 ** 31 else v
