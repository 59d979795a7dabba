"""State of one POU's compilation (emitted lines, temporaries, loops) and the helpers every part uses; and
PouCompilerApi, what the call compiler (stdlib) needs of a POU compiler."""

from __future__ import annotations

import dataclasses
from typing import Optional, Protocol

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.model import PouInfo, VarInfo
from transpiler.exec.stexec.pycode import (ERR_EX, P_ADD, P_BAND, Context, Ex, Loop, const_ex, paren, py_literal,
                                           storage_attr, wrap_value)
from transpiler.exec.stexec.rtlib import f32


class PouBase:
    """Compiles one POU body (or stand-alone initialisers when pou is None): state and shared helpers."""

    def __init__(self, ctx: Context, pou: Optional[PouInfo], ordinal: int):
        self.ctx = ctx
        self.pou = pou
        self.ordinal = ordinal
        self.lines: list[tuple[int, str, Optional[Span]]] = []
        self.indent = 1
        self.pre: list[str] = []
        self.temp_counter = 0
        self.loops: list[Loop] = []
        self.cur_span: Optional[Span] = None
        self.is_function = pou is not None and pou.kind == "function"

    def err(self, span: Span, msg: str) -> Ex:
        self.ctx.error(span, msg)
        return ERR_EX

    def temp(self, prefix: str = "_t") -> str:
        self.temp_counter += 1
        return f"{prefix}{self.temp_counter}"

    def emit(self, line: str, span: Optional[Span] = None) -> None:
        self.lines.append((self.indent, line, span or self.cur_span))

    def flush_pre(self) -> None:
        for line in self.pre:
            self.emit(line)
        self.pre = []

    def wrap(self, ex: Ex, ty: Optional[T.Type] = None) -> Ex:
        """Bring an integer value into its type's range (two's complement wrap-around)."""
        ty = ty or ex.ty
        b = T.base(ty)
        if ex.wrapped and ty is ex.ty or not isinstance(b, T.Elem) or b.cat not in ("int", "bit"):
            return dataclasses.replace(ex, ty=ty) if ty is not ex.ty and not isinstance(ty, T.ErrType) else ex
        if ex.const is not None:
            return const_ex(wrap_value(int(ex.const), b), ty)
        if b.signed:
            off = 1 << (b.bits - 1)
            return Ex(f"({paren(ex, P_ADD)} + {off} & {b.mask}) - {off}", ty, P_ADD)
        return Ex(f"{paren(ex, P_BAND)} & {b.mask}", ty, P_BAND)

    def val(self, ex: Ex) -> Ex:
        """The expression with an exact (in-range) value, as comparisons, division and calls need."""
        if ex.wrapped or isinstance(ex.ty, T.LitType):
            return ex
        return self.wrap(ex)

    @staticmethod
    def real_round(value: float, ty: T.Type) -> float:
        return f32(value) if T.base(ty) is T.REAL else value

    def var_code(self, v: VarInfo) -> str:
        if v.constant and v.const_value is not None:
            return py_literal(v.const_value)[0]
        if v.kind == "global" or v.location is not None:
            return f"G.{storage_attr(v)}"
        if v.kind == "external":
            g = self.ctx.globals.get(v.key)
            return f"G.{storage_attr(g)}" if g is not None else "None"
        if self.is_function or v.kind == "temp":
            return f"v_{v.key}"
        return f"self.v_{v.key}"

    def lookup(self, name: str) -> Optional[VarInfo]:
        if self.pou is None:
            return None
        return self.pou.vars.get(name.lower())

    @staticmethod
    def copy_code(ty: T.Type, code: str) -> str:
        """Python expression that makes an independent copy of an aggregate value."""
        b = T.base(ty)
        if isinstance(b, T.ArrayT):
            if T.is_aggregate(b.elem):
                return f"[_e._copy() for _e in {code}]"
            return f"{code}[:]"
        if isinstance(b, T.StructT):
            return f"{code}._copy()"
        return code

    def assign_lines(self, target: Ex, value: Ex) -> list[str]:
        b = T.base(target.ty)
        if isinstance(b, T.ArrayT):
            if T.is_aggregate(b.elem):
                return [f"_aset({target.code}, {value.code})"]
            return [f"{target.code}[:] = {value.code}"]
        if isinstance(b, T.StructT):
            return [f"{target.code}._set({value.code})"]
        return [f"{target.code} = {value.code}"]


class PouCompilerApi(Protocol):
    """The part of a POU compiler that the call compiler uses (implemented by codegen.PouCompiler)."""

    ctx: Context
    pou: Optional[PouInfo]
    ordinal: int
    pre: list[str]

    def err(self, span: Span, msg: str) -> Ex: ...
    def temp(self, prefix: str = "_t") -> str: ...
    def emit(self, line: str, span: Optional[Span] = None) -> None: ...
    def flush_pre(self) -> None: ...
    def wrap(self, ex: Ex, ty: Optional[T.Type] = None) -> Ex: ...
    def val(self, ex: Ex) -> Ex: ...
    def lookup(self, name: str) -> Optional[VarInfo]: ...
    def copy_code(self, ty: T.Type, code: str) -> str: ...
    def assign_lines(self, target: Ex, value: Ex) -> list[str]: ...
    def expr(self, node: n.Expr, allow_fb: bool = False) -> Ex: ...
    def var_ex(self, v: VarInfo) -> Ex: ...
    def lvalue(self, node: n.Expr) -> Ex: ...
    def coerce(self, ex: Ex, ty: T.Type, span: Span, what: str, report: bool = True) -> Optional[Ex]: ...
    def arith(self, op: str, l: Ex, r: Ex, span: Span) -> Ex: ...
    def compare(self, op: str, l: Ex, r: Ex, span: Span) -> Ex: ...
    def power(self, l: Ex, r: Ex, span: Span) -> Ex: ...
    def init_code(self, ty: T.Type, init: Optional[n.Init], span: Span) -> str: ...
