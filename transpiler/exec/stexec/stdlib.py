"""Calls: user FUNCTIONs and FB instances, the IEC standard functions and the X_TO_Y conversions (typing and code)."""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Optional

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.model import PouInfo
from transpiler.exec.stexec.pou_base import PouCompilerApi
from transpiler.exec.stexec.pycode import ERR_EX, P_ADD, P_ATOM, P_BAND, P_CMP, P_COND, Ex, const_ex, paren
from transpiler.exec.stexec.rtlib import real_to_int, time_to_secs

# Standard function name -> formal parameter names (a trailing "..." means more numbered inputs may follow).
_SIGNATURES: Mapping[str, tuple[str, ...]] = MappingProxyType({
    "abs": ("IN",), "sqrt": ("IN",), "ln": ("IN",), "log": ("IN",), "exp": ("IN",), "sin": ("IN",),
    "cos": ("IN",), "tan": ("IN",), "asin": ("IN",), "acos": ("IN",), "atan": ("IN",), "trunc": ("IN",),
    "move": ("IN",), "len": ("IN",), "expt": ("IN1", "IN2"),
    "add": ("IN1", "IN2", "..."), "mul": ("IN1", "IN2", "..."), "sub": ("IN1", "IN2"), "div": ("IN1", "IN2"),
    "mod": ("IN1", "IN2"), "min": ("IN1", "IN2", "..."), "max": ("IN1", "IN2", "..."),
    "gt": ("IN1", "IN2", "..."), "ge": ("IN1", "IN2", "..."), "eq": ("IN1", "IN2", "..."),
    "le": ("IN1", "IN2", "..."), "lt": ("IN1", "IN2", "..."), "ne": ("IN1", "IN2"),
    "limit": ("MN", "IN", "MX"), "sel": ("G", "IN0", "IN1"), "mux": ("K", "IN0", "IN1", "..."),
    "shl": ("IN", "N"), "shr": ("IN", "N"), "rol": ("IN", "N"), "ror": ("IN", "N"),
    "left": ("IN", "L"), "right": ("IN", "L"), "mid": ("IN", "L", "P"), "concat": ("IN1", "IN2", "..."),
    "insert": ("IN1", "IN2", "P"), "delete": ("IN", "L", "P"), "replace": ("IN1", "IN2", "L", "P"),
    "find": ("IN1", "IN2"),
})
_BCD = MappingProxyType({"byte_bcd_to_usint": (T.BYTE, T.USINT), "word_bcd_to_uint": (T.WORD, T.UINT),
                        "dword_bcd_to_udint": (T.DWORD, T.UDINT), "lword_bcd_to_ulint": (T.LWORD, T.ULINT),
                        "usint_to_bcd_byte": (T.USINT, T.BYTE), "uint_to_bcd_word": (T.UINT, T.WORD),
                        "udint_to_bcd_dword": (T.UDINT, T.DWORD), "ulint_to_bcd_lword": (T.ULINT, T.LWORD)})
_MATH = MappingProxyType({"sqrt": "sqrt", "ln": "log", "log": "log10", "exp": "exp", "sin": "sin", "cos": "cos",
                          "tan": "tan", "asin": "asin", "acos": "acos", "atan": "atan"})


# Which helper compiles which standard function (the others: shifts, then string functions).
_MATH_KEYS = frozenset({"abs", "expt", "trunc", "move"} | set(_MATH))
_ARITH_KEYS = frozenset({"add", "mul", "sub", "div", "mod", "gt", "ge", "eq", "le", "lt", "ne"})
_SELECT_KEYS = frozenset({"min", "max", "limit", "sel", "mux"})


def conversion_types(key: str) -> Optional[tuple[T.Elem, T.Elem]]:
    if key in _BCD:
        return _BCD[key]
    if "_to_" not in key:
        return None
    src, dst = key.split("_to_", 1)
    s, d = T.ELEMENTARY.get(src), T.ELEMENTARY.get(dst)
    if s is None or d is None or s is d:
        return None
    return s, d


def is_standard_name(key: str) -> bool:
    return key in _SIGNATURES or conversion_types(key) is not None


