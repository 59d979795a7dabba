"""Operators: NOT and unary minus, logic, comparison, arithmetic (with literal folding), ** and TIME arithmetic."""

from __future__ import annotations

import dataclasses
from typing import Optional

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.errors import Trap
from transpiler.exec.stexec.pou_base import PouBase
from transpiler.exec.stexec.pycode import (ERR_EX, P_ADD, P_ATOM, P_BAND, P_BOR, P_BXOR, P_CMP, P_MUL, P_NOT, P_UNARY,
                                           Ex, const_ex, fold_op, paren, wrap_value)


class OperatorCompiler(PouBase):
    """Operators: NOT and unary minus, logic, comparison, arithmetic (with literal folding), ** and TIME arithmetic."""

    def unary(self, node: n.Unary) -> Ex:
        x = self.expr(node.operand)
        if x.ty is T.ERR:
            return ERR_EX
        b = T.base(x.ty)
        if node.op == "NOT":
            if b is T.BOOL:
                if x.const is not None:
                    return const_ex(not x.const, x.ty)
                return Ex(f"not {paren(x, P_NOT)}", x.ty, P_NOT)
            if T.is_bit(x.ty):
                x = self.val(x)
                if x.const is not None:
                    return const_ex(x.const ^ b.mask, x.ty)
                return Ex(f"{paren(x, P_BXOR + 1)} ^ {b.mask}", x.ty, P_BXOR)
            if isinstance(x.ty, T.LitType):
                return self.err(node.span, "NOT of an untyped literal: write a typed literal such as WORD#16#00FF")
            return self.err(node.span, f"invalid data type {x.ty} for 'NOT' (only BOOL and bit strings)")
        # unary minus
        if x.const is not None and (isinstance(x.ty, T.LitType) or b.cat in ("real", "time")):
            refold = (lambda t, x=x: wrap_value(-x.value_in(t), t)) if x.refold is not None else None
            return dataclasses.replace(const_ex(-x.const, x.ty), folded=x.folded, refold=refold)
        if isinstance(x.ty, T.LitType) or (isinstance(b, T.Elem) and b.cat in ("int", "real", "time")):
            wrapped = not (isinstance(b, T.Elem) and b.cat == "int")
            return Ex(f"-{paren(x, P_UNARY)}", x.ty, P_UNARY, wrapped)
        return self.err(node.span, f"invalid data type {x.ty} for unary '-'")

    def unify(self, l: Ex, r: Ex, opname: str, span: Span) -> Optional[tuple[Ex, Ex, T.Type]]:
        """Give both operands one type: an untyped literal adapts to the other side, otherwise types must match."""
        lt, rt = isinstance(l.ty, T.LitType), isinstance(r.ty, T.LitType)
        if lt and rt:
            if l.ty is not r.ty:
                self.err(span, f"data type mismatch for '{opname}': {l.ty} and {r.ty}")
                return None
            return l, r, l.ty
        if lt:
            l2 = self.coerce(l, r.ty, span, f"'{opname}' expression", report=False)
            if l2 is None:
                self.err(span, f"data type mismatch for '{opname}': {l.ty} literal and {r.ty}")
                return None
            return l2, r, r.ty
        if rt:
            r2 = self.coerce(r, l.ty, span, f"'{opname}' expression", report=False)
            if r2 is None:
                self.err(span, f"data type mismatch for '{opname}': {l.ty} and {r.ty} literal")
                return None
            return l, r2, l.ty
        if not T.same(l.ty, r.ty):
            self.err(span, f"data type mismatch for '{opname}': {l.ty} and {r.ty} (convert explicitly, "
                           "e.g. INT_TO_DINT)")
            return None
        return l, r, T.base(l.ty)

    def binary(self, node: n.Binary) -> Ex:
        l = self.expr(node.left)
        r = self.expr(node.right)
        if l.ty is T.ERR or r.ty is T.ERR:
            return ERR_EX
        op = node.op
        if op in ("AND", "OR", "XOR"):
            return self.logic(op, l, r, node.span)
        if op in ("=", "<>", "<", ">", "<=", ">="):
            return self.compare(op, l, r, node.span)
        if op == "**":
            return self.power(l, r, node.span)
        return self.arith(op, l, r, node.span)

    def logic(self, op: str, l: Ex, r: Ex, span: Span) -> Ex:
        u = self.unify(l, r, op, span)
        if u is None:
            return ERR_EX
        l, r, ty = u
        b = T.base(ty)
        pyop, prec = {"AND": ("&", P_BAND), "OR": ("|", P_BOR), "XOR": ("^", P_BXOR)}[op]
        if not (b is T.BOOL or T.is_bit(b) or (isinstance(b, T.LitType) and b.cat == "int")):
            return self.err(span, f"data type mismatch for '{op}': {ty} (only BOOL and bit strings; "
                                  "convert integers with e.g. INT_TO_WORD)")
        l, r = self.val(l), self.val(r)
        if l.const is not None and r.const is not None:
            value = {"&": l.const & r.const, "|": l.const | r.const, "^": l.const ^ r.const}[pyop]
            return const_ex(bool(value) if b is T.BOOL else value, ty)
        return Ex(f"{paren(l, prec)} {pyop} {paren(r, prec + 1)}", ty, prec)

    def compare(self, op: str, l: Ex, r: Ex, span: Span) -> Ex:
        u = self.unify(l, r, op, span)
        if u is None:
            return ERR_EX
        l, r, ty = u
        b = T.base(ty)
        if not isinstance(b, (T.Elem, T.LitType, T.EnumT)):
            return self.err(span, f"'{op}' cannot compare values of type {ty}")
        l, r = self.val(l), self.val(r)
        pyop = {"=": "==", "<>": "!="}.get(op, op)
        if l.const is not None and r.const is not None:
            return const_ex(bool(eval(f"{l.const!r} {pyop} {r.const!r}")), T.BOOL)  # noqa: S307 - literals only
        return Ex(f"{paren(l, P_CMP + 1)} {pyop} {paren(r, P_CMP + 1)}", T.BOOL, P_CMP)

    def power(self, l: Ex, r: Ex, span: Span) -> Ex:
        lb, rb = T.base(l.ty), T.base(r.ty)
        l_real = (isinstance(lb, T.Elem) and lb.cat == "real") or lb is T.ANY_REAL_LIT
        r_num = (isinstance(rb, T.Elem) and rb.cat in ("int", "real")) or isinstance(rb, T.LitType)
        if not (l_real and r_num):
            return self.err(span, f"'**' needs a REAL or LREAL base and a numeric exponent, not {l.ty} ** {r.ty} "
                                  "(matiec rejects ** on integers; use EXPT or multiply)")
        ty = l.ty
        if isinstance(ty, T.LitType) and isinstance(rb, T.Elem) and rb.cat == "real":
            ty = r.ty
        code = f"_fpow({self.val(l).code}, {self.val(r).code})"
        if T.base(ty) is T.REAL:
            code = f"_f32({code})"
        return Ex(code, ty, P_ATOM)

    def arith(self, op: str, l: Ex, r: Ex, span: Span) -> Ex:
        lb = T.base(l.ty)
        if lb is T.TIME or (T.base(r.ty) is T.TIME and op in ("+", "-")):
            return self.time_arith(op, l, r, span)
        u = self.unify(l, r, op, span)
        if u is None:
            return ERR_EX
        l, r, ty = u
        b = T.base(ty)
        cat = b.cat if isinstance(b, (T.Elem, T.LitType)) else ""
        if cat == "bit":
            return self.err(span, f"data type mismatch for '{op}': arithmetic on bit string {ty} (convert first, "
                                  "e.g. UINT_TO_WORD(WORD_TO_UINT(w) + 1))")
        if cat not in ("int", "real"):
            return self.err(span, f"data type mismatch for '{op}': {ty} is not a number")
        if op == "MOD" and cat != "int":
            return self.err(span, f"MOD needs integer operands, not {ty}")
        if isinstance(b, T.LitType) and l.const is not None and r.const is not None:
            return self.fold_arith(op, l, r, ty, span)
        if cat == "int":
            if op in ("+", "-", "*"):
                prec = P_ADD if op != "*" else P_MUL
                return Ex(f"{paren(l, prec)} {op} {paren(r, prec + 1)}", ty, prec, isinstance(b, T.LitType))
            l, r = self.val(l), self.val(r)
            if op == "/":
                if r.const == 0:
                    return self.err(span, "division by zero")
                return Ex(f"_idiv({l.code}, {r.code})", ty, P_ATOM, isinstance(b, T.LitType) or not b.signed)
            if r.const == 0:
                return self.err(span, "MOD by zero")
            return Ex(f"_imod({l.code}, {r.code})", ty, P_ATOM)
        if op == "/":
            code = f"_fdiv({l.code}, {r.code})"
            prec = P_ATOM
        else:
            prec = P_ADD if op != "*" else P_MUL
            code = f"{paren(l, prec)} {op} {paren(r, prec + 1)}"
        if b is T.REAL:
            return Ex(f"_f32({code})", ty, P_ATOM)
        return Ex(code, ty, prec)

    def fold_arith(self, op: str, l: Ex, r: Ex, ty: T.Type, span: Span) -> Ex:
        if op in ("/", "MOD") and r.const == 0:
            return self.err(span, "division by zero" if op == "/" else "MOD by zero")
        value = fold_op(op, l.const, r.const, ty.cat == "real")
        if ty.cat != "int":
            return dataclasses.replace(const_ex(value, ty), folded=True)

        def refold(t: T.Elem) -> int:
            rv = r.value_in(t)
            if op in ("/", "MOD") and rv == 0:
                raise Trap("division by zero")
            return wrap_value(fold_op(op, l.value_in(t), rv, False), t)
        return dataclasses.replace(const_ex(value, ty), folded=True, refold=refold)

    def time_arith(self, op: str, l: Ex, r: Ex, span: Span) -> Ex:
        lb, rb = T.base(l.ty), T.base(r.ty)
        if op in ("+", "-"):
            if lb is not T.TIME or rb is not T.TIME:
                return self.err(span, f"data type mismatch for '{op}': {l.ty} and {r.ty}")
            if l.const is not None and r.const is not None:
                return const_ex(l.const + r.const if op == "+" else l.const - r.const, T.TIME)
            return Ex(f"{paren(l, P_ADD)} {op} {paren(r, P_ADD + 1)}", T.TIME, P_ADD)
        if op in ("*", "/") and lb is T.TIME:
            if not ((isinstance(rb, T.Elem) and rb.cat in ("int", "real")) or isinstance(rb, T.LitType)):
                return self.err(span, f"data type mismatch for '{op}': TIME and {r.ty}")
            r = self.val(r)
            fn = "_time_mul" if op == "*" else "_time_div"
            return Ex(f"{fn}({l.code}, {r.code})", T.TIME, P_ATOM)
        return self.err(span, f"data type mismatch for '{op}': {l.ty} and {r.ty}")
