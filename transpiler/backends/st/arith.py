"""Word arithmetic on expressions: wrap-around add/sub/negate, MUL/DIV/MOD with error markers, comparisons, gates."""

from __future__ import annotations

from types import MappingProxyType

from transpiler.ir import Operand
from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.st.exprs import Expr
from transpiler.backends.st.routine import ExecutorPart

REL = MappingProxyType({"==": "=", "<>": "<>", "<": "<", ">": ">", "<=": "<=", ">=": ">="})
WIDTH_TYPE = MappingProxyType({8: "SINT", 16: "INT", 32: "DINT"})


class ArithmeticMixin(ExecutorPart):
    """Builds the expression of an arithmetic result, using plain ST where the value ranges allow and HH_* helpers elsewhere."""

    def _fn(self, name: str, args: list[Expr], typ: str = "DINT", lo: int | None = None, hi: int | None = None) -> Expr:
        self.ctx.helper(name)
        return E.call(name, args, typ, lo, hi)

    def _bit_of(self, word: Expr, k: int) -> Expr:
        """Bit k of `word` (E.bit_of), through the HH_BIT helper where the target has no bit access."""
        if not self.ctx.dialect.bit_access:
            self.ctx.helper("HH_BIT")
        return E.bit_of(word, k, self.ctx.dialect.bit_access)

    def _add(self, a: Expr, b: Expr, sub: bool = False) -> Expr:
        a, b = E.to_dint(a), E.to_dint(b)
        lo = a.lo - b.hi if sub else a.lo + b.lo
        hi = a.hi - b.lo if sub else a.hi + b.hi
        if a.const is not None and b.const is not None:
            return E.int_const(wrap32(a.const - b.const if sub else a.const + b.const))
        if E.INT32[0] <= lo and hi <= E.INT32[1]:
            return E.binop("-" if sub else "+", a, b, "DINT", E.PREC_ADD, lo, hi)
        return self._fn("HH_SUB" if sub else "HH_ADD", [a, b])

    def _neg(self, a: Expr) -> Expr:
        a = E.to_dint(a)
        if a.const is not None:
            return E.int_const(wrap32(-a.const))
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
        keep_left = self.ctx.semantics["mul_overflow_result"] == "unchanged"
        if a.const is not None and b.const is not None:
            overflow, low = mul_value(a.const, b.const)
            self._flag(flag, E.bool_const(overflow))
            return E.int_const(a.const if overflow and keep_left else low)
        a = self._stable(a)
        b = self._stable(b)
        self._flag(flag, self._fn("HH_MULOVF", [a, b], "BOOL", 0, 1))
        if keep_left:
            # the switch that keeps the accumulator on overflow: the left operand where the product does not fit
            return E.call("SEL", [self._fn("HH_MULOVF", [a, b], "BOOL", 0, 1), self._fn("HH_MUL", [a, b]), a], "DINT")
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
        if b.lo > 0 or b.hi < 0:
            # a divisor whose range excludes 0 (a KFIELD entry without 0, say): no zero check, the marker is reset
            self._flag(flag, E.bool_const(False))
            return self._fn(fn, [a, b])
        return self._divmod_checked(a, b, flag, fn)

    def _divmod_checked(self, a: Expr, b: Expr, flag: int, fn: str) -> Expr:
        """Division or MOD by a divisor known only at run time: WA keeps `a` and the marker is set when it is 0."""
        # Unknown divisor: keep WA and set the marker when it is 0.
        result_var = self.ctx.register("WA")
        if not b.simple or E.base_name(result_var) in b.deps:
            b = self._temp_copy(b)
        self.s.regs["WA"] = None
        self.prepare_write(E.base_name(result_var))
        if a.var is None or a.var.upper() != result_var.upper():
            self.ctx.out.add(S.Assign(result_var, a))
        wa = E.var(result_var, "DINT")
        marker = self.ctx.layout.bit_lvalue(Operand("M", flag))
        self.prepare_write(E.written_name(marker))
        self.ctx.helper(fn)
        nonzero = E.binop("<>", b, E.int_const(0), "BOOL", E.PREC_EQ, 0, 1)
        self.ctx.out.add(S.If(nonzero, (S.Assign(result_var, E.call(fn, [wa, b], "DINT")),
                                        S.Assign(marker.text, E.bool_const(False))),
                              (S.Assign(marker.text, E.bool_const(True)),)))
        return wa

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
        a, b = E.to_dint(a), E.to_dint(b)
        if a.const is not None and b.const is not None:
            return E.int_const(gate_value(kind, a.const, b.const, width))
        fn = {"A": "HH_WAND", "O": "HH_WOR", "X": "HH_WXOR"}[kind]
        return self._fn(fn, [a, b, E.int_const(width)])


def gate_value(kind: str, a: int, b: int, width: int) -> int:
    """What HH_WAND/HH_WOR/HH_WXOR (A/O/X) give for constant arguments: the operand's `width` bits of the word
    accumulator combined, the bits above them kept (AND) or combined with zeros (OR, XOR)."""
    mask = {8: 0xFF, 16: 0xFFFF}.get(width, 0xFFFFFFFF)
    a, u = a & 0xFFFFFFFF, b & mask
    value = {"A": (a & ~mask) | (a & u), "O": a | u, "X": a ^ u}[kind]
    return wrap32(value)


def mul_value(a: int, b: int) -> tuple[bool, int]:
    """What HH_MULOVF and HH_MUL give for constant arguments: whether the product leaves the DINT range, and its
    low 32 bits."""
    product = a * b
    return not E.INT32[0] <= product <= E.INT32[1], wrap32(product)


def shift_value(fn: str, a: int, count: int) -> int:
    """What HH_SHL, HH_SHR (arithmetic), HH_BSET and HH_BCLR give for constant arguments, `count` in 0..31."""
    value = {"HH_SHL": lambda: a << count, "HH_SHR": lambda: a >> count,
             "HH_BSET": lambda: a | (1 << count), "HH_BCLR": lambda: a & ~(1 << count)}[fn]()
    return wrap32(value)


def wrap32(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - 2 ** 32 if v >= 2 ** 31 else v