# ====================================================================== argument binding

def _positional(pc: PouCompilerApi, node: n.Call, formals: tuple[str, ...]) -> Optional[list[n.Expr]]:
    """Actual arguments of a standard function in formal order (named arguments are reordered)."""
    args = node.args
    if any(a.target is not None for a in args):
        pc.err(node.span, f"{node.name.upper()} has no output parameters ('=>' is not allowed)")
        return None
    named = [a.name is not None for a in args]
    if any(named) and not all(named):
        pc.err(node.span, "positional and named arguments cannot be mixed in one call")
        return None
    variadic = formals[-1] == "..."
    fixed = [f for f in formals if f != "..."]
    if not any(named):
        values = [a.value for a in args]
    else:
        by_name = {}
        for a in args:
            k = a.name.upper()
            if k in by_name:
                pc.err(a.span, f"parameter {a.name} given twice")
                return None
            by_name[k] = a.value
        values = []
        names = list(fixed)
        if variadic:
            prefix = "IN0" if "IN0" in fixed else "IN1"
            first = int(prefix[2:])
            count = len(by_name) - (len(fixed) - sum(1 for f in fixed if f.startswith("IN")))
            names = [f for f in fixed if not f.startswith("IN")] + [f"IN{first + i}" for i in range(max(count, 0))]
            if "K" in fixed:
                names = ["K"] + [f"IN{first + i}" for i in range(len(by_name) - 1)]
        for k in names:
            if k not in by_name:
                pc.err(node.span, f"missing parameter {k} in call of {node.name.upper()}")
                return None
            values.append(by_name.pop(k))
        if by_name:
            pc.err(node.span, f"{node.name.upper()} has no parameter {', '.join(by_name)}")
            return None
    if len(values) < len(fixed) or (not variadic and len(values) > len(fixed)):
        expected = f"at least {len(fixed)}" if variadic else str(len(fixed))
        pc.err(node.span, f"{node.name.upper()} takes {expected} argument(s), {len(values)} given")
        return None
    return values


def _unify_all(pc: PouCompilerApi, exs: list[Ex], span: Span, fname: str) -> Optional[tuple[list[Ex], T.Type]]:
    typed = [e for e in exs if not isinstance(e.ty, T.LitType)]
    if not typed:
        cats = {e.ty for e in exs}
        if len(cats) > 1:
            pc.err(span, f"data type mismatch in {fname}: mixed integer and real literals")
            return None
        return exs, exs[0].ty
    ty = typed[0].ty
    out = []
    for e in exs:
        c = pc.coerce(e, ty, span, f"{fname} argument", report=False)
        if c is None or (not isinstance(e.ty, T.LitType) and not T.same(e.ty, ty)):
            pc.err(span, f"data type mismatch in {fname}: {e.ty} and {ty}")
            return None
        out.append(pc.val(c))
    return out, ty


def _int_arg(pc: PouCompilerApi, e: Ex, span: Span, what: str) -> Optional[Ex]:
    if T.is_int(e.ty) or (isinstance(e.ty, T.LitType) and e.ty.cat == "int"):
        return pc.val(e)
    pc.err(span, f"{what} must be an integer (INT, DINT, ...), not {e.ty}")
    return None


def _string_arg(pc: PouCompilerApi, e: Ex, span: Span, what: str) -> Optional[Ex]:
    if T.base(e.ty) is T.STRING:
        return e
    pc.err(span, f"{what} must be a STRING, not {e.ty}")
    return None


# ====================================================================== standard functions

def _std(pc: PouCompilerApi, key: str, node: n.Call) -> Ex:
    nodes_ = _positional(pc, node, _SIGNATURES[key])
    if nodes_ is None:
        return ERR_EX
    exs = [pc.expr(a) for a in nodes_]
    if any(e.ty is T.ERR for e in exs):
        return ERR_EX
    span = node.span
    name = key.upper()
    if key in _MATH_KEYS:
        return _math_fn(pc, key, exs, span, name)
    if key in _ARITH_KEYS:
        return _arith_fn(pc, key, exs, span, name)
    if key in _SELECT_KEYS:
        return _select_fn(pc, key, exs, span, name)
    if key in ("shl", "shr", "rol", "ror"):
        return _shift(pc, key, exs, span)
    return _string_fn(pc, key, exs, span)


