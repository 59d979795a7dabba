"""Type-checks the statements and expressions of one POU and translates them into Python source lines."""

from __future__ import annotations

import dataclasses
import re
from typing import Any, Callable, Optional

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.errors import Trap
from transpiler.exec.stexec.model import PouInfo, VarInfo
from transpiler.exec.stexec.rtlib import f32, idiv, imod, wrap_int

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


class PouCompiler:
    """Compiles one POU body (or stand-alone initialisers when pou is None)."""

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

    # ================================================================ helpers
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

    # ================================================================ literals
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

    @staticmethod
    def real_round(value: float, ty: T.Type) -> float:
        return f32(value) if T.base(ty) is T.REAL else value

    # ================================================================ names and variables
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

    def name_ex(self, node: n.Name) -> Ex:
        key = node.name.lower()
        v = self.lookup(key)
        if v is not None:
            return self.var_ex(v)
        if key in ("true", "false"):
            return const_ex(key == "true", T.BOOL)
        if self.pou is not None and self.pou.prelude and key == "__current_time":
            return Ex("G.now", T.TIME)
        enums = self.ctx.enum_values.get(key, [])
        enums = [(e, i) for e, i in enums if self.ctx.types[e.name.lower()][2] < self.ordinal]
        if len(enums) == 1:
            return const_ex(enums[0][1], enums[0][0])
        if len(enums) > 1:
            return self.err(node.span, f"enum value '{node.name}' is ambiguous; write Type#{node.name}")
        if key in self.ctx.globals:
            return self.err(node.span, f"'{node.name}' is a global variable; declare it in a VAR_EXTERNAL block "
                                       "to use it here")
        return self.err(node.span, f"undeclared variable '{node.name}'")

    def var_ex(self, v: VarInfo) -> Ex:
        const = v.const_value if v.constant else None
        code = self.var_code(v)
        prec = P_UNARY if code.startswith("-") else P_ATOM
        writable, why = True, ""
        if v.constant:
            writable, why = False, f"'{v.name}' is a CONSTANT"
        elif isinstance(v.ty, T.FbT):
            writable, why = False, f"'{v.name}' is a function block instance"
        is_global = v.kind == "external"
        return Ex(code, v.ty, prec, True, const, v, writable, why, is_global)

    def addr_ex(self, node: n.Addr) -> Ex:
        addr = normalise_address(node.address)
        if addr is None:
            return self.err(node.span, f"invalid address '{node.address}'")
        if self.pou is not None:
            for v in self.pou.vars.values():
                if v.location == addr:
                    return self.var_ex(v)
        if self.pou is None or self.pou.kind != "program" or self.ctx.use_address is None:
            return self.err(node.span, f"directly represented variable {addr} outside a PROGRAM")
        found = self.ctx.use_address(addr, node.span)
        if found is None:
            return ERR_EX
        ty, attr = found
        return Ex(f"G.{attr}", ty, P_ATOM, True, None, None, True)

    def field_ex(self, node: n.Field) -> Ex:
        base_ex = self.expr(node.base, allow_fb=True)
        if base_ex.ty is T.ERR:
            return ERR_EX
        key = node.name.lower()
        bty = T.base(base_ex.ty)
        if isinstance(bty, T.StructT):
            f = bty.fields.get(key)
            if f is None:
                return self.err(node.span, f"struct {bty.name} has no field '{node.name}'")
            return Ex(f"{paren(base_ex, P_ATOM)}.v_{key}", f.ty, P_ATOM, True, None, base_ex.var,
                      base_ex.writable, base_ex.why_readonly, base_ex.is_global)
        if isinstance(bty, T.FbT):
            fv = bty.pou.vars.get(key)
            if fv is None or fv.kind in ("external", "temp") or fv.location is not None:
                return self.err(node.span, f"function block {bty.name} has no parameter '{node.name}'")
            writable, why = base_ex.writable or isinstance(base_ex.ty, T.FbT), ""
            if fv.kind == "output":
                writable, why = False, f"'{node.name}' is an output of {bty.name} (only the FB writes it)"
            elif fv.kind == "var":
                writable, why = False, f"'{node.name}' is a private variable of {bty.name}"
            return Ex(f"{paren(base_ex, P_ATOM)}.v_{key}", fv.ty, P_ATOM, True, None, base_ex.var,
                      writable, why, base_ex.is_global)
        return self.err(node.span, f"'.{node.name}' applied to a value of type {base_ex.ty}, which has no fields "
                                   "(bit access w.n is not supported by matiec; use SHR and AND)")

    def index_ex(self, node: n.Index) -> Ex:
        base_ex = self.expr(node.base)
        if base_ex.ty is T.ERR:
            return ERR_EX
        aty = T.base(base_ex.ty)
        if not isinstance(aty, T.ArrayT):
            return self.err(node.span, f"index applied to a value of type {base_ex.ty}, which is not an array")
        if len(node.indices) != len(aty.dims):
            return self.err(node.span, f"array {aty.name} has {len(aty.dims)} dimension(s), "
                                       f"{len(node.indices)} index(es) given")
        parts, checks, temps, consts = [], [], [], []
        strides = aty.strides()
        for idx_node, (lo, hi), stride in zip(node.indices, aty.dims, strides):
            ix = self.expr(idx_node)
            if ix.ty is T.ERR:
                return ERR_EX
            if not (T.is_int(ix.ty) or (isinstance(ix.ty, T.LitType) and ix.ty.cat == "int")):
                return self.err(idx_node.span, f"array index must be an integer (INT, DINT, ...), not {ix.ty}")
            ix = self.val(ix)
            if ix.const is not None:
                if not lo <= ix.const <= hi:
                    return self.err(idx_node.span, f"array index {ix.const} outside {lo}..{hi}")
                consts.append((ix.const - lo) * stride)
                temps.append(str(ix.const))
                continue
            t = self.temp("_i")
            checks.append(f"{lo} <= ({t} := {ix.code}) <= {hi}")
            term = f"{t} - {lo}" if lo else t
            parts.append(f"({term}) * {stride}" if stride != 1 else term)
            temps.append(t)
        offset = sum(consts)
        if offset or not parts:
            parts.append(str(offset))
        flat = " + ".join(parts)
        if checks:
            cond = " and ".join(checks) if len(checks) == 1 else " & ".join(f"({c})" for c in checks)
            dims = repr(aty.dims)
            flat = f"{flat} if {cond} else _oob(({', '.join(temps)},), {dims})"
        return Ex(f"{paren(base_ex, P_ATOM)}[{flat}]", aty.elem, P_ATOM, True, None, base_ex.var,
                  base_ex.writable, base_ex.why_readonly, base_ex.is_global)

    # ================================================================ expressions
    def expr(self, node: n.Expr, allow_fb: bool = False) -> Ex:
        if isinstance(node, n.Lit):
            return self.literal(node)
        if isinstance(node, n.Name):
            ex = self.name_ex(node)
        elif isinstance(node, n.Addr):
            ex = self.addr_ex(node)
        elif isinstance(node, n.Field):
            ex = self.field_ex(node)
        elif isinstance(node, n.Index):
            ex = self.index_ex(node)
        elif isinstance(node, n.Call):
            from transpiler.exec.stexec.stdlib import compile_call
            return compile_call(self, node)
        elif isinstance(node, n.Unary):
            return self.unary(node)
        elif isinstance(node, n.Binary):
            return self.binary(node)
        else:
            return self.err(self.cur_span, f"unsupported expression {type(node).__name__}")
        if isinstance(ex.ty, T.FbT) and not allow_fb:
            return self.err(node.span, f"function block instance '{ex.var.name if ex.var else '?'}' used as a value")
        return ex

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
        value = _apply(op, l.const, r.const, ty.cat == "real")
        if ty.cat != "int":
            return dataclasses.replace(const_ex(value, ty), folded=True)

        def refold(t: T.Elem) -> int:
            rv = r.value_in(t)
            if op in ("/", "MOD") and rv == 0:
                raise Trap("division by zero")
            return wrap_value(_apply(op, l.value_in(t), rv, False), t)
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

    # ================================================================ coercion
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

    # ================================================================ lvalues and copies
    def lvalue(self, node: n.Expr) -> Ex:
        if not isinstance(node, (n.Name, n.Addr, n.Field, n.Index)):
            return self.err(node.span, "assignment to an expression or a literal value is not allowed")
        ex = self.expr(node, allow_fb=True)
        if ex.ty is T.ERR:
            return ex
        if isinstance(node, n.Name) and ex.var is None:
            return self.err(node.span, f"'{node.name}' cannot be assigned")
        if not ex.writable:
            return self.err(node.span, f"assignment not allowed: {ex.why_readonly}")
        if isinstance(ex.ty, T.FbT):
            return self.err(node.span, "a function block instance cannot be assigned")
        return ex

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

    # ================================================================ statements
    def stmts(self, body: list[n.Stmt]) -> None:
        start = len(self.lines)
        for s in body:
            self.stmt(s)
        if len(self.lines) == start:
            self.emit("pass")

    def stmt(self, s: n.Stmt) -> None:
        self.cur_span = s.span
        self.pre = []
        handler = getattr(self, "s_" + type(s).__name__.lower())
        handler(s)

    def cond(self, node: n.Expr, what: str) -> Ex:
        ex = self.expr(node)
        if ex.ty is not T.ERR and T.base(ex.ty) is not T.BOOL:
            return self.err(node.span, f"{what} must be BOOL, not {ex.ty}")
        return ex

    def s_assign(self, s: n.Assign) -> None:
        value = self.expr(s.value)
        target = self.lvalue(s.target)
        if value.ty is T.ERR or target.ty is T.ERR:
            return
        value = self.coerce(value, target.ty, s.value.span, "assignment")
        if value.ty is T.ERR:
            return
        self.flush_pre()
        for line in self.assign_lines(target, value):
            self.emit(line)

    def s_callstmt(self, s: n.CallStmt) -> None:
        from transpiler.exec.stexec.stdlib import compile_call_stmt
        compile_call_stmt(self, s)

    def s_if(self, s: n.If) -> None:
        first = True
        opened = 0
        for cond_node, body in s.branches:
            self.cur_span = cond_node.span
            self.pre = []
            c = self.cond(cond_node, "IF condition")
            if first:
                self.flush_pre()
                self.emit(f"if {c.code}:")
                first = False
            elif self.pre:
                # A call with outputs inside an ELSIF condition must run only when the ELSIF is reached.
                self.emit("else:")
                self.indent += 1
                opened += 1
                self.flush_pre()
                self.emit(f"if {c.code}:")
            else:
                self.emit(f"elif {c.code}:")
            self.indent += 1
            self.stmts(body)
            self.indent -= 1
        if s.orelse is not None:
            self.emit("else:", s.span)
            self.indent += 1
            self.stmts(s.orelse)
            self.indent -= 1
        self.indent -= opened

    def s_case(self, s: n.Case) -> None:
        sel = self.expr(s.selector)
        if sel.ty is T.ERR:
            return
        sty = T.base(sel.ty)
        is_enum = isinstance(sty, T.EnumT)
        if not (is_enum or T.is_int(sty) or (isinstance(sty, T.LitType) and sty.cat == "int")):
            self.err(s.selector.span, f"'CASE' selector must be an integer or an enumerated value, not {sel.ty} "
                                      "(convert a BYTE/WORD first, e.g. BYTE_TO_INT)")
            return
        sel = self.val(sel)
        var = self.temp("_c")
        self.flush_pre()
        self.emit(f"{var} = {sel.code}")
        kw = "if"
        for labels, body in s.elems:
            conds = []
            singles = []
            for lab in labels:
                rng = self.case_label(lab, sel.ty, is_enum)
                if rng is None:
                    continue
                # Overlapping labels are legal for matiec (a warning only); like its if/else-if chain, the first
                # matching branch wins.
                lo, hi = rng
                if lo == hi:
                    singles.append(lo)
                else:
                    conds.append(f"{lo} <= {var} <= {hi}")
            if len(singles) == 1:
                conds.insert(0, f"{var} == {singles[0]}")
            elif singles:
                conds.insert(0, f"{var} in {tuple(singles)!r}")
            self.emit(f"{kw} {' or '.join(conds) or 'False'}:", labels[0].span if labels else s.span)
            kw = "elif"
            self.indent += 1
            self.stmts(body)
            self.indent -= 1
        if s.orelse is not None:
            self.emit("else:" if kw == "elif" else "if True:", s.span)
            self.indent += 1
            self.stmts(s.orelse)
            self.indent -= 1

    def case_label(self, lab: n.CaseLabel, sty: T.Type, is_enum: bool) -> Optional[tuple[int, int]]:
        b = T.base(sty)
        if lab.enum is not None:
            text = lab.enum
            if "#" in text:
                prefix, value = text.split("#", 1)
                if not is_enum or prefix.lower() != b.name.lower():
                    self.err(lab.span, f"CASE label '{text}': labels must be plain decimal integers or values of "
                                       "the selector's enum (matiec rejects typed and based labels)")
                    return None
            else:
                value = text
            if not is_enum:
                self.err(lab.span, f"CASE label '{text}' is not an integer (selector is {sty})")
                return None
            idx = b.index(value)
            if idx is None:
                self.err(lab.span, f"'{value}' is not a value of enum {b.name}")
                return None
            return idx, idx
        if is_enum:
            self.err(lab.span, f"integer CASE label for an enum selector ({b.name})")
            return None
        lo, hi = lab.lo, lab.hi
        if lo > hi:
            self.err(lab.span, f"empty CASE range {lo}..{hi}")
            return None
        if isinstance(b, T.Elem) and not (b.lo <= lo and hi <= b.hi):
            self.err(lab.span, f"CASE label {lo if lo == hi else f'{lo}..{hi}'} does not fit the selector type {b}")
            return None
        return lo, hi

    def loop_guard_open(self) -> None:
        self.emit("for _ in _LOOP_RANGE:")

    def loop_guard_close(self, span: Span) -> None:
        self.emit("else:", span)
        self.indent += 1
        self.emit(f"_loop_trap({self.ctx.loop_limit})", span)
        self.indent -= 1

    def s_while(self, s: n.While) -> None:
        c = self.cond(s.cond, "WHILE condition")
        pre, self.pre = self.pre, []
        self.loop_guard_open()
        self.indent += 1
        for line in pre:
            self.emit(line)
        self.emit(f"if not {paren(c, P_NOT)}:")
        self.indent += 1
        self.emit("break")
        self.indent -= 1
        self.loops.append(Loop("while", []))
        self.stmts(s.body)
        self.loops.pop()
        self.indent -= 1
        self.loop_guard_close(s.span)

    def s_repeat(self, s: n.Repeat) -> None:
        saved = self.cur_span
        self.cur_span = s.cond.span
        c = self.cond(s.cond, "UNTIL condition")
        test = self.pre + [f"if {c.code}: break"]
        self.pre = []
        self.cur_span = saved
        self.loop_guard_open()
        self.indent += 1
        self.loops.append(Loop("repeat", test))
        self.stmts(s.body)
        self.loops.pop()
        self.cur_span = s.cond.span
        for line in test:
            self.emit(line)
        self.indent -= 1
        self.loop_guard_close(s.span)

    def s_for(self, s: n.For) -> None:
        v = self.lookup(s.var)
        if v is None:
            self.err(s.var_span, f"undeclared FOR control variable '{s.var}'")
            return
        ctl = self.var_ex(v)
        if not T.is_int(ctl.ty):
            self.err(s.var_span, f"invalid data type {ctl.ty} for the FOR control variable (needs an integer type)")
            return
        if not ctl.writable:
            self.err(s.var_span, f"FOR control variable: {ctl.why_readonly}")
            return
        start = self.coerce(self.expr(s.start), ctl.ty, s.start.span, "FOR start value")
        end = self.coerce(self.expr(s.end), ctl.ty, s.end.span, "FOR end value")
        step = self.coerce(self.expr(s.step), ctl.ty, s.step.span, "FOR step") if s.step is not None \
            else const_ex(1, ctl.ty)
        if T.ERR in (start.ty, end.ty, step.ty):
            return
        self.flush_pre()
        self.emit(f"{ctl.code} = {start.code}")
        if step.const is None:
            step_var = self.temp("_s")
            self.emit(f"{step_var} = {step.code}")
            step_code = step_var
            test = f"({ctl.code} <= {paren(end, P_CMP + 1)} if {step_var} > 0 else {ctl.code} >= {paren(end, P_CMP + 1)})"
        else:
            step_code = py_literal(step.const)[0]
            test = f"{ctl.code} {'<=' if step.const > 0 else '>='} {paren(end, P_CMP + 1)}"
        incr = self.wrap(Ex(f"{ctl.code} + {step_code}", ctl.ty, P_ADD, False)).code
        self.loop_guard_open()
        self.indent += 1
        self.emit(f"if not ({test}):")
        self.indent += 1
        self.emit("break")
        self.indent -= 1
        self.loops.append(Loop("for", [f"{ctl.code} = {incr}"]))
        self.stmts(s.body)
        self.loops.pop()
        self.emit(f"{ctl.code} = {incr}")
        self.indent -= 1
        self.loop_guard_close(s.span)

    def s_exit(self, s: n.Exit) -> None:
        if not self.loops:
            self.err(s.span, "EXIT outside a loop")
            return
        self.emit("break")

    def s_continue(self, s: n.Continue) -> None:
        if not self.loops:
            self.err(s.span, "CONTINUE outside a loop")
            return
        for line in self.loops[-1].step_code:
            self.emit(line)
        self.emit("continue")

    def s_return(self, s: n.Return) -> None:
        self.emit(self.return_line())

    def return_line(self) -> str:
        if not self.is_function:
            return "return"
        pou = self.pou
        outs = pou.tuple_outputs
        if not outs:
            return f"return v_{pou.key}"
        return "return (" + ", ".join([f"v_{pou.key}"] + [f"v_{o.key}" for o in outs]) + ")"

    # ================================================================ initial values
    def init_code(self, ty: T.Type, init: Optional[n.Init], span: Span) -> str:
        """Python expression that builds a fresh value of type ty with the given initialiser (None: default)."""
        b = T.base(ty)
        if init is None:
            return default_code(ty)
        if isinstance(b, T.ArrayT):
            if not isinstance(init, n.ArrayInit):
                self.err(span, f"an array ({ty}) needs an initialiser in brackets [ ... ]")
                return default_code(ty)
            items: list[str] = []
            for count, item in init.items:
                code = self.init_code(b.elem, item, span) if item is not None \
                    else default_code(b.elem)
                items.extend([code] * (count if count is not None else 1))
            if len(items) > b.size:
                self.err(init.span, f"{len(items)} initial values for an array of {b.size} elements")
                items = items[:b.size]
            rest = b.size - len(items)
            if T.is_aggregate(b.elem):
                items.extend([default_code(b.elem)] * rest)
                return "[" + ", ".join(items) + "]"
            tail = f" + [{default_code(b.elem)}] * {rest}" if rest else ""
            return "[" + ", ".join(items) + "]" + tail
        if isinstance(b, (T.StructT, T.FbT)):
            if not isinstance(init, n.StructInit):
                self.err(span, f"a {ty} needs an initialiser in parentheses ( field := value, ... )")
                return default_code(ty)
            parts = []
            for fname, finit, fspan in init.fields:
                key = fname.lower()
                if isinstance(b, T.StructT):
                    f = b.fields.get(key)
                    fty = f.ty if f is not None else None
                else:
                    fv = b.pou.vars.get(key)
                    fty = fv.ty if fv is not None and fv.kind in ("input", "output", "var") else None
                if fty is None:
                    self.err(fspan, f"{ty} has no field or input '{fname}'")
                    continue
                parts.append(f"v_{key}={self.init_code(fty, finit, fspan)}")
            return f"_sinit({default_code(ty)}, {', '.join(parts)})" if parts else default_code(ty)
        if isinstance(init, (n.ArrayInit, n.StructInit)):
            self.err(span, f"a {ty} cannot take an array or struct initialiser")
            return default_code(ty)
        ex = self.expr(init)
        if ex.ty is T.ERR:
            return default_code(ty)
        ex = self.coerce(ex, ty, init.span, "initial value")
        if ex.ty is T.ERR:
            return default_code(ty)
        if ex.const is None:
            self.err(init.span, "an initial value must be a literal (constant expression)")
            return default_code(ty)
        return py_literal(ex.const)[0]


def _apply(op: str, a, b, real: bool):
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
