"""Literals and how a value takes a type: typed literals, untyped literals adapting to their context,
and the no-implicit-conversion rule of assignments and parameters."""

from __future__ import annotations

import dataclasses
import re
from typing import Optional

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.pou_base import PouBase
from transpiler.exec.stexec.pycode import ERR_EX, Ex, const_ex, decode_string, parse_time_ms


class ValueCompiler(PouBase):
    """Literals, and coercion of a value to the type its context expects."""

    def literal(self, node: n.Lit) -> Ex:
        text = node.text
        if node.kind == "int":
            return const_ex(int(text.replace("_", "")), T.ANY_INT_LIT)
        if node.kind == "based":
            base_s, digits = text.split("#", 1)
            try:
                return const_ex(int(digits.replace("_", ""), int(base_s)), T.ANY_INT_LIT)
            except ValueError:
                return self.err(node.span, f"invalid literal '{text}'")
        if node.kind == "real":
            return const_ex(float(text.replace("_", "")), T.ANY_REAL_LIT)
        if node.kind == "string":
            value, problem = decode_string(text)
            if value is None:
                return self.err(node.span, problem)
            if len(value) > T.STR_MAX:
                return self.err(node.span, f"string literal of {len(value)} characters; at most {T.STR_MAX} "
                                           "fit a STRING (matiec does not check this and corrupts memory)")
            return const_ex(value, T.STRING)
        return self.typed_literal(text, node.span)

    def typed_literal(self, text: str, span: Span) -> Ex:
        prefix, rest = text.split("#", 1)
        key = prefix.lower()
        if key in ("t", "time"):
            ms = parse_time_ms(rest)
            if ms is None:
                return self.err(span, f"invalid TIME literal '{text}'")
            if ms != int(ms):
                return self.err(span, f"TIME literal '{text}' is not a whole number of milliseconds; the built-in "
                                      "executor keeps TIME in milliseconds")
            return const_ex(int(ms), T.TIME)
        if key in ("d", "date", "tod", "time_of_day", "dt", "date_and_time", "ltime", "lt"):
            return self.err(span, f"{prefix.upper()} literals are not supported by the built-in executor")
        ty = T.ELEMENTARY.get(key)
        if ty is None:
            entry = self.ctx.types.get(key)
            if entry is not None and entry[2] < self.ordinal:
                ety = entry[0]
                if isinstance(ety, T.EnumT):
                    idx = ety.index(rest)
                    if idx is None:
                        return self.err(span, f"'{rest}' is not a value of enum {ety.name}")
                    return const_ex(idx, ety)
                if isinstance(T.base(ety), T.Elem):
                    inner = self.typed_literal(f"{T.base(ety).name}#{rest}", span)
                    return dataclasses.replace(inner, ty=ety) if inner.ty is not T.ERR else inner
            return self.err(span, f"unknown type '{prefix}' in literal '{text}'")
        if ty is T.BOOL:
            low = rest.lower()
            if low in ("1", "true"):
                return const_ex(True, T.BOOL)
            if low in ("0", "false"):
                return const_ex(False, T.BOOL)
            return self.err(span, f"invalid BOOL literal '{text}'")
        if ty.cat == "real":
            try:
                value = float(rest.replace("_", ""))
            except ValueError:
                return self.err(span, f"invalid {ty.name} literal '{text}'")
            return const_ex(self.real_round(value, ty), ty)
        if ty.cat in ("int", "bit"):
            m = re.fullmatch(r"([+-]?)(?:(2|8|16)#([0-9a-fA-F_]+)|([0-9][0-9_]*))", rest)
            if not m:
                return self.err(span, f"invalid {ty.name} literal '{text}'")
            value = int(m.group(3).replace("_", ""), int(m.group(2))) if m.group(2) else int(m.group(4).replace("_", ""))
            if m.group(1) == "-":
                value = -value
            if not ty.lo <= value <= ty.hi:
                return self.err(span, f"literal '{text}' does not fit {ty.name} ({ty.lo}..{ty.hi})")
            return const_ex(value, ty)
        return self.err(span, f"typed literals of {ty.name} are not supported")

    def coerce(self, ex: Ex, ty: T.Type, span: Span, what: str, report: bool = True) -> Optional[Ex]:
        """The expression as a value of type ty (literals adapt; otherwise the types must be the same)."""
        if ex.ty is T.ERR or ty is T.ERR:
            return ex
        b = T.base(ty)
        if isinstance(ex.ty, T.LitType):
            out = self.adapt_literal(ex, ty, span, report)
            if out is not None or not report:
                return out
            return ERR_EX
        if T.same(ex.ty, ty):
            if isinstance(b, T.Elem) and b.cat in ("int", "bit"):
                ex = self.wrap(ex, ty)
            if isinstance(ty, T.SubrangeT) and ex.const is not None and not ty.lo <= ex.const <= ty.hi:
                if report:
                    self.err(span, f"value {ex.const} outside the subrange {ty.lo}..{ty.hi} of {ty}")
                return ERR_EX if report else None
            return ex
        if report:
            self.err(span, f"incompatible data types in {what}: {ex.ty} where {ty} is expected "
                           "(IEC has no implicit conversion; use e.g. INT_TO_DINT)")
            return ERR_EX
        return None

    def adapt_literal(self, ex: Ex, ty: T.Type, span: Span, report: bool) -> Optional[Ex]:
        b = T.base(ty)
        cat = ex.ty.cat
        if not isinstance(b, T.Elem):
            if report:
                self.err(span, f"a {ex.ty} literal cannot be a {ty}")
            return None
        if cat == "int" and b.cat in ("int", "bit"):
            if ex.const is None:
                return self.wrap(dataclasses.replace(ex, wrapped=False), ty)
            lo, hi = (ty.lo, ty.hi) if isinstance(ty, T.SubrangeT) else (b.lo, b.hi)
            if ex.folded and not isinstance(ty, T.SubrangeT):
                # literal arithmetic happens in the context's type, so it wraps like any other operation
                try:
                    return const_ex(ex.value_in(b), ty)
                except Exception:   # noqa: BLE001 - a division by zero that only the wrapped arithmetic reveals
                    if report:
                        self.err(span, "division by zero in a constant expression")
                    return None
            if not lo <= ex.const <= hi:
                if report:
                    self.err(span, f"literal {ex.const} does not fit {ty} ({lo}..{hi})")
                return None
            return const_ex(ex.const, ty)
        if cat == "int" and b is T.BOOL and ex.const in (0, 1):
            return const_ex(bool(ex.const), ty)
        if cat == "real" and b.cat == "real":
            if ex.const is None:
                return Ex(f"_f32({ex.code})", ty) if b is T.REAL else dataclasses.replace(ex, ty=ty)
            return const_ex(self.real_round(ex.const, b), ty)
        if report:
            extra = " (write 2.0 for a REAL)" if cat == "int" and b.cat == "real" else ""
            self.err(span, f"incompatible data types: {ex.ty} literal where {ty} is expected{extra}")
        return None