def _math_fn(pc: PouCompilerApi, key: str, exs: list[Ex], span: Span, name: str) -> Ex:
    """ABS, the REAL math functions, EXPT, TRUNC and MOVE."""
    if key == "abs":
        x = exs[0]
        b = T.base(x.ty)
        if not (T.is_int(b) or T.is_real(b) or isinstance(b, T.LitType)):
            return pc.err(span, f"ABS needs a number, not {x.ty}")
        x = pc.val(x)
        if x.const is not None:
            return const_ex(abs(x.const), x.ty)
        return Ex(f"abs({x.code})", x.ty, P_ATOM, not (T.is_int(b) and b.signed))
    if key in _MATH:
        x = exs[0]
        if not (T.is_real(x.ty) or x.ty is T.ANY_REAL_LIT):
            return pc.err(span, f"{name} needs a REAL or LREAL argument, not {x.ty}")
        code = f"_fmath(_math.{_MATH[key]}, {x.code})"
        return Ex(f"_f32({code})" if T.base(x.ty) is T.REAL else code, x.ty)
    if key == "expt":
        return pc.power(exs[0], exs[1], span)
    if key == "trunc":
        x = exs[0]
        if not (T.is_real(x.ty) or x.ty is T.ANY_REAL_LIT):
            return pc.err(span, f"TRUNC needs a REAL or LREAL argument, not {x.ty}")
        return Ex(f"_trunc({x.code})", T.ANY_INT_LIT, P_ATOM, False)
    if key == "move":
        return exs[0]
    raise AssertionError(key)


def _arith_fn(pc: PouCompilerApi, key: str, exs: list[Ex], span: Span, name: str) -> Ex:
    """ADD, MUL, SUB, DIV, MOD and the comparison functions GT ... NE, typed like their operators."""
    if key in ("add", "mul", "sub"):
        op = {"add": "+", "mul": "*", "sub": "-"}[key]
        acc = exs[0]
        for e in exs[1:]:
            acc = pc.arith(op, acc, e, span)
            if acc.ty is T.ERR:
                return ERR_EX
        return acc
    if key in ("div", "mod"):
        probe = pc.arith("*", exs[0], exs[1], span)     # type check as for arithmetic
        if probe.ty is T.ERR:
            return ERR_EX
        if key == "mod" and not (T.is_int(probe.ty) or probe.ty is T.ANY_INT_LIT):
            return pc.err(span, f"MOD needs integer arguments, not {probe.ty}")
        u = _unify_all(pc, exs, span, name)
        if u is None:
            return ERR_EX
        (a, b), ty = u
        fn = "_div_fn" if key == "div" else "_mod_fn"
        code = f"{fn}({a.code}, {b.code})"
        if T.base(ty) is T.REAL:
            code = f"_f32({code})"
        signed_int = T.is_int(ty) and T.base(ty).signed
        return Ex(code, ty, P_ATOM, not (signed_int and key == "div"))
    if key in ("gt", "ge", "eq", "le", "lt", "ne"):
        op = {"gt": ">", "ge": ">=", "eq": "=", "le": "<=", "lt": "<", "ne": "<>"}[key]
        parts = [pc.compare(op, a, b, span) for a, b in zip(exs, exs[1:])]
        if any(p.ty is T.ERR for p in parts):
            return ERR_EX
        if len(parts) == 1:
            return parts[0]
        return Ex(" & ".join(f"({p.code})" for p in parts), T.BOOL, P_BAND)
    raise AssertionError(key)


