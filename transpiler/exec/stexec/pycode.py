"""Pieces the code generator works with: compiled expressions (Ex) and Python precedence, literals, addresses and
storage names, default values, and the context a POU is compiled in. No POU compilation here."""

from __future__ import annotations

import dataclasses
import re
from typing import Any, Callable, Optional

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.model import PouInfo, VarInfo
from transpiler.exec.stexec.rtlib import idiv, imod, wrap_int


# Python operator precedence levels, used to parenthesise only where needed (deep parentheses nesting
# makes CPython's parser fail on long AND/OR chains).
P_COND, P_NOT, P_CMP, P_BOR, P_BXOR, P_BAND, P_ADD, P_MUL, P_UNARY, P_POW, P_ATOM = 1, 4, 5, 6, 7, 8, 10, 11, 12, 13, 14


@dataclasses.dataclass
class Ex:
    """A compiled expression: Python code, its ST type, whether an integer value is already within its type's
    range (+, - and * results are wrapped lazily), and its value when known at compile time."""

    code: str
    ty: T.Type
    prec: int = P_ATOM
    wrapped: bool = True
    const: Any = None
    var: Optional[VarInfo] = None      # the variable an lvalue designates (root variable for fields/elements)
    writable: bool = False
    why_readonly: str = ""
    is_global: bool = False
    folded: bool = False               # a constant computed from several literals (not one literal as written)
    # For folded integer literal arithmetic: recompute the value with every step wrapped to a given type, because
    # literal operations take the type of their context (x + 40000 * 2 is INT arithmetic when x is an INT).
    refold: Optional[Callable[[T.Elem], int]] = None

    def value_in(self, ty: T.Elem) -> Any:
        return self.refold(ty) if self.refold is not None else self.const


ERR_EX = Ex("None", T.ERR)


def paren(ex: Ex, prec: int) -> str:
    return ex.code if ex.prec >= prec else f"({ex.code})"


def py_literal(value: Any) -> tuple[str, int]:
    if isinstance(value, bool):
        return ("True" if value else "False"), P_ATOM
    if isinstance(value, float):
        if value != value:
            return "float('nan')", P_ATOM
        if value in (float("inf"), float("-inf")):
            return ("float('inf')" if value > 0 else "-float('inf')"), (P_ATOM if value > 0 else P_UNARY)
        text = repr(value)
        return text, (P_UNARY if text.startswith("-") else P_ATOM)
    if isinstance(value, int):
        return repr(value), (P_UNARY if value < 0 else P_ATOM)
    return repr(value), P_ATOM


def const_ex(value: Any, ty: T.Type) -> Ex:
    code, prec = py_literal(value)
    return Ex(code, ty, prec, True, value)


def wrap_value(value: int, ty: T.Type) -> int:
    b = T.base(ty)
    return wrap_int(value, b.bits, b.signed)


_TIME_PART = re.compile(r"(\d+(?:\.\d+)?)(ms|us|ns|d|h|m|s)", re.I)


def parse_time_ms(text: str) -> Optional[float]:
    """Milliseconds of the part after `T#` (e.g. 1h2m3s4ms, 1.5s, -5ms); None if malformed."""
    body = text.replace("_", "").lower()
    sign = 1
    if body.startswith(("-", "+")):
        sign = -1 if body[0] == "-" else 1
        body = body[1:]
    if not body:
        return None
    total, pos = 0.0, 0
    scale = {"d": 86400000.0, "h": 3600000.0, "m": 60000.0, "s": 1000.0, "ms": 1.0, "us": 0.001, "ns": 1e-6}
    while pos < len(body):
        m = _TIME_PART.match(body, pos)
        if not m:
            return None
        total += float(m.group(1)) * scale[m.group(2)]
        pos = m.end()
    return sign * total


def decode_string(text: str) -> tuple[Optional[str], str]:
    """Decode an IEC single-quoted string literal; returns (value, error)."""
    body = text[1:-1]
    out, i = [], 0
    simple = {"$": "$", "'": "'", "n": "\n", "r": "\r", "t": "\t", "p": "\f"}
    while i < len(body):
        ch = body[i]
        if ch != "$":
            out.append(ch)
            i += 1
            continue
        nxt = body[i + 1:i + 2]
        if nxt.lower() in simple and nxt:
            out.append(simple[nxt.lower()])
            i += 2
        elif nxt.lower() == "l":
            return None, "the escape '$L' is not supported (matiec generates C that does not compile)"
        elif re.fullmatch(r"[0-9a-fA-F]{2}", body[i + 1:i + 3]):
            out.append(chr(int(body[i + 1:i + 3], 16)))
            i += 3
        else:
            return None, f"invalid escape '${nxt}' in string literal"
    return "".join(out), ""


@dataclasses.dataclass
class Loop:
    kind: str                  # for, while, repeat
    step_code: list[str]       # lines that must run before CONTINUE (FOR increment, REPEAT test)


class Context:
    """What the code generator needs from the project: diagnostics, declarations, naming."""

    def __init__(self, error: Callable[[Span, str], None], loop_limit: int):
        self.error = error
        self.loop_limit = loop_limit
        self.types: dict[str, tuple[T.Type, Optional[n.Init], int]] = {}
        self.pous: dict[str, PouInfo] = {}
        self.globals: dict[str, VarInfo] = {}
        self.enum_values: dict[str, list[tuple[T.EnumT, int]]] = {}
        # address -> (type, attribute); set by the compiler so that code may use %QX0.1 without a declaration
        self.use_address: Optional[Callable[[str, Span], Optional[tuple[T.Type, str]]]] = None
        # the mutations to switch (schema.SchemaPlan) when the file is compiled as a mutant schema
        self.schema: Any = None


_ADDR = re.compile(r"%([IQM])([XBWDL]?)(\d+(?:\.\d+)*)$", re.I)


def normalise_address(text: str) -> Optional[str]:
    """%IX0.1 / %ix0.1 / %I0.1 -> '%IX0.1' (the size prefix X is the default); None if not a full address."""
    m = _ADDR.match(text)
    if not m:
        return None
    size = (m.group(2) or "X").upper()
    return f"%{m.group(1).upper()}{size}{m.group(3)}"


def location_attr(addr: str) -> str:
    """Attribute of the globals object that stores a (normalised) address: one cell per address."""
    return "l_" + addr[1:].lower().replace(".", "_")


def storage_attr(v: VarInfo) -> str:
    return location_attr(v.location) if v.location is not None else "v_" + v.key


def fold_op(op: str, a, b, real: bool):
    """The value of a + - * / MOD on two known operands (integer / and MOD truncate toward zero)."""
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if real:
        return a / b
    return idiv(a, b) if op == "/" else imod(a, b)


def default_code(ty: T.Type) -> str:
    """Python expression that builds the default value of a type."""
    b = T.base(ty)
    if isinstance(b, T.ErrType):
        return "None"
    if isinstance(b, T.ArrayT):
        if T.is_aggregate(b.elem):
            return f"[{default_code(b.elem)} for _ in range({b.size})]"
        return f"[{default_code(b.elem)}] * {b.size}"
    if isinstance(b, T.StructT):
        return f"{b.pyname}()"
    if isinstance(b, T.FbT):
        return f"C_{b.pou.key}()"
    return py_literal(T.default_value(ty))[0]