def _select_fn(pc: PouCompilerApi, key: str, exs: list[Ex], span: Span, name: str) -> Ex:
    """MIN, MAX, LIMIT, SEL and MUX."""
    if key in ("min", "max"):
        u = _unify_all(pc, exs, span, name)
        if u is None:
            return ERR_EX
        vals, ty = u
        if not isinstance(T.base(ty), (T.Elem, T.LitType, T.EnumT)):
            return pc.err(span, f"{name} needs elementary values, not {ty}")
        if all(v.const is not None for v in vals):
            fn = min if key == "min" else max
            return const_ex(fn(v.const for v in vals), ty)
        return Ex(f"{key}({', '.join(v.code for v in vals)})", ty)
    if key == "limit":
        u = _unify_all(pc, exs, span, name)
        if u is None:
            return ERR_EX
        (mn, x, mx), ty = u
        return Ex(f"_limit({mn.code}, {x.code}, {mx.code})", ty)
    if key == "sel":
        g = exs[0]
        if T.base(g.ty) is not T.BOOL:
            return pc.err(span, f"SEL selector G must be BOOL, not {g.ty}")
        u = _unify_all(pc, exs[1:], span, name)
        if u is None:
            return ERR_EX
        (a, b), ty = u
        return Ex(f"{paren(b, P_COND + 1)} if {paren(g, P_COND + 1)} else {paren(a, P_COND)}", ty, P_COND)
    if key == "mux":
        k = _int_arg(pc, exs[0], span, "MUX selector K")
        u = _unify_all(pc, exs[1:], span, name)
        if k is None or u is None:
            return ERR_EX
        vals, ty = u
        return Ex(f"_mux({k.code}, {', '.join(v.code for v in vals)})", ty)
    raise AssertionError(key)


def _shift(pc: PouCompilerApi, key: str, exs: list[Ex], span: Span) -> Ex:
    x, cnt = exs
    if T.is_int(cnt.ty) or cnt.ty is T.ANY_INT_LIT:
        cnt = pc.val(cnt)
    else:
        return pc.err(span, f"{key.upper()} shift count N must be INT or DINT, not {cnt.ty} "
                            "(matiec cannot resolve the overload for a bit-string count)")
    if x.ty is T.ANY_INT_LIT and key in ("shl", "shr"):
        op = "<<" if key == "shl" else ">>"
        return Ex(f"{paren(x, P_ADD)} {op} {paren(cnt, P_ADD)}", T.ANY_INT_LIT, P_BAND - 1, False)
    if not T.is_bit(x.ty):
        return pc.err(span, f"{key.upper()} needs a bit string (BYTE, WORD, DWORD, LWORD), not {x.ty}")
    x = pc.val(x)
    b = T.base(x.ty)
    if key == "shl":
        return Ex(f"({paren(x, P_ADD)} << {paren(cnt, P_ADD)}) & {b.mask}", x.ty, P_BAND)
    if key == "shr":
        return Ex(f"{paren(x, P_ADD)} >> {paren(cnt, P_ADD)}", x.ty, P_BAND - 1)
    return Ex(f"_{key}({x.code}, {cnt.code}, {b.bits})", x.ty)


def _string_fn(pc: PouCompilerApi, key: str, exs: list[Ex], span: Span) -> Ex:
    name = key.upper()
    kinds = {"len": "s", "left": "si", "right": "si", "mid": "sii", "concat": "s" * len(exs),
             "insert": "ssi", "delete": "sii", "replace": "ssii", "find": "ss"}[key]
    vals = []
    for e, kind, pos in zip(exs, kinds, range(1, len(exs) + 1)):
        v = _string_arg(pc, e, span, f"argument {pos} of {name}") if kind == "s" \
            else _int_arg(pc, e, span, f"argument {pos} of {name}")
        if v is None:
            return ERR_EX
        vals.append(v.code)
    if key == "len":
        return Ex(f"len({vals[0]})", T.ANY_INT_LIT)
    if key == "find":
        return Ex(f"_s_find({', '.join(vals)})", T.ANY_INT_LIT)
    if key == "concat":
        return Ex(f"_concat({', '.join(vals)})", T.STRING)
    return Ex(f"_s_{key}({', '.join(vals)})", T.STRING)


# ====================================================================== conversions

def _conversion(pc: PouCompilerApi, key: str, node: n.Call, src: T.Elem, dst: T.Elem) -> Ex:
    nodes_ = _positional(pc, node, ("IN",))
    if nodes_ is None:
        return ERR_EX
    x = pc.expr(nodes_[0])
    if x.ty is T.ERR:
        return ERR_EX
    x = pc.coerce(x, src, nodes_[0].span, f"argument of {key.upper()}", report=False)
    if x is None or x.ty is T.ERR:
        got = pc.expr(nodes_[0]).ty
        return pc.err(nodes_[0].span, f"data type incompatibility: {key.upper()} needs a {src}, not {got}")
    x = pc.val(x)
    if key in _BCD:
        if src.cat == "bit":
            return pc.wrap(Ex(f"_bcd_to_int({x.code})", dst, P_ATOM, False))
        return Ex(f"_int_to_bcd({x.code}, {dst.bits})", dst)
    code, wrapped = convert_code(src, dst, x)
    out = Ex(code[0], dst, code[1], wrapped)
    if x.const is not None and not isinstance(x.const, str) and wrapped and dst.cat in ("int", "bit", "bool"):
        try:
            value = eval(code[0], {"_real_to_int": real_to_int, "_time_to_secs": time_to_secs})  # noqa: S307
            return const_ex(value, dst)
        except Exception:   # noqa: BLE001 - a conversion that traps at run time is left to run time
            return out
    return out


def convert_code(src: T.Elem, dst: T.Elem, x: Ex) -> tuple[tuple[str, int], bool]:
    """((code, precedence), wrapped) of SRC_TO_DST applied to x (already exact)."""
    sc, dc = src.cat, dst.cat
    X = x.code
    xa = paren(x, P_ATOM)
    if sc in ("int", "bit"):
        if dc in ("int", "bit"):
            fits = src.lo >= dst.lo and src.hi <= dst.hi
            return (X, x.prec), fits
        if dc == "bool":
            return (f"{paren(x, P_CMP + 1)} != 0", P_CMP), True
        if dc == "real":
            return (f"_f32({X})" if dst is T.REAL else f"float({X})", P_ATOM), True
        if dc == "time":
            return (f"{paren(x, P_ADD)} * 1000", P_ADD), True
        if dc == "string":
            return (f"_bits_to_string({X})" if sc == "bit" else f"str({X})", P_ATOM), True
    if sc == "bool":
        as_int = f"({paren(x, P_ADD)} + 0)"
        if dc in ("int", "bit"):
            return (as_int, P_ATOM), True
        if dc == "real":
            return (f"float({X})", P_ATOM), True
        if dc == "time":
            return (f"{as_int} * 1000", P_ADD), True
        if dc == "string":
            return (f"_bool_to_string({X})", P_ATOM), True
    if sc == "real":
        if dc in ("int", "bit"):
            return (f"_real_to_int({X}, {dst.bits}, {dst.signed})", P_ATOM), True
        if dc == "bool":
            return (f"{paren(x, P_CMP + 1)} != 0", P_CMP), True
        if dc == "real":
            return (f"_f32({X})" if dst is T.REAL else X, P_ATOM if dst is T.REAL else x.prec), True
        if dc == "time":
            return (f"_real_to_time({X})", P_ATOM), True
        if dc == "string":
            return (f"_real_to_string({X})", P_ATOM), True
    if sc == "time":
        secs = f"_time_to_secs({X})"
        if dc in ("int", "bit"):
            return (secs, P_ATOM), False
        if dc == "bool":
            return (f"{secs} != 0", P_CMP), True
        if dc == "real":
            return (f"_f32({xa} / 1000)" if dst is T.REAL else f"{xa} / 1000", P_ATOM), True
        if dc == "string":
            return (f"_time_to_string({X})", P_ATOM), True
    if sc == "string":
        if dc in ("int", "bit"):
            return (f"_string_to_int({X})", P_ATOM), False
        if dc == "bool":
            return (f"_string_to_bool({X})", P_ATOM), True
        if dc == "real":
            return (f"_f32(_string_to_real({X}))" if dst is T.REAL else f"_string_to_real({X})", P_ATOM), True
        if dc == "time":
            return (f"_string_to_time({X})", P_ATOM), True
    raise AssertionError(f"no conversion {src} -> {dst}")


# ====================================================================== user functions

def _bind(pc: PouCompilerApi, pou: PouInfo, args: list[n.Arg], span: Span) -> Optional[dict[str, n.Arg]]:
    named = [a.name is not None for a in args]
    if any(named) and not all(named):
        pc.err(span, "positional and named arguments cannot be mixed in one call")
        return None
    bound: dict[str, n.Arg] = {}
    if args and not any(named):
        slots = [v for v in pou.params if v.kind != "output"]
        if len(args) > len(slots):
            pc.err(span, f"{pou.name} takes {len(slots)} positional argument(s), {len(args)} given")
            return None
        for v, a in zip(slots, args):
            bound[v.key] = a
        return bound
    for a in args:
        key = a.name.lower()
        v = pou.vars.get(key)
        if v is None or v.kind not in ("input", "output", "inout"):
            pc.err(a.span, f"{pou.name} has no parameter '{a.name}'")
            return None
        if key in bound:
            pc.err(a.span, f"parameter '{a.name}' given twice")
            return None
        if a.target is not None and v.kind != "output":
            pc.err(a.span, f"'{a.name}' is not an output of {pou.name}; use ':='")
            return None
        if a.target is None and v.kind == "output":
            pc.err(a.span, f"'{a.name}' is an output of {pou.name}; use '=>'")
            return None
        bound[key] = a
    return bound


def _inout_actual(pc: PouCompilerApi, pou: PouInfo, v, a: Optional[n.Arg], span: Span, is_fb: bool) -> Optional[Ex]:
    if a is None:
        pc.err(span, f"VAR_IN_OUT '{v.name}' of {pou.name} must be given")
        return None
    node = a.value
    if not isinstance(node, (n.Name, n.Field, n.Index, n.Addr)):
        pc.err(a.span, f"the VAR_IN_OUT '{v.name}' needs a variable; assignment to an expression or a literal "
                       "value is not allowed")
        return None
    ex = pc.lvalue(node)
    if ex.ty is T.ERR:
        return None
    if not T.same(ex.ty, v.ty):
        pc.err(a.span, f"data type incompatibility for VAR_IN_OUT '{v.name}': {ex.ty} where {v.ty} is expected")
        return None
    if ex.is_global and not is_fb:
        pc.err(a.span, f"a global variable passed to the VAR_IN_OUT '{v.name}' of FUNCTION {pou.name} "
                       "(matiec generates C that does not compile; copy it to a local variable first)")
        return None
    return ex


def _user_function(pc: PouCompilerApi, pou: PouInfo, node: n.Call) -> Ex:
    bound = _bind(pc, pou, node.args, node.span)
    if bound is None:
        return ERR_EX
    codes = []
    inouts = {}
    for v in pou.pyparams:
        a = bound.get(v.key)
        if v.kind == "input":
            if a is None:
                codes.append(pc.init_code(v.ty, v.init, v.span))    # the declared initial value, else the default
                continue
            ex = pc.expr(a.value)
            ex = pc.coerce(ex, v.ty, a.value.span, f"argument '{v.name}' of {pou.name}")
            if ex.ty is T.ERR:
                return ERR_EX
            ex = pc.val(ex)
            codes.append(pc.copy_code(v.ty, ex.code) if T.is_aggregate(v.ty) else ex.code)
        else:
            ex = _inout_actual(pc, pou, v, a, node.span, False)
            if ex is None:
                return ERR_EX
            inouts[v.key] = ex
            codes.append(ex.code)
    outs = {}
    for v in pou.vars.values():
        if v.kind == "output" and v.key in bound:
            a = bound[v.key]
            tgt = pc.lvalue(a.target)
            if tgt.ty is T.ERR:
                return ERR_EX
            if not T.same(tgt.ty, v.ty) and not (a.negated and T.base(v.ty) is T.BOOL):
                return pc.err(a.span, f"output '{v.name}' is {v.ty} but the target is {tgt.ty}")
            outs[v.key] = (tgt, a.negated)
    call = f"F_{pou.key}({', '.join(codes)})"
    rest = pou.tuple_outputs
    if not rest:
        return Ex(call, pou.result)
    t = pc.temp("_r")
    pc.pre.append(f"{t} = {call}")
    for i, v in enumerate(rest, start=1):
        target = outs.get(v.key)
        if target is not None:
            tgt, neg = target
            value = Ex(f"not {t}[{i}]" if neg else f"{t}[{i}]", v.ty)
            pc.pre.extend(pc.assign_lines(tgt, value))
        elif v.key in inouts:
            pc.pre.extend(pc.assign_lines(inouts[v.key], Ex(f"{t}[{i}]", v.ty)))
    return Ex(f"{t}[0]", pou.result)


def compile_call(pc: PouCompilerApi, node: n.Call) -> Ex:
    key = node.name.lower()
    pou = pc.ctx.pous.get(key)
    if pou is not None and pou.ordinal < pc.ordinal:
        if pou.kind == "function":
            return _user_function(pc, pou, node)
        return pc.err(node.span, f"{pou.kind.replace('_', ' ')} '{node.name}' cannot be called in an expression")
    if pou is not None and pou.key == (pc.pou.key if pc.pou else None):
        return pc.err(node.span, f"recursive call of '{node.name}' (the name is not known inside its own body)")
    if pou is not None:
        return pc.err(node.span, f"'{node.name}' is used before its declaration (emit callees before callers)")
    v = pc.lookup(key)
    if v is not None and isinstance(v.ty, T.FbT):
        return pc.err(node.span, f"function block instance '{node.name}' can only be called as a statement")
    if key in _SIGNATURES:
        return _std(pc, key, node)
    conv = conversion_types(key)
    if conv is not None:
        return _conversion(pc, key, node, *conv)
    return pc.err(node.span, f"unknown function '{node.name}'")


# ====================================================================== FB calls (statements)

def compile_call_stmt(pc: PouCompilerApi, s: n.CallStmt) -> None:
    key = s.name.lower()
    v = pc.lookup(key)
    if v is None:
        pou = pc.ctx.pous.get(key)
        if (pou is not None and pou.kind == "function") or is_standard_name(key):
            pc.err(s.span, f"function '{s.name}' called as a statement; matiec only allows function calls inside "
                           "expressions (x := F(...))")
        else:
            pc.err(s.span, f"undeclared function block instance '{s.name}'")
        return
    if not isinstance(v.ty, T.FbT):
        pc.err(s.span, f"'{s.name}' is not a function block instance (it is {v.ty})")
        return
    fb = v.ty.pou
    bound = _bind(pc, fb, s.args, s.span)
    if bound is None:
        return
    inst = pc.var_ex(v).code
    lines: list[str] = []
    after: list[str] = []
    if len(bound) + 1 > 2 and "." in inst:
        alias = pc.temp("_f")
        lines.append(f"{alias} = {inst}")
        inst = alias
    for fv in fb.params:
        a = bound.get(fv.key)
        slot = Ex(f"{inst}.v_{fv.key}", fv.ty)
        if fv.kind == "input":
            if a is None:
                continue
            ex = pc.coerce(pc.expr(a.value), fv.ty, a.value.span, f"input '{fv.name}' of {fb.name}")
            if ex.ty is T.ERR:
                return
            lines.extend(pc.assign_lines(slot, pc.val(ex)))
        elif fv.kind == "inout":
            ex = _inout_actual(pc, fb, fv, a, s.span, True)
            if ex is None:
                return
            lines.append(f"{slot.code} = {ex.code}")
            if not T.is_aggregate(fv.ty):
                after.append(f"{ex.code} = {slot.code}")
        elif a is not None:
            tgt = pc.lvalue(a.target)
            if tgt.ty is T.ERR:
                return
            if not T.same(tgt.ty, fv.ty):
                pc.err(a.span, f"output '{fv.name}' is {fv.ty} but the target is {tgt.ty}")
                return
            value = Ex(f"not {slot.code}" if a.negated else slot.code, fv.ty)
            after.extend(pc.assign_lines(tgt, value))
    pc.flush_pre()
    for line in lines:
        pc.emit(line)
    pc.emit(f"B_{fb.key}({inst})")
    for line in after:
        pc.emit(line)

